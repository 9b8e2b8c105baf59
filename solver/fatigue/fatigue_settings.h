// The fatigue engine's settings: which law (000, 003, 004) with its parameters, the phase III
// criterion (000 Eq. 7-12), and how the engine re-solves. The config names of the laws and their
// readers are in solver/fatigue/law_registry.h; each law's arithmetic in solver/fatigue/laws/.
#pragma once

#include <cstdint>

#include "solver/fatigue/laws/bilinear.h"
#include "solver/fatigue/laws/crack_closure.h"
#include "solver/fatigue/laws/kinetic.h"
#include "solver/fatigue/laws/remaining_life.h"
#include "solver/fatigue/laws/strain_range.h"

namespace peritwin::fatigue {

enum class FatigueLaw {
  strain_range,  ///< 000 Eq. (14)-(20)
  energy,        ///< 000 Eq. (30)-(46)
  kinetic,       ///< 004 Eq. (12)-(16)
  bilinear,      ///< 003 bilinear bond with the third degradation law, Eq. (27)-(30), (45)-(50)
};

/// Phase III (static failure at P_max) criterion.
enum class StaticFailure {
  critical_stretch,      ///< 000 Eq. (7)-(8): a bond breaks when s ≥ s_c
  critical_bond_energy,  ///< 000 Eq. (9)-(12): a bond breaks when ḡ (Eq. 10-11, 31) ≥ g_c
};

/// How the compressive part of a reversed cycle (R < 0) counts (issue 34, docs/compression.md);
/// laws strain_range and energy (contact: strain_range only).
enum class CompressionRule {
  /// 000 Eq. (15)-(16) as the papers write it: the bond range is |s⁺(1 − R)| whatever the sign of
  /// P_min; the crack faces pass through each other. What the design codes count for welded
  /// details (tensile residual stress keeps the crack open), and the papers' B1-B3.
  full_range,
  /// The crack faces touch: at P_min < 0 the broken bonds that close carry compression
  /// (statics::CrackFaceContact), and each bond's range is |s⁺ − s(P_min)| with s(P_min) the
  /// contact solution. R >= 0 is unchanged. Exact stepping in the engine's direct mode.
  contact,
  /// Newman's crack-opening function (fatigue::NewmanClosure): the range |s⁺|(1 − f(R)), for
  /// every R (also R >= 0: A2 is then calibrated to ΔK_eff data, as NASGRO's C is).
  closure,
};

struct FatigueSettings {
  FatigueLaw law = FatigueLaw::strain_range;
  fatigue::StrainLawParams strain;  ///< laws strain_range and energy (000 Eq. 44-46 maps A, m)
  fatigue::KineticParams kinetic;   ///< law kinetic (004 Eq. 12-16)
  /// law kinetic: segments, k_U, k_γ, Eq. (26) (004); apart from `kinetic`, see its comment.
  fatigue::KineticExtension kinetic_extension;
  /// law bilinear: s0, sc (003 Eq. 43-44), A, m of the third law (003 Eq. 27). Bond-based only.
  fatigue::BilinearParams bilinear;
  /// law bilinear: ΔN, cycles per damage increment (003 Sec. 5.1, 6.5-6.7: 100 to 50000); >= 1.
  std::int64_t cycle_increment = 1000;
  /// law bilinear: the secant iteration of an increment stops when no bond's stiffness factor
  /// f = 1 − D changed by more than this in the last re-solve (absolute); > 0.
  double softening_tolerance = 1e-6;
  /// law bilinear: at most this many re-solves per increment (then the last iterate is kept and
  /// counted in FatigueEngine::unconverged_increments()); >= 1.
  int softening_max_iterations = 100;
  /// law bilinear: the oracle — refactorize K(f) in every secant iteration instead of solving by
  /// preconditioned conjugate gradients (see the file comment).
  bool bilinear_refactor_every_iteration = false;
  /// law bilinear, preconditioned path: stop when sqrt(rᵀM⁻¹r / bᵀM⁻¹b) ≤ this (≈ the relative
  /// error in the energy norm); > 0.
  double bilinear_solve_tolerance = 1e-12;
  /// law bilinear, preconditioned path: reference factors are powers of 2^this (1 to 64): larger
  /// means fewer refactorizations and more iterations (spectrum in (2^−step, 1]). With 8 a bond
  /// moves the reference only when it breaks or passes D = 1 − 1/256 (docs/solver.md).
  int bilinear_reference_step = 8;
  /// Laws strain_range and energy: whether a bond compressed at P_max fatigues. 000 Eq. (15)
  /// takes the absolute range |s⁺(1 − R)| and says stretches "can be either positive or negative"
  /// (true, the default). false: only bonds in tension at P_max lose life (a closed crack face
  /// carries the compression). Under near-pure mode II the default grows a second branch on the
  /// compressed side of the tip, the mirror of the tensile one (docs/validation.md, B2).
  bool compressed_bonds_fatigue = true;
  /// Laws strain_range and energy: the rule for the compressive part of a cycle (see there).
  CompressionRule compression = CompressionRule::full_range;
  /// CompressionRule::closure: the opening function's parameters.
  NewmanClosure closure;
  /// Whether a fully compressive cycle (P_max <= 0) is applied as its tensile mirror
  /// (loads/cycle_blocks.h): only when compressed bonds fatigue over the full range. Under contact
  /// or closure the crack is shut through such a cycle (K_max <= 0: no growth, ASTM E647), so it
  /// is skipped and counted.
  [[nodiscard]] bool mirrors_compressive_cycles() const {
    return compressed_bonds_fatigue && compression == CompressionRule::full_range;
  }
  /// 000 Sec. 4.4: a node's bonds follow phase II once it or a family member has φ ≥ φ0. The
  /// default suits δ = 3.015Δx; other horizons: phase_switch_damage_for_horizon.
  double phase_switch_damage = fatigue::kPhaseSwitchDamage2D;
  /// Phase III (000 Eq. 7-8, 20): bonds whose stretch at P_max reaches s_c break statically.
  /// (Not used by the bilinear law, whose sc plays this role.)
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
  /// Incremental only: after every this many re-solves the solver is rebuilt from scratch (a
  /// fresh StaticSolver, one refactorization with the broken bonds) — at a fixed, history-counted
  /// point and by the same operations on resume, so bit-identical runs stay bit-identical. It
  /// bounds the round-off carried by long chains of updates and what import_state must replay on
  /// resume (the re-solves since the last rebuild, not the whole history). 0 = never.
  std::int64_t refactor_every_resolves = 1024;
  /// Incremental only: free the Cholesky factor after each factorization (initialize, rebuild)
  /// until the next bond breaks, which factorizes again first (StaticSolver::release_factor: the
  /// same factor bit for bit, so the same states and hashes). Memory for time: a detail that
  /// idles holds no factor (most of its memory), the first break after it pays one
  /// factorization. For fleets of details that mostly idle (issue 18).
  bool release_idle_factor = false;
};

}  // namespace peritwin::fatigue
