#include "core/blas_kernel.h"

#include <dlfcn.h>

namespace peritwin::core {

const std::string& blas_kernel_name() {
  // Looked up at run time: linking the symbol would tie the build to OpenBLAS, while Debian lets
  // the administrator switch libblas.so.3 to another implementation. OpenBLAS chose its kernels
  // when it loaded, so the answer cannot change: asked once.
  static const std::string name = [] {
    using CoreName = char* (*)();
    void* symbol = dlsym(RTLD_DEFAULT, "openblas_get_corename");
    const char* core = symbol != nullptr ? reinterpret_cast<CoreName>(symbol)() : nullptr;
    return core != nullptr && *core != '\0' ? std::string(core) : std::string("unknown");
  }();
  return name;
}

}  // namespace peritwin::core
