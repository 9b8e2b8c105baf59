// peritwin-validate --case B5; contracts in b5_run.h.
#include "validation/b5_run.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <vector>

#include "core/json_line.h"
#include "outputs/damage_png.h"
#include "solver/fatigue/laws/kinetic_calibration.h"
#include "validation/b5_low_cycle.h"

namespace peritwin::validation {

namespace {

constexpr double kElectronVolt = 1.602176634e-19;

/// 004 Sec. 5's lives (N25): symmetric 183,410 / 190,170, POL 147,060 / 185,280, PUL 3,185 /
/// 74,675 (conventional / modified).
double paper_n25(const std::string& loading, bool modified) {
  if (loading == "symmetric") return modified ? 190170 : 183410;
  if (loading == "pol") return modified ? 185280 : 147060;
  return modified ? 74675 : 3185;
}

/// The segments' fits as JSON lines.
void print_calibration(const std::string& model_name, const std::vector<B5SegmentFit>& fits,
                       double kt) {
  for (std::size_t s = 0; s < fits.size(); ++s) {
    const B5Segment& r = kB5Segments[s];
    core::JsonLine line;
    line["case"] = "B5-calibration";
    line["model"] = model_name;
    line["segment"] = s + 1;
    line["stress_from_mpa"] = core::whole(r.from / 1e6);
    line["stress_to_mpa"] = core::whole(r.to / 1e6);
    line["U_eV"] = core::significant(fits[s].fit.U / kElectronVolt, 6);
    line["gamma_m3"] = core::significant(fits[s].fit.gamma, 6);
    line["theta_over_kT"] = core::significant(fits[s].theta / kt, 6);
    line["loop_area_j_m3"] = core::significant(fits[s].loop_area, 6);
    line["max_abs_log_error"] = core::fixed(fits[s].fit.max_abs_log_error, 4);
    core::print_line(line);
  }
}

}  // namespace

int run_b5(const B5RunOptions& options, const std::filesystem::path& out_dir) {
  const model::PowerLawCurve curve;  // 004 Fig. 7c's 316L curve (its printed constants)
  std::vector<B5SegmentFit> fits[2];
  auto conventional = calibrate_b5_kinetics(curve, 0.0, options.k_u, &fits[0]);
  auto modified = calibrate_b5_kinetics(curve, options.psi, options.k_u, &fits[1]);
  if (!conventional.ok() || !modified.ok()) {
    std::fprintf(stderr, "%s\n",
                 (conventional.ok() ? modified : conventional).error().reason.c_str());
    return 3;
  }
  modified->own_loop_area = options.own_loops;
  const double kt = fatigue::kt_thermal_energy(conventional->base.temperature);
  print_calibration("conventional", fits[0], kt);
  print_calibration("modified", fits[1], kt);
  B5Specimen spec;
  spec.points_across = options.points_across;
  const statics::Specimen strip = make_b5_specimen(spec);
  B5Options run;
  run.kappa = calibrate_b5_kappa(strip, curve, 0.0018);
  run.loop_cycles = {10, 1000, 100000};
  {
    // The strip's own curve against the material's: κ matches it at 0.18 %; the off-axis bonds
    // yield later, so the strip hardens more (the big cycles of POL and PUL reach 0.6 %).
    core::JsonLine line;
    line["case"] = "B5-strip";
    line["kappa"] = core::significant(run.kappa, 6);
    for (const double strain : {0.0018, 0.004, 0.006}) {
      const std::string at = std::to_string(static_cast<int>(std::lround(strain * 1e4)));
      line["strip_stress_mpa_at_" + at] =
          core::fixed(virgin_stress(strip, curve, run.kappa, strain) / 1e6, 1);
      line["curve_stress_mpa_at_" + at] = core::fixed(curve.stress(strain) / 1e6, 1);
    }
    line["strain_unit"] = "1e-4";
    core::print_line(line);
  }
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);

  const double a230 = loop_area_at_stress(curve, 230e6);
  const double a270 = loop_area_at_stress(curve, 270e6);
  struct Loading {
    StrainLoading loading;
    double table_area;  ///< 004 Fig. 12b's measured area for the modified model
  };
  const std::vector<Loading> loadings = {
      {symmetric_loading(), model::masing_symmetric_loop_area(curve, 0.0018)},
      {pol_loading(), 0.78 * a230},
      {pul_loading(), 0.45 * a270}};
  int rc = 0;
  for (const Loading& l : loadings) {
    if (options.loadings != "all" && options.loadings != l.loading.name) continue;
    for (const bool is_modified : {false, true}) {
      const std::string model_name = is_modified ? "modified" : "conventional";
      if (options.models != "all" && options.models != model_name) continue;
      B5Kinetics k = is_modified ? *modified : *conventional;
      if (is_modified && !options.own_loops) k.extension.loop_area = l.table_area;
      outputs::LinePlot plot;
      plot.title = "B5 " + l.loading.name + ", " + model_name + ": specimen loops";
      plot.x_title = "nominal strain (%)";
      plot.y_title = "stress R/A (MPa)";
      const outputs::Rgb colours[3] = {{31, 90, 180}, {200, 120, 20}, {190, 30, 45}};
      run.loop = [&](std::int64_t at, const std::vector<double>& strain,
                     const std::vector<double>& stress) {
        outputs::PlotSeries s;
        s.label = "N = " + std::to_string(at);
        s.color = colours[plot.series.size() % 3];
        for (std::size_t i = 0; i < strain.size(); ++i) {
          s.x.push_back(100.0 * strain[i]);
          s.y.push_back(stress[i] / 1e6);
        }
        plot.series.push_back(std::move(s));
      };
      const B5Result r = run_b5_loading(strip, curve, l.loading, k, run);
      const double paper = paper_n25(l.loading.name, is_modified);
      core::JsonLine line;
      line["case"] = "B5";
      line["loading"] = l.loading.name;
      line["model"] = model_name;
      line["n25_cycles"] = r.n25_cycles;
      line["paper_n25"] = core::whole(paper);
      line["life_cycles"] = r.life_cycles;
      line["life_by"] = r.n25_cycles >= 0    ? "n25"
                        : r.life_cycles >= 0 ? "lost_equilibrium"
                                             : "none";
      line["to_paper"] =
          r.life_cycles > 0 ? core::fixed(static_cast<double>(r.life_cycles) / paper, 4) : -1.0;
      line["loop_area_j_m3"] =
          is_modified && !options.own_loops ? core::significant(l.table_area, 6) : -1.0;
      line["broken_bonds"] = r.broken_bonds;
      line["static_breaks"] = r.static_breaks;
      line["phase_two_breaks"] = r.phase_two_breaks;
      line["break_groups"] = r.break_groups;
      line["peak_stress_mpa"] = core::fixed(r.peak_stress / 1e6, 2);
      line["final_stress_mpa"] = core::fixed(r.final_stress / 1e6, 2);
      line["kappa"] = core::significant(r.kappa, 6);
      line["turning_points"] = r.turning_points;
      line["newton_iterations"] = r.newton_iterations;
      line["stalled_turning_points"] = r.stalled_turning_points;
      line["substepped_turning_points"] = r.substepped_turning_points;
      line["deepest_memory"] = r.deepest_memory;
      line["dropped_reversals"] = r.dropped_reversals;
      line["stopped"] = r.reason;
      line["wall_s"] = core::fixed(r.wall_s, 1);
      core::print_line(line);
      if (r.life_cycles < 0) rc = 3;
      if (!plot.series.empty()) {
        outputs::write_line_plot_png(out_dir / ("b5_" + l.loading.name + "_" + model_name + ".png"),
                                     plot);
      }
    }
  }
  return rc;
}

}  // namespace peritwin::validation
