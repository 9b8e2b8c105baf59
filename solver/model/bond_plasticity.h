// One bond's (one material point's) uniaxial elastoplastic response with Masing kinematic
// hardening and Madelung memory (issue 35, paper 004), as pure functions of a plain state.
// Units: SI (strain dimensionless, stress and tangent Pa, work J/m³).
//
// Skeleton (monotonic curve). 004, "KTF-PD model" (the text under Fig. 7): "σ = −0.242·ε^−0.891 +
// 295 MPa if ε > σ_y/E = 6.6·10⁻⁴", E = 193 GPa; a = −0.242 MPa, so the strain is dimensionless
// (g(0.18 %) = 227.5 MPa, g(0.6 %) = 271.9 MPa). For ε > 0
//     g(ε) = E·ε                  for ε ≤ ε_y
//     g(ε) = a·ε^b + σ∞           for ε > ε_y,       and g(−ε) = −g(ε).
// Decision on the join (/work/notes/004-design.md (a) check 2): the printed curve does not meet
// the elastic line at the stated 6.6·10⁻⁴ (E·ε = 127.4 MPa against 130.0 MPa there, and the power
// law is steeper than E on (6.6, 7.13)·10⁻⁴). h(ε) = E·ε − a·ε^b − σ∞ is convex with two roots;
// ε_y is the LARGER one (8.35·10⁻⁴ for the defaults, 161 MPa), where the power law's slope is below
// E. This is g = min(E·ε, a·ε^b + σ∞) on ε ≥ ε_m (the minimum of h), and E·ε below ε_m (the
// literal min would follow the power law to −∞ near 0). g is continuous, concave, 0 < g' ≤ E.
// Energy G(ε) = ∫_0^|ε| g = E·ε²/2 below ε_y, else E·ε_y²/2 + [a/(b+1)·x^(b+1) + σ∞·x]_{ε_y}^{|ε|}.
//
// Masing rule. A reversal at (ε_r, σ_r) starts the branch
//     σ(ε) = σ_r + 2·g((ε − ε_r)/2)          (= σ_r + d·2·g(|ε − ε_r|/2), d the new direction)
// with tangent g'((ε − ε_r)/2) and work ∫σ dε from ε_a to ε_b on it
//     σ_r·(ε_b − ε_a) + 4·[G((ε_b − ε_r)/2) − G((ε_a − ε_r)/2)].
// Symmetric cycles ±a: each half cycle does 4·G(a) − 2a·g(a), so the loop area is
//     A(a) = ∮σ dε = 8·∫_0^a g − 4a·g(a)                       (004-design.md (a) check 3).
//
// Memory (Madelung rules), with the stack R_1 … R_k of open reversals (R_1 the oldest):
//  - depth 0: the path is on the skeleton, moving away from 0 (a virgin state moves either way).
//  - A path that turns against the current branch pushes the current point as R_{k+1}.
//  - The branch from R_k (k ≥ 2) heads towards R_{k−1}, the reversal that started the previous
//    branch (the opposite direction). On reaching ε_{k−1} the loop R_{k−1} → R_k → R_{k−1}
//    closes: the point snaps to the stored (ε_{k−1}, σ_{k−1}) bit for bit, R_k and R_{k−1} are
//    popped, and the path continues on the branch from R_{k−2} (the skeleton if k = 2), exactly as
//    if the small loop had not happened.
//  - R_1 is always on the skeleton, at the largest excursion so far. Its branch reaches the
//    skeleton at the mirror point (−ε_1, −σ_1) (Masing: σ_1 + 2·g(−ε_1) = −σ_1, tangent there
//    g'(ε_1), the skeleton's own); it snaps there, pops R_1 and continues on the skeleton.
//  - "Reaching" means d·(ε − ε_c) ≥ −tol with tol = kMasingSnapTolerance·max(|ε_c|, |ε_c − ε_k|):
//    a turning point short of a stored point by rounding (1e-12 relative) closes the loop too, so
//    turning points recomputed by a solver to a few ulps still give periodic states.
//  - Overflow: a push onto a full stack (kMasingMemory) drops the oldest inner pair R_2, R_3 and
//    counts 2 in MasingState::dropped_reversals. Decision: dropping R_1 itself (the literal "oldest
//    entry") would forget where the path rejoins the skeleton, and the next entry lies inside the
//    loop, so treating it as a skeleton point would jump by up to the loop's height at its mirror;
//    dropping R_2 and R_3 keeps R_1 (so every later return to the skeleton stays exact) and the
//    stack's alternation of directions. The price: the branch from R_4 now closes at R_1 and the
//    stress snaps there by the difference between the branches from R_4 and from R_2 (bounded by
//    the forgotten loop's height). Turning-point cycles (004's blocks) never nest deeper than 2.
// Edge cases: trial == committed strain returns the committed stress, zero work and the tangent of
// the current branch continued in its own direction (E for a virgin state). A path that ends on a
// closure point (within tol) returns the closing branch's tangent there (the one it arrived on);
// the committed state is already popped. A reversal at a stored point simply pushes that point
// again (its values are the stored bits).
#pragma once

#include <array>
#include <cstdint>

#include "core/expected.h"

namespace peritwin::model {

/// 004's monotonic (skeleton) curve of 316L joined to the elastic line, in uniaxial strain–stress:
/// g(ε) = min(E·ε, a·ε^b + σ∞) for ε > 0 (004: "σ = −0.242·ε^−0.891 + 295 MPa"), odd:
/// g(−ε) = −g(ε). The join is the larger root of E·ε = a·ε^b + σ∞ (see the top of this file).
struct PowerLawCurve {
  double youngs_modulus = 193e9;  ///< E (Pa), 004 "E = 193 ± 3 GPa"
  double a = -0.242e6;            ///< Pa (004: −0.242 MPa)
  double b = -0.891;              ///< exponent (004)
  double sigma_inf = 295e6;       ///< σ∞ (Pa), the saturation stress (004: 295 MPa)
  /// g(ε) (Pa).
  [[nodiscard]] double stress(double strain) const;
  /// g'(ε) (Pa): E up to and including ε_y, a·b·|ε|^(b−1) beyond.
  [[nodiscard]] double tangent(double strain) const;
  /// ε_y: the larger root of E·ε = a·ε^b + σ∞, by Newton from σ∞/E (monotone from the right on
  /// the convex h; ≈ 8.35e-4 for the defaults). Requires validate() to pass.
  [[nodiscard]] double yield_strain() const;
  /// G(ε) = ∫_0^|ε| g (J/m³), closed form: E·ε²/2 below ε_y, else the elastic part plus the
  /// power law's antiderivative a/(b+1)·x^(b+1) + σ∞·x between ε_y and |ε|.
  [[nodiscard]] double energy(double strain) const;
};

/// OK, or the offending field: E, σ∞ finite and > 0; a < 0 and b < 0 (the power law increasing
/// and concave); b ≠ −1 (the energy would be logarithmic); the join exists, i.e. the minimum of
/// h(ε) = E·ε − a·ε^b − σ∞, at ε_m = (E/(a·b))^(1/(b−1)), is negative.
core::Status validate(const PowerLawCurve& curve);

/// Open reversals remembered per bond.
inline constexpr int kMasingMemory = 32;
/// Relative tolerance of "a branch reached a stored point" (see the top of this file).
inline constexpr double kMasingSnapTolerance = 1e-12;

/// The curve with its join solved once (ε_y, G(ε_y)): the same arithmetic as PowerLawCurve's
/// members, bit for bit, without the Newton solve for ε_y on every call (measured: 0.12 µs per
/// masing_evaluate against 0.7 µs with the solve). Build one per material (or per bond when E
/// scatters) and pass it to the overloads of masing_evaluate and masing_commit in hot loops; the
/// PowerLawCurve overloads build one per call.
class MasingSkeleton {
 public:
  /// Requires validate(curve).
  /// `snap_tolerance`: the relative tolerance of "a branch reached a stored point" (see the top
  /// of this file); a solver whose turning strains are converged to a tolerance τ needs one
  /// above τ, or each repeated cycle leaves a loop of size τ open and the memory fills.
  explicit MasingSkeleton(const PowerLawCurve& curve, double snap_tolerance = kMasingSnapTolerance);
  [[nodiscard]] double snap_tolerance() const { return snap_tolerance_; }
  [[nodiscard]] const PowerLawCurve& curve() const { return curve_; }
  [[nodiscard]] double yield_strain() const { return yield_strain_; }
  [[nodiscard]] double stress(double strain) const;   ///< g(ε), odd
  [[nodiscard]] double tangent(double strain) const;  ///< g'(ε), even
  [[nodiscard]] double energy(double strain) const;   ///< G(ε) = ∫_0^|ε| g, even

 private:
  [[nodiscard]] double antiderivative(double x) const;  ///< a/(b+1)·x^(b+1) + σ∞·x
  PowerLawCurve curve_;
  double yield_strain_;
  double yield_energy_;          ///< E·ε_y²/2
  double yield_antiderivative_;  ///< antiderivative(ε_y)
  double snap_tolerance_;
};

/// One bond's (one material point's) Masing state: the committed strain and stress and the stack of
/// open reversal points. Plain data; the default is the virgin state. Entries at and above `depth`
/// are always 0, so equal histories give equal bytes.
struct MasingState {
  double strain = 0.0;
  double stress = 0.0;
  std::array<double, kMasingMemory> reversal_strain{};  ///< R_1 … R_depth (index 0 = oldest)
  std::array<double, kMasingMemory> reversal_stress{};
  std::uint8_t depth = 0;  ///< open reversals (0 = virgin / on the skeleton)
  /// Reversal points dropped because the memory was full (2 per overflow, see the top of this
  /// file).
  std::uint32_t dropped_reversals = 0;
};

/// Stress (Pa), tangent dσ/dε (Pa) at the trial strain, and the work ∫σ dε (J/m³) along the path.
struct MasingResponse {
  double stress;
  double tangent;
  double work;
};

/// The response at `trial_strain` reached from the committed state by a MONOTONE strain path (one
/// half-cycle ramp), without changing the state: stress, tangent dσ/dε at the trial strain, and the
/// work ∫σ dε from committed.strain to trial_strain along the Masing branches actually followed
/// (closed form through PowerLawCurve::energy, no quadrature). Requires validate(curve).
MasingResponse masing_evaluate(const PowerLawCurve& curve, const MasingState& committed,
                               double trial_strain);

/// The state after that monotone path (the same rules), i.e. commit a turning point.
MasingState masing_commit(const PowerLawCurve& curve, const MasingState& committed,
                          double trial_strain);

/// The same two functions on a prebuilt skeleton (bit-identical results, no ε_y solve per call).
MasingResponse masing_evaluate(const MasingSkeleton& skeleton, const MasingState& committed,
                               double trial_strain);
MasingState masing_commit(const MasingSkeleton& skeleton, const MasingState& committed,
                          double trial_strain);

/// The area of the stable symmetric loop ±a (J/m³): 8·G(a) − 4a·g(a) (Masing closed form).
double masing_symmetric_loop_area(const PowerLawCurve& curve, double strain_amplitude);

}  // namespace peritwin::model
