// Law 3: the bilinear bond with damage of 003 (Bazazzadeh et al.), Sec. 3, 6.2: static damage
// (Eq. 13-18, 42-46) and the third fatigue degradation law (Eq. 27-30, 50).
#pragma once

#include "core/expected.h"
#include "core/param_reader.h"

namespace peritwin::fatigue {
struct FatigueSettings;
}  // namespace peritwin::fatigue

namespace peritwin::fatigue {

// ============================ law 3: bilinear bond with damage (003) =============================

/// Bilinear bond (003 Sec. 3, 6.2) with the third fatigue degradation law (003 Eq. 27-30, 50).
struct BilinearParams {
  double s0 = 0.0;  ///< elastic-limit stretch, 003 Eq. (43) (plane stress/strain) or (42) (3D)
  double sc = 0.0;  ///< failure stretch, sc = kr·s0, 003 Eq. (44); must exceed s0
  /// third-law coefficient, 003 Eq. (27). No default: the exponent sign of 003 Sec. 6.7's
  /// "2.1×108" was lost in conversion. Must be calibrated.
  double A = 0.0;
  double m = 4.0;  ///< third-law exponent, 003 Eq. (27); 4.0 in 003 Sec. 6.6-6.7
  /// Which of 003's three fatigue degradation laws (Sec. 4.2-4.4): 1, 2 or 3 (default: the third,
  /// Eq. 27-30/50, whose A and m are above). 003's Table 2 (their values) was lost in conversion.
  int law = 3;
  /// First law (003 Eq. 19-22, 47-48): dD/dN = C e^{λD} (s/sc)^β, integrated over ΔN as 003 writes
  /// it, ΔN C/(1+β) e^{λ D_μ} (s_μ/sc)^{1+β} with D_μ, s_μ the μ-weighted end values (Eq. 21, 48).
  double C = 0.0;       ///< first-law coefficient C (per cycle), 003 Eq. (19)
  double beta = 0.0;    ///< first-law exponent β, 003 Eq. (19); > -1
  double lambda = 0.0;  ///< first-law damage sensitivity λ, 003 Eq. (19); >= 0
  double mu = 0.7;      ///< first-law weight μ of the end of the increment, 003 Eq. (21): 0.7
  /// Second law (003 Eq. 23-26, 49), in stretch form: the failure stretch of a bond beyond s0
  /// shrinks, sc' = sc − B (s' − s0)^n ΔN, and D = sc'(s − s0)/(s (sc' − s0)) (Eq. 24 = Eq. 14 with
  /// sc').
  double B = 0.0;  ///< second-law coefficient B (stretch per cycle), 003 Eq. (23)
  double n = 1.0;  ///< second-law exponent n, 003 Eq. (23)
};
core::Status validate(const BilinearParams& p);

/// 003 Eq. (43), plane stress: s0 = sqrt(4π G0 / (9 E δ)).
double bilinear_s0_plane_stress(double g0, double youngs_modulus, double horizon);
/// 003 Eq. (43), plane strain: s0 = sqrt(5π G0 / (12 E δ)).
double bilinear_s0_plane_strain(double g0, double youngs_modulus, double horizon);

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
/// 003 Eq. (20): the first law's fatigue increment ΔN C/(1+β) e^{λ D_μ} (s_μ/sc)^{1+β}; 0 for
/// s_μ <= 0. 003 writes the exponent 1+β and the factor 1/(1+β) although the rate of Eq. (19) has
/// the exponent β: we follow Eq. (20)/(47) (the paper's integrated form, the one its numbers were
/// fitted with), i.e. the rate actually integrated is C/(1+β) e^{λD} (s/sc)^{1+β}.
double first_law_fatigue_damage_increment(double d_mu, double s_mu, double delta_n,
                                          const BilinearParams& p);
/// 003 Eq. (22)/(47): D' = D + static(Eq. 46) + Eq. (20) with D_μ = (1−μ)D + μD', s_μ = (1−μ)s_N +
/// μ s' (Eq. 21, 48). Implicit in D': solved per bond by Newton from D (g(D') = D' − D − a −
/// b e^{λμD'} is concave, so Newton from the left rises monotonically to the smallest root); no
/// root in [D, 1] means the bond fails (returns 1). `s_env` is the envelope (largest stretch so
/// far) that the static part starts from; `s_start` the stretch at the start of the increment.
double first_law_update_damage(double damage, double s_env, double s_start, double s_new,
                               double delta_n, const BilinearParams& p);
/// 003 Eq. (23) in stretch form: sc' = sc_N − B (s' − s0)^n ΔN for s' > s0, else sc_N (a bond
/// below its elastic limit does not lose failure stretch: (s' − s0)^n is not real there).
double second_law_failure_stretch(double sc_n, double s_new, double delta_n,
                                  const BilinearParams& p);
/// The second law's current failure stretch sc_N recovered from (D, s_env): Eq. (24) solved for
/// sc, sc_N = D s_env s0 / (s0 − (1 − D) s_env) for s_env > s0 and 0 < D < 1; p.sc when D = 0
/// (the failure stretch only shrinks while s > s0, which also damages). So the law needs no state
/// beyond the engine's damage and stretch envelope.
double second_law_current_failure_stretch(double damage, double s_env, const BilinearParams& p);
/// 003 Eq. (24)/(25)/(49): D' = Eq. (14) with sc' of Eq. (23) at max(s_env, s'), never below D
/// (irreversible), 1 when sc' <= max(s_env, s') (failed).
double second_law_update_damage(double damage, double s_env, double s_new, double delta_n,
                                const BilinearParams& p);
/// The damage update of the chosen law (p.law): D' from D, the envelope s_env, the stretch at the
/// start of the increment s_N and the trial end stretch s' (003 Eq. 47, 49, 50). Law 3 is the
/// engine's original arithmetic: D + static(s_env → s') + Eq. (29)(s_N, s'), clamped to [D, 1].
double bilinear_update_damage(double damage, double s_env, double s_start, double s_new,
                              double delta_n, const BilinearParams& p);
/// Single bond held at a constant stretch s (displacement control) from damage D0 (003's spring
/// at a fixed opening): first law, Eq. (19)-(20) integrated exactly: e^{−λD0} − e^{−λD} = λ k N
/// with k = C/(1+β) (s/sc)^{1+β} (λ = 0: D = D0 + kN); cycles to D = 1.
double first_law_cycles_constant_stretch(double s, double d0, const BilinearParams& p);
/// Second law at a constant stretch s0 < s < sc: sc(N) = sc − B (s − s0)^n N (Eq. 23, exact for
/// any ΔN since s is constant); failure when sc(N) = s: N = (sc − s)/(B (s − s0)^n).
double second_law_cycles_constant_stretch(double s, const BilinearParams& p);
/// Second law at a constant stretch: D after N cycles, Eq. (24) with sc(N) of Eq. (23).
double second_law_damage_constant_stretch(double s, double cycles, const BilinearParams& p);

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

/// Config reader of the law bilinear: s0, sc > s0 (003 Eq. 43-44) required; degradation_law (1, 2
/// or 3, default 3); law 3: A (003 Eq. 27) required, m > 0 (003 Eq. 27); law 1: C > 0 required,
/// beta > -1 (default 0), lambda >= 0 (default 0), mu in [0, 1] (default 0.7) (003 Eq. 19-21); law
/// 2: B > 0 required, n > 0 (default 1) (003 Eq. 23); and the increment settings cycle_increment >=
/// 1 (ΔN, 003 Sec. 5.1), softening_tolerance > 0, softening_max_iterations >= 1 (FatigueSettings).
void read_bilinear(core::ParamReader& r, FatigueSettings& f);

}  // namespace peritwin::fatigue
