// peritwin-validate --case D1 | D2 | D3 | D4: paper 001's dynamics (validation/dynamics_cases.h),
// one JSON line per result, a CSV per series and a PNG per case (docs/validation.md).
#include "validation/d_dynamics.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <numbers>

#include "core/json_line.h"
#include "outputs/damage_png.h"
#include "solver/dynamics/dispersion.h"
#include "validation/dynamics_cases.h"

namespace peritwin::validation {

namespace {

using dynamics::KernelChoice;

const dynamics::KernelChoice kConstant{dynamics::KernelChoice::Shape::constant, 0.0};
const dynamics::KernelChoice kGaussian{dynamics::KernelChoice::Shape::gaussian, 2.0};
constexpr outputs::Rgb kBlue{31, 90, 180};
constexpr outputs::Rgb kRed{200, 40, 40};
constexpr outputs::Rgb kBlack{0, 0, 0};
constexpr outputs::Rgb kGreen{30, 150, 60};

std::string kernel_key(const dynamics::KernelChoice& k) {
  return k.shape == dynamics::KernelChoice::Shape::constant ? "constant" : "gaussian";
}
std::string kernel_label(const dynamics::KernelChoice& k) {
  if (k.shape == dynamics::KernelChoice::Shape::constant) return "constant";
  char text[32];
  std::snprintf(text, sizeof text, "gaussian p=%g", k.p);
  return text;
}

void write_columns(const std::filesystem::path& path, const std::string& header,
                   const std::vector<const std::vector<double>*>& columns) {
  std::ofstream out(path);
  out << header << '\n';
  const std::size_t n = columns.front()->size();
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      char text[40];
      std::snprintf(text, sizeof text, "%.10g", (*columns[c])[i]);
      out << (c ? "," : "") << text;
    }
    out << '\n';
  }
}

std::vector<double> scaled(const std::vector<double>& v, double s) {
  std::vector<double> out(v);
  for (auto& x : out) x *= s;
  return out;
}

}  // namespace

int run_d1(const std::filesystem::path& out, int threads) {
  outputs::LinePlot plot;
  plot.title = "d1 bar: strain at x = 0.5 m";
  plot.x_title = "time [ms]";
  plot.y_title = "strain [1e-3]";
  bool exact_drawn = false;
  for (const bool calibrated : {false, true}) {
    for (const auto& kernel : {kConstant, kGaussian}) {
      BarSpec spec;
      spec.kernel = kernel;
      spec.threads = threads;
      spec.lattice_calibrated = calibrated;
      const BarResult r = run_bar(spec);
      const std::string micro = calibrated ? "lattice" : "paper";
      write_columns(out / ("d1_" + kernel_key(kernel) + "_" + micro + ".csv"),
                    "time_s,strain,exact", {&r.time, &r.strain, &r.exact});
      core::JsonLine line;
      line["case"] = "D1";
      line["kernel"] = kernel_key(kernel);
      if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) line["p"] = kernel.p;
      line["micromodulus"] = calibrated ? "lattice_calibrated" : "paper_eq26_33";
      if (calibrated) {
        line["c0_factor"] =
            core::significant(dynamics::lattice_calibration_factor(dynamics::Dimension::one, kernel,
                                                                   spec.dx, spec.m * spec.dx),
                              5);
      }
      line["dx_m"] = spec.dx;
      line["horizon_m"] = spec.m * spec.dx;
      line["dt_s"] = spec.time_step;
      line["stable_dt_s"] = core::significant(r.stable_time_step, 4);
      line["transits"] = spec.transits;
      line["rel_l2_error"] = core::significant(r.rel_l2_error, 4);
      line["max_abs_error_over_eps0"] = core::significant(r.max_abs_error_over_strain, 4);
      line["undershoot_first_jump_over_eps0"] = core::significant(r.undershoot_first_jump, 3);
      line["overshoot_second_jump_over_eps0"] = core::significant(r.overshoot_second_jump, 3);
      line["goal"] = kernel.shape == dynamics::KernelChoice::Shape::gaussian
                         ? "rel_l2_error <= 0.05"
                         : "measured";
      line["met"] =
          kernel.shape == dynamics::KernelChoice::Shape::gaussian ? r.rel_l2_error <= 0.05 : true;
      line["wall_s"] = core::fixed(r.wall_s, 1);
      core::print_line(line);
      if (!exact_drawn) {
        plot.series.push_back(
            {"exact eq. 56", scaled(r.time, 1e3), scaled(r.exact, 1e3), kBlack, true});
        exact_drawn = true;
      }
      if (!calibrated) {
        plot.series.push_back(
            {kernel_label(kernel), scaled(r.time, 1e3), scaled(r.strain, 1e3),
             kernel.shape == dynamics::KernelChoice::Shape::constant ? kRed : kBlue, false});
      } else if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) {
        plot.series.push_back(
            {"gaussian, lattice c0", scaled(r.time, 1e3), scaled(r.strain, 1e3), kGreen, false});
      }
    }
  }
  std::swap(plot.series[0], plot.series.back());  // the exact curve on top
  outputs::write_line_plot_png(out / "d1_bar_strain.png", plot);
  return 0;
}

int run_d2(const std::filesystem::path& out) {
  const double v = std::sqrt(200e9 / 7850.0);
  // The lattice against Eq. (48)-(50): the integrator's own coefficients at an interior node.
  outputs::LinePlot plot;
  plot.title = "d2 dispersion, delta = 4 mm, m = 3 (dx = 1.33 mm)";
  plot.x_title = "k [1/m]";
  plot.y_title = "omega/v [1/m]";
  for (const auto& kernel :
       {kConstant, dynamics::KernelChoice{dynamics::KernelChoice::Shape::gaussian, 1.0},
        kGaussian}) {
    for (const int m : {3, 5, 10}) {
      const double delta = 4e-3, dx = delta / m;
      const mesh::Discretization disc =
          dynamics::bar_discretization(0.0, 4 * m + 1, dx, delta, 1.0);
      dynamics::DynamicsSetup setup;
      setup.dimension = dynamics::Dimension::one;
      setup.kernel = kernel;
      setup.youngs_modulus = 200e9;
      setup.density = 7850;
      setup.time_step = 1e-12;
      auto dyn = dynamics::ExplicitDynamics::create(disc, setup);
      if (!dyn) return 3;
      double worst = 0.0, worst_uncorrected = 0.0;
      std::vector<double> ks, omega;
      for (int s = 1; s <= 400; ++s) {
        const double k = std::numbers::pi / dx * s / 400.0;
        const double lattice = std::sqrt(dyn.value()->lattice_omega_squared(2 * m, k));
        const double formula = dynamics::dispersion_omega(kernel, v, m, dx, k, true);
        const double printed = dynamics::dispersion_omega(kernel, v, m, dx, k, false);
        worst = std::max(worst, std::abs(lattice - formula) / formula);
        worst_uncorrected = std::max(worst_uncorrected, std::abs(lattice - printed) / printed);
        ks.push_back(k);
        omega.push_back(lattice / v);
      }
      core::JsonLine line;
      line["case"] = "D2";
      line["check"] = "lattice_vs_formula";
      line["kernel"] = kernel_key(kernel);
      if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) line["p"] = kernel.p;
      line["m"] = m;
      line["horizon_m"] = delta;
      line["max_rel_error"] = core::significant(worst, 3);
      line["max_rel_error_without_partial_volumes"] = core::significant(worst_uncorrected, 3);
      line["goal"] = "max_rel_error <= 1e-6";
      line["met"] = worst <= 1e-6;
      core::print_line(line);
      if (m == 3) {
        const outputs::Rgb colour = kernel.shape == dynamics::KernelChoice::Shape::constant ? kRed
                                    : kernel.p == 1.0                                       ? kGreen
                                                                                            : kBlue;
        plot.series.push_back({kernel_label(kernel), ks, omega, colour, false});
      }
    }
  }
  {
    std::vector<double> ks, local;
    for (int s = 0; s <= 400; ++s) {
      ks.push_back(std::numbers::pi / (4e-3 / 3) * s / 400.0);
      local.push_back(ks.back());
    }
    plot.series.push_back({"local omega = vk", ks, local, kBlack, true});
  }
  outputs::write_line_plot_png(out / "d2_dispersion.png", plot);
  // 001 Figs. 5 and 9: the effect of Δx at m = 3 (Gaussian p = 2), and of m at δ = 4 mm
  // (constant kernel), the formula with the partial volumes (equal to the lattice, above).
  {
    outputs::LinePlot by_dx;
    by_dx.title = "d2 gaussian p=2, m = 3: dx = 0.5, 1, 2 mm";
    by_dx.x_title = "k [1/m]";
    by_dx.y_title = "omega/v [1/m]";
    const outputs::Rgb colours[] = {kBlue, kGreen, kRed};
    int c = 0;
    for (const double dx : {0.5e-3, 1e-3, 2e-3}) {
      std::vector<double> ks, w;
      for (int s = 1; s <= 400; ++s) {
        ks.push_back(3000.0 * s / 400.0);
        w.push_back(dynamics::dispersion_omega(kGaussian, v, 3, dx, ks.back(), true) / v);
      }
      char label[32];
      std::snprintf(label, sizeof label, "dx = %g mm", dx * 1e3);
      by_dx.series.push_back({label, ks, w, colours[c++], false});
    }
    std::vector<double> ks, local;
    for (int s = 0; s <= 400; ++s) {
      ks.push_back(3000.0 * s / 400.0);
      local.push_back(ks.back());
    }
    by_dx.series.push_back({"local", ks, local, kBlack, true});
    outputs::write_line_plot_png(out / "d2_dispersion_dx.png", by_dx);
    outputs::LinePlot by_m;
    by_m.title = "d2 constant kernel, delta = 4 mm: m = 2, 3, 5, 10";
    by_m.x_title = "k [1/m]";
    by_m.y_title = "omega/v [1/m]";
    const outputs::Rgb more[] = {kRed, kGreen, kBlue, outputs::Rgb{150, 90, 0}};
    c = 0;
    for (const int m : {2, 3, 5, 10}) {
      std::vector<double> kk, w;
      for (int s = 1; s <= 400; ++s) {
        kk.push_back(3000.0 * s / 400.0);
        w.push_back(dynamics::dispersion_omega(kConstant, v, m, 4e-3 / m, kk.back(), true) / v);
      }
      by_m.series.push_back({"m = " + std::to_string(m), kk, w, more[c++], false});
    }
    by_m.series.push_back({"local", ks, local, kBlack, true});
    outputs::write_line_plot_png(out / "d2_dispersion_m.png", by_m);
  }
  // The packet: measured speed against the group speed dω/dk of the same lattice.
  for (const auto& kernel : {kConstant, kGaussian}) {
    PacketSpec spec;
    spec.kernel = kernel;
    const PacketResult r = run_packet(spec);
    core::JsonLine line;
    line["case"] = "D2";
    line["check"] = "packet_speed";
    line["kernel"] = kernel_key(kernel);
    if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) line["p"] = kernel.p;
    line["dx_m"] = spec.dx;
    line["horizon_m"] = spec.m * spec.dx;
    line["k_per_m"] = spec.wave_number;
    line["measured_speed"] = core::significant(r.measured_speed, 6);
    line["group_speed"] = core::significant(r.group_speed, 6);
    line["phase_speed"] = core::significant(r.phase_speed, 6);
    line["classical_speed"] = core::significant(r.classical_speed, 6);
    const double err = r.measured_speed / r.group_speed - 1.0;
    line["rel_error_vs_group"] = core::significant(err, 3);
    line["goal"] = "|rel_error_vs_group| <= 0.01";
    line["met"] = std::abs(err) <= 0.01;
    core::print_line(line);
  }
  return 0;
}

int run_d3(const std::filesystem::path& out, int threads) {
  for (const auto kind : {dynamics::LoadHistory::Kind::ramp, dynamics::LoadHistory::Kind::step}) {
    const std::string loading = kind == dynamics::LoadHistory::Kind::ramp ? "ramp" : "step";
    outputs::LinePlot plot;
    plot.title = "d3 semi-infinite crack, " + loading + ": k/(s0 sqrt h)";
    plot.x_title = "t/t_c";
    plot.y_title = "normalized k";
    bool exact_drawn = false;
    for (const auto& kernel : {kConstant, kGaussian}) {
      for (const std::string extrapolation :
           {"delta_2delta", "nearest_nodes", "both_edges", "lattice_c0"}) {
        if ((extrapolation == "both_edges" || extrapolation == "lattice_c0") &&
            kernel.shape == dynamics::KernelChoice::Shape::constant) {
          continue;
        }
        CrackSpec spec;
        spec.both_edges = extrapolation == "both_edges";
        spec.lattice_calibrated = extrapolation == "lattice_c0";
        spec.kernel = kernel;
        spec.threads = threads;
        spec.loading = {kind, 3.36e-4};
        if (extrapolation == "nearest_nodes") {  // the first two node columns behind the tip
          spec.r1 = 0.5 * spec.dx;
          spec.r2 = 1.5 * spec.dx;
        }
        const CrackResult r = run_semi_infinite_crack(spec);
        const std::string name = "d3_" + loading + "_" + kernel_key(kernel) + "_" + extrapolation;
        write_columns(out / (name + ".csv"), "time_s,k_i,k_freund", {&r.time, &r.k_pd, &r.k_exact});
        core::JsonLine line;
        line["case"] = "D3";
        line["kernel"] = kernel_key(kernel);
        if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) line["p"] = kernel.p;
        line["loading"] = loading;
        line["extrapolation"] = extrapolation == "nearest_nodes" ? "nearest_nodes" : "delta_2delta";
        line["micromodulus"] = spec.lattice_calibrated ? "lattice_calibrated" : "paper_eq29";
        line["loaded_edges"] = spec.both_edges ? "both (compared with 2 x Freund)" : "top";
        line["r1_m"] = r.r1;
        line["r2_m"] = r.r2;
        line["nodes"] = r.nodes;
        line["t_c_s"] = core::significant(r.t_c, 5);
        line["window_s"] = {core::significant(1.2 * r.t_c, 5),
                            core::significant(r.first_reflection, 5)};
        line["mean_rel_error"] = core::significant(r.mean_rel_error, 4);
        line["max_rel_error"] = core::significant(r.max_rel_error, 4);
        if (spec.lattice_calibrated) {
          line["c0_factor"] = core::significant(
              dynamics::lattice_calibration_factor(dynamics::Dimension::two, kernel, spec.dx,
                                                   spec.horizon_ratio * spec.dx),
              5);
        }
        if (kernel.shape == dynamics::KernelChoice::Shape::gaussian && loading == "ramp" &&
            !spec.both_edges) {
          line["goal"] = "mean <= 0.05, max <= 0.10";
          line["met"] = r.mean_rel_error <= 0.05 && r.max_rel_error <= 0.10;
        }
        line["wall_s"] = core::fixed(r.wall_s, 1);
        core::print_line(line);
        const double norm = 1.0 / (spec.stress * std::sqrt(spec.half_height));  // Eq. (66)
        const auto t = scaled(r.time, 1.0 / r.t_c);
        if (!exact_drawn) {
          plot.series.push_back({"freund", t, scaled(r.k_exact, norm), kBlack, true});
          exact_drawn = true;
        }
        if (extrapolation == "delta_2delta" || extrapolation == "nearest_nodes") {
          const bool nearest = extrapolation == "nearest_nodes";
          if (!nearest || kernel.shape == dynamics::KernelChoice::Shape::gaussian) {
            plot.series.push_back(
                {nearest ? std::string("gaussian, nearest nodes") : kernel_label(kernel), t,
                 scaled(r.k_pd, norm),
                 nearest                                                   ? kGreen
                 : kernel.shape == dynamics::KernelChoice::Shape::constant ? kRed
                                                                           : kBlue,
                 false});
          }
        }
      }
    }
    outputs::write_line_plot_png(out / ("d3_" + loading + ".png"), plot);
  }
  return 0;
}

int run_d4(const std::filesystem::path& out, int threads, double dx) {
  outputs::LinePlot plot;
  plot.title = "d4 mode ii plate: k_ii/(tau sqrt(pi a))";
  plot.x_title = "time [us]";
  plot.y_title = "normalized k_ii";
  for (const auto& kernel : {kConstant, kGaussian}) {
    ShearPlateSpec spec;
    spec.kernel = kernel;
    spec.threads = threads;
    if (dx > 0) spec.dx = dx;
    const ShearPlateResult r = run_shear_plate(spec);
    write_columns(out / ("d4_" + kernel_key(kernel) + ".csv"), "time_s,k_ii_over_tau_sqrt_pi_a",
                  {&r.time, &r.k_ii_normalized});
    core::JsonLine line;
    line["case"] = "D4";
    line["kernel"] = kernel_key(kernel);
    if (kernel.shape == dynamics::KernelChoice::Shape::gaussian) line["p"] = kernel.p;
    line["dx_m"] = spec.dx;
    line["nodes"] = r.nodes;
    line["dt_s"] = core::significant(r.time_step, 4);
    line["peak"] = core::significant(r.peak, 4);
    line["peak_time_s"] = core::significant(r.peak_time, 4);
    // The series, every 1 µs.
    core::JsonLine series = core::JsonLine::array();
    double next = 0.0;
    for (std::size_t i = 0; i < r.time.size(); ++i) {
      if (r.time[i] + 1e-12 < next) continue;
      series.push_back(
          {core::significant(r.time[i], 4), core::significant(r.k_ii_normalized[i], 4)});
      next += 1e-6;
    }
    line["series_t_s_k"] = series;
    line["wall_s"] = core::fixed(r.wall_s, 1);
    core::print_line(line);
    plot.series.push_back({kernel_label(kernel), scaled(r.time, 1e6), r.k_ii_normalized,
                           kernel.shape == dynamics::KernelChoice::Shape::constant ? kRed : kBlue,
                           false});
  }
  outputs::write_line_plot_png(out / "d4_mode_ii.png", plot);
  return 0;
}

}  // namespace peritwin::validation
