// B7 (issue 36): 003 Sec. 6.6's DCB, the Paris plot of the third law; contracts in b7_dcb_paris.h.
#include "validation/b7_dcb_paris.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <vector>

#include "core/json_line.h"
#include "outputs/damage_png.h"

namespace peritwin::validation {

DcbSpec b7_spec(double horizon_ratio, int rows_per_arm, double ligament) {
  DcbSpec s;
  s.height = 2 * 0.0031;
  s.crack = 0.035;
  s.length = s.crack + ligament;
  s.thickness = 0.020;
  s.youngs = 120e9;
  s.poisson = 0.25;
  s.plane = model::PlaneCondition::plane_strain;
  s.gc = 260.0;
  s.kr = 4.38;
  s.horizon_ratio = horizon_ratio;
  s.horizon = horizon_ratio * 0.0031 / rows_per_arm;
  return s;
}

fatigue::BilinearParams b7_law() {
  fatigue::BilinearParams p;
  p.law = 3;
  p.A = 0.01;
  p.m = 4.0;
  return p;
}

int run_b7(const std::string& out_dir, bool quick, double only_ratio) {
  const DcbSpec spec = b7_spec(quick ? 2.0 : 3.0, quick ? 6 : 8, quick ? 0.02 : 0.040);
  // G from the model's compliance against Eq. (56), before any bond breaks.
  {
    const double m = dcb_moment_for(spec, 0.3 * spec.gc);
    core::JsonLine line;
    line["case"] = "B7";
    line["check"] = "compliance_g_vs_eq56";
    line["value"] = core::significant(dcb_compliance_energy_release_rate(spec, m), 6);
    line["expected"] = core::significant(dcb_energy_release_rate(spec, m), 6);
    core::print_line(line);
  }
  const std::vector<double> ratios = only_ratio > 0 ? std::vector<double>{only_ratio}
                                     : quick        ? std::vector<double>{0.2, 0.4}
                                             : std::vector<double>{0.1, 0.15, 0.2, 0.3, 0.45};
  std::vector<double> lx, ly;
  for (const double ratio : ratios) {
    DcbRun run;
    run.spec = spec;
    run.law = b7_law();
    run.moment = dcb_moment_for(spec, ratio * spec.gc);
    // ΔN ∝ 1/rate (the predicted G² scaling) keeps every run near 400 increments; B6 shows the
    // third law's slope insensitive to ΔN over 1000-50000.
    run.delta_n = static_cast<std::int64_t>(std::round(5000.0 * std::pow(0.2 / ratio, 2.0)));
    run.stop_growth = quick ? 0.002 : 0.004;
    run.fit_from = quick ? 0.0005 : 0.001;
    run.fit_to = run.stop_growth;
    run.max_cycles = 1e9;
    run.progress = only_ratio > 0;
    const DcbResult r = run_dcb(run);
    core::JsonLine line;
    line["case"] = "B7";
    line["moment_nm"] = core::significant(run.moment, 6);
    line["g_over_gc"] = core::significant(ratio, 4);
    line["rate_m_per_cycle"] = core::significant(r.slope, 6);
    line["rate_variation"] = core::significant(r.rate_variation, 4);
    line["delta_n"] = core::whole(static_cast<double>(run.delta_n));
    line["dx_m"] = core::significant(r.dx, 6);
    line["increments"] = core::whole(static_cast<double>(r.increments));
    line["failed"] = r.failed;
    if (r.failed) line["failure"] = r.failure;
    line["growth_m"] = core::significant(r.crack.back() - spec.crack, 5);
    line["wall_s"] = core::fixed(r.wall_s, 1);
    core::print_line(line);
    std::fflush(stdout);
    if (std::isfinite(r.slope) && r.slope > 0) {
      lx.push_back(std::log10(ratio));
      ly.push_back(std::log10(r.slope));
    }
  }
  // The Paris line through the points: log10(dX/dN) = log10(C) + n log10(G/G_c).
  const double n = fitted_slope(lx, ly, -1e9, 1e9);
  double mean_x = 0, mean_y = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    mean_x += lx[i] / static_cast<double>(lx.size());
    mean_y += ly[i] / static_cast<double>(lx.size());
  }
  core::JsonLine line;
  line["case"] = "B7";
  line["paris_exponent"] = core::significant(n, 5);
  line["paris_exponent_predicted"] = core::significant(b7_law().m / 2.0, 5);
  // The local exponents between neighbouring moments: → m/2 at low G, above it where the static
  // part of Eq. (50) joins the fatigue zone (G > G_0 = G_c/k_r near the tip).
  std::vector<double> local;
  for (std::size_t i = 1; i < lx.size(); ++i) {
    local.push_back(core::significant((ly[i] - ly[i - 1]) / (lx[i] - lx[i - 1]), 4));
  }
  line["local_exponents"] = local;
  line["paris_coefficient_m_per_cycle"] = core::significant(std::pow(10.0, mean_y - n * mean_x), 5);
  core::print_line(line);
  if (!quick && lx.size() >= 2) {
    outputs::LinePlot plot;
    plot.title = "B7: Paris plot of the third law (003 Sec. 6.6 DCB, pure moments)";
    plot.x_title = "log10(G/Gc)";
    plot.y_title = "log10(dX/dN) (m/cycle)";
    plot.series.push_back({"PD, third law (m = 4)", lx, ly, {31, 90, 180}, false});
    std::vector<double> fx{lx.front(), lx.back()}, fy;
    for (double x : fx) fy.push_back(mean_y + n * (x - mean_x));
    plot.series.push_back({"least-squares line", fx, fy, {200, 40, 40}, true});
    // The prediction holds where the fatigue zone carries no static damage (low G): the line of
    // slope m/2 through the lowest-G point.
    std::vector<double> py;
    for (double x : fx) py.push_back(ly.front() + b7_law().m / 2.0 * (x - lx.front()));
    plot.series.push_back(
        {"slope m/2 = 2 through the lowest G (predicted)", fx, py, {30, 150, 60}, true});
    outputs::write_line_plot_png(std::filesystem::path(out_dir) / "b7_paris.png", plot);
  }
  return 0;
}

}  // namespace peritwin::validation
