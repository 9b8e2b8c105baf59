// Strain gauges -> the cycle's load (issue 33 item 3): P (N) and its angle α (rad) of each sample
// of gauge strains, from the model's influence coefficients. Strains are dimensionless (m/m),
// loads in N, angles in rad.
//
// The model. A detail's load pattern is affine in the cycle's load: the force is
// P·(constant + cos α·per_cos + sin α·per_sin) (the three basis cases of the static solve). The
// model gives, per gauge g, the strain it reads per N of P in each basis case, c_g = (c0, c1, c2),
// so the gauge reads
//     ε_g = P·(c0_g + c1_g cos α + c2_g sin α) + noise_g.
// LoadIdentifier inverts this for one sample of the chosen gauges (the "columns").
//
// Decisions, and why:
// - Coefficients of magnitude <= 1e-9 × the largest |c| of the columns' gauges are taken as 0,
//   in identify() and model_strain() alike (they are the solver's rounding, and a residual must
//   be ε − model_strain exactly).
// - The form of the load, from the columns' coefficients:
//   * p_only: every c1, c2 is 0. The strains do not depend on α: one unknown, P; α is reported
//     as 0. Weighted least squares; the solution is a fixed row vector applied to the strains.
//   * linear_pair: every c0 is 0. Then x = P cos α, y = P sin α enter linearly: weighted least
//     squares for (x, y) (a fixed 2×n map), then α = atan2(y, x) brought into (−π/2, π/2] with
//     P signed. (−P, α+π) gives the same strains as (P, α): α alone in (−π, π] could not be
//     told, and this choice keeps the angle of a load reversing through 0 steady, as a rainflow
//     counter of signed P with its angle wants.
//   * constant_and_angle: the constant and the α parts both. For a given α the best P is in
//     closed form, P(α) = vᵀWε / vᵀWv with v(α) = c0 + c1 cos α + c2 sin α, so the weighted
//     misfit is minimized over α alone: it equals εᵀWε − N²/D with N = u·b, D = uᵀGu,
//     u = (1, cos α, sin α), b = CᵀWε (3 sums per sample) and G = CᵀWC (fixed). Candidates:
//     the angle of the unconstrained linear solution (P, P cos α, P sin α) = G⁻¹b (exact for
//     exact strains), and the 3 largest local maxima of N²/D on a scan over (−π, π] (D and the
//     cos, sin of its angles precomputed). Each is refined by a safeguarded Newton on
//     d(N²/D)/dα (bisection when a step leaves the bracket) to |Δα| < 1e-12 rad; the smallest
//     misfit wins. The scan has 72 angles, more where a minimum of the misfit can be narrower:
//     near the α where D is smallest, N²/D is a peak √(Dmin/Dmax) rad wide, so the step is
//     half that (at most 4096 angles: √(Dmin/Dmax) >= 1/cond(√W C), so only coefficients with
//     a condition number above ~300 could hide a minimum narrower than the step; such gauges
//     barely tell the load anyway). Deterministic, no allocation; under 1 µs for 8 gauges
//     (peritwin-bench stream --gauges). α is in (−π, π], P signed (the constant
//     part makes (P, α) and (−P, α+π) different loads).
// - Weights: w_g = 1/noise_g² when every column's noise is > 0 (the maximum-likelihood estimate
//   for independent normal noise), else every w_g = 1: one gauge without a noise figure would
//   get an infinite weight, and mixing given and made-up figures is worse than none.
//   residual_rms is the weighted RMS of ε − model: sqrt(Σ w r² / Σ w) (the plain RMS unweighted).
// - Independence: the rank of the columns' coefficient matrix (gauges × the basis columns the
//   form uses: c0; c1, c2; or c0, c1, c2) by Eigen's SVD, singular values below 1e-8 × the
//   largest not counted. The rank must be the number of those basis columns. For p_only and
//   linear_pair that is the number of unknowns (1, 2). For constant_and_angle it is 3, one more
//   than the 2 unknowns: with rank 2 the strains P·v(α) lie in a plane where v(α) traces an
//   ellipse, and a line through the origin that meets an ellipse meets it twice (bar
//   tangents), so two different (P, α) fit a sample exactly (for instance α and −α when the c2
//   are 0). All coefficients 0 is refused too (the gauges do not see the load).
//
// Not thread-safe to update() while another thread identifies; identify() is const and may run
// on many threads at once.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/expected.h"

namespace peritwin::stream {

/// One gauge's influence coefficients: strain per N of P for the constant, cos α, sin α basis
/// cases; and its noise (strain, standard deviation, >= 0; 0 = not known).
struct GaugeInfluence {
  std::string id;
  std::array<double, 3> per_basis{};
  double noise = 0.0;
};

/// A sample's load: P (N, signed), α (rad) and the weighted RMS strain misfit.
struct IdentifiedLoad {
  double p = 0.0;
  double alpha = 0.0;
  double residual_rms = 0.0;
};

/// The form of the load the columns' coefficients show (see the top of the file).
enum class LoadForm {
  p_only,              ///< no α part: 1 unknown (P), α reported as 0
  linear_pair,         ///< no constant part: P cos α, P sin α linear; α in (−π/2, π/2]
  constant_and_angle,  ///< both: P(α) in closed form, α by scan and Newton; α in (−π, π]
};

/// P and α of samples of gauge strains (see the top of the file).
class LoadIdentifier {
 public:
  /// `columns`: the gauge ids in the order the samples give their strains; `influence`: the
  /// model's gauges (any order, may hold more gauges than columns). Refused, with a reason a
  /// user can act on, when there is no column, a column is no gauge of the model, a column
  /// repeats, the model names a gauge twice, a column's coefficients or noise are not finite
  /// (or the noise < 0), every coefficient is 0, or the columns' gauges give fewer independent
  /// equations than the form needs ("2 unknowns (P, α) but the gauges g1, g2 give only 1
  /// independent equation ...").
  static core::Expected<LoadIdentifier, std::string> create(
      std::vector<std::string> columns, const std::vector<GaugeInfluence>& influence);

  /// New coefficients (the model re-solved after bonds broke) for the same columns; the same
  /// refusal rules; on refusal the old ones stay. The form (and unknowns()) may change. For 8
  /// gauges about 2 µs (p_only, linear_pair) or 13 µs (constant_and_angle): fine per STATE.
  core::Status update(const std::vector<GaugeInfluence>& influence);

  /// P and α of one sample of strains (one per column, in columns() order, finite) and the
  /// misfit; the per-column residual ε − model_strain(i, p, alpha) to `residuals` (resized) if
  /// non-null. A sample of the wrong size or with a non-finite strain gives NaN p, alpha,
  /// residual_rms (and residuals). All strains 0 gives p = 0, alpha = 0.
  [[nodiscard]] IdentifiedLoad identify(std::span<const double> strains,
                                        std::vector<double>* residuals = nullptr) const;

  /// 1 (P) or 2 (P, α).
  [[nodiscard]] int unknowns() const { return form_ == LoadForm::p_only ? 1 : 2; }
  [[nodiscard]] LoadForm form() const { return form_; }
  [[nodiscard]] const std::vector<std::string>& columns() const { return columns_; }
  /// The model's strain of column `column` (< columns().size(), asserted) for (p, alpha):
  /// p·(c0 + c1 cos α + c2 sin α), with the negligible coefficients as 0.
  [[nodiscard]] double model_strain(std::size_t column, double p, double alpha) const;

  /// constant_and_angle: the angles of the scan over (−π, π] (see the top of the file); else 0.
  [[nodiscard]] int scan_angles() const { return static_cast<int>(scan_cos_.size()); }
  static constexpr int kMinScanAngles = 72;
  static constexpr int kMaxScanAngles = 4096;

 private:
  LoadIdentifier() = default;
  [[nodiscard]] double weighted_rms(std::span<const double> strains, double p, double alpha,
                                    std::vector<double>* residuals) const;
  [[nodiscard]] IdentifiedLoad identify_constant_and_angle(std::span<const double> strains) const;

  std::vector<std::string> columns_;
  LoadForm form_ = LoadForm::p_only;
  std::size_t n_ = 0;
  std::vector<double> c0_, c1_, c2_;  ///< per column, negligible ones as 0
  std::vector<double> w_;             ///< weights, the largest 1 (scaling changes nothing)
  double w_sum_ = 0.0;
  /// p_only: P = Σ map0_i ε_i. linear_pair: x = Σ map0_i ε_i, y = Σ map1_i ε_i.
  /// constant_and_angle: b_j = Σ (w c_j)_i ε_i, map0/1/2 = w∘c0, w∘c1, w∘c2.
  std::vector<double> map0_, map1_, map2_;
  std::array<double, 9> g_{};     ///< constant_and_angle: G = CᵀWC, row-major
  std::array<double, 9> ginv_{};  ///< constant_and_angle: G⁻¹, row-major
  std::vector<double> scan_cos_, scan_sin_, scan_inv_d_;  ///< per scan angle: cos, sin, 1/D
};

/// The header "time_s,<gauge id>,..." -> the gauge ids (fields trimmed of blanks; a UTF-8 BOM
/// is skipped). Refused with a reason: no time_s first, an empty or repeated id, no gauge.
core::Expected<std::vector<std::string>, std::string> parse_gauge_header(std::string_view line);

/// One data line's time (s) and strains (one per gauge, in the header's order).
struct GaugeSample {
  double t = 0.0;
  std::vector<double> strains;
};

/// One line after the header: "t,e1,...,en" (n = `gauges` strains) -> the sample; nullopt for
/// nothing (a blank line or a '#' comment: skip it); an error (why) for anything else: the wrong
/// number of fields, a field that is no number, a non-finite time or strain, a header line in
/// the data. Numbers as std::from_chars reads them ('.' decimals whatever the locale, exponents;
/// a leading '+' is taken too), blanks around a field ignored.
core::Expected<std::optional<GaugeSample>, std::string> parse_gauge_line(std::string_view line,
                                                                         std::size_t gauges);

}  // namespace peritwin::stream
