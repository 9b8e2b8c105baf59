// B6 (issue 36): 003 Sec. 6.5's DCB with the three degradation laws; contracts in b6_dcb.h.
#include "validation/b6_dcb.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include "core/json_line.h"
#include "outputs/damage_png.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/mesh/discretization.h"
#include "solver/statics/static_solver.h"

namespace peritwin::validation {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double dcb_spacing(const DcbSpec& spec) {
  const double target = spec.horizon / spec.horizon_ratio;
  const double rows = 2.0 * std::max(1.0, std::round(spec.height / (2.0 * target)));
  return spec.height / rows;
}

double dcb_bending_modulus(const DcbSpec& spec) {
  if (spec.plane == model::PlaneCondition::plane_stress) return spec.youngs;
  const double nu = 0.25;  // bond-based plane strain (003 Sec. 6.1)
  return spec.youngs / (1.0 - nu * nu);
}

double dcb_energy_release_rate(const DcbSpec& spec, double moment) {
  const double h = 0.5 * spec.height;
  const double inertia = spec.thickness * h * h * h / 12.0;
  return moment * moment / (spec.thickness * dcb_bending_modulus(spec) * inertia);  // 003 Eq. (56)
}

double dcb_moment_for(const DcbSpec& spec, double g) {
  return std::sqrt(g / dcb_energy_release_rate(spec, 1.0));
}

statics::Specimen make_dcb(const DcbSpec& spec) {
  const double dx = dcb_spacing(spec);
  const double length = std::round(spec.length / dx) * dx;  // whole columns
  const double half = 0.5 * spec.height;
  statics::Specimen s;
  s.name = "DCB";
  s.material = {spec.youngs, spec.poisson, 0.0};
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back(mesh::Rectangle{0.0, -half, length, half});
  s.initial_crack_tip = {spec.crack, 0.0};
  s.geometry.notches.push_back({"pre-crack", {{-dx, 0.0}, s.initial_crack_tip}});
  // The arms and the clamped end never soften (see DcbSpec): only the band |y| < δ beyond
  // x = a − δ and short of the clamp.
  const double band = spec.horizon;
  s.geometry.no_fail_zones.push_back(mesh::Rectangle{-dx, band, length + dx, half + dx});
  s.geometry.no_fail_zones.push_back(mesh::Rectangle{-dx, -half - dx, length + dx, -band});
  s.geometry.no_fail_zones.push_back(
      mesh::Rectangle{-dx, -half - dx, spec.crack - spec.horizon, half + dx});
  s.geometry.no_fail_zones.push_back(
      mesh::Rectangle{length - 2.0 * spec.horizon, -half - dx, length + dx, half + dx});
  s.disc = discretize(s.geometry, dx, spec.horizon_ratio * dx);
  model::ModelOptions options;
  options.kind = model::ModelKind::bond_based;
  options.plane = spec.plane;
  s.model = model::build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  // Opposing moments on the arms' end columns; clamp at x = L.
  std::vector<mesh::NodeIndex> upper, lower, clamp;
  for (mesh::NodeIndex n = 0; n < s.disc.num_nodes(); ++n) {
    const mesh::Point p = s.disc.position[n];
    if (p.x < dx) (p.y > 0 ? upper : lower).push_back(n);
    if (p.x > length - dx) clamp.push_back(n);
  }
  for (const auto* arm : {&upper, &lower}) {
    const double sign = arm == &upper ? 1.0 : -1.0;
    double yc = 0.0;
    for (auto n : *arm) yc += s.disc.position[n].y;
    yc /= static_cast<double>(arm->size());
    double sum = 0.0;
    for (auto n : *arm) sum += std::pow(s.disc.position[n].y - yc, 2);
    // Upper arm: its outer fibre pushed (+x), its inner fibre pulled (−x) — the end moment that
    // lifts it; the lower arm mirrored. Σ F_i (y_i − y_c) = ±1 N·m per unit P.
    for (auto n : *arm) {
      s.loads.push_back({{n}, {sign * (s.disc.position[n].y - yc) / sum, 0.0}, {}, {}});
    }
  }
  s.supports.push_back({clamp, true, true});
  return s;
}

fatigue::BilinearParams dcb_bond(const DcbSpec& spec, fatigue::BilinearParams law) {
  const double g0 = spec.gc / spec.kr;  // 003 Eq. (44)
  law.s0 = spec.plane == model::PlaneCondition::plane_stress
               ? fatigue::bilinear_s0_plane_stress(g0, spec.youngs, spec.horizon)
               : fatigue::bilinear_s0_plane_strain(g0, spec.youngs, spec.horizon);
  law.sc = spec.kr * law.s0;  // 003 Eq. (44)
  return law;
}

double dcb_compliance_energy_release_rate(const DcbSpec& spec, double moment, int k) {
  const double dx = dcb_spacing(spec);
  double theta[2];
  for (int side = 0; side < 2; ++side) {
    DcbSpec sp = spec;
    sp.crack = spec.crack + (side == 0 ? -1.0 : 1.0) * k * dx;
    const statics::Specimen s = make_dcb(sp);
    statics::StaticSolver solver(s.disc, s.model, s.supports, s.loads);
    if (!solver.solve().ok()) return kNaN;
    std::vector<double> u;
    solver.displacement(moment, 0.0, u);
    double work = 0.0;  // Σ F·u = M θ
    for (const auto& l : s.loads) {
      for (auto n : l.nodes) {
        work += moment * l.constant.x * u[2 * static_cast<std::size_t>(n)] /
                static_cast<double>(l.nodes.size());
      }
    }
    theta[side] = work / moment;
  }
  const double dc_da = (theta[1] - theta[0]) / moment / (2.0 * k * dx);
  return moment * moment / (2.0 * spec.thickness) * dc_da;
}

double fitted_slope(const std::vector<double>& x, const std::vector<double>& y, double lo,
                    double hi) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (y[i] < lo || y[i] > hi) continue;
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
    ++n;
  }
  if (n < 3) return kNaN;
  const double den = n * sxx - sx * sx;
  return den > 0 ? (n * sxy - sx * sy) / den : kNaN;
}

DcbResult run_dcb(const DcbRun& run) {
  const auto t0 = std::chrono::steady_clock::now();
  DcbResult r;
  const statics::Specimen s = make_dcb(run.spec);
  r.dx = s.disc.dx;
  r.horizon = s.disc.horizon;
  fatigue::FatigueSettings settings;
  settings.law = fatigue::FatigueLaw::bilinear;
  settings.bilinear = dcb_bond(run.spec, run.law);
  settings.cycle_increment = run.delta_n;
  fatigue::FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings);
  if (!engine.initialize()) {
    r.failed = true;
    r.failure = engine.failure_reason();
    return r;
  }
  // Where each bond crosses y = 0 (NaN: it does not).
  const auto& d = s.disc;
  std::vector<double> cross(static_cast<std::size_t>(d.num_bonds()), kNaN);
  for (mesh::BondIndex b = 0; b < d.num_bonds(); ++b) {
    const mesh::Point a = d.position[d.bond_i[b]], c = d.position[d.bond_j[b]];
    if (a.y * c.y < 0) cross[b] = a.x + (c.x - a.x) * (0.0 - a.y) / (c.y - a.y);
  }
  // The crack length: a0 plus the broken crossing bonds beyond a0 over the crossing bonds per
  // unit length of the intact plane (an effective length, smoother than the farthest break).
  const double a0 = run.spec.crack;
  const double x_end = d.box.x_max - 3.0 * run.spec.horizon;
  const double x_from = a0 + run.spec.horizon;
  double per_length = 0.0;
  for (double x : cross) per_length += std::isfinite(x) && x >= x_from && x < x_end ? 1.0 : 0.0;
  per_length /= x_end - x_from;
  double tip = a0;
  std::int64_t broken_crossing = 0;
  std::size_t seen = 0;
  const core::LoadBlock block{run.moment, 0.0, 0.0, run.delta_n};
  r.cycles.push_back(0.0);
  r.crack.push_back(tip);
  while (static_cast<double>(engine.total_cycles()) < run.max_cycles) {
    const auto status = engine.apply(block);
    const auto& ev = engine.break_events();
    for (; seen < ev.size(); ++seen) {
      const double x = cross[static_cast<std::size_t>(ev[seen].bond)];
      if (std::isfinite(x) && x > a0) ++broken_crossing;
    }
    tip = a0 + static_cast<double>(broken_crossing) / per_length;
    r.cycles.push_back(static_cast<double>(engine.total_cycles()));
    r.crack.push_back(tip);
    if (run.progress && r.cycles.size() % 20 == 0) {
      std::fprintf(stderr, "  N %.0f crack %.4f mm broken %lld solves %d (%.1f s)\n",
                   r.cycles.back(), 1e3 * tip, static_cast<long long>(engine.broken_bonds()),
                   engine.solves(),
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    if (status == fatigue::EngineStatus::final_failure) {
      r.failed = true;
      r.failure = engine.failure_reason();
      break;
    }
    if (tip - a0 >= run.stop_growth) break;
  }
  r.broken = engine.broken_bonds();
  r.increments = engine.increments();
  r.unconverged = engine.unconverged_increments();
  r.slope = tip - a0 >= run.fit_to
                ? fitted_slope(r.cycles, r.crack, a0 + run.fit_from, a0 + run.fit_to)
                : kNaN;
  // The rate over the middle half of the window, as two slopes (its quarters 2 and 3).
  if (std::isfinite(r.slope)) {
    const double lo = a0 + run.fit_from, w = run.fit_to - run.fit_from;
    const double r1 = fitted_slope(r.cycles, r.crack, lo + 0.25 * w, lo + 0.5 * w);
    const double r2 = fitted_slope(r.cycles, r.crack, lo + 0.5 * w, lo + 0.75 * w);
    r.rate_variation = std::max(r1, r2) / std::min(r1, r2) - 1.0;
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace peritwin::validation

namespace peritwin::validation {

namespace {

void print_b6(const char* law, const DcbRun& run, const DcbResult& r, const char* study) {
  core::JsonLine line;
  line["case"] = "B6";
  line["study"] = study;
  line["law"] = law;
  line["m"] = core::significant(run.spec.horizon_ratio, 4);
  line["delta_n"] = core::whole(static_cast<double>(run.delta_n));
  line["horizon_m"] = core::significant(r.horizon, 6);
  line["dx_m"] = core::significant(r.dx, 6);
  line["slope_m_per_cycle"] = core::significant(r.slope, 6);
  line["rate_variation"] = core::significant(r.rate_variation, 4);
  line["cycles"] = core::whole(r.cycles.back());
  line["growth_m"] = core::significant(r.crack.back() - run.spec.crack, 6);
  line["broken_bonds"] = core::whole(static_cast<double>(r.broken));
  line["increments"] = core::whole(static_cast<double>(r.increments));
  line["unconverged"] = core::whole(static_cast<double>(r.unconverged));
  line["failed"] = r.failed;
  line["wall_s"] = core::fixed(r.wall_s, 1);
  core::print_line(line);
  std::fflush(stdout);
}

}  // namespace

double b6_critical_energy_release_rate(const DcbSpec& spec) {
  return dcb_energy_release_rate(spec, 0.048) / 0.25;
}

fatigue::BilinearParams b6_law(int law) {
  fatigue::BilinearParams p;
  p.law = law;
  if (law == 3) {  // 003 Eq. (27): m = 4 as 003 Sec. 6.7; A chosen (Table 2 lost)
    p.A = 0.27;
    p.m = 4.0;
  } else if (law == 1) {  // 003 Eq. (19): β + 1 = 4 to match law 3's exponent, λ = 1, μ = 0.7
    p.C = 0.38;
    p.beta = 3.0;
    p.lambda = 1.0;
  } else {  // 003 Eq. (23): n = 1
    p.B = 2.1e-3;
    p.n = 1.0;
  }
  return p;
}

int run_b6_single(int law, double horizon_ratio, std::int64_t delta_n, double horizon,
                  double coefficient, double max_cycles) {
  DcbRun run = b6_run(law, horizon_ratio, delta_n, horizon);
  run.max_cycles = max_cycles;
  run.progress = true;
  if (coefficient > 0) (law == 3 ? run.law.A : law == 1 ? run.law.C : run.law.B) = coefficient;
  const fatigue::BilinearParams bond = dcb_bond(run.spec, run.law);
  std::fprintf(stderr, "B6: G(M_a) %.4g J/m2, Gc %.4g, s0 %.4g, sc %.4g\n",
               dcb_energy_release_rate(run.spec, run.moment), run.spec.gc, bond.s0, bond.sc);
  const DcbResult r = run_dcb(run);
  const char* names[] = {"", "first", "second", "third"};
  print_b6(names[law], run, r, "single");
  return r.failed ? 1 : 0;
}

DcbRun b6_run(int law, double horizon_ratio, std::int64_t delta_n, double horizon) {
  DcbRun run;
  run.spec.horizon = horizon;
  run.spec.horizon_ratio = horizon_ratio;
  run.spec.gc = b6_critical_energy_release_rate(run.spec);
  run.law = b6_law(law);
  run.delta_n = delta_n;
  return run;
}

}  // namespace peritwin::validation

namespace peritwin::validation {

int run_b6(const std::string& out_dir, bool quick, int only_law) {
  const char* names[] = {"", "first", "second", "third"};
  // 003 Sec. 6.5: ΔN ∈ {1000, 10000, 50000}, the second law {500, 1000, 10000} (Table 3).
  const std::vector<std::int64_t> dns[] = {
      {}, {1000, 10000, 50000}, {500, 1000, 10000}, {1000, 10000, 50000}};
  const std::vector<double> ms = quick ? std::vector<double>{2.0} : std::vector<double>{2, 3, 4};
  for (const int law : {3, 2, 1}) {
    if (only_law > 0 && law != only_law) continue;
    outputs::LinePlot cracks;
    cracks.title = std::string("B6: crack length against cycles, ") + names[law] + " law, m = 3";
    cracks.x_title = "cycles (millions)";
    cracks.y_title = "crack length (mm)";
    outputs::LinePlot slopes;
    slopes.title = std::string("B6: slope dX/dN of the ") + names[law] + " law against dN";
    slopes.x_title = "log10(dN)";
    slopes.y_title = "dX/dN (nm/cycle)";
    const outputs::Rgb m_colors[] = {{31, 90, 180}, {200, 40, 40}, {30, 150, 60}};
    int k = 0;
    for (const double m : ms) {
      outputs::PlotSeries series{
          "m = " + std::to_string(static_cast<int>(m)), {}, {}, m_colors[k++ % 3], false};
      for (const std::int64_t dn : dns[law]) {
        if (quick && dn == dns[law].front()) continue;
        DcbRun run = b6_run(law, m, dn);
        const DcbResult r = run_dcb(run);
        print_b6(names[law], run, r, "delta_n");
        series.x.push_back(std::log10(static_cast<double>(dn)));
        series.y.push_back(1e9 * r.slope);
        if (m == 3.0) {
          const outputs::Rgb dn_colors[] = {{31, 90, 180}, {200, 40, 40}, {30, 150, 60}};
          const auto which = static_cast<std::size_t>(&dn - dns[law].data());
          outputs::PlotSeries c{"dN " + std::to_string(dn), {}, {}, dn_colors[which % 3], false};
          for (std::size_t i = 0; i < r.cycles.size(); ++i) {
            c.x.push_back(1e-6 * r.cycles[i]);
            c.y.push_back(1e3 * r.crack[i]);
          }
          cracks.series.push_back(std::move(c));
        }
      }
      slopes.series.push_back(std::move(series));
    }
    if (!quick) {
      const std::filesystem::path dir(out_dir);
      outputs::write_line_plot_png(dir / ("b6_slopes_" + std::string(names[law]) + ".png"), slopes);
      outputs::write_line_plot_png(dir / ("b6_cracks_" + std::string(names[law]) + ".png"), cracks);
    }
  }
  if (quick) return 0;
  // δ-convergence at m = 3 (003 Fig. 20): 003's spacings were 1.25e-4, 1.06e-4, 6.27e-5 m; the
  // last (11,800 nodes) is replaced by 8.3e-5 m (δ = 0.25 mm) to keep the case's wall time.
  for (const int law : {3, 1, 2}) {
    if (only_law > 0 && law != only_law) continue;
    for (const double horizon : {3.75e-4, 3.18e-4, 2.5e-4}) {
      const DcbRun run = b6_run(law, 3.0, law == 2 ? 1000 : 10000, horizon);
      print_b6(names[law], run, run_dcb(run), "horizon");
    }
  }
  return 0;
}

}  // namespace peritwin::validation

namespace peritwin::validation {

int plot_b6_slopes(const std::string& jsonl, const std::string& png) {
  std::ifstream in(jsonl);
  if (!in) return 1;
  // (law, m) -> (log10 ΔN, slope) in file order
  std::map<std::pair<std::string, double>, outputs::PlotSeries> by;
  std::string text;
  while (std::getline(in, text)) {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || j.value("case", "") != "B6" || !j.contains("law")) continue;
    if (!j["slope_m_per_cycle"].is_number()) continue;
    if (j.value("study", "") == "horizon") continue;
    const std::string law = j["law"];
    const double m = j["m"];
    auto& series = by[{law, m}];
    series.x.push_back(std::log10(j["delta_n"].get<double>()));
    series.y.push_back(1e9 * j["slope_m_per_cycle"].get<double>());
  }
  outputs::LinePlot plot;
  plot.title = "B6: slope of crack length against cycles, the three laws of 003";
  plot.x_title = "log10(dN)";
  plot.y_title = "dX/dN (nm/cycle)";
  const std::map<std::string, outputs::Rgb> colors{
      {"first", {140, 60, 170}}, {"second", {200, 40, 40}}, {"third", {30, 150, 60}}};
  for (auto& [key, series] : by) {
    // sorted by ΔN
    std::vector<std::size_t> order(series.x.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return series.x[a] < series.x[b]; });
    outputs::PlotSeries out;
    out.label = key.first + " law, m = " + std::to_string(static_cast<int>(key.second));
    for (auto i : order) {
      out.x.push_back(series.x[i]);
      out.y.push_back(series.y[i]);
    }
    out.color = colors.at(key.first);
    if (key.second != 3.0) {  // m = 2 dashed, m = 4 lighter
      out.dashed = key.second == 2.0;
      if (key.second == 4.0) {
        out.color = {static_cast<std::uint8_t>(out.color.r / 2),
                     static_cast<std::uint8_t>(out.color.g / 2),
                     static_cast<std::uint8_t>(out.color.b / 2)};
      }
    }
    plot.series.push_back(std::move(out));
  }
  outputs::write_line_plot_png(png, plot);
  return 0;
}

}  // namespace peritwin::validation
