// Law 4: kinetic theory of fracture (004); contracts in kinetic.h.
#include "solver/fatigue/laws/kinetic.h"

#include <algorithm>
#include <cmath>
#include <limits>
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

// ============================ law 4: kinetic theory of fracture =================================

core::Status validate(const KineticParams& p) {
  std::string msg;
  require(msg, positive(p.U), "U must be finite and > 0 (004 Eq. 14)");
  require(msg, positive(p.gamma), "gamma must be finite and > 0 (004 Eq. 14)");
  require(msg, positive(p.lambda), "lambda must be finite and > 0 (004 Eq. 12)");
  require(msg, std::isfinite(p.n0) && p.n0 > 1.0, "n0 must be finite and > 1 (004 Eq. 12)");
  require(msg, positive(p.temperature), "temperature must be finite and > 0 K (004 Eq. 14)");
  require(msg, positive(p.frequency), "frequency must be finite and > 0 Hz (004 Eq. 15)");
  return msg.empty() ? core::Status{} : core::Status{core::failure(msg)};
}

core::Status validate(const KineticExtension& p) {
  std::string msg;
  require(msg,
          p.segment_count == 0 || (p.segment_count >= 2 && p.segment_count <= kMaxKineticSegments),
          "segment_count must be 0 (one U, gamma) or 2 to 3 (004 Fig. 8b)");
  if (p.segment_count >= 2 && p.segment_count <= kMaxKineticSegments) {
    double below = 0.0;
    for (int i = 0; i < p.segment_count; ++i) {
      const KineticSegment& s = p.segments[static_cast<std::size_t>(i)];
      const bool last = i + 1 == p.segment_count;
      require(msg, positive(s.U) && positive(s.gamma),
              "every segment's U and gamma must be finite and > 0 (004 Eq. 14)");
      require(msg,
              last ? s.sigma_upper == kInf : (positive(s.sigma_upper) && s.sigma_upper > below),
              "segment upper stresses must ascend, finite and > 0, the last one +inf");
      below = s.sigma_upper;
    }
  }
  require(msg, positive(p.kU) && positive(p.kgamma),
          "kU and kgamma must be finite and > 0 (004 step 6)");
  require(msg, non_negative(p.psi) && non_negative(p.loop_area) && non_negative(p.loop_area_yield),
          "psi, loop_area and loop_area_yield must be finite and >= 0 (004 Eq. 26)");
  return msg.empty() ? core::Status{} : core::Status{core::failure(msg)};
}

double kt_thermal_energy(double temperature) { return kBoltzmann * temperature; }

double kt_thermal_energy(double temperature, double psi, double loop_area, double loop_area_yield) {
  const double kt = kt_thermal_energy(temperature);
  // 004 Eq. (26): kT + ψA "if ... A ≥ A_σy"; Eq. (15)'s kT otherwise. kt + 0.0 is kt exactly.
  return loop_area >= loop_area_yield ? kt + psi * loop_area : kt;
}

KineticActivation kt_activation(const KineticParams& p, const KineticExtension& e, double sigma_max,
                                int phase) {
  KineticActivation a{p.U, p.gamma};
  for (int i = 0; i < e.segment_count; ++i) {  // 004: "σ ≤ 250, 250 < σ ≤ 290, σ > 290 MPa"
    const KineticSegment& s = e.segments[static_cast<std::size_t>(i)];
    if (sigma_max <= s.sigma_upper || i + 1 == e.segment_count) {
      a = {s.U, s.gamma};
      break;
    }
  }
  if (phase == 2) {  // 004 step 6: U = k_U·U, γ = k_γ·γ in the crack growth phase
    a.U *= e.kU;
    a.gamma *= e.kgamma;
  }
  return a;
}

double kt_bond_dose(const KineticParams& p, const KineticExtension& e, double sigma_max,
                    double load_ratio, int phase) {
  if (!(sigma_max > 0.0)) return 0.0;
  const KineticActivation a = kt_activation(p, e, sigma_max, phase);
  const double theta = kt_thermal_energy(p.temperature, e.psi, e.loop_area, e.loop_area_yield);
  return kt_cycle_dose(sigma_max, load_ratio, p.frequency, a.U, a.gamma, theta);
}

double kt_breakage_rate(double sigma, double U, double gamma, double thermal_energy) {
  return thermal_energy / kPlanck * std::exp(-(U - gamma * sigma) / thermal_energy);  // 004 (14)
}

double kt_cycle_dose(double sigma_max, double load_ratio, double frequency, double U, double gamma,
                     double thermal_energy) {
  // ∫ K_b dt over σ ramping linearly from Rσ_max to σ_max in 1/f (004 Eq. 15 per cycle):
  // (θ/(h f)) e^(−U/θ) (e^x1 − e^x2)/(x1 − x2) = (θ/(h f)) e^(x_hi − U/θ) (1 − e^(−w))/w.
  const double x1 = gamma * sigma_max / thermal_energy;
  const double x2 = gamma * load_ratio * sigma_max / thermal_energy;
  const double hi = std::max(x1, x2);
  const double w = hi - std::min(x1, x2);
  const double mean_factor = w > 0.0 ? -std::expm1(-w) / w : 1.0;
  return thermal_energy / (kPlanck * frequency) * std::exp(hi - U / thermal_energy) * mean_factor;
}

double kt_damage_after_cycles(double n_initial, double cycles, double dose_per_cycle, double lambda,
                              double n0) {
  const double nd = cycles * dose_per_cycle;
  if (lambda == 1.0) return n0 - (n0 - n_initial) * std::exp(-nd);  // λ → 1 limit of Eq. (15)
  const double one_minus = 1.0 - lambda;
  const double base = std::pow(n0 - n_initial, one_minus) - one_minus * nd;  // 004 Eq. (15)
  if (!(base > 0.0)) return n0;  // λ < 1: n reaches n0 in finite N
  return n0 - std::pow(base, 1.0 / one_minus);
}

double kt_damage_increment(double n, double dose_per_cycle, double lambda, double n0) {
  return kt_damage_after_cycles(n, 1.0, dose_per_cycle, lambda, n0) - n;
}

double kt_consumed_life(double n, double lambda, double n0) {
  if (lambda == 1.0) return std::log(n0 / (n0 - n));
  return (std::pow(n0 - n, 1.0 - lambda) - std::pow(n0, 1.0 - lambda)) / (lambda - 1.0);
}

double kt_remaining_life(double n, double lambda, double n0) {
  // z(1) − z(n) written without the common n0 term.
  if (lambda == 1.0) return std::log((n0 - n) / (n0 - 1.0));
  return (std::pow(n0 - 1.0, 1.0 - lambda) - std::pow(n0 - n, 1.0 - lambda)) / (lambda - 1.0);
}

double kt_damage_from_remaining_life(double remaining, double lambda, double n0) {
  if (lambda == 1.0) return n0 - (n0 - 1.0) * std::exp(remaining);
  const double one_minus = 1.0 - lambda;
  const double base = std::pow(n0 - 1.0, one_minus) + one_minus * remaining;
  if (!(base > 0.0)) return n0;
  return n0 - std::pow(base, 1.0 / one_minus);
}

double kt_n0_for_unit_life(double lambda) {
  if (!(lambda > 0.0) || !std::isfinite(lambda)) return kNaN;
  // z_{n0}(1) decreases from +inf (λ >= 1) or 1/(1 − λ) > 1 (λ < 1) at n0 = 1+ to 0 as n0 → ∞.
  const auto excess = [lambda](double n0) { return kt_consumed_life(1.0, lambda, n0) - 1.0; };
  double lo = 1.0;
  double hi = 2.0;
  while (excess(hi) > 0.0) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 200 && hi - lo > 4.0 * std::numeric_limits<double>::epsilon() * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (excess(mid) > 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

/// 004's segments from the keys U2, gamma2, U3, gamma3, sigma_upper1, sigma_upper2 (Pa); every
/// problem reported at its key.
void read_segments(core::ParamReader& r, const KineticParams& k, KineticExtension& e) {
  const bool second = r.has("U2") || r.has("gamma2");
  const bool third = r.has("U3") || r.has("gamma3");
  if (!second) {
    r.check("U3", !third, "needs U2 and gamma2 (segments fill in order, 004 Fig. 8b)");
    r.check("sigma_upper1", !r.has("sigma_upper1"), "needs U2 and gamma2 (a second segment)");
    r.check("sigma_upper2", !r.has("sigma_upper2"), "needs U3 and gamma3 (a third segment)");
    return;
  }
  r.check("sigma_upper2", third || !r.has("sigma_upper2"), "needs U3 and gamma3 (a third segment)");
  e.segment_count = third ? 3 : 2;
  e.segments[0] = {kInf, k.U, k.gamma};
  for (int i = 1; i < e.segment_count; ++i) {
    auto& s = e.segments[static_cast<std::size_t>(i)];
    const std::string n = std::to_string(i + 1);
    if (const auto v = r.required("U" + n, core::Bound::positive)) s.U = *v;
    if (const auto v = r.required("gamma" + n, core::Bound::positive)) s.gamma = *v;
    const std::string upper = "sigma_upper" + std::to_string(i);
    if (const auto v = r.required(upper, core::Bound::positive)) {
      e.segments[static_cast<std::size_t>(i - 1)].sigma_upper = *v;
      if (i > 1) {
        const double below = e.segments[static_cast<std::size_t>(i - 2)].sigma_upper;
        r.check(upper, *v > below,
                "must be > sigma_upper" + std::to_string(i - 1) + " (got " +
                    core::format_number(*v) + " <= " + core::format_number(below) + ")");
      }
    }
  }
}

}  // namespace

// 004 Eq. (12)-(15), (26) and step 6: the activation parameters (per stress segment), the shape
// λ, n0, the test conditions, the phase II factors and the hysteresis energy.
void read_kinetic(core::ParamReader& r, FatigueSettings& f) {
  const auto set = [&r](double& field, std::string_view key) {
    if (const auto v = r.required(key, core::Bound::positive)) field = *v;
  };
  set(f.kinetic.U, "U");
  set(f.kinetic.gamma, "gamma");
  f.kinetic.lambda = r.optional("lambda", f.kinetic.lambda, core::Bound::positive);
  f.kinetic.n0 = r.number("n0", f.kinetic.n0);
  r.check("n0", f.kinetic.n0 > 1, "must be > 1 (got " + core::format_number(f.kinetic.n0) + ")");
  f.kinetic.temperature = r.optional("temperature", f.kinetic.temperature, core::Bound::positive);
  f.kinetic.frequency = r.optional("frequency", f.kinetic.frequency, core::Bound::positive);
  auto& e = f.kinetic_extension;
  read_segments(r, f.kinetic, e);
  e.kU = r.optional("kU", e.kU, core::Bound::positive);
  e.kgamma = r.optional("kgamma", e.kgamma, core::Bound::positive);
  e.psi = r.optional("psi", e.psi, core::Bound::non_negative);
  e.loop_area = r.optional("loop_area", e.loop_area, core::Bound::non_negative);
  e.loop_area_yield = r.optional("loop_area_yield", e.loop_area_yield, core::Bound::non_negative);
}

}  // namespace peritwin::fatigue
