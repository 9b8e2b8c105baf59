// The fatigue engine: advances every bond's remaining life through blocks of identical load
// cycles, breaks bonds, re-solves, and repeats (000 Sec. 5, Figs. 3-5).
//
// A block of n identical cycles is not n iterations: while no bond breaks, every bond's decrement
// per cycle is constant, so the engine finds the exact cycle of the next break, jumps there,
// breaks, re-solves and continues. `apply_per_cycle` is the naive oracle (one cycle at a time) and
// gives bit-identical states. Two exact stepping modes:
//  - dose mode (strain-range law without fatigue limits): λ_b = λ0_b − F_b·D_phase, the decrement
//    factorizes into a bond factor F_b = A|ŝ_b|^m (ŝ the stretch per unit load) and a load dose
//    D = Σ|P(1−R)|^m accumulated cycle by cycle; a block that reaches no bond's threshold is
//    absorbed in O(1) (DESIGN.md).
//  - direct mode (every other law): λ_b −= d_b once per cycle, advanced k cycles at a time with
//    fatigue::advance_life, which reproduces k subtractions bit for bit.
// Units: SI (N, m); cycles are counted in int64.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "solver/discretization.h"
#include "solver/fatigue_law.h"
#include "solver/pd_model.h"
#include "solver/static_solver.h"

namespace peritwin {

/// One block of identical load cycles: P_max (N), R = P_min/P_max, load angle α (rad), count.
struct LoadBlock {
  double p_max = 0.0;
  double r = 0.0;
  double alpha = 0.0;
  std::int64_t count = 0;
};

/// Empty when the block can be applied, else the reason (non-finite numbers, count < 1, R ≥ 1).
std::string validate(const LoadBlock& block);

enum class FatigueLaw { strain_range, energy, kinetic };

/// Phase III (static failure at P_max) criterion.
enum class StaticFailure {
  critical_stretch,      ///< 000 Eq. (7)-(8): a bond breaks when s ≥ s_c
  critical_bond_energy,  ///< 000 Eq. (9)-(12): a bond breaks when ḡ (Eq. 10-11, 31) ≥ g_c
};

struct FatigueSettings {
  FatigueLaw law = FatigueLaw::strain_range;
  fatigue::StrainLawParams strain;  ///< laws strain_range and energy (000 Eq. 44-46 maps A, m)
  fatigue::KineticParams kinetic;   ///< law kinetic (004 Eq. 12-16)
  /// 000 Sec. 4.4: a node's bonds follow phase II once it or a family member has φ ≥ φ0.
  double phase_switch_damage = fatigue::kPhaseSwitchDamage2D;
  /// Phase III (000 Eq. 7-8, 20): bonds whose stretch at P_max reaches s_c break statically.
  /// 0 = compute s_c from G_c = K_c²/E with 000 Eq. (8); < 0 = no static failure.
  double critical_stretch = 0.0;
  /// Which phase III criterion applies (the other one's value is ignored).
  StaticFailure static_failure = StaticFailure::critical_stretch;
  /// 000 Eq. (9): critical energy release rate of one bond g_c (J/m²), compared with the bond's ḡ
  /// of 000 Eq. (10)-(11) (written out as Eq. 31; bond-based: a = 0, Eq. 33). 0 = g_c = G_c/N_c
  /// from K_c (000 Eq. 12, G_c = K_c²/E); < 0 = no static failure.
  double critical_bond_energy = 0.0;
  /// N_c of 000 Eq. (12): interactions per unit crack area, 36 for δ = 3.015Δx (000 Sec. 2);
  /// 0 = count them on the grid (crack_crossing_interactions). Used only when g_c comes from K_c.
  double crack_interactions = 36.0;
  /// Re-solve after breaks by CHOLMOD rank updates (exact) instead of refactorizing.
  bool incremental = true;
};

/// 000 Eq. (8): s_c = sqrt(G_c / ((6μ/π + 16(κ − 2μ)/(9π²))·δ)), plane-stress κ, μ of the material.
double critical_stretch(const Material& material, double horizon);

/// 000 Eq. (12): g_c = G_c/N_c with G_c = K_c²/E; 0 when K_c is not given.
double critical_bond_energy(const Material& material, double crack_interactions);

/// N_c of 000 Eq. (12) counted on a square grid with families within δ: a straight cut between two
/// grid rows is crossed, per Δx of its length, by Σ q bonds over the family offsets (p, q) with
/// q > 0 (q rows apart), and every bond counts twice since 000 Eq. (10a) gives it the energy
/// ḡ = ½(g_kj + g_jk) = E_b/(2Δx·h) (E_b the bond's strain energy, Eq. 10b-11): a crack of unit
/// area then releases N_c·ḡ. 36 for δ = 3.015Δx (28 neighbours), the value of 000 Sec. 2.
double crack_crossing_interactions(double horizon_over_dx);

enum class BreakCause : std::uint8_t { fatigue = 1, overload = 2 };

struct BreakEvent {
  std::int64_t cycle = 0;  ///< total cycle count at which the bond broke
  BondIndex bond = 0;
  BreakCause cause = BreakCause::fatigue;
};

enum class EngineStatus { ok, final_failure };

/// Everything needed to resume an engine bit-identically (checkpoints). The stiffness state is
/// rebuilt from `intact` by one solve; rates are recomputed for the saved key without folding.
struct EngineState {
  std::vector<double> anchor_life;
  std::vector<std::uint8_t> intact;
  double dose[2] = {0.0, 0.0};
  bool rates_valid = false;
  LoadBlock rate_key;
  std::int64_t total_cycles = 0;
  std::vector<BreakEvent> events;
  /// Number of events per re-solve, in order: import_state replays the re-solves group by group,
  /// so that an incrementally updated factor is rebuilt by the same updates (bit-identical).
  std::vector<std::int64_t> resolve_groups;
  bool failed = false;
  std::string failure_reason;
};

class FatigueEngine {
 public:
  FatigueEngine(const Discretization& disc, const PdModel& model, std::vector<Support> supports,
                std::vector<LoadTerm> loads, FatigueSettings settings);

  /// First static solve. Returns false (with failure_reason()) if the model is singular.
  bool initialize();
  /// Applies a block with exact next-break stepping. Stops early on final failure.
  EngineStatus apply(const LoadBlock& block);
  /// The oracle: the same block cycle by cycle.
  EngineStatus apply_per_cycle(const LoadBlock& block);

  [[nodiscard]] std::int64_t total_cycles() const { return total_cycles_; }
  [[nodiscard]] const std::vector<BreakEvent>& break_events() const { return events_; }
  [[nodiscard]] std::int64_t broken_bonds() const;
  /// λ of every bond now (1 = fresh, ≤ 0 = failed by fatigue).
  [[nodiscard]] std::vector<double> remaining_life() const;
  [[nodiscard]] const std::vector<std::uint8_t>& bond_phase() const { return phase_; }
  [[nodiscard]] const std::vector<double>& node_damage() const { return node_damage_; }
  [[nodiscard]] bool failed() const { return failed_; }
  [[nodiscard]] const std::string& failure_reason() const { return failure_reason_; }
  [[nodiscard]] const StaticSolver& solver() const { return solver_; }
  [[nodiscard]] const Discretization& discretization() const { return disc_; }
  [[nodiscard]] int solves() const { return solves_; }

  [[nodiscard]] EngineState export_state() const;
  /// Restores a state exported from an engine built from the same model; false if it does not fit.
  bool import_state(const EngineState& state);
  /// FNV-1a 64 over the bits of every number that defines the state (lives, doses, bonds, cycles).
  [[nodiscard]] std::uint64_t state_hash() const;

 private:
  [[nodiscard]] bool dose_mode() const;
  /// Makes rate_ valid for the block (recomputing after a re-solve or a change of load key).
  void prepare_rates(const LoadBlock& block);
  /// Recomputes rate_ (and the dose thresholds) for `block` without folding the dose.
  void compute_rates(const LoadBlock& block);
  /// Folds the accumulated dose into the anchors (λ0 ← λ, D ← 0).
  void materialize();
  /// Smallest k in [1, limit] at which some breakable bond reaches λ ≤ 0, or limit + 1.
  std::int64_t cycles_to_next_break(const LoadBlock& block, std::int64_t limit) const;
  /// Advances all bonds by k cycles of the block.
  void advance(const LoadBlock& block, std::int64_t k);
  /// Life of bond b after the current dose (dose mode) or as stored (direct mode).
  [[nodiscard]] double life(std::size_t b) const;
  /// Breaks the bonds at λ ≤ 0, re-solves, cascades static failure at P_max; false on failure.
  bool break_and_resolve(const LoadBlock& block);
  /// Phase III cascade at the block's P_max; false on final failure.
  bool static_cascade(const LoadBlock& block);
  bool resolve(const std::vector<BondIndex>& newly_broken);
  void update_phases();

  const Discretization& disc_;
  const PdModel& model_;
  StaticSolver solver_;
  FatigueSettings settings_;
  double critical_stretch_ = 0.0;
  double critical_bond_energy_ = 0.0;  ///< g_c, 000 Eq. (9), (12)

  std::vector<double> anchor_life_;      ///< λ0 (dose mode) or λ (direct mode)
  std::vector<double> rate_;             ///< F_b (dose mode) or d_b (direct mode)
  std::vector<std::uint8_t> phase_;      ///< 1 or 2 per bond
  std::vector<std::uint8_t> breakable_;  ///< intact and outside no-fail zones
  std::vector<double> node_damage_;
  double dose_[2] = {0.0, 0.0};  ///< D for phase I and phase II (dose mode)
  /// min over breakable bonds of λ0/F per phase (dose mode): no bond can fail before D reaches it.
  double dose_threshold_[2] = {0.0, 0.0};
  bool rates_valid_ = false;
  LoadBlock rate_key_;
  std::vector<double> stretch_;  ///< stretch at the rate key's (P_max, α)

  /// The phase III scan found nothing at (cascade_p_max_, cascade_alpha_) since the last re-solve.
  bool cascade_checked_ = false;
  double cascade_p_max_ = 0.0;
  double cascade_alpha_ = 0.0;

  std::int64_t total_cycles_ = 0;
  std::vector<BreakEvent> events_;
  std::vector<std::int64_t> resolve_groups_;  ///< events per resolve() call (EngineState)
  bool failed_ = false;
  std::string failure_reason_;
  int solves_ = 0;
};

}  // namespace peritwin
