// Law 3: bilinear bond with damage (003); contracts in bilinear.h.
#include "solver/fatigue/laws/bilinear.h"

#include <algorithm>
#include <cmath>
#include <numbers>
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

// ============================ law 3: bilinear bond with damage ==================================

core::Status validate(const BilinearParams& p) {
  std::string msg;
  require(msg, positive(p.s0), "s0 must be finite and > 0 (003 Eq. 43)");
  require(msg, std::isfinite(p.sc) && p.sc > p.s0, "sc must be finite and > s0 (003 Eq. 44)");
  require(msg, p.law >= 1 && p.law <= 3, "law must be 1, 2 or 3 (003 Sec. 4.2-4.4)");
  if (p.law == 3) {
    require(msg, positive(p.A), "A must be finite and > 0 (003 Eq. 27)");
    require(msg, positive(p.m), "m must be finite and > 0 (003 Eq. 27)");
  } else if (p.law == 1) {
    require(msg, positive(p.C), "C must be finite and > 0 (003 Eq. 19)");
    require(msg, std::isfinite(p.beta) && p.beta > -1.0,
            "beta must be finite and > -1 (003 Eq. 20)");
    require(msg, non_negative(p.lambda), "lambda must be finite and >= 0 (003 Eq. 19)");
    require(msg, p.mu >= 0.0 && p.mu <= 1.0, "mu must be in [0, 1] (003 Eq. 21)");
  } else if (p.law == 2) {
    require(msg, positive(p.B), "B must be finite and > 0 (003 Eq. 23)");
    require(msg, positive(p.n), "n must be finite and > 0 (003 Eq. 23)");
  }
  return msg.empty() ? core::Status{} : core::Status{core::failure(msg)};
}

double bilinear_s0_plane_stress(double g0, double youngs_modulus, double horizon) {
  return std::sqrt(4.0 * std::numbers::pi * g0 / (9.0 * youngs_modulus * horizon));  // 003 Eq. (43)
}

double bilinear_s0_plane_strain(double g0, double youngs_modulus, double horizon) {
  return std::sqrt(5.0 * std::numbers::pi * g0 /
                   (12.0 * youngs_modulus * horizon));  // 003 Eq. (43)
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

double first_law_fatigue_damage_increment(double d_mu, double s_mu, double delta_n,
                                          const BilinearParams& p) {
  // 003 Eq. (20)/(47)
  return delta_n * p.C / (1.0 + p.beta) * std::exp(p.lambda * d_mu) *
         pow_pos(s_mu / p.sc, 1.0 + p.beta);
}

double first_law_update_damage(double damage, double s_env, double s_start, double s_new,
                               double delta_n, const BilinearParams& p) {
  // 003 Eq. (22)/(47): D' = D + a + b·e^{λμD'} with a the static part (Eq. 46) and
  // b = ΔN C/(1+β) e^{λ(1−μ)D} (s_μ/sc)^{1+β} (Eq. 20, 21, 48).
  const double a = bilinear_static_damage_increment(s_env, s_new, p.s0, p.sc);
  const double s_mu = (1.0 - p.mu) * s_start + p.mu * s_new;
  const double b = first_law_fatigue_damage_increment((1.0 - p.mu) * damage, s_mu, delta_n, p);
  const double k = p.lambda * p.mu;
  if (k == 0.0) return std::clamp(damage + a + b, damage, 1.0);
  double d = damage;
  for (int it = 0; it < 100; ++it) {
    const double e = b * std::exp(k * d);
    const double g = d - damage - a - e;  // concave in d
    const double slope = 1.0 - k * e;
    if (g >= 0.0) break;             // root reached (from the left)
    if (!(slope > 0.0)) return 1.0;  // past the maximum of g below 0: no root
    const double next = d - g / slope;
    if (next >= 1.0) return 1.0;  // the root lies beyond D = 1: fails
    if (!(next > d) || next - d <= 1e-15 * std::max(1.0, d)) {
      d = std::max(next, d);
      break;
    }
    d = next;
  }
  return std::clamp(d, damage, 1.0);
}

double second_law_failure_stretch(double sc_n, double s_new, double delta_n,
                                  const BilinearParams& p) {
  if (!(s_new > p.s0)) return sc_n;
  return sc_n - p.B * std::pow(s_new - p.s0, p.n) * delta_n;  // 003 Eq. (23)
}

double second_law_current_failure_stretch(double damage, double s_env, const BilinearParams& p) {
  if (!(damage > 0.0) || !(s_env > p.s0)) return p.sc;
  if (damage >= 1.0) return s_env;
  // 003 Eq. (24) solved for sc: D s (sc − s0) = sc (s − s0)
  return std::min(p.sc, damage * s_env * p.s0 / (p.s0 - (1.0 - damage) * s_env));
}

double second_law_update_damage(double damage, double s_env, double s_new, double delta_n,
                                const BilinearParams& p) {
  if (damage >= 1.0) return 1.0;
  const double sc_n = second_law_current_failure_stretch(damage, s_env, p);
  const double sc_new = second_law_failure_stretch(sc_n, s_new, delta_n, p);  // Eq. (23)
  const double s = std::max(s_env, s_new);
  if (!(sc_new > s)) return 1.0;
  return std::clamp(bilinear_static_damage(s, p.s0, sc_new), damage, 1.0);  // Eq. (24)/(49)
}

double bilinear_update_damage(double damage, double s_env, double s_start, double s_new,
                              double delta_n, const BilinearParams& p) {
  if (p.law == 1) return first_law_update_damage(damage, s_env, s_start, s_new, delta_n, p);
  if (p.law == 2) return second_law_update_damage(damage, s_env, s_new, delta_n, p);
  // 003 Eq. (50): static increment along the envelope (Eq. 46) + fatigue (Eq. 29)
  const double d = damage + bilinear_static_damage_increment(s_env, s_new, p.s0, p.sc) +
                   third_law_fatigue_damage_increment(s_start, s_new, delta_n, p);
  return std::clamp(d, damage, 1.0);
}

double first_law_cycles_constant_stretch(double s, double d0, const BilinearParams& p) {
  const double k = p.C / (1.0 + p.beta) * pow_pos(s / p.sc, 1.0 + p.beta);
  if (!(k > 0.0)) return kInf;
  if (p.lambda == 0.0) return (1.0 - d0) / k;
  return (std::exp(-p.lambda * d0) - std::exp(-p.lambda)) / (p.lambda * k);
}

double second_law_cycles_constant_stretch(double s, const BilinearParams& p) {
  if (!(s > p.s0)) return kInf;
  if (s >= p.sc) return 0.0;
  return (p.sc - s) / (p.B * std::pow(s - p.s0, p.n));  // 003 Eq. (23) reaching sc = s
}

double second_law_damage_constant_stretch(double s, double cycles, const BilinearParams& p) {
  if (!(s > p.s0)) return 0.0;
  const double sc_n = p.sc - p.B * std::pow(s - p.s0, p.n) * cycles;  // 003 Eq. (23)
  if (!(sc_n > s)) return 1.0;
  return bilinear_static_damage(s, p.s0, sc_n);  // 003 Eq. (24)
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

// 003 Eq. (27), (43)-(44): the bond's parameters; 003 Sec. 5.1: the increments.
void read_bilinear(core::ParamReader& r, FatigueSettings& f) {
  const auto set = [&r](double& field, std::string_view key) {
    if (const auto v = r.required(key, core::Bound::positive)) field = *v;
  };
  set(f.bilinear.s0, "s0");
  set(f.bilinear.sc, "sc");
  f.bilinear.law = static_cast<int>(r.integer("degradation_law", f.bilinear.law));
  r.check("degradation_law", f.bilinear.law >= 1 && f.bilinear.law <= 3, "must be 1, 2 or 3");
  if (f.bilinear.law == 1) {  // 003 Eq. (19)-(21)
    set(f.bilinear.C, "C");
    f.bilinear.beta = r.number("beta", f.bilinear.beta);
    r.check("beta", std::isfinite(f.bilinear.beta) && f.bilinear.beta > -1.0, "must be > -1");
    f.bilinear.lambda = r.optional("lambda", f.bilinear.lambda, core::Bound::non_negative);
    f.bilinear.mu = r.optional("mu", f.bilinear.mu, core::Bound::non_negative);
    r.check("mu", f.bilinear.mu <= 1.0, "must be <= 1");
  } else if (f.bilinear.law == 2) {  // 003 Eq. (23)
    set(f.bilinear.B, "B");
    f.bilinear.n = r.optional("n", f.bilinear.n, core::Bound::positive);
  } else {
    set(f.bilinear.A, "A");
    f.bilinear.m = r.optional("m", f.bilinear.m, core::Bound::positive);
  }
  if (f.bilinear.s0 > 0 && r.has("sc")) {
    r.check("sc", f.bilinear.sc > f.bilinear.s0, "must be > s0");
  }
  f.cycle_increment = r.integer("cycle_increment", f.cycle_increment);
  r.check("cycle_increment", f.cycle_increment >= 1, "must be >= 1");
  f.softening_tolerance =
      r.optional("softening_tolerance", f.softening_tolerance, core::Bound::positive);
  f.softening_max_iterations =
      static_cast<int>(r.integer("softening_max_iterations", f.softening_max_iterations));
  r.check("softening_max_iterations", f.softening_max_iterations >= 1, "must be >= 1");
}

}  // namespace peritwin::fatigue
