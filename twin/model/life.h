// Remaining life: cycles until the detail's end criterion under a reference spectrum, by forward
// simulation on a copy of the model (a fresh FatigueEngine that imports the state), with a band
// from the scatter of the calibrated A2 (A2·(1 ± s): the larger A2 damages faster and gives the
// low end). The rolling empirical spectrum of the received cycles is kept here too.
//
// Forward simulation (simulate_life):
//  * the spectrum's blocks are applied in order, pass after pass, until the criterion is met;
//  * exact cycle of the criterion: the engine stops there (end_of_life_check after every group of
//    breaks, the live twin's rule: crack_length, phase3); connectivity (and, for every criterion,
//    a singular stiffness) is the cycle at which the engine reached final failure;
//  * a pass that breaks no bond doubles the counts of the next pass (exact in the engine's block
//    stepping, it only coarsens how blocks interleave) so that lightly loaded details finish
//    quickly; the multiplier returns to 1 after a pass with breaks;
//  * +Inf when the criterion is not met within kMaxSimulatedCycles.
// All of it is a pure function of (model, engine state, spectrum, A2 factor).
#pragma once

#include <atomic>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "solver/fatigue/fatigue_engine.h"
#include "twin/model/detail_model.h"

namespace peritwin::twin {

inline constexpr double kMaxSimulatedCycles = 1e12;

/// The latest estimate and the state it was computed on.
struct LifeEstimate {
  double central = std::numeric_limits<double>::quiet_NaN();
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
  std::int64_t state_seq = -1;  ///< Twin state_seq it belongs to (-1: none)
  std::int64_t seq = -1;        ///< (source, seq) of the batch that produced that state
  std::string source;           ///< "" with seq -1: none, or the initial state
};

/// The rolling empirical spectrum: the last kCapacity received blocks (a block equal in
/// (p_max, r, alpha) to the newest one is merged into it). Deterministic.
class RollingSpectrum {
 public:
  static constexpr std::size_t kCapacity = 4096;
  /// Largest number of levels reference() returns.
  static constexpr std::size_t kMaxLevels = 32;

  void add(const LoadBlock& block);
  [[nodiscard]] const std::deque<LoadBlock>& blocks() const { return blocks_; }
  [[nodiscard]] bool empty() const { return blocks_.empty(); }
  void clear() { blocks_.clear(); }
  void assign(std::vector<LoadBlock> blocks);
  /// The reference spectrum: equal (p_max, r, alpha) summed, in order of first appearance; with
  /// more than kMaxLevels levels, levels sorted by load range P_max(1−R) are grouped into
  /// kMaxLevels groups of about equal cycle counts, each represented (conservatively) by its
  /// largest-range level with the group's total count.
  [[nodiscard]] std::vector<LoadBlock> reference() const;

 private:
  std::deque<LoadBlock> blocks_;
};

/// The detail's configured reference spectrum, or `empirical.reference()` when it says
/// "empirical". Empty = no spectrum yet (no estimate possible).
std::vector<LoadBlock> reference_spectrum(const DetailModel& model,
                                          const RollingSpectrum& empirical);

/// Cycles from `state` until the end criterion under `spectrum` (repeated), A2 scaled by
/// `a2_factor`. 0 when already met, +Inf when not met within kMaxSimulatedCycles, NaN when the
/// state cannot be imported or the spectrum is empty, or when `cancel` becomes true (checked
/// between blocks).
double simulate_life(const DetailModel& model, const EngineState& state,
                     const std::vector<LoadBlock>& spectrum, double a2_factor,
                     const std::atomic<bool>* cancel = nullptr);

/// Central value and band (3 forward simulations, run concurrently when `parallel`).
/// state_seq/seq/source are left for the caller to fill in.
LifeEstimate estimate_life(const DetailModel& model, const EngineState& state,
                           const std::vector<LoadBlock>& spectrum, bool parallel = true,
                           const std::atomic<bool>* cancel = nullptr);

}  // namespace peritwin::twin
