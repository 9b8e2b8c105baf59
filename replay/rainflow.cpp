#include "replay/rainflow.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace peritwin::replay {

Reversals extract_reversals(std::span<const double> loads) {
  Reversals out;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    const double v = loads[i];
    if (!std::isfinite(v)) {
      throw std::invalid_argument("extract_reversals: non-finite load at sample " +
                                  std::to_string(i));
    }
    const std::size_t n = out.values.size();
    if (n > 0 && v == out.values[n - 1]) continue;  // plateau: keep its first sample
    if (n >= 2) {
      const double a = out.values[n - 2];
      const double b = out.values[n - 1];
      // b lies on the monotone stretch a -> v: it is no reversal, v replaces it.
      if ((b > a && v > b) || (b < a && v < b)) {
        out.values[n - 1] = v;
        out.sample_index[n - 1] = i;
        continue;
      }
    }
    out.values.push_back(v);
    out.sample_index.push_back(i);
  }
  return out;
}

std::vector<RainflowCycle> rainflow_count(std::span<const double> reversals) {
  for (std::size_t i = 0; i < reversals.size(); ++i) {
    if (!std::isfinite(reversals[i])) {
      throw std::invalid_argument("rainflow_count: non-finite value at reversal " +
                                  std::to_string(i));
    }
    const bool repeats = i >= 1 && reversals[i] == reversals[i - 1];
    const bool monotone =
        i >= 2 && (reversals[i] - reversals[i - 1]) * (reversals[i - 1] - reversals[i - 2]) > 0.0;
    if (repeats || monotone) {
      throw std::invalid_argument("rainflow_count: point " + std::to_string(i) +
                                  " is not a reversal (use extract_reversals first)");
    }
  }

  std::vector<RainflowCycle> cycles;
  auto emit = [&](std::size_t first, std::size_t last, double count) {
    const double a = reversals[first];
    const double b = reversals[last];
    cycles.push_back(RainflowCycle{std::abs(b - a), 0.5 * (a + b), count, first, last});
  };

  // Undiscarded reversals (indices); stack.front() is always the starting point S.
  std::vector<std::size_t> stack;
  for (std::size_t i = 0; i < reversals.size(); ++i) {
    stack.push_back(i);          // step (1)
    while (stack.size() >= 3) {  // step (2)
      const std::size_t k = stack.size();
      const double x = std::abs(reversals[stack[k - 1]] - reversals[stack[k - 2]]);
      const double y = std::abs(reversals[stack[k - 2]] - reversals[stack[k - 3]]);
      if (x < y) break;  // step (3)
      if (k == 3) {
        // Step (5): Y starts at S -> half cycle, S moves to Y's second point.
        emit(stack[0], stack[1], 0.5);
        stack.erase(stack.begin());
      } else {
        // Step (4): full cycle, both points of Y discarded.
        emit(stack[k - 3], stack[k - 2], 1.0);
        stack.erase(stack.begin() + static_cast<std::ptrdiff_t>(k - 3),
                    stack.begin() + static_cast<std::ptrdiff_t>(k - 1));
      }
    }
  }
  // Step (6): residue -> half cycles.
  for (std::size_t j = 0; j + 1 < stack.size(); ++j) emit(stack[j], stack[j + 1], 0.5);
  return cycles;
}

}  // namespace peritwin::replay
