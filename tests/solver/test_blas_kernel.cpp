#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/blas_kernel.h"

namespace peritwin {
namespace {

TEST(BlasKernel, NamesTheKernelSetOpenBlasRuns) {
  // Debian's libblas.so.3 is OpenBLAS (scripts/install-deps.sh installs libopenblas0-pthread).
  const std::string name = core::blas_kernel_name();
  EXPECT_NE(name, "unknown");
  EXPECT_FALSE(name.empty());
  // Run once more by CTest with OPENBLAS_CORETYPE=Nehalem (tests/solver/CMakeLists.txt): the
  // variable pins the kernel set, as docs/solver.md tells an operator to do for bit-identical
  // runs across machines.
  if (const char* pinned = std::getenv("OPENBLAS_CORETYPE")) {
    EXPECT_EQ(name, std::string(pinned));
  }
}

}  // namespace
}  // namespace peritwin
