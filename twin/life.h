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
#include "twin/detail_model.h"

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
  // Diagnostics, not part of the twin's state (not hashed, not checkpointed):
  double wall_s = std::numeric_limits<double>::quiet_NaN();  ///< wall time of the estimate
  std::int64_t start_cycles = -1;  ///< engine cycles of the state it started from
  bool forked = false;             ///< continued from a live engine's factor (FatigueEngine::fork)
  bool coarse = false;             ///< on the coarser grid of [detail.life] dx (coarse_life.h)
  /// Coarse only: calibrated A2 over its 000 Eq. (29) value; NaN when not calibrated.
  double coarse_a2_factor = std::numeric_limits<double>::quiet_NaN();
};

/// Where one forward simulation's wall time went (seconds; a phase not taken is 0).
struct SimulationStats {
  double build_s = 0.0;     ///< a fresh engine: its first solve (assembly, analysis, factor)
  double import_s = 0.0;    ///< a fresh engine: import_state (replay of the re-solves)
  double fork_s = 0.0;      ///< FatigueEngine::fork (copy of the live factor)
  double stepping_s = 0.0;  ///< blocks until the criterion (bond breaks, rank updates, solves)
  double wall_s = 0.0;      ///< the whole simulate_life call
  std::int64_t breaks = 0;  ///< bonds broken in the simulation
  int updates = 0;          ///< rank updates in the simulation
};

/// The rolling empirical spectrum: the last kCapacity received blocks (a block equal in
/// (p_max, r, alpha) to the newest one is merged into it). Deterministic.
class RollingSpectrum {
 public:
  static constexpr std::size_t kCapacity = 4096;
  /// Largest number of levels reference() returns.
  static constexpr std::size_t kMaxLevels = 32;

  void add(const core::LoadBlock& block);
  [[nodiscard]] const std::deque<core::LoadBlock>& blocks() const { return blocks_; }
  [[nodiscard]] bool empty() const { return blocks_.empty(); }
  void clear() { blocks_.clear(); }
  void assign(std::vector<core::LoadBlock> blocks);
  /// The reference spectrum: equal (p_max, r, alpha) summed, in order of first appearance; with
  /// more than kMaxLevels levels, levels sorted by load range P_max(1−R) are grouped into
  /// kMaxLevels groups of about equal cycle counts, each represented (conservatively) by its
  /// largest-range level with the group's total count.
  [[nodiscard]] std::vector<core::LoadBlock> reference() const;

 private:
  std::deque<core::LoadBlock> blocks_;
};

/// The detail's configured reference spectrum, or `empirical.reference()` when it says
/// "empirical". Empty = no spectrum yet (no estimate possible).
std::vector<core::LoadBlock> reference_spectrum(const DetailModel& model,
                                                const RollingSpectrum& empirical);

/// Cycles from `state` until the end criterion under `spectrum` (repeated), A2 scaled by
/// `a2_factor`. 0 when already met, +Inf when not met within kMaxSimulatedCycles, NaN when the
/// state cannot be imported or the spectrum is empty, or when `cancel` becomes true (checked
/// between blocks).
/// With `live` (an engine on `model` whose export_state() is `state`, e.g. the twin's), the
/// simulation continues from a fork of it (FatigueEngine::fork: its factor copied, not rebuilt
/// and replayed) instead of a fresh engine that imports `state`; the result is the same bit for
/// bit (the bilinear law always imports, see fork()). `stats` (optional) receives the phases.
double simulate_life(const DetailModel& model, const fatigue::EngineState& state,
                     const std::vector<core::LoadBlock>& spectrum, double a2_factor,
                     const std::atomic<bool>* cancel = nullptr,
                     const fatigue::FatigueEngine* live = nullptr,
                     SimulationStats* stats = nullptr);

/// The stepping of a forward simulation: the spectrum's blocks, pass after pass (a pass without
/// breaks doubles the next pass's counts), each applied with `stop`, until a block ends early
/// (the stop check said so, or final failure). Returns the cycles applied; +Inf past
/// kMaxSimulatedCycles, NaN when cancelled or the spectrum is empty. Adds its time, breaks and
/// updates to `stats` (optional).
double run_to_end(fatigue::FatigueEngine& engine, const std::vector<core::LoadBlock>& spectrum,
                  const fatigue::FatigueEngine::StopCheck& stop,
                  const std::atomic<bool>* cancel = nullptr, SimulationStats* stats = nullptr);

/// Whether simulate_life can continue from a live engine of `model` (every law but bilinear).
bool can_fork(const DetailModel& model);

/// Central value and band (3 forward simulations, run concurrently when `parallel`), from a fork
/// of `live` when given (see simulate_life). With `[detail.life] dx` the simulations run on the
/// coarser grid instead (estimate_life_coarse, twin/coarse_life.h; `live` and `stats` are
/// not used). state_seq/seq/source are left for the caller to fill
/// in; wall_s, start_cycles and forked are filled. `stats` (optional, 3 entries: central, low
/// A2·(1 + s), high A2·(1 − s); only the first without a band) receives each simulation's phases.
LifeEstimate estimate_life(const DetailModel& model, const fatigue::EngineState& state,
                           const std::vector<core::LoadBlock>& spectrum, bool parallel = true,
                           const std::atomic<bool>* cancel = nullptr,
                           const fatigue::FatigueEngine* live = nullptr,
                           std::vector<SimulationStats>* stats = nullptr);

}  // namespace peritwin::twin
