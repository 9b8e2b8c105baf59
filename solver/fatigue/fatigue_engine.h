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
//    absorbed in O(1) (docs/design.md).
//  - direct mode (every other law): λ_b −= d_b once per cycle, advanced k cycles at a time with
//    fatigue::advance_life, which reproduces k subtractions bit for bit.
// The bilinear law (003) is different: its damage D softens the bonds, so the stretches change
// with every cycle and there is no exact jump. It advances in cycle increments ΔN (003 Sec. 5.1,
// 6), see "bilinear mode" below.
//
// Bilinear mode (FatigueLaw::bilinear, bond-based models only; 003 Eq. 13-15, 27-30, 45-50):
//  - Increments: a fixed ΔN = FatigueSettings::cycle_increment. Cycles at one load key (P_max, α)
//    are collected; every time ΔN of them are pending, one increment of ΔN is integrated. When a
//    block with another key arrives, the pending cycles of the old key are integrated first as one
//    shorter increment. So the increment sequence depends only on the sequence of cycles, not on
//    how a constant-load stretch is cut into blocks: apply() of any split equals one block, and
//    equals apply_increments() given that sequence, bit for bit. Up to ΔN − 1 cycles may be
//    pending: they count in total_cycles() but their damage is integrated later (or by flush()).
//    R is not used: 003 Sec. 4 holds the load at its maximum (the envelope of Fig. 5). A history
//    whose every block has a new key (rainflow of a random series) costs one nonlinear solve per
//    block.
//  - One increment (003 Eq. 50): D' = D + [D14(s') − D14(s_max)]⁺ + A ΔN ((s_N + s')/(2 sc))^m,
//    with s_N the stretch at the start, s' the stretch at equilibrium with the stiffness factors
//    f = 1 − D' (Eq. 13, 45) and s_max the largest equilibrium stretch so far (the static damage
//    of Eq. 14-15/46 follows the envelope and does not return on reloading). s' depends on D', so
//    the increment is solved by a secant (fixed-point) iteration instead of 003's Newton-Raphson
//    (Eq. 52-55): set the factors, re-solve the linear system K(D')u = F (Eq. 52), recompute D',
//    until no factor changes by more than softening_tolerance (at the solution the out-of-balance
//    force of Eq. 53 vanishes: K(D') is the secant stiffness). A bond breaks (f = 0, irreversibly)
//    when D' reaches 1 (BreakCause::fatigue) or s' reaches sc (Eq. 45, third line;
//    BreakCause::overload); the phase III settings of 000 are not used. With ΔN → 0 the same
//    iteration is the static softening solve at a new load. Bonds in no-fail zones neither soften
//    nor break.
//  - Re-solves are not rank updates (every loaded bond softens in every increment, more columns
//    than an update pays off for) but preconditioned conjugate gradients on K(f), preconditioned
//    by the factor of a reference K(f_ref) with every f_ref the next power of 2^step above f
//    (StaticSolver::set_preconditioned): refactorized only when some bond's f_ref changes, at
//    most 2^step·f so the iterations converge fast, and a function of the factors alone, so
//    import_state stays bit-identical. bilinear_refactor_every_iteration = true refactorizes K(f)
//    in every secant iteration instead (the oracle; the two agree to the solve tolerance).
// Units: SI (N, m); cycles are counted in int64.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/fnv1a.h"
#include "core/load_block.h"
#include "solver/fatigue/fatigue_settings.h"
#include "solver/fatigue/laws/energy.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"
#include "solver/statics/crack_contact.h"
#include "solver/statics/static_solver.h"

namespace peritwin::fatigue {

/// 000 Eq. (8): s_c = sqrt(G_c / ((6μ/π + 16(κ − 2μ)/(9π²))·δ)), plane-stress κ, μ of the material.
double critical_stretch(const model::Material& material, double horizon);

/// 000 Eq. (12): g_c = G_c/N_c with G_c = K_c²/E; 0 when K_c is not given.
double critical_bond_energy(const model::Material& material, double crack_interactions);

/// N_c of 000 Eq. (12) counted on a square grid with families within δ: a straight cut between two
/// grid rows is crossed, per Δx of its length, by Σ q bonds over the family offsets (p, q) with
/// q > 0 (q rows apart), and every bond counts twice since 000 Eq. (10a) gives it the energy
/// ḡ = ½(g_kj + g_jk) = E_b/(2Δx·h) (E_b the bond's strain energy, Eq. 10b-11): a crack of unit
/// area then releases N_c·ḡ. 36 for δ = 3.015Δx (28 neighbours), the value of 000 Sec. 2.
double crack_crossing_interactions(double horizon_over_dx);

/// φ0 for δ = horizon_ratio·Δx (000 Sec. 4.4): the damage along a straight split
/// (straight_crack_face_damage) truncated to 3 decimals, which gives 000's 0.398 at δ = 3.015Δx
/// (face 0.3986). Any horizon then puts a crack's face nodes in phase II; a fixed 0.398 would not
/// at δ = 2Δx (face 0.350), and the crack would grow on phase I lives alone.
double phase_switch_damage_for_horizon(double horizon_ratio);

enum class BreakCause : std::uint8_t { fatigue = 1, overload = 2 };

struct BreakEvent {
  std::int64_t cycle = 0;  ///< total cycle count at which the bond broke
  mesh::BondIndex bond = 0;
  BreakCause cause = BreakCause::fatigue;
};

/// What became of a block: all of it applied, final failure (singular stiffness), or stopped by
/// the caller's StopCheck after a re-solve (the rest of the block not applied).
enum class EngineStatus { ok, final_failure, stopped };

/// Everything needed to resume an engine bit-identically (checkpoints), and what the engine keeps
/// of its history: the engine holds one (FatigueEngine::state_) and works on it. The stiffness
/// state is rebuilt from `intact` by one solve; rates are recomputed for the saved key without
/// folding. for_each_field below is its field table: add a field there and the checkpoint keys
/// and the state hash follow.
struct EngineState {
  std::vector<double> anchor_life;  ///< λ0 (dose mode) or λ (direct mode) per bond
  /// Intact flag per bond. Filled by export_state from the solver, which owns the broken set
  /// while the engine runs (the engine's own copy is not kept up to date).
  std::vector<std::uint8_t> intact;
  double dose[2] = {0.0, 0.0};  ///< D for phase I and phase II (dose mode)
  bool rates_valid = false;
  core::LoadBlock rate_key;
  std::int64_t total_cycles = 0;
  std::vector<BreakEvent> events;
  /// Number of events per re-solve, in order: import_state replays the re-solves group by group,
  /// so that an incrementally updated factor is rebuilt by the same updates (bit-identical).
  std::vector<std::int64_t> resolve_groups;
  bool failed = false;
  std::string failure_reason;
  /// Bilinear law only (empty otherwise): damage D per bond (003 Eq. 13, 50), largest equilibrium
  /// stretch per bond (the static envelope), and the cycles collected at pending_key (P_max, α)
  /// but not yet integrated.
  std::vector<double> damage;
  std::vector<double> max_stretch;
  std::int64_t pending_cycles = 0;
  core::LoadBlock pending_key;
};

/// The field table of EngineState: every field once, with its checkpoint key, in hash order.
/// `visit(key, field)` is called with the field's type (double, bool, int64, string, LoadBlock,
/// and vectors of double, uint8, int64, BreakEvent); State is EngineState or const EngineState.
template <class State, class Visit>
void for_each_field(State& s, Visit&& visit) {
  visit("anchor_life", s.anchor_life);
  visit("intact", s.intact);
  visit("dose0", s.dose[0]);
  visit("dose1", s.dose[1]);
  visit("rates_valid", s.rates_valid);
  visit("rate_key", s.rate_key);
  visit("total_cycles", s.total_cycles);
  visit("event", s.events);
  visit("resolve_groups", s.resolve_groups);
  visit("failed", s.failed);
  visit("failure_reason", s.failure_reason);
  visit("damage", s.damage);
  visit("max_stretch", s.max_stretch);
  visit("pending_cycles", s.pending_cycles);
  visit("pending_key", s.pending_key);
}

/// Adds a state field to a word-wise FNV-1a 64 hash (core/fnv1a.h): numbers by their bits,
/// strings and byte arrays packed, vectors with their length first. `Hash` is Fnv1a64 or
/// Fnv1a64Pair (the same words into two hashes).
template <class Hash>
void hash_field(Hash& h, double v) {
  h.real(v);
}
template <class Hash>
void hash_field(Hash& h, std::int64_t v) {
  h.integer(v);
}
template <class Hash>
void hash_field(Hash& h, bool v) {
  h.integer(v ? 1 : 0);
}
template <class Hash>
void hash_field(Hash& h, const std::string& v) {
  h.packed(v);
}
template <class Hash>
void hash_field(Hash& h, const std::vector<std::uint8_t>& v) {
  h.packed(v.data(), v.size());
}
template <class Hash>
void hash_field(Hash& h, const std::vector<double>& v) {
  h.integer(static_cast<std::int64_t>(v.size()));
  h.reals(v.data(), v.size());
}
template <class Hash>
void hash_field(Hash& h, const core::LoadBlock& v) {
  h.real(v.p_max);
  h.real(v.r);
  h.real(v.alpha);
  h.integer(v.count);
}
template <class Hash>
void hash_field(Hash& h, const BreakEvent& v) {
  h.integer(v.cycle);
  h.integer(v.bond);
  h.integer(static_cast<std::int64_t>(v.cause));
}
template <class Hash, class T>
void hash_field(Hash& h, const std::vector<T>& v) {
  h.integer(static_cast<std::int64_t>(v.size()));
  for (const T& x : v) hash_field(h, x);
}

class FatigueEngine {
 public:
  /// `ties`: constraints outside the bond families (a loading fixture, see Tie); part of the
  /// stiffness in every solve, never broken.
  FatigueEngine(const mesh::Discretization& disc, const model::PdModel& model,
                std::vector<statics::Support> supports, std::vector<statics::LoadTerm> loads,
                FatigueSettings settings, std::vector<statics::Tie> ties = {},
                std::vector<statics::PrescribedDisplacement> prescribed = {});

  /// First static solve. Returns false (with failure_reason()) if the model is singular.
  bool initialize();
  /// Called by apply() after every group of breaks: the fatigue breaks of one cycle together with
  /// the phase III cascade they set off, the overload cascade at the start of a block with a
  /// higher P_max, or (bilinear law) an increment that broke a bond. true stops the block there:
  /// total_cycles() is then the cycle of those breaks and the rest of the block is not applied.
  /// Since splitting a block is exact, the state at a stop is that of applying exactly the cycles
  /// up to it, whatever the blocks were (the twin's end of life, twin/twin.h).
  using StopCheck = std::function<bool(const FatigueEngine&)>;

  /// Applies a block with exact next-break stepping. Stops early on final failure, or when `stop`
  /// (optional) says so after a group of breaks (EngineStatus::stopped).
  EngineStatus apply(const core::LoadBlock& block, const StopCheck& stop = {});
  /// The oracle: the same block cycle by cycle. Bilinear law: flush(), then increments of one
  /// cycle (ΔN = 1, the converged reference; not bit-equal to apply()).
  EngineStatus apply_per_cycle(const core::LoadBlock& block);
  /// Bilinear law, the increment oracle: flush(), then integrate the block in exactly the given
  /// increments (each >= 1, summing to block.count; std::invalid_argument otherwise), nothing left
  /// pending. std::logic_error for the other laws.
  EngineStatus apply_increments(const core::LoadBlock& block,
                                std::span<const std::int64_t> increments);
  /// Bilinear law: integrates the pending cycles now as one increment (no-op otherwise).
  EngineStatus flush();
  /// Changes the propagation-phase limit ε̃∞ (002 Eq. 12) for the blocks applied from now on, e.g.
  /// in proportion to the load (002 Sec. 7); the lives so far are kept. Not part of EngineState:
  /// a resumed engine must be given the same limit. std::invalid_argument unless finite, >= 0.
  void set_propagation_limit(double eps_inf_prop);

  [[nodiscard]] std::int64_t total_cycles() const { return state_.total_cycles; }
  [[nodiscard]] const std::vector<BreakEvent>& break_events() const { return state_.events; }
  [[nodiscard]] std::int64_t broken_bonds() const;
  /// λ of every bond now (1 = fresh, ≤ 0 = failed by fatigue).
  [[nodiscard]] std::vector<double> remaining_life() const;
  [[nodiscard]] const std::vector<std::uint8_t>& bond_phase() const { return phase_; }
  [[nodiscard]] const std::vector<double>& node_damage() const { return node_damage_; }
  [[nodiscard]] bool failed() const { return state_.failed; }
  [[nodiscard]] const std::string& failure_reason() const { return state_.failure_reason; }
  [[nodiscard]] const statics::StaticSolver& solver() const { return *solver_; }
  [[nodiscard]] const mesh::Discretization& discretization() const { return disc_; }
  [[nodiscard]] int solves() const { return solves_; }
  /// Rank-update work over the engine's life, across solver rebuilds (refactor_every_resolves):
  /// seconds in updates (incl. their re-solves), number of updates, seconds in basis solves.
  [[nodiscard]] double update_seconds() const;
  [[nodiscard]] int updates() const;
  [[nodiscard]] double basis_solve_seconds() const;
  /// Of all solvers so far, as update_seconds(): the sweeps' seconds and flops
  /// (StaticSolver::sweep_seconds, update_flops), the groups refactorized instead of updated
  /// (StaticSolver::refactorized_groups) and the numeric factorizations.
  [[nodiscard]] double sweep_seconds() const;
  [[nodiscard]] double update_flops() const;
  [[nodiscard]] int refactorized_groups() const;
  [[nodiscard]] int factorizations() const;
  /// Solver rebuilds done (refactor_every_resolves) and the seconds they took.
  [[nodiscard]] int rebuilds() const { return rebuilds_; }
  [[nodiscard]] double rebuild_seconds() const { return rebuild_s_; }
  /// Bilinear law: damage D per bond (empty otherwise), pending cycles, largest stretches.
  [[nodiscard]] const std::vector<double>& damage() const { return state_.damage; }
  [[nodiscard]] const std::vector<double>& max_stretch() const { return state_.max_stretch; }
  [[nodiscard]] std::int64_t pending_cycles() const { return state_.pending_cycles; }
  /// Bilinear law: increments integrated, and those that hit softening_max_iterations.
  [[nodiscard]] std::int64_t increments() const { return increments_; }
  [[nodiscard]] std::int64_t unconverged_increments() const { return unconverged_increments_; }
  /// CompressionRule::contact: the crack-face contact solver (nullptr otherwise).
  [[nodiscard]] const statics::CrackFaceContact* contact() const { return contact_.get(); }

  /// A copy of this engine that continues with `settings` (which may differ from this engine's
  /// only in the fatigue laws' coefficients, e.g. A2 for a life band): the factor is copied, not
  /// rebuilt. Its state, and every later step, is bit for bit that of a fresh engine built with
  /// `settings` that initialize()d and import_state(export_state()) (tested): the lives, doses,
  /// broken bonds and the factor are the same, the rates are recomputed for the new
  /// coefficients as import_state does. Not for the bilinear law (std::logic_error), whose
  /// import refactorizes with the softened factors and so differs in the last bits from a
  /// solver that got there by preconditioned increments.
  [[nodiscard]] std::unique_ptr<FatigueEngine> fork(const FatigueSettings& settings) const;

  [[nodiscard]] EngineState export_state() const;
  /// Restores a state exported from an engine built from the same model; false if it does not fit.
  bool import_state(const EngineState& state);
  /// Word-wise FNV-1a 64 over export_state(), field by field in for_each_field's order.
  [[nodiscard]] std::uint64_t state_hash() const;
  /// Adds what state_hash() hashes to `h`, read in place (export_state() copies every bond's
  /// fields; the daemon hashes after every batch).
  void hash_state(core::Fnv1a64& h) const;
  void hash_state(core::Fnv1a64Pair& h) const;

 private:
  [[nodiscard]] bool dose_mode() const;
  [[nodiscard]] bool bilinear() const { return settings_.law == FatigueLaw::bilinear; }
  /// One bilinear increment of dn >= 0 cycles at (P_max, α); false on final failure.
  bool bilinear_increment(const core::LoadBlock& key, std::int64_t dn);
  EngineStatus apply_bilinear(const core::LoadBlock& block, const StopCheck& stop);
  bool import_bilinear_state(const EngineState& state);
  /// Makes rate_ valid for the block (recomputing after a re-solve or a change of load key);
  /// false on final failure (a crack-face contact solve that failed, with failure_reason()).
  bool prepare_rates(const core::LoadBlock& block);
  /// Recomputes rate_ (and the dose thresholds) for `block` without folding the dose; false when
  /// the crack-face contact solve failed (its reason in state_.failure_reason).
  bool compute_rates(const core::LoadBlock& block);
  /// The R that the bond ranges take: R itself, or Newman's opening ratio f(R) under
  /// CompressionRule::closure (the range |s⁺|(1 − f)).
  [[nodiscard]] double range_ratio(double load_ratio) const;
  /// The load dose of one cycle of `block` for exponent m (dose mode), with range_ratio.
  [[nodiscard]] double cycle_dose(const core::LoadBlock& block, double m) const;
  /// CompressionRule::contact: contact_stretch_ made the stretches at P = −1, α with the crack
  /// faces in contact for the current broken set (cached per α and re-solve); false on failure.
  bool prepare_contact(double alpha);
  /// Folds the accumulated dose into the anchors (λ0 ← λ, D ← 0).
  void materialize();
  /// Smallest k in [1, limit] at which some breakable bond reaches λ ≤ 0, or limit + 1.
  std::int64_t cycles_to_next_break(const core::LoadBlock& block, std::int64_t limit) const;
  /// Advances all bonds by k cycles of the block.
  void advance(const core::LoadBlock& block, std::int64_t k);
  /// Life of bond b after the current dose (dose mode) or as stored (direct mode).
  [[nodiscard]] double life(std::size_t b) const;
  /// Breaks the bonds at λ ≤ 0, re-solves, cascades static failure at P_max; false on failure.
  bool break_and_resolve(const core::LoadBlock& block);
  /// Phase III cascade at the block's P_max; false on final failure.
  bool static_cascade(const core::LoadBlock& block);
  bool resolve(const std::vector<mesh::BondIndex>& newly_broken);
  /// The fields of `s` every law restores as they are: lives, cycles, events, failure.
  void restore_history(const EngineState& s);
  /// Whether resolve() rebuilds the factor after its `resolves`-th re-solve.
  [[nodiscard]] bool rebuild_due(std::size_t resolves) const;
  /// Replaces the solver by a fresh one with exactly the bonds not in `intact` broken (one
  /// refactorization): the same operations whatever the previous solver went through.
  core::Status rebuild_solver(std::vector<std::uint8_t> intact);
  void update_phases();
  /// update_phases() after `newly_broken` broke (the phases and damages were current before):
  /// only their end nodes' damage and the bonds it can put in phase II.
  void update_phases_after(const std::vector<mesh::BondIndex>& newly_broken);
  /// fork(): every member copied (the solver deeply), settings_ replaced.
  FatigueEngine(const FatigueEngine& other, const FatigueSettings& settings);

  const mesh::Discretization& disc_;
  const model::PdModel& model_;
  std::vector<statics::Support>
      supports_;  ///< kept to rebuild the solver (refactor_every_resolves)
  std::vector<statics::LoadTerm> loads_;
  std::vector<statics::Tie> ties_;
  std::vector<statics::PrescribedDisplacement> prescribed_;
  std::unique_ptr<statics::StaticSolver> solver_;
  /// The counters of the solvers replaced by rebuild_solver, summed (update_seconds() etc. add the
  /// current solver's).
  struct RetiredCounters {
    double update_s = 0.0;
    double basis_solve_s = 0.0;
    double sweep_s = 0.0;
    double update_flops = 0.0;
    int updates = 0;
    int refactorized_groups = 0;
    int factorizations = 0;
  };
  RetiredCounters retired_;
  int rebuilds_ = 0;
  double rebuild_s_ = 0.0;
  FatigueSettings settings_;
  double critical_stretch_ = 0.0;
  double critical_bond_energy_ = 0.0;  ///< g_c, 000 Eq. (9), (12)

  /// The history: lives, doses, rate key, cycles, break events, failure, bilinear damage
  /// (EngineState; its `intact` is the solver's, see there).
  EngineState state_;

  std::vector<double> rate_;             ///< F_b (dose mode) or d_b (direct mode)
  std::vector<std::uint8_t> phase_;      ///< 1 or 2 per bond
  std::vector<std::uint8_t> breakable_;  ///< intact and outside no-fail zones
  std::vector<double> node_damage_;
  /// min over breakable bonds of λ0/F per phase (dose mode): no bond can fail before D reaches it.
  double dose_threshold_[2] = {0.0, 0.0};
  std::vector<double> stretch_;  ///< stretch at the rate key's (P_max, α)
  /// Direct mode, cycles_to_next_break: (lower bound, bond) of the bonds that may fail first.
  mutable std::vector<std::pair<std::int64_t, std::size_t>> candidates_;

  /// The phase III scan found nothing at (cascade_p_max_, cascade_alpha_) since the last re-solve.
  bool cascade_checked_ = false;
  double cascade_p_max_ = 0.0;
  double cascade_alpha_ = 0.0;

  int solves_ = 0;

  // CompressionRule::contact (issue 34): the contact solver, and its stretches at P = −1 for the
  // angle and the number of break events they were computed at (not state: recomputed alike).
  std::unique_ptr<statics::CrackFaceContact> contact_;
  std::vector<double> contact_stretch_;
  std::vector<std::int64_t> contact_rank_;  ///< per bond, the canonical order of its break
  bool contact_valid_ = false;
  double contact_alpha_ = 0.0;
  std::size_t contact_events_ = 0;

  // Bilinear law (003): see the file comment.
  std::int64_t increments_ = 0;
  std::int64_t unconverged_increments_ = 0;
};

}  // namespace peritwin::fatigue
