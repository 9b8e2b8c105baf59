// Per-bond fatigue laws; see fatigue_law.h for the contracts and the paper references.
#include "solver/model/fatigue_law.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>

namespace peritwin::fatigue {

namespace {

constexpr std::int64_t kTwo52 = std::int64_t{1} << 52;
constexpr std::int64_t kTwo53 = std::int64_t{1} << 53;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------
// Exact emulation of repeated IEEE subtraction. A positive finite double x lies in a binade whose
// representable numbers are the integers a times 2^q (a < 2^53; a >= 2^52 for normal x). While the
// exact result of x - d stays in the same binade (and positive), fl(x - d) = (a - D) 2^q, where D
// is d/2^q rounded to the nearest integer, with ties (d/2^q = f + 1/2) going to the even result:
// after at most one step a is even and D is the even one of f, f + 1. So a run of such steps is one
// integer subtraction. Steps that leave the binade are done in hardware. Adding (for negative x,
// whose magnitude grows) is the mirror image.

struct Binade {
  int q = 0;             // x = a * 2^q exactly
  std::int64_t a = 0;    // integer significand
  std::int64_t low = 0;  // smallest a of the binade (2^52; 0 for subnormals)
};

Binade binade_of(double x) {  // x > 0, finite: read the IEEE fields directly (hot path)
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const auto biased = static_cast<int>(bits >> 52);
  const auto fraction = static_cast<std::int64_t>(bits & ((std::uint64_t{1} << 52) - 1));
  if (biased == 0) return {-1074, fraction, 0};
  return {biased - 1075, fraction | kTwo52, kTwo52};
}

// v * 2^k, exact for the values used here (v an integer < 2^54, or d scaled by the ulp).
double scale(double v, int k) {
  if (k >= -1022 && k <= 1023) {
    return v * std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52);
  }
  return std::ldexp(v, k);
}

// floor(num / den) for 0 <= num < 2^54, 0 < den < 2^54: a double division (much cheaper than an
// int64 one) corrected by at most a step or two to the exact integer quotient.
std::int64_t quotient(std::int64_t num, std::int64_t den) {
  auto q = static_cast<std::int64_t>(static_cast<double>(num) / static_cast<double>(den));
  while (q > 0 && q * den > num) --q;
  while ((q + 1) * den <= num) ++q;
  return q;
}

// Rounded step D (in units of 2^q) for t = d/2^q in [0, 2^53), or -1 when t is a tie and a is odd
// (the next step must be taken in hardware to reach an even a). Also returns floor(t), ceil(t).
struct Step {
  std::int64_t step = 0;
  std::int64_t floor = 0;
  std::int64_t ceil = 0;
};
Step rounded_step(double t, std::int64_t a) {
  Step s;
  s.floor = static_cast<std::int64_t>(t);                // truncation == floor for t >= 0
  const double frac = t - static_cast<double>(s.floor);  // exact
  s.ceil = s.floor + (frac > 0.0 ? 1 : 0);
  if (frac == 0.5) {
    s.step = a % 2 != 0 ? -1 : (s.floor % 2 == 0 ? s.floor : s.floor + 1);
  } else {
    s.step = frac < 0.5 ? s.floor : s.floor + 1;
  }
  return s;
}

// Up to `budget` steps x <- fl(x - d) for x > d > 0 that stay in x's binade and positive, taken in
// one integer subtraction. Returns the number taken (0: do the next step in hardware). Sets
// `stalled` when a step would not change x (then x never changes again).
std::int64_t bulk_subtract(double& x, double d, std::int64_t budget, bool& stalled) {
  const Binade b = binade_of(x);
  const Step s = rounded_step(scale(d, -b.q), b.a);  // t exact and < 2^53 because d < x
  if (s.step < 0) return 0;
  // The step from a_i is in-binade and positive iff a_i - t >= low and a_i - t > 0.
  const std::int64_t room = b.a - std::max(b.low + s.ceil, s.floor + 1);
  if (room < 0) return 0;
  if (s.step == 0) {
    stalled = true;
    return 0;
  }
  const std::int64_t taken = std::min(quotient(room, s.step) + 1, budget);
  x = scale(static_cast<double>(b.a - taken * s.step), b.q);
  return taken;
}

// Up to `budget` steps y <- fl(y + d) for y > 0, d > 0 that stay below the top of y's binade.
std::int64_t bulk_add(double& y, double d, std::int64_t budget, bool& stalled) {
  if (!(y > 0.0) || !std::isfinite(y)) return 0;
  const Binade b = binade_of(y);
  const double t = scale(d, -b.q);
  if (!(t < static_cast<double>(kTwo53))) return 0;  // leaves the binade at once
  const Step s = rounded_step(t, b.a);
  if (s.step < 0) return 0;
  // The step from a_i keeps ulp 2^q iff a_i + t < 2^53, i.e. a_i <= 2^53 - 1 - floor(t).
  const std::int64_t room = kTwo53 - 1 - s.floor - b.a;
  if (room < 0) return 0;
  if (s.step == 0) {
    stalled = true;
    return 0;
  }
  const std::int64_t taken = std::min(quotient(room, s.step) + 1, budget);
  y = scale(static_cast<double>(b.a + taken * s.step), b.q);
  return taken;
}

double pow_pos(double base, double exponent) { return base > 0.0 ? std::pow(base, exponent) : 0.0; }

void require(std::string& msg, bool ok, const char* text) {
  if (ok) return;
  if (!msg.empty()) msg += "; ";
  msg += text;
}

bool positive(double v) { return std::isfinite(v) && v > 0.0; }
bool non_negative(double v) { return std::isfinite(v) && v >= 0.0; }

}  // namespace

// ============================ remaining-life arithmetic =========================================

double advance_life(double lambda, double decrement, std::int64_t k) {
  if (k <= 0) return lambda;
  if (decrement < 0.0) {  // increasing iterate: not a fatigue decrement, plain loop
    for (std::int64_t i = 0; i < k; ++i) lambda = step_life(lambda, decrement);
    return lambda;
  }
  if (!std::isfinite(decrement) || !std::isfinite(lambda)) {  // NaN/inf: fixed after <= 2 steps
    for (std::int64_t i = 0; i < std::min<std::int64_t>(k, 2); ++i) {
      lambda = step_life(lambda, decrement);
    }
    return lambda;
  }
  if (decrement == 0.0) return lambda;  // x - 0 == x bit for bit (also -0)
  while (k > 0) {
    bool stalled = false;
    std::int64_t taken = 0;
    if (lambda > decrement) {
      taken = bulk_subtract(lambda, decrement, k, stalled);
    } else if (lambda <= 0.0) {  // x - d == -((-x) + d) exactly (rounding is sign-symmetric)
      double magnitude = -lambda;
      taken = bulk_add(magnitude, decrement, k, stalled);
      lambda = -magnitude;
    }
    if (stalled) return lambda;
    k -= taken;
    if (k == 0) break;
    // The step after a bulk run (or when none is possible) changes binade: do it in hardware.
    const double next = step_life(lambda, decrement);
    if (next == lambda || !std::isfinite(next)) return next;  // fixed point (e.g. 1 - 2^-54 == 1)
    lambda = next;
    --k;
  }
  return lambda;
}

std::int64_t cycles_to_failure(double remaining_life, double decrement_per_cycle) {
  double x = remaining_life;
  const double d = decrement_per_cycle;
  if (step_life(x, d) <= 0.0) return 1;
  // Here x - d > 0. Without d > 0 the iterate never decreases; +inf stays +inf.
  if (!(d > 0.0) || !std::isfinite(x)) return kNeverFails;
  std::int64_t n = 0;  // steps taken; invariant x > d, so the next step keeps x > 0
  for (;;) {           // invariant: x > d
    bool stalled = false;
    const std::int64_t taken = bulk_subtract(x, d, kNeverFails, stalled);
    if (stalled) return kNeverFails;
    if (n > kNeverFails - 3 - taken) return kNeverFails;
    n += taken;
    // A bulk run keeps x > 0 but may end with x <= d in the subnormal range.
    if (step_life(x, d) <= 0.0) return n + 1;
    // The next step changes binade: do it in hardware.
    const double next = step_life(x, d);
    if (next == x) return kNeverFails;  // fixed point at the bottom of a binade
    x = next;
    n += 1;
    if (step_life(x, d) <= 0.0) return n + 1;
  }
}

CycleBounds cycles_to_failure_bounds(double remaining_life, double decrement_per_cycle) {
  const double x = remaining_life;
  const double d = decrement_per_cycle;
  if (step_life(x, d) <= 0.0) return {1, 1};
  if (!(d > 0.0) || !std::isfinite(x)) return {kNeverFails, kNeverFails};
  // Each step removes d + err, |err| <= u/2 with u the spacing of x's binade. Failing at step n
  // needs (n − 1)(d + u/2) >= x − d and (n − 2)(d − u/2) < x − d. Margins of 1e-15 cover the
  // rounding of the bound arithmetic itself.
  const double half_ulp = 0.5 * scale(1.0, binade_of(x).q);
  const double big = 9.0e18;  // below INT64_MAX
  CycleBounds b;
  const double lo = std::floor((x - d) / (d + half_ulp) * (1.0 - 1e-15)) + 1.0;
  b.lo = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::min(lo, big)));
  if (d > half_ulp) {
    const double hi = std::ceil((x - d) / (d - half_ulp) * (1.0 + 1e-15)) + 2.0;
    if (hi < big) b.hi = static_cast<std::int64_t>(hi);
  }
  return b;
}

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

Status validate(const StrainLawParams& p) {
  std::string msg;
  require(msg, positive(p.A1), "A1 must be finite and > 0 (000 Eq. 14a)");
  require(msg, positive(p.m1), "m1 must be finite and > 0 (000 Eq. 14a)");
  require(msg, non_negative(p.eps_inf), "eps_inf must be finite and >= 0 (000 Eq. 17)");
  require(msg, positive(p.A2), "A2 must be finite and > 0 (000 Eq. 14b)");
  require(msg, positive(p.m2), "m2 must be finite and > 0 (000 Eq. 14b)");
  require(msg, non_negative(p.eps_inf_prop), "eps_inf_prop must be finite and >= 0 (002 Eq. 12)");
  return msg.empty() ? Status{} : Status{failure(msg)};
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

// ============================ law 3: bilinear bond with damage ==================================

Status validate(const BilinearParams& p) {
  std::string msg;
  require(msg, positive(p.s0), "s0 must be finite and > 0 (003 Eq. 43)");
  require(msg, std::isfinite(p.sc) && p.sc > p.s0, "sc must be finite and > s0 (003 Eq. 44)");
  require(msg, positive(p.A), "A must be finite and > 0 (003 Eq. 27)");
  require(msg, positive(p.m), "m must be finite and > 0 (003 Eq. 27)");
  return msg.empty() ? Status{} : Status{failure(msg)};
}

double bilinear_s0_plane_stress(double g0, double youngs_modulus, double horizon) {
  return std::sqrt(4.0 * std::numbers::pi * g0 / (9.0 * youngs_modulus * horizon));  // 003 Eq. (43)
}

double bilinear_s0_plane_strain(double g0, double youngs_modulus, double horizon) {
  return std::sqrt(5.0 * std::numbers::pi * g0 /
                   (12.0 * youngs_modulus * horizon));  // 003 Eq. (43)
}

double bilinear_s0_3d(double g0, double youngs_modulus, double horizon) {
  return std::sqrt(5.0 * g0 / (6.0 * youngs_modulus * horizon));  // 003 Eq. (42)
}

double bilinear_static_damage(double s, double s0, double sc) {
  if (s <= s0) return 0.0;
  if (s >= sc) return 1.0;
  return sc * (s - s0) / (s * (sc - s0));  // 003 Eq. (14)
}

double bilinear_static_damage_increment(double s_old, double s_new, double s0, double sc) {
  // 003 Eq. (15)/(18)/(46), written as a difference of Eq. (14) so that it also covers steps that
  // start below s0 or end beyond sc.
  return std::max(0.0,
                  bilinear_static_damage(s_new, s0, sc) - bilinear_static_damage(s_old, s0, sc));
}

double third_law_fatigue_rate(double s, double sc, double A, double m) {
  return A * pow_pos(s / sc, m);  // 003 Eq. (27)
}

double third_law_fatigue_damage_increment(double s_old, double s_new, double delta_n,
                                          const BilinearParams& p) {
  const double mid = 0.5 * (s_old / p.sc + s_new / p.sc);
  return p.A * delta_n * pow_pos(mid, p.m);  // 003 Eq. (29)
}

double third_law_damage_increment(double s_old, double s_new, double delta_n,
                                  const BilinearParams& p) {
  // 003 Eq. (50) = static (Eq. 46) + fatigue (Eq. 29)
  return bilinear_static_damage_increment(s_old, s_new, p.s0, p.sc) +
         third_law_fatigue_damage_increment(s_old, s_new, delta_n, p);
}

double third_law_update_damage(double damage, double s_old, double s_new, double delta_n,
                               const BilinearParams& p) {
  const double d = damage + third_law_damage_increment(s_old, s_new, delta_n, p);
  return std::clamp(d, damage, 1.0);
}

double bilinear_force_factor(double s, double damage, double sc) {
  if (s >= sc || damage >= 1.0) return 0.0;  // 003 Eq. (45), third line; D = 1 broken
  return 1.0 - std::max(damage, 0.0);        // 003 Eq. (13)/(45)
}

double bilinear_bond_force(double c, double s, double damage, double sc) {
  return c * bilinear_force_factor(s, damage, sc) * s;  // 003 Eq. (45)
}

double third_law_cycles_constant_stretch(double s, const BilinearParams& p) {
  const double rate = third_law_fatigue_rate(s, p.sc, p.A, p.m);  // 003 Eq. (27)
  return rate > 0.0 ? 1.0 / rate : kInf;
}

double third_law_bar_cycles_to_failure(double s_elastic, const BilinearParams& p) {
  if (!(s_elastic > 0.0)) return kInf;
  if (s_elastic >= p.s0) return 0.0;
  // 003 Eq. (27) with s = s_e/(1 − D) (Eq. 13), integrated from D = 0 to D = 1 − s_e/s0
  return (1.0 - std::pow(s_elastic / p.s0, p.m + 1.0)) /
         ((p.m + 1.0) * p.A * std::pow(s_elastic / p.sc, p.m));
}

double third_law_bar_cycles_numerical(double s_elastic, double delta_n, const BilinearParams& p) {
  if (!(s_elastic > 0.0)) return kInf;
  if (s_elastic >= p.s0) return 0.0;
  const double d_star = 1.0 - s_elastic / p.s0;  // where s reaches s0
  double damage = 0.0, s = s_elastic, cycles = 0.0;
  const double s_hist = s_elastic;  // below s0 until failure: no static damage (Eq. 46)
  while (cycles < 1e300) {
    double s_new = s, d_new = damage;
    for (int it = 0; it < 1000; ++it) {  // implicit mid-point rule, 003 Eq. (29)-(30)
      d_new = damage + bilinear_static_damage_increment(s_hist, s_new, p.s0, p.sc) +
              third_law_fatigue_damage_increment(s, s_new, delta_n, p);
      const double next = d_new < 1.0 ? s_elastic / (1.0 - d_new) : kInf;  // Eq. (13)
      const bool done = std::abs(next - s_new) <= 1e-15 * next || next >= p.s0;
      s_new = next;
      if (done) break;
    }
    if (d_new >= d_star || s_new >= p.s0) {
      // s reaches s0 inside this increment: D* = D + A δn ((s + s0)/(2 sc))^m (Eq. 29)
      return cycles + (d_star - damage) / third_law_fatigue_damage_increment(s, p.s0, 1.0, p);
    }
    damage = d_new;
    s = s_new;
    cycles += delta_n;
  }
  return kInf;
}

// ============================ law 4: kinetic theory of fracture =================================

Status validate(const KineticParams& p) {
  std::string msg;
  require(msg, positive(p.U), "U must be finite and > 0 (004 Eq. 14)");
  require(msg, positive(p.gamma), "gamma must be finite and > 0 (004 Eq. 14)");
  require(msg, positive(p.lambda), "lambda must be finite and > 0 (004 Eq. 12)");
  require(msg, std::isfinite(p.n0) && p.n0 > 1.0, "n0 must be finite and > 1 (004 Eq. 12)");
  require(msg, positive(p.temperature), "temperature must be finite and > 0 K (004 Eq. 14)");
  require(msg, positive(p.frequency), "frequency must be finite and > 0 Hz (004 Eq. 15)");
  return msg.empty() ? Status{} : Status{failure(msg)};
}

double kt_thermal_energy(double temperature) { return kBoltzmann * temperature; }

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

}  // namespace peritwin::fatigue
