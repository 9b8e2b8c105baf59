// Rainflow cycle counting per ASTM E1049-85 (reapproved 2017), Sec. 5.4.4, incrementally: one
// sample at a time, the residue kept open between calls, so any split of a history into chunks
// (and any save()/restore() between them) gives exactly the cycles of the whole history, in the
// same order. SI units: loads in N, angles in rad.
//
// Reversals (peaks and valleys, Sec. 5.4.4), found in push():
//  * the first finite sample is the starting point S, always a reversal;
//  * plateaus and repeated values collapse to their first sample (its angle is the one kept);
//  * hysteresis gate (the "gate" of fatpack / pyLife, 0 by default): a candidate extremum becomes
//    a reversal only when the load has moved back from it by MORE than `gate` (gate 0: any strict
//    change of direction). Before the first candidate exists, the load must leave S by more than
//    `gate`. So every range between consecutive reversals is > gate: smaller wiggles are no
//    reversals (they are neither counted nor do they split a larger range);
//  * the last, unconfirmed extremum (the candidate) is part of the state; finish() reads it as the
//    last reversal of the history (ASTM: the last point is a reversal).
//  * a NaN or infinite load (or angle) is skipped and counted in RainflowStats::nonfinite_samples.
//
// Counting, the three-point algorithm of Sec. 5.4.4 with the starting point S, run on every new
// reversal (stack = the reversals not yet discarded, stack.front() = S):
//   (1) read the next reversal; if out of data go to (6);
//   (2) with fewer than three points go to (1); X = most recent range, Y = the range before it;
//   (3) if X < Y go to (1);  (ties X == Y count: the standard's "X >= Y")
//   (4) if Y contains S go to (5); otherwise count Y as ONE cycle, discard both points of Y,
//       go to (2);
//   (5) count Y as ONE-HALF cycle, discard the first point of Y (S moves to its second point),
//       go to (2);
//   (6) the residue (ResidueRule): every range between consecutive points left at the end of the
//       history is ONE-HALF cycle (ASTM, `half`, the default), or ONE cycle (`whole`,
//       conservative: the residue's largest ranges are the history's largest loads, and a
//       history that is repeated closes them as whole cycles), or is not counted and stays open
//       (`keep`: the history continues in a later chunk or run).
// Step (5) and the residue are the only sources of half cycles. Property used by the tests: with
// `half`, sum over cycles of 2 * count * |to - from| is the path length sum |r[i+1] - r[i]| over
// the reversals (every piece of the load path is counted exactly once).
//
// Cost: O(1) amortized per sample; the stack grows only with the residue (for a stationary
// history, a few dozen points) and push() allocates nothing once it has its capacity.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/expected.h"

namespace peritwin::loads {

/// What finish() does with the residue (step (6) in the header comment).
enum class ResidueRule {
  half,   ///< each residue range is a half cycle (ASTM E1049-85, the default)
  whole,  ///< each residue range is a whole cycle (conservative)
  keep,   ///< kept open, not counted: a stream that will continue
};

/// One rainflow cycle or half cycle.
struct CountedCycle {
  double from = 0.0;   ///< the earlier reversal value (N)
  double to = 0.0;     ///< the later reversal value (N); never equal to `from`
  double count = 1.0;  ///< 1.0 or 0.5
  double alpha = 0.0;  ///< load angle (rad) at the reversal of the larger of from/to (the peak)
  friend bool operator==(const CountedCycle&, const CountedCycle&) = default;
};

struct RainflowStats {
  std::uint64_t samples = 0;            ///< push() calls (finite or not)
  std::uint64_t nonfinite_samples = 0;  ///< of those, skipped for a NaN/inf load or angle
  std::uint64_t reversals = 0;          ///< reversals read by the counting (S included)
  std::uint64_t full_cycles = 0;        ///< cycles counted 1.0 (residue `whole` included)
  std::uint64_t half_cycles = 0;        ///< cycles counted 0.5
  friend bool operator==(const RainflowStats&, const RainflowStats&) = default;
};

/// The incremental rainflow counter (see the header comment).
class RainflowCounter {
 public:
  /// `gate` (N): finite and >= 0, else std::invalid_argument.
  explicit RainflowCounter(double gate = 0.0);

  /// One sample: appends the cycles it closes to `out` (steps (1)-(5)).
  void push(double load, double alpha, std::vector<CountedCycle>& out);

  /// End of the history: with `half` or `whole` the candidate is read as the last reversal,
  /// counted, and the residue is appended to `out` (step (6)); the counter then starts a new
  /// history (stats kept). With `keep` nothing is counted and the state is unchanged.
  void finish(ResidueRule rule, std::vector<CountedCycle>& out);

  /// The whole state (gate, stats, reversal detection, residue) as text; floating-point values as
  /// hexadecimal floats (%a), so restore(save()) continues bit-identically.
  [[nodiscard]] std::string save() const;
  /// The counter save() wrote, or the reason the text is not one (truncated, malformed, a value
  /// out of range, a residue that the counting could not have left).
  static core::Expected<RainflowCounter, std::string> restore(std::string_view text);

  [[nodiscard]] const RainflowStats& stats() const { return stats_; }
  [[nodiscard]] double gate() const { return gate_; }
  /// The open reversal stack (S first), then the candidate if there is one: what finish() with
  /// `half` would count as the residue if no more cycle closed.
  [[nodiscard]] std::vector<double> residue() const;

 private:
  struct Reversal {
    double load = 0.0;
    double alpha = 0.0;
  };
  void read_reversal(Reversal reversal, std::vector<CountedCycle>& out);  // steps (1)-(5)

  double gate_ = 0.0;
  RainflowStats stats_;
  bool started_ = false;  ///< S has been seen
  int direction_ = 0;     ///< +1: the candidate is a running maximum, -1: minimum, 0: none yet
  Reversal candidate_;    ///< the unconfirmed extremum (direction_ != 0)
  std::vector<Reversal> stack_;
};

/// A whole history at once: push() every sample (angle from `angles`, 0 when empty; otherwise
/// as many as `loads`, else std::invalid_argument), then finish(rule).
[[nodiscard]] std::vector<CountedCycle> count_cycles(std::span<const double> loads,
                                                     std::span<const double> angles = {},
                                                     ResidueRule rule = ResidueRule::half,
                                                     double gate = 0.0);

}  // namespace peritwin::loads
