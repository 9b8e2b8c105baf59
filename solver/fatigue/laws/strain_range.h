// Law 1: the cyclic bond strain-range law (000 Sec. 3, Eq. 14-29; 002 Sec. 4, Eq. 6, 12-15), as
// pure scalar functions the engine calls element-wise. Units: SI; see remaining_life.h for the
// per-cycle life arithmetic and the paper prefixes (000 Nguyen et al., 002 Zhang & Bobaru).
#pragma once

#include <span>

#include "core/expected.h"
#include "core/param_reader.h"
#include "solver/fatigue/laws/remaining_life.h"

namespace peritwin::fatigue {
struct FatigueSettings;
}  // namespace peritwin::fatigue

namespace peritwin::fatigue {

// ============================ law 1: cyclic bond strain range (000 Sec. 3, 002 Sec. 4) ===========

/// Parameters of the Silling-Askari strain-range law. Defaults: B1 Al 6061-T6.
struct StrainLawParams {
  double A1 = 103.7465;  ///< phase I coefficient, 000 Eq. (14a), value 000 Eq. (48c)
  double m1 = 2.29153;   ///< phase I exponent, 000 Eq. (14a), value 000 Eq. (48a)
  double eps_inf = 0.0;  ///< phase I fatigue limit ε∞ >= 0, 000 Eq. (17) (Al 6061-T6: not used)
  /// phase II coefficient, 000 Eq. (14b). 1055 is 000 Sec. 6.1's calibration for ITS mesh
  /// (δ = 3.015Δx, Δx = 0.6 mm); recalibrate (000 App. A, Eq. 26) and rescale (Eq. 29).
  double A2 = 1055.0;
  double m2 = 2.6183;         ///< phase II exponent = Paris M, 000 Eq. (25), value 000 Sec. 6.1
  double eps_inf_prop = 0.0;  ///< propagation-phase limit ε̃∞ >= 0, 002 Eq. (12); 0 = off
};

/// B1: Al 6061-T6 (000 Eq. 48, Sec. 6.1); A2 as in StrainLawParams.
StrainLawParams al6061_t6_strain_params();
/// B3: SAE 1020 steel (002 Table 2): A1 1.32e15, p1 9, ε∞ 1e-3, A2 7.76e6, p2 2.1, ε̃∞ 1e-4.
StrainLawParams sae1020_strain_params();
/// OK, or a message naming every bad field (A_i, m_i > 0, limits >= 0, finite).
core::Status validate(const StrainLawParams& p);

/// 000 Eq. (15): ε = |s⁺ − s⁻| from the stretches at P_max and P_min (002 Eq. 6 likewise).
double strain_range(double s_max_load, double s_min_load);
/// 000 Eq. (15)-(16): ε = |s⁺(1 − R)|, R = P_min/P_max. For R < 0 the whole excursion counts
/// (ε = |s⁺|(1 + |R|)): the papers define ε as the full range |s⁺ − s⁻| and 000 Eq. (35a) uses this
/// same relation for R < 0; no crack-closure cut-off is applied.
double strain_range_from_ratio(double s_max_load, double load_ratio);

/// 000 Eq. (17)-(18): A1 (ε − ε∞)^m1 if ε > ε∞, else 0.
double strain_decrement_phase1(double eps, double A1, double m1, double eps_inf);
/// 000 Eq. (19) with 002 Eq. (12): A2 ε^m2 if ε > ε̃∞, else 0 (a cut-off: NOT shifted by ε̃∞).
double strain_decrement_phase2(double eps, double A2, double m2, double eps_inf_prop = 0.0);
/// Dispatches on the phase with the parameters of p.
double strain_decrement(double eps, Phase phase, const StrainLawParams& p);

/// Factorization for threshold-free laws at linear elasticity: s⁺ = s_unit·P_max, so
/// A ε^m = [A |s_unit|^m] × [|P_max (1 − R)|^m]. bond_factor depends on the bond and the current
/// (damaged) structure only; load_dose on the load block only. The product bond_factor*load_dose is
/// mathematically, not bitwise, equal to strain_decrement_*: use one form for both engine modes.
double strain_bond_factor(double A, double m, double stretch_per_unit_load);
double load_dose(double p_max, double load_ratio, double m);
inline double factorized_decrement(double bond_factor, double dose) { return bond_factor * dose; }

/// 000 Eq. (21)-(22): cycles to nucleation N1 = 1/(A1 (ε − ε∞)^m1) (real); +inf if ε <= ε∞.
double nucleation_cycles(double eps, double A1, double m1, double eps_inf = 0.0);
/// Eq. (22) solved for A1 from one (ε1, N1) point.
double a1_from_nucleation(double n1_cycles, double eps1, double m1, double eps_inf = 0.0);
/// 000 Eq. (23)/(48b): A1 from the fitted log10 intercept y0 = −log10(A1)/m1, A1 = 10^(−m1·y0).
double a1_from_log_intercept(double m1, double log10_intercept);

struct Phase1Fit {
  double A1 = 0.0;
  double m1 = 0.0;
  bool ok = false;  ///< false: < 2 usable points, ε <= ε∞, N <= 0, or a non-negative slope
};
/// 000 Eq. (23a-b): least squares of log10(ε − ε∞) on log10 N; slope −1/m1, intercept −log10 A1/m1.
Phase1Fit fit_phase1(std::span<const double> eps, std::span<const double> cycles, double eps_inf);

/// 000 Eq. (25): m2 = M (Paris exponent).
inline double m2_from_paris_exponent(double paris_m) { return paris_m; }
/// 000 Eq. (26b) (002 Eq. 15 likewise): A2 = A2_trial · C_experiment / C_trial.
double a2_calibrated(double a2_trial, double c_experiment, double c_trial);
/// 000 Eq. (28): Â2 = A2(δ1) / δ1^((m2−2)/2).
double a2_hat(double a2_at_delta1, double delta1, double m2);
/// 000 Eq. (27), (29): A2(δ2) = Â2 δ2^((m2−2)/2) = A2(δ1) (δ2/δ1)^((m2−2)/2).
double a2_scaled(double a2_at_delta1, double delta1, double delta2, double m2);
/// 002 Eq. (13): ε̃∞ = ε̄ ΔK_th/ΔK, ε̄ the mean cyclic strain of the bonds at the crack tip.
double propagation_fatigue_limit(double mean_tip_strain_range, double delta_k_th, double delta_k);

/// Config reader of the laws strain_range and energy: A1, m1, A2, m2 > 0 (required; 000 Eq. 14,
/// 17-19, 44-46), eps_inf >= 0 (000 Eq. 17), eps_inf_prop >= 0 (002 Eq. 12), and
/// compressed_bonds_fatigue (000 Eq. 15, FatigueSettings::compressed_bonds_fatigue).
void read_strain_range(core::ParamReader& r, FatigueSettings& f);

}  // namespace peritwin::fatigue
