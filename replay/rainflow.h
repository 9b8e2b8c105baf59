// Rainflow cycle counting per ASTM E1049-85 (reapproved 2017), Sec. 5.4.4.
//
// Two steps:
//  1. extract_reversals(): reduce a sampled load history to its peaks and valleys (Sec. 5.4.4
//     "reversals"). Runs of equal consecutive values collapse to their first sample; samples on a
//     monotone stretch are dropped; the first and the last sample are always reversals.
//  2. rainflow_count(): the three-point algorithm of Sec. 5.4.4 with the starting point S:
//       (1) read the next reversal; if out of data go to (6);
//       (2) with fewer than three points go to (1); X = most recent range, Y = the range before it;
//       (3) if X < Y go to (1);
//       (4) if Y contains S go to (5); otherwise count Y as ONE cycle, discard both points of Y,
//           go to (2);
//       (5) count Y as ONE-HALF cycle, discard the first point of Y (S moves to its second
//           point), go to (2);
//       (6) RESIDUE RULE: every range between consecutive points left over at the end of the
//           history is counted as ONE-HALF cycle (no closing of the residue, no repetition of the
//           history). Together with the half cycles of step (5) this is the standard's rule.
//     Ties (X == Y) count, as the standard's "X >= Y" says.
//
// Cycles are returned in the order in which they are counted. Property used by the tests:
// sum over cycles of 2 * count * range == sum of |r[i+1] - r[i]| over the reversals (every piece of
// the load path is counted exactly once).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace peritwin::replay {

/// Peaks and valleys of a sampled history: values[i] occurs at sample sample_index[i] of the input.
struct Reversals {
  std::vector<double> values;
  std::vector<std::size_t> sample_index;
};

/// One counted rainflow cycle (or half cycle).
struct RainflowCycle {
  double range = 0.0;     ///< |r[last] - r[first]| (> 0)
  double mean = 0.0;      ///< (r[first] + r[last]) / 2
  double count = 0.0;     ///< 1.0 (full cycle) or 0.5 (half cycle)
  std::size_t first = 0;  ///< index of the earlier reversal of the range (into the reversal list)
  std::size_t last = 0;   ///< index of the later reversal of the range
};

/// Reversals of a sampled history (see the header comment). Empty input gives no reversals; a
/// constant history gives one. Throws std::invalid_argument on a non-finite value.
[[nodiscard]] Reversals extract_reversals(std::span<const double> loads);

/// ASTM E1049-85 Sec. 5.4.4 rainflow counting of a reversal sequence (see the header comment).
/// Throws std::invalid_argument unless the input alternates strictly (each value differs from its
/// predecessor and the direction changes at every point), i.e. is the output of
/// extract_reversals(), or contains a non-finite value.
[[nodiscard]] std::vector<RainflowCycle> rainflow_count(std::span<const double> reversals);

}  // namespace peritwin::replay
