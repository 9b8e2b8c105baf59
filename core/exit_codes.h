// The exit codes of the peritwin programs (each program's header comment says which it uses).
// The benchmarks' option-parse errors keep CLI11's own codes (core/program.h, ParseErrors).
#pragma once

namespace peritwin::core {

inline constexpr int kExitOk = 0;       ///< done (also: --help, a clean stop by SIGINT/SIGTERM)
inline constexpr int kExitUsage = 2;    ///< bad usage, config or input: nothing was run
inline constexpr int kExitRuntime = 3;  ///< runtime failure (LCM, I/O, a calibration that failed)

}  // namespace peritwin::core
