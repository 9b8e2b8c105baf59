// Law 2: the energy-based law (000 Sec. 4, Eq. 30-46): a bond's energy release rate ḡ (Eq. 31-33)
// and its range (Eq. 30, 34-35), with B_i, n_i mapped from the strain law's A_i, m_i (Eq. 44-46).
#pragma once

#include "solver/fatigue/laws/strain_range.h"

namespace peritwin::fatigue {

// ============================ law 2: energy-based (000 Sec. 4) ==================================

/// 000 Eq. (31): ḡ of a state-based bond; a, b, d PD constants (000 Eq. 4), θ the dilatations.
double bond_energy_release_rate_osb(double a, double b, double d, double theta_k, double theta_j,
                                    double s, double xi, double v_k, double v_j, double dx,
                                    double h);
/// 000 Eq. (32c): C0 = ḡ/s² of a state-based bond (s != 0; for proportional loading θ ∝ s so C0 is
/// load independent). Returns 0 for s == 0 (000: ḡ = 0 there).
double c0_osb(double a, double b, double d, double theta_k, double theta_j, double s, double xi,
              double v_k, double v_j, double dx, double h);
/// 000 Eq. (33): C0 = b V_k V_j ξ / (Δx h²) of a bond-based bond (a = 0).
double c0_bond_based(double b, double xi, double v_k, double v_j, double dx, double h);
/// 000 Eq. (32b): ḡ = C0 s².
double bond_energy_release_rate(double c0, double s);
/// 000 Eq. (30): g = |ḡ⁺ − (R/|R|) ḡ⁻|; R = 0 takes the R >= 0 branch of Eq. (30b).
double energy_release_rate_range(double g_max_load, double g_min_load, double load_ratio);
/// 000 Eq. (34b): g = |C0| |1 − (R/|R|) R²| (s⁺)², i.e. Eq. (30) with ḡ⁻ = R² ḡ⁺.
double energy_release_rate_range_from_ratio(double c0, double s_max_load, double load_ratio);
/// 000 Eq. (35c): C1 = |C0| |1 − (R/|R|) R²| / (1 − R)², so g = C1 ε² (Eq. 35b). NaN for R == 1.
double c1_coefficient(double c0, double load_ratio);

struct EnergyLawBondParams {
  double B = 0.0;  ///< B_i(k)(j), 000 Eq. (44b)
  double n = 0.0;  ///< n_i, 000 Eq. (44a)
};
/// 000 Eq. (44)-(46): n_i = m_i/2, B_i = A_i / C1^(m_i/2).
EnergyLawBondParams energy_params_from_strain(double A, double m, double c1);
/// 000 Eq. (37b): g∞ = C1 ε∞² (also used for ε̃∞ in phase II, by analogy; 000 has no ε̃∞).
double energy_fatigue_limit(double c1, double eps_limit);

/// 000 Eq. (37a)-(38): B1 (g − g∞)^n1 if g > g∞, else 0. With g∞ > 0 this is A1 (ε² − ε∞²)^(m1/2),
/// NOT the strain law's A1 (ε − ε∞)^m1: the two models coincide only without a fatigue limit.
double energy_decrement_phase1(double g, double g_inf, double B1, double n1);
/// 000 Eq. (39): B2 g^n2 if g > g̃∞ (default 0: plain Eq. 39), else 0.
double energy_decrement_phase2(double g, double B2, double n2, double g_inf_prop = 0.0);
/// Per-bond convenience: B, n, g∞ from p and the bond's C1, then the phase's decrement.
double energy_decrement(double g, Phase phase, double c1, const StrainLawParams& p);
/// Threshold-free factorization B g^n = [B (C1 s_unit²)^n] × |P_max(1 − R)|^(2n) (pair with
/// load_dose using m = 2n). C1 depends on R: recompute the bond factor when R changes.
double energy_bond_factor(double B, double n, double c1, double stretch_per_unit_load);

}  // namespace peritwin::fatigue
