// Which BLAS kernel set this process runs. CHOLMOD's supernodal factorization and solves call the
// BLAS, and OpenBLAS (Debian's build picks its kernels at start-up for the CPU it finds) rounds
// differently with different kernels, so the last bits of a model's state depend on it: the same
// config and messages give the same bits on the same kernel set, and agree only to rounding on
// another. OPENBLAS_CORETYPE=<name> in the environment pins the set (docs/solver.md).
#pragma once

#include <string>

namespace peritwin::core {

/// OpenBLAS's core name (openblas_get_corename, e.g. "Haswell"), or "unknown" when the BLAS in
/// this process is not OpenBLAS. Looked up once per process.
const std::string& blas_kernel_name();

}  // namespace peritwin::core
