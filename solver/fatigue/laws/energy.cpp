// Law 2: energy-based (000 Sec. 4); contracts in energy.h.
#include "solver/fatigue/laws/energy.h"

#include <cmath>

#include "solver/fatigue/laws/law_math.h"

namespace peritwin::fatigue {

using detail::kInf;
using detail::kNaN;
using detail::non_negative;
using detail::positive;
using detail::pow_pos;
using detail::require;

// ============================ law 2: energy-based ===============================================

double bond_energy_release_rate_osb(double a, double b, double d, double theta_k, double theta_j,
                                    double s, double xi, double v_k, double v_j, double dx,
                                    double h) {
  // 000 Eq. (31)
  return 0.5 * (2.0 * a * d / xi * (theta_k + theta_j) + 4.0 * b * s) * xi * s * v_k * v_j /
         (2.0 * dx * h * h);
}

double c0_osb(double a, double b, double d, double theta_k, double theta_j, double s, double xi,
              double v_k, double v_j, double dx, double h) {
  if (s == 0.0) return 0.0;
  // 000 Eq. (32c)
  return (a * d / xi * (theta_k / s + theta_j / s) + 2.0 * b) * v_k * v_j / (2.0 * dx * h * h) * xi;
}

double c0_bond_based(double b, double xi, double v_k, double v_j, double dx, double h) {
  return b * v_k * v_j / (dx * h * h) * xi;  // 000 Eq. (33)
}

double bond_energy_release_rate(double c0, double s) { return c0 * s * s; }  // 000 Eq. (32b)

double energy_release_rate_range(double g_max_load, double g_min_load, double load_ratio) {
  // 000 Eq. (30b)
  return load_ratio >= 0.0 ? std::abs(g_max_load - g_min_load) : std::abs(g_max_load + g_min_load);
}

double energy_release_rate_range_from_ratio(double c0, double s_max_load, double load_ratio) {
  const double sign = load_ratio >= 0.0 ? 1.0 : -1.0;
  // 000 Eq. (34b)
  return std::abs(c0) * std::abs(1.0 - sign * load_ratio * load_ratio) * s_max_load * s_max_load;
}

double c1_coefficient(double c0, double load_ratio) {
  if (load_ratio == 1.0) return kNaN;
  const double sign = load_ratio >= 0.0 ? 1.0 : -1.0;
  const double one_minus_r = 1.0 - load_ratio;
  // 000 Eq. (35c)
  return std::abs(c0) * std::abs(1.0 - sign * load_ratio * load_ratio) /
         (one_minus_r * one_minus_r);
}

EnergyLawBondParams energy_params_from_strain(double A, double m, double c1) {
  EnergyLawBondParams e;
  e.n = 0.5 * m;                // 000 Eq. (44a)
  e.B = A / std::pow(c1, e.n);  // 000 Eq. (44b)
  return e;
}

double energy_fatigue_limit(double c1, double eps_limit) {
  return c1 * eps_limit * eps_limit;  // 000 Eq. (37b)
}

double energy_decrement_phase1(double g, double g_inf, double B1, double n1) {
  if (!(g > g_inf)) return 0.0;         // 000 Eq. (37a)
  return B1 * std::pow(g - g_inf, n1);  // 000 Eq. (38)
}

double energy_decrement_phase2(double g, double B2, double n2, double g_inf_prop) {
  if (!(g > g_inf_prop)) return 0.0;
  return B2 * std::pow(g, n2);  // 000 Eq. (39)
}

double energy_decrement(double g, Phase phase, double c1, const StrainLawParams& p) {
  if (phase == Phase::kNucleation) {
    const EnergyLawBondParams e = energy_params_from_strain(p.A1, p.m1, c1);  // 000 Eq. (45)
    return energy_decrement_phase1(g, energy_fatigue_limit(c1, p.eps_inf), e.B, e.n);
  }
  const EnergyLawBondParams e = energy_params_from_strain(p.A2, p.m2, c1);  // 000 Eq. (46)
  return energy_decrement_phase2(g, e.B, e.n, energy_fatigue_limit(c1, p.eps_inf_prop));
}

double energy_bond_factor(double B, double n, double c1, double stretch_per_unit_load) {
  return B * pow_pos(c1 * stretch_per_unit_load * stretch_per_unit_load, n);
}

}  // namespace peritwin::fatigue
