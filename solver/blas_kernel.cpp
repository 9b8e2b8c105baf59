#include "solver/blas_kernel.h"

#include <dlfcn.h>

namespace peritwin {

std::string blas_kernel_name() {
  // Looked up at run time: linking the symbol would tie the build to OpenBLAS, while Debian lets
  // the administrator switch libblas.so.3 to another implementation.
  using CoreName = char* (*)();
  void* symbol = dlsym(RTLD_DEFAULT, "openblas_get_corename");
  if (symbol == nullptr) return "unknown";
  const char* name = reinterpret_cast<CoreName>(symbol)();
  return name != nullptr && *name != '\0' ? std::string(name) : std::string("unknown");
}

}  // namespace peritwin
