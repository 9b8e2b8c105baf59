// Elastoplastic bonds in a static solve (issue 35 item 2, 004 Sec. 2.3): each intact bond follows
// 004's power-law curve with Masing kinematic hardening and memory (model/bond_plasticity.h) in
// the bond strain ε = s/κ, and the body is brought from one turning point of a cycle to the
// next by Newton–Raphson on the bond-by-bond residual (as 003 Eq. 52-55 do for their nonlinear
// bonds), each step's tangent system solved by conjugate gradients preconditioned with the
// static solver's elastic factor (no refactorization per iteration).
//
// Bond force (N): F_b = k_b·ξ·κ·σ(s/κ)/E, which is the elastic k_b·ξ·s below yield; tangent
// factor dF_b/(k_b·ξ·ds) = σ'(ε)/E ∈ (0, 1]. κ maps the bond's stretch to the uniaxial strain of
// 004's curve: 004 derives "the equivalent material plastic stretch" s_p = 6.98e-4 from σ_y/E =
// 6.6e-4 by its Eq. (5) (κ = 1.058 in its 3D model); a 2D model calibrates its own (B5 does, on a
// uniaxial bar).
// Work: each bond's ∮σ dε over a cycle (J/m³ of bond strain) is exact from the Masing branches;
// the loop area of node x (J/m³ of body) is A_x = Σ_{b∋x} W_b/(2V_x), W_b = k_b·ξ²·κ²/E·∮σ dε the
// bond's dissipated work (J), split between its two ends as 004 Eq. (5) splits the energy.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "core/expected.h"
#include "solver/model/bond_plasticity.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

struct BondPlasticity {
  model::PowerLawCurve curve;
  double stretch_per_strain = 1.0;  ///< κ: s = κ·ε
  double tolerance = 1e-10;  ///< Newton stops at ‖r_free‖ ≤ tolerance·‖F_int at the grips‖
  int max_iterations = 100;
  /// Newton's residual is piecewise smooth (each bond's tangent jumps where it reverses, at
  /// yield and where a loop closes): near a kink it can stall above `tolerance`. A turning point
  /// whose residual has stalled at or below this is accepted and counted (stalled_points()).
  double stall_tolerance = 1e-4;
  /// Masing snap tolerance (relative) of a commit: above the Newton tolerance's effect on the
  /// strains, so a repeated cycle closes its loop instead of leaving one of that size open.
  double snap_tolerance = 1e-2;
  double linear_tolerance = 1e-6;  ///< each Newton step's conjugate gradients (relative)
  int max_linear_iterations = 500;
};

/// What one turning point's solve gives.
struct TurningPoint {
  double control = 0.0;   ///< P reached
  int iterations = 0;     ///< Newton iterations (tangent factorizations)
  double residual = 0.0;  ///< final ‖r_free‖ / reference
  int substeps = 1;       ///< the ramp was solved in this many committed parts
};

/// Drives a bond-based StaticSolver through turning points. The solver keeps the elastic stiffness
/// of the intact bonds (its factor, updated or refactorized as it breaks bonds): each Newton step
/// solves with the tangent stiffness by conjugate gradients preconditioned with that factor.
class ElastoplasticSolver {
 public:
  /// The solver must be solved already (elastic, virgin); std::invalid_argument for a
  /// state-based model or an invalid curve.
  ElastoplasticSolver(StaticSolver& solver, BondPlasticity law);
  /// `other`'s bond states, displacement and control, driving `solver` (a copy of other's
  /// solver): to trace a loop in small steps without touching the original.
  ElastoplasticSolver(const ElastoplasticSolver& other, StaticSolver& solver);

  /// Moves the load from the committed value to (p, α) monotonically: Newton from the committed
  /// displacement with the grips (and loads) at p, then commits every intact bond's Masing state
  /// and records each bond's work along the ramp. When Newton fails on the whole ramp, it is
  /// solved in 2, 4, … 64 committed parts. A failure leaves the committed state as it was.
  core::Expected<TurningPoint> solve_turning_point(double p, double alpha);
  /// Breaks bonds (their state is dropped) and nothing else: the next turning point re-solves.
  core::Status break_bonds(std::span<const mesh::BondIndex> bonds);

  [[nodiscard]] const std::vector<model::MasingState>& bond_states() const { return state_; }
  /// Bond stress σ (Pa) at the committed state: the curve's stress at the bond's strain.
  [[nodiscard]] double bond_stress(std::size_t b) const { return state_[b].stress; }
  /// ∫σ dε (J/m³ of bond strain) of each bond along the last ramp.
  [[nodiscard]] const std::vector<double>& ramp_work() const { return work_; }
  /// Committed displacement (full DOFs) and the reaction of prescribed term t there.
  [[nodiscard]] const std::vector<double>& displacement() const { return u_; }
  [[nodiscard]] double reaction(std::size_t term) const { return reaction_[term]; }
  [[nodiscard]] double control() const { return p_; }
  /// The point stress of every node at the committed state (Pa), [σxx, σyy, σxy] per node: the
  /// virial of its bonds' forces, σ_k = (1/(2V_k))·Σ_{b∋k} F_b·ξ_b·e_b⊗e_b (each bond's share
  /// split between its ends; a uniform field gives the continuum stress away from surfaces).
  [[nodiscard]] std::vector<std::array<double, 3>> node_stress() const;
  /// Node loop areas A_x (J/m³) from per-bond ∮σ dε (e.g. the sum of two ramps' works).
  [[nodiscard]] std::vector<double> node_loop_area(const std::vector<double>& bond_loop) const;
  [[nodiscard]] const BondPlasticity& law() const { return law_; }
  [[nodiscard]] std::int64_t newton_iterations() const { return iterations_; }
  [[nodiscard]] std::int64_t stalled_points() const { return stalled_; }
  [[nodiscard]] std::int64_t substepped_points() const { return substepped_; }

 private:
  /// F_b = k_b·ξ·κ·σ/E (N): bond b's force at bond stress σ (the elastic k_b·ξ·s below yield).
  [[nodiscard]] double bond_force(std::size_t b, double stress) const;
  /// W_b = k_b·ξ²·κ²/E·w (J): bond b's work for w = ∫σ dε along its strain path.
  [[nodiscard]] double bond_work(std::size_t b, double work) const;
  /// One Newton solve of the ramp to (p, α); commits on success.
  core::Expected<TurningPoint> ramp(double p, double alpha);
  /// Δu with K_t·Δu = r over the free DOFs (PCG, M = the solver's elastic factor).
  void tangent_step(const std::vector<double>& tangent, const std::vector<double>& residual,
                    std::vector<double>& step) const;
  /// Internal force (full DOFs), tangents and works at displacement u; returns the bonds' work
  /// along the ramp from the committed state (J), the potential whose gradient is that force.
  double evaluate(const std::vector<double>& u, std::vector<double>& force,
                  std::vector<double>& tangent_factor, std::vector<double>* work) const;

  StaticSolver& solver_;
  BondPlasticity law_;
  /// Newton evaluates with the exact rules (snapping only at round-off: the residual stays
  /// continuous in u), and commits with law_.snap_tolerance (a repeated cycle closes its loop).
  model::MasingSkeleton skeleton_;
  model::MasingSkeleton commit_skeleton_;
  std::vector<model::MasingState> state_;
  std::vector<double> work_;
  std::vector<double> u_;
  std::vector<double> reaction_;
  double p_ = 0.0;
  std::int64_t iterations_ = 0;
  std::int64_t stalled_ = 0;
  std::int64_t substepped_ = 0;
};

}  // namespace peritwin::statics
