// The stopwatch of StaticSolver's timings, shared by its source files (not part of its interface).
#pragma once

#include <chrono>

namespace peritwin::statics::static_solver_detail {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace peritwin::statics::static_solver_detail
