// Latency percentiles of the service benchmarks (stream, dashboard, fleet): the nearest-rank
// definition, the smallest value with at least q of the samples at or below it; NaN when empty.
// (peritwin-bench-ingest keeps its own rounded-rank percentile: its published figures use it.)
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace peritwin::core {

inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(k, v.size() - 1)];
}

}  // namespace peritwin::core
