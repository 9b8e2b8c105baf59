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
  require(msg, positive(p.A), "A must be finite and > 0 (003 Eq. 27)");
  require(msg, positive(p.m), "m must be finite and > 0 (003 Eq. 27)");
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
  set(f.bilinear.A, "A");
  f.bilinear.m = r.optional("m", f.bilinear.m, core::Bound::positive);
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
