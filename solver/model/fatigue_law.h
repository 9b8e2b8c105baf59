// Per-bond fatigue laws as pure scalar functions (no I/O, no globals, no per-bond objects): the
// engine keeps every per-bond quantity in its own arrays and calls these element-wise.
//
// Units: SI throughout. Stretches and strain ranges are dimensionless, stresses Pa, lengths m,
// volumes m^3, energies J, energy release rates J/m^2, temperatures K, frequencies Hz, activation
// volumes m^3, hysteresis loop areas as the caller's ψ expects (ψ·A must be in J). The fatigue
// constants A_i keep the units implied by their laws (A_i ε^m_i is dimensionless per cycle).
//
// Paper prefixes: 000 Nguyen et al. (energy-based PD fatigue), 002 Zhang & Bobaru
// (propagation-phase fatigue limit), 003 Bazazzadeh et al. (bilinear bond + fatigue degradation),
// 004 Vaitkunas et al. (kinetic theory of fracture).
//
// ---- Remaining-life arithmetic contract (laws 1, 2 and the KTF remaining life) ----------------
// Per cycle the remaining life is updated by ONE double subtraction, `lambda = step_life(lambda,
// d)` (i.e. `lambda -= d`), 000 Eq. (18), (19), (38), (39). This repeated-subtraction form is the
// reference ("per-cycle oracle"). `advance_life(lambda, d, k)` returns bit-for-bit the value of k
// such subtractions in O(log(lambda/d)) time, and `cycles_to_failure(lambda, d)` the exact number
// of them needed to reach lambda <= 0. Because k1 subtractions followed by k2 subtractions are
// k1+k2 subtractions, block stepping with ANY split of a constant-load stretch into blocks is
// bit-identical to per-cycle stepping; the engine may commit lambda after every block. (The
// multiplication form lambda0 - k*d was rejected: it is only identical if both modes re-anchor
// lambda0 at exactly the same cycles.) Note that the iterated count can differ from the
// real-arithmetic lambda/d by many cycles when d is tiny compared with ulp(lambda): each
// subtraction really removes d rounded to a multiple of ulp(lambda); that is why cycles_to_failure
// emulates the rounding exactly instead of correcting a closed-form estimate by a few cycles.
// Assumes IEEE-754 binary64 with round-to-nearest-even (no -ffast-math in the translation unit that
// iterates).
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>

#include "solver/core/expected.h"

namespace peritwin::fatigue {

inline constexpr double kBoltzmann = 1.380649e-23;  ///< k (J/K), exact SI 2019
inline constexpr double kPlanck = 6.62607015e-34;   ///< h (J·s), exact SI 2019
/// Returned by cycles_to_failure when the iteration never reaches lambda <= 0.
inline constexpr std::int64_t kNeverFails = std::numeric_limits<std::int64_t>::max();
/// 000 Sec. 4.4: damage index switching a point's bonds to phase II in 2D (δ = 3Δx); [54] used 0.5.
inline constexpr double kPhaseSwitchDamage2D = 0.398;

enum class Phase : std::uint8_t {
  kNucleation = 1,  ///< phase I, 000 Eq. (17)-(18) / (37)-(38)
  kGrowth = 2,      ///< phase II, 000 Eq. (19) / (39), optional limit 002 Eq. (12)
};

// ============================ remaining-life arithmetic (see contract above) =====================

/// One cycle of 000 Eq. (18)/(19): the canonical per-cycle update `lambda - d`.
inline double step_life(double lambda, double decrement) { return lambda - decrement; }

/// Value of `lambda` after k >= 0 applications of step_life, bit-identical to the loop, also past
/// failure (negative lambda). O(number of binades crossed) for decrement >= 0 (NaN/inf inputs are
/// fixed points after <= 2 steps); decrement < 0 (not a fatigue decrement) falls back to the loop.
double advance_life(double lambda, double decrement, std::int64_t k);

/// Smallest n >= 1 such that n applications of step_life give a value <= 0, exactly as iterating
/// (n = 1 whenever lambda - decrement <= 0, including lambda already <= 0). kNeverFails when the
/// iteration stalls or increases (decrement <= 0, NaN, or decrement < ulp(lambda)/2 somewhere) or
/// the count would exceed int64.
/// Cost: O(log2(lambda/d)) binades crossed, ~35 ns each on the build machine (~0.7 µs at 2^19).
std::int64_t cycles_to_failure(double remaining_life, double decrement_per_cycle);

/// Cheap guaranteed bracket lo <= cycles_to_failure(lambda, d) <= hi (hi may be kNeverFails), from
/// the per-step rounding error |fl(x − d) − (x − d)| <= ulp(lambda)/2. Relative width
/// ~ulp(lambda)/d: lets the engine find the next failing bond with few exact evaluations.
struct CycleBounds {
  std::int64_t lo = 1;
  std::int64_t hi = kNeverFails;
};
CycleBounds cycles_to_failure_bounds(double remaining_life, double decrement_per_cycle);

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
Status validate(const StrainLawParams& p);

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

// ============================ law 3: bilinear bond with damage (003) =============================

/// Bilinear bond (003 Sec. 3, 6.2) with the third fatigue degradation law (003 Eq. 27-30, 50).
struct BilinearParams {
  double s0 = 0.0;  ///< elastic-limit stretch, 003 Eq. (43) (plane stress/strain) or (42) (3D)
  double sc = 0.0;  ///< failure stretch, sc = kr·s0, 003 Eq. (44); must exceed s0
  /// third-law coefficient, 003 Eq. (27). No default: the exponent sign of 003 Sec. 6.7's
  /// "2.1×108" was lost in conversion. Must be calibrated.
  double A = 0.0;
  double m = 4.0;  ///< third-law exponent, 003 Eq. (27); 4.0 in 003 Sec. 6.6-6.7
};
Status validate(const BilinearParams& p);

/// 003 Eq. (43), plane stress: s0 = sqrt(4π G0 / (9 E δ)).
double bilinear_s0_plane_stress(double g0, double youngs_modulus, double horizon);
/// 003 Eq. (43), plane strain: s0 = sqrt(5π G0 / (12 E δ)).
double bilinear_s0_plane_strain(double g0, double youngs_modulus, double horizon);
/// 003 Eq. (42), 3D (also 004 Eq. 9 with G_c): s0 = sqrt(5 G0 / (6 E δ)).
double bilinear_s0_3d(double g0, double youngs_modulus, double horizon);

/// 003 Eq. (14) in stretch form: D = 0 (s <= s0), sc (s − s0) / (s (sc − s0)) (s0 < s < sc), 1.
double bilinear_static_damage(double s, double s0, double sc);
/// 003 Eq. (15)/(18)/(46): static damage increment max(0, D14(s_new) − D14(s_old)); equals
/// s0 sc/(sc − s0) (1/s_old − 1/s_new) for s0 < s_old < s_new < sc. Only an opening increment
/// damages; pass the historical maximum stretch as s_old to keep the envelope irreversible.
double bilinear_static_damage_increment(double s_old, double s_new, double s0, double sc);
/// 003 Eq. (27): dD_f/dN = A (s/sc)^m; compressive stretch (s <= 0) gives 0 (no opening).
double third_law_fatigue_rate(double s, double sc, double A, double m);
/// 003 Eq. (29): A ΔN ((s_old/sc + s_new/sc)/2)^m (mid-point rule over ΔN cycles); 0 if the mean
/// stretch is <= 0.
double third_law_fatigue_damage_increment(double s_old, double s_new, double delta_n,
                                          const BilinearParams& p);
/// 003 Eq. (30)/(50): total increment = static (Eq. 46) + fatigue (Eq. 29).
double third_law_damage_increment(double s_old, double s_new, double delta_n,
                                  const BilinearParams& p);
/// D + Eq. (50) increment, clamped to [D, 1]; D >= 1 means the bond is broken.
double third_law_update_damage(double damage, double s_old, double s_new, double delta_n,
                               const BilinearParams& p);
/// 003 Eq. (45) with Eq. (13): f = c·factor·s, factor = 1 − D for s < sc and D < 1, else 0. Eq.
/// (13) is applied for every s < sc (not only s > s0) so that fatigue damage accumulated at s <= s0
/// softens the bond (003 Fig. 6); with static damage only (D = 0 for s <= s0) this is Eq. (45).
double bilinear_force_factor(double s, double damage, double sc);
/// 003 Eq. (45): bond force magnitude c·factor·s.
double bilinear_bond_force(double c, double s, double damage, double sc);
/// 003 Eq. (27) integrated at a constant stretch 0 < s <= s0 (no static damage): D goes from 0 to
/// 1 in N = 1/(A (s/sc)^m) cycles; +inf for s <= 0.
double third_law_cycles_constant_stretch(double s, const BilinearParams& p);
/// One bond under a constant force F = c·s_e (load control; the PD analogue of one spring of 003's
/// cylinder model, Sec. 2): equilibrium c(1 − D)s = F (Eq. 13/45) gives s = s_e/(1 − D), and
/// Eq. (27) becomes dD/dN = A (s_e/((1 − D) sc))^m, i.e. (1 − (1 − D)^(m+1))/(m+1) = A (s_e/sc)^m
/// N. The bond reaches s0 at D = 1 − s_e/s0; beyond s0 its force c(1 − D_f − D_s(s))s (Eq. 14, 16)
/// falls with s (slope s_e/s0 − sc/(sc − s0) < 0), so it cannot carry F and fails at once. Cycles
/// to failure N_f = (1 − (s_e/s0)^(m+1)) / ((m+1) A (s_e/sc)^m) for 0 < s_e < s0; 0 for s_e >= s0.
double third_law_bar_cycles_to_failure(double s_elastic, const BilinearParams& p);
/// The same bond integrated with 003 Eq. (50) in increments of ΔN cycles: per increment the
/// implicit mid-point rule of Eq. (29), D' = D + static(Eq. 46) + A ΔN ((s + s')/(2 sc))^m with
/// s' = s_e/(1 − D'), solved by fixed-point iteration; the crossing of s0 is located inside the
/// last increment with the same rule (D* = 1 − s_e/s0). Converges to
/// third_law_bar_cycles_to_failure as O(ΔN²).
double third_law_bar_cycles_numerical(double s_elastic, double delta_n, const BilinearParams& p);

// ============================ law 4: kinetic theory of fracture (004) ============================

struct KineticParams {
  double U = 0.0;      ///< activation energy (J), 004 Eq. (13)-(14); from the S-N curve, no default
  double gamma = 0.0;  ///< activation volume (m^3), 004 Eq. (13)-(14); no default
  double lambda = 9.0;  ///< shape parameter λ, 004 Eq. (12) (value from 004 Sec. KTF)
  double n0 = 1.771;    ///< initial constant, 004 Eq. (12); 1.771 for λ = 9 (kt_n0_for_unit_life)
  double temperature = 293.0;  ///< T (K), 004 test temperature 20 °C
  double frequency = 0.56;     ///< f (Hz), 004 test frequency
};
Status validate(const KineticParams& p);

/// k T (J): the thermal energy of 004 Eq. (14)-(15).
double kt_thermal_energy(double temperature);
// Not implemented: 004's self-heating, Eq. (17) (T = T* + ψσa²/Δt), and its hysteresis energy,
// Eq. (26) (θ = kT + ψA above the yield loop area A_σy). The twin's bonds are linear elastic: they
// have no hysteresis loop A, and ψ is fitted in 004 to one steel's measured temperatures. The
// law runs at the configured temperature (KineticParams::temperature) instead.
/// 004 Eq. (14): K_b = (θ/h) exp(−(U − γσ)/θ), θ = kT (or the Eq. 26 thermal energy).
double kt_breakage_rate(double sigma, double U, double gamma, double thermal_energy);
/// Per-cycle dose Φ = ∫ K_b dt over one cycle in which σ ramps linearly between Rσ_max and σ_max in
/// 1/f (the assumption behind 004 Eq. 15): Φ = θ²/(h γ f σ_max(1 − R)) e^(−U/θ) [e^(γσ_max/θ) −
/// e^(γRσ_max/θ)], evaluated overflow-safely; for R → 1 its limit (θ/(h f)) e^((γσ_max − U)/θ).
double kt_cycle_dose(double sigma_max, double load_ratio, double frequency, double U, double gamma,
                     double thermal_energy);
/// 004 Eq. (15): damage after N cycles from n_I, n = n0 − {(n0 − n_I)^(1−λ) − (1 − λ) N
/// Φ}^(1/(1−λ)); λ = 1 (not covered by the paper) uses the exact limit n0 − (n0 − n_I) e^(−NΦ).
/// Capped at n0.
double kt_damage_after_cycles(double n_initial, double cycles, double dose_per_cycle, double lambda,
                              double n0);
/// Damage increment of one cycle, Eq. (15) with N = 1 from n.
double kt_damage_increment(double n, double dose_per_cycle, double lambda, double n0);
/// n0 with ∫_0^1 dn/(n0 − n)^λ = 1 (004 Sec. KTF; 1.771 for λ = 9), by bisection. λ > 0.
double kt_n0_for_unit_life(double lambda);
/// Consumed life z(n) = ∫_0^n dn'/(n0 − n')^λ; Eq. (12) integrates to dz/dN = Φ exactly.
double kt_consumed_life(double n, double lambda, double n0);
/// Remaining life r = z(1) − z(n) (> 0 intact, <= 0 failed, n >= 1). Unlike q = 1 − n (004 Eq. 16)
/// r falls by exactly Φ per cycle at constant σ_max, R: use it with step_life/advance_life/
/// cycles_to_failure and decrement Φ. z(1) = 1 when n0 = kt_n0_for_unit_life(λ).
double kt_remaining_life(double n, double lambda, double n0);
/// Inverse of kt_remaining_life: damage n for a remaining life r (r <= 0 gives n >= 1).
double kt_damage_from_remaining_life(double remaining, double lambda, double n0);

}  // namespace peritwin::fatigue
