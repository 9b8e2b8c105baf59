// Law 1: cyclic bond strain range (000 Sec. 3, 002 Sec. 4); contracts in strain_range.h.
#include "solver/fatigue/laws/strain_range.h"

#include <cmath>
#include <cstddef>
#include <string>

#include "core/param_reader.h"
#include "solver/fatigue/fatigue_settings.h"
#include "solver/fatigue/laws/law_math.h"

namespace peritwin::fatigue {

using detail::kInf;
using detail::kNaN;
using detail::non_negative;
using detail::positive;
using detail::pow_pos;
using detail::require;

// ============================ law 1: cyclic bond strain range ===================================

StrainLawParams al6061_t6_strain_params() { return StrainLawParams{}; }

StrainLawParams sae1020_strain_params() {
  StrainLawParams p;
  p.A1 = 1.32e15;  // 002 Table 2
  p.m1 = 9.0;
  p.eps_inf = 1e-3;
  p.A2 = 7.76e6;
  p.m2 = 2.1;
  p.eps_inf_prop = 1e-4;
  return p;
}

core::Status validate(const StrainLawParams& p) {
  std::string msg;
  require(msg, positive(p.A1), "A1 must be finite and > 0 (000 Eq. 14a)");
  require(msg, positive(p.m1), "m1 must be finite and > 0 (000 Eq. 14a)");
  require(msg, non_negative(p.eps_inf), "eps_inf must be finite and >= 0 (000 Eq. 17)");
  require(msg, positive(p.A2), "A2 must be finite and > 0 (000 Eq. 14b)");
  require(msg, positive(p.m2), "m2 must be finite and > 0 (000 Eq. 14b)");
  require(msg, non_negative(p.eps_inf_prop), "eps_inf_prop must be finite and >= 0 (002 Eq. 12)");
  return msg.empty() ? core::Status{} : core::Status{core::failure(msg)};
}

double strain_range(double s_max_load, double s_min_load) {
  return std::abs(s_max_load - s_min_load);  // 000 Eq. (15)
}

double strain_range_from_ratio(double s_max_load, double load_ratio) {
  return std::abs(s_max_load * (1.0 - load_ratio));  // 000 Eq. (15)-(16)
}

double strain_decrement_phase1(double eps, double A1, double m1, double eps_inf) {
  if (!(eps > eps_inf)) return 0.0;         // 000 Eq. (17): no damage at or below the fatigue limit
  return A1 * std::pow(eps - eps_inf, m1);  // 000 Eq. (18)
}

double strain_decrement_phase2(double eps, double A2, double m2, double eps_inf_prop) {
  if (!(eps > eps_inf_prop)) return 0.0;  // 002 Eq. (12) (frozen below ε̃∞)
  return A2 * std::pow(eps, m2);          // 000 Eq. (19)
}

double strain_decrement(double eps, Phase phase, const StrainLawParams& p) {
  return phase == Phase::kNucleation ? strain_decrement_phase1(eps, p.A1, p.m1, p.eps_inf)
                                     : strain_decrement_phase2(eps, p.A2, p.m2, p.eps_inf_prop);
}

double strain_bond_factor(double A, double m, double stretch_per_unit_load) {
  return A * pow_pos(std::abs(stretch_per_unit_load), m);
}

double load_dose(double p_max, double load_ratio, double m) {
  return pow_pos(std::abs(p_max * (1.0 - load_ratio)), m);
}

double nucleation_cycles(double eps, double A1, double m1, double eps_inf) {
  if (!(eps > eps_inf)) return kInf;
  return 1.0 / (A1 * std::pow(eps - eps_inf, m1));  // 000 Eq. (21)-(22)
}

double a1_from_nucleation(double n1_cycles, double eps1, double m1, double eps_inf) {
  if (!(eps1 > eps_inf) || !(n1_cycles > 0.0)) return kNaN;
  return 1.0 / (n1_cycles * std::pow(eps1 - eps_inf, m1));  // 000 Eq. (22) solved for A1
}

double a1_from_log_intercept(double m1, double log10_intercept) {
  return std::pow(10.0, -m1 * log10_intercept);  // 000 Eq. (48b) -> (48c)
}

Phase1Fit fit_phase1(std::span<const double> eps, std::span<const double> cycles, double eps_inf) {
  // 000 Eq. (23): log10(ε − ε∞) = −(1/m1) log10 N − log10(A1)/m1.
  const std::size_t n = std::min(eps.size(), cycles.size());
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, count = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!(eps[i] > eps_inf) || !(cycles[i] > 0.0)) return {};
    const double x = std::log10(cycles[i]);
    const double y = std::log10(eps[i] - eps_inf);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    count += 1.0;
  }
  if (count < 2.0) return {};
  const double var = sxx - sx * sx / count;
  if (!(var > 0.0)) return {};
  const double slope = (sxy - sx * sy / count) / var;
  const double intercept = (sy - slope * sx) / count;
  if (!(slope < 0.0)) return {};
  Phase1Fit fit;
  fit.m1 = -1.0 / slope;
  fit.A1 = a1_from_log_intercept(fit.m1, intercept);
  fit.ok = true;
  return fit;
}

double a2_calibrated(double a2_trial, double c_experiment, double c_trial) {
  return a2_trial * c_experiment / c_trial;  // 000 Eq. (26b)
}

double a2_hat(double a2_at_delta1, double delta1, double m2) {
  return a2_at_delta1 / std::pow(delta1, 0.5 * (m2 - 2.0));  // 000 Eq. (28)
}

double a2_scaled(double a2_at_delta1, double delta1, double delta2, double m2) {
  return a2_at_delta1 * std::pow(delta2 / delta1, 0.5 * (m2 - 2.0));  // 000 Eq. (29)
}

double propagation_fatigue_limit(double mean_tip_strain_range, double delta_k_th, double delta_k) {
  return mean_tip_strain_range * delta_k_th / delta_k;  // 002 Eq. (13)
}

// 000 Eq. (14), (17)-(19), 002 Eq. (12): the parameters; 000 Eq. (15): compressed bonds.
void read_strain_range(core::ParamReader& r, FatigueSettings& f) {
  const auto set = [&r](double& field, std::string_view key) {
    if (const auto v = r.required(key, core::Bound::positive)) field = *v;
  };
  set(f.strain.A1, "A1");
  set(f.strain.m1, "m1");
  set(f.strain.A2, "A2");
  set(f.strain.m2, "m2");
  f.strain.eps_inf = r.optional("eps_inf", 0.0, core::Bound::non_negative);
  f.strain.eps_inf_prop = r.optional("eps_inf_prop", 0.0, core::Bound::non_negative);
  f.compressed_bonds_fatigue = r.boolean("compressed_bonds_fatigue", f.compressed_bonds_fatigue);
}

}  // namespace peritwin::fatigue
