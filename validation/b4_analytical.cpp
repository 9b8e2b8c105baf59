// B4 (docs/benchmarks.md): single-bond and analytical checks, one JSON line each.
#include "validation/b4_analytical.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>

#include "core/json_line.h"
#include "loads/rainflow.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/bilinear.h"
#include "solver/fatigue/laws/energy.h"
#include "solver/fatigue/laws/kinetic.h"
#include "solver/fatigue/laws/remaining_life.h"
#include "solver/fatigue/laws/strain_range.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"

namespace peritwin::validation {

namespace {
void print(const char* check, double value, double expected) {
  core::JsonLine line;
  line["case"] = "B4";
  line["check"] = check;
  line["value"] = core::significant(value, 10);
  line["expected"] = core::significant(expected, 10);
  line["rel_error"] = core::significant(expected != 0 ? value / expected - 1 : value, 4);
  core::print_line(line);
}

/// 000 Eq. (9)-(12): N_c counted on the grid against the paper's 36 for δ = 3.015Δx, and the two
/// phase III criteria against each other: bonds crossing a cut, all at the critical stretch of
/// 000 Eq. (8), have a mean ḡ (Eq. 31/33) that should be g_c = G_c/N_c (lattice error ~6 %).
void critical_bond_energy_checks() {
  print("gc_crack_interactions_eq12", fatigue::crack_crossing_interactions(3.015), 36.0);
  const double dx = 0.001;
  mesh::DetailGeometry geometry;
  geometry.thickness = 0.002;
  geometry.outline = {mesh::Rectangle{0.0, 0.0, 40 * dx, 40 * dx}};
  const mesh::Discretization d = discretize(geometry, dx, 3.015 * dx);
  model::ModelOptions options;
  options.kind = model::ModelKind::bond_based;
  const model::Material al{68.9e9, 1.0 / 3.0, 29e6};
  const model::PdModel model = model::build_model(d, al, options, 200.0);
  const double sc = fatigue::critical_stretch(al, d.horizon);
  const std::vector<double> s(static_cast<std::size_t>(d.num_bonds()), sc);
  std::vector<double> theta, g;
  model::dilatations(d, model, std::vector<std::uint8_t>(s.size(), 1), s, theta);
  model::bond_energy_release_rates(d, model, s, theta, g);
  const double y_cut = 20 * dx, x0 = 15 * dx;
  double sum = 0.0;
  int n = 0;
  for (mesh::BondIndex b = 0; b < d.num_bonds(); ++b) {
    const mesh::Point a = d.position[d.bond_i[b]];
    const mesh::Point c = d.position[d.bond_j[b]];
    if ((a.y - y_cut) * (c.y - y_cut) >= 0) continue;
    const double x = a.x + (c.x - a.x) * (y_cut - a.y) / (c.y - a.y);
    if (x < x0 || x >= x0 + 10 * dx) continue;
    sum += g[static_cast<std::size_t>(b)];
    ++n;
  }
  print("gc_mean_crossing_energy_at_sc_eq8_vs_eq12", sum / n,
        fatigue::critical_bond_energy(al, 36.0));
}

/// 003 third degradation law with the bilinear bond: (a) constant stretch s < s0, Eq. (27)
/// integrated: D = 1 after N = 1/(A (s/sc)^m); Eq. (50) cycle by cycle must reach D >= 1 at
/// ceil(N). (b) One bond under constant force (003's single spring, load control): the closed form
/// N_f = (1 − (s_e/s0)^(m+1))/((m+1) A (s_e/sc)^m) against Eq. (29)-(30) in 10^4 increments.
void bilinear_checks() {
  using namespace fatigue;
  const fatigue::BilinearParams p{2e-3, 8e-3, 3.7e-3, 4.0};
  const double s = 1.5e-3;
  double damage = 0.0;
  std::int64_t cycles = 0;
  while (damage < 1.0 && cycles < 100000000) {
    damage = fatigue::third_law_update_damage(damage, s, s, 1.0, p);
    ++cycles;
  }
  print("bilinear_constant_stretch_life_eq27", static_cast<double>(cycles),
        std::ceil(fatigue::third_law_cycles_constant_stretch(s, p)));
  const double s_e = 1.2e-3;
  const double exact = fatigue::third_law_bar_cycles_to_failure(s_e, p);
  print("bilinear_load_controlled_bond_life_eq29_30",
        fatigue::third_law_bar_cycles_numerical(s_e, exact / 1e4, p), exact);
}

}  // namespace

int run_b4() {
  using namespace fatigue;
  const fatigue::StrainLawParams al = fatigue::al6061_t6_strain_params();
  // 000 Eq. (21): a bond at constant strain range fails after N = 1/(A1 ε^m1) cycles; the
  // per-cycle remaining-life iteration must reach λ ≤ 0 at ceil(N).
  const double eps = 1e-3;
  const double n21 = 1.0 / (al.A1 * std::pow(eps, al.m1));
  print("strain_life_eq21",
        static_cast<double>(fatigue::cycles_to_failure(
            1.0, fatigue::strain_decrement_phase1(eps, al.A1, al.m1, 0.0))),
        std::ceil(n21));
  // 000 Eq. (22) with the fatigue limit of SAE 1020 (002 Table 2).
  const fatigue::StrainLawParams steel = fatigue::sae1020_strain_params();
  const double eps2 = 5e-3;
  const double n22 = 1.0 / (steel.A1 * std::pow(eps2 - steel.eps_inf, steel.m1));
  print("strain_life_eq22",
        static_cast<double>(fatigue::cycles_to_failure(
            1.0, fatigue::strain_decrement_phase1(eps2, steel.A1, steel.m1, steel.eps_inf))),
        std::ceil(n22));
  // Energy-based model (000 Eq. 30-46): with B_i, n_i from Eq. (44)-(46) the decrement per cycle
  // equals the strain law's, for a bond-based bond with C0 from Eq. (33), R = 0.1.
  const double c0 = 1e9, r = 0.1, s_max = eps / (1 - r);
  const double g = fatigue::energy_release_rate_range_from_ratio(c0, s_max, r);
  const double energy =
      fatigue::energy_decrement(g, fatigue::Phase::kGrowth, fatigue::c1_coefficient(c0, r), al);
  print("energy_equals_strain_decrement", energy,
        fatigue::strain_decrement(eps, fatigue::Phase::kGrowth, al));
  // KTF: damage after N cycles by the closed form 004 Eq. (15) against an RK4 integration of
  // Eq. (12), dn/dN = Φ·(n0 − n)^λ, over 20 cycles (λ = 9, n0 = 1.771, Φ = 1e-4 per cycle).
  const double lambda = 9.0, n0 = fatigue::kt_n0_for_unit_life(lambda), dose = 1e-4;
  auto dndn = [&](double x) { return dose * std::pow(n0 - x, lambda); };
  double n = 0.0;
  const int steps = 20000;
  const double h = 20.0 / steps;
  for (int i = 0; i < steps; ++i) {
    const double k1 = dndn(n), k2 = dndn(n + 0.5 * h * k1), k3 = dndn(n + 0.5 * h * k2),
                 k4 = dndn(n + h * k3);
    n += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  print("ktf_eq15_vs_rk4_eq12", fatigue::kt_damage_after_cycles(0.0, 20.0, dose, lambda, n0), n);
  // Rainflow on the ASTM E1049-85 example: total counted cycles 4.0 and Σ count·range = 25.
  const double history[] = {-2, 1, -3, 5, -1, 3, -4, 4, -2};
  const auto cycles = loads::count_cycles(history);
  double total = 0, weighted = 0;
  for (const auto& c : cycles) {
    total += c.count;
    weighted += c.count * std::abs(c.to - c.from);
  }
  print("rainflow_astm_cycles", total, 4.0);
  print("rainflow_astm_range_sum", weighted, 3 * 0.5 + 4 * 1.5 + 6 * 0.5 + 8 * 1.0 + 9 * 0.5);
  critical_bond_energy_checks();
  bilinear_checks();
  return 0;
}

}  // namespace peritwin::validation
