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

/// Config reader of the law bilinear: s0, sc > s0 (003 Eq. 43-44) and A (003 Eq. 27) required,
/// m > 0 (003 Eq. 27), and the increment settings cycle_increment >= 1 (ΔN, 003 Sec. 5.1),
/// softening_tolerance > 0, softening_max_iterations >= 1 (FatigueSettings).
void read_bilinear(core::ParamReader& r, FatigueSettings& f);

}  // namespace peritwin::fatigue
