// peritwin-calibrate: the fatigue parameters of the strain-range law (000 Eq. 14-20) for a user's
// material, grid and PD model, printed as a ready-to-paste [detail.fatigue] table.
//   A1, m1 (phase I): fitted to strain-life points by 000 Eq. (23), or from 000 Eq. (48b)'s inputs,
//     or given; without any, B1's (Al 6061-T6, 000 Eq. 48), said so in the snippet.
//   m2 = M (000 Eq. 25).
//   A2 (phase II, grid dependent): 000 App. A on an ASTM E647 CT coupon (B1's specimen scaled to
//     W, with the user's material): PD runs at the calibration load, A2 rescaled until the PD life
//     to K_max = K_c equals the Paris life in integral form (validation/ct_calibration.h).
// Then the PD life against the Paris life at other loads (the prediction check of B1).
// --kinetic: another mode, the kinetic law's U and γ per stress segment on an S-N curve (004
// Fig. 4a, 8b; fatigue::kt_calibrate_segment), no PD run; docs/kinetic.md.
// Exit codes: 0 calibrated, 2 bad usage or input, 3 the calibration failed (did not converge, or
// the PD crack never reached K_max = K_c; --kinetic: no fit in a segment).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/cli_checks.h"
#include "core/exit_codes.h"
#include "core/json_line.h"
#include "core/program.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/kinetic_calibration.h"
#include "validation/b5_low_cycle.h"
#include "validation/ct_calibration.h"

namespace {

using namespace peritwin;
using namespace peritwin::validation;

using core::kExitOk;
using core::kExitUsage;
constexpr int kExitFailed = core::kExitRuntime;  // the calibration failed

/// A finite number in the open interval (lo, hi).
CLI::Validator finite_open(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        double v = 0.0;
        if (!core::parse_double(text, v) || !std::isfinite(v))
          return "not a finite number: " + text;
        if (!(v > lo && v < hi)) {
          return "must lie in (" + core::shortest(lo) + ", " + core::shortest(hi) + "), got " +
                 text;
        }
        return {};
      },
      "FLOAT in (" + core::shortest(lo) + ", " + core::shortest(hi) + ")");
}

/// A real for TOML: 7 significant digits, always with a '.' or an exponent.
std::string toml_number(double v) {
  char text[64];
  std::snprintf(text, sizeof text, "%.7g", v);
  std::string s = text;
  if (s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

std::string format(const char* fmt, auto... args) {
  char text[512];
  std::snprintf(text, sizeof text, fmt, args...);
  return text;
}

/// Where A1, m1 and ε∞ came from.
struct PhaseOne {
  fatigue::StrainLawParams law = fatigue::al6061_t6_strain_params();
  std::string source;
  bool from_b1 = true;
};

/// "EPS:N" strain-life points.
std::optional<std::vector<std::pair<double, double>>> parse_points(
    const std::vector<std::string>& items, std::string& error) {
  std::vector<std::pair<double, double>> points;
  for (const auto& item : items) {
    const auto colon = item.find(':');
    double eps = 0.0, n = 0.0;
    if (colon == std::string::npos || !core::parse_double(item.substr(0, colon), eps) ||
        !core::parse_double(item.substr(colon + 1), n) || !(eps > 0 && eps < 1) ||
        !(n >= 1 && std::isfinite(n))) {
      error = "--sn-curve " + item +
              ": expected EPS:N, a strain range 0 < EPS < 1 and cycles N >= 1 (e.g. 0.004:2e5)";
      return std::nullopt;
    }
    points.emplace_back(eps, n);
  }
  return points;
}

struct Inputs {
  CalibrationSetup setup;
  double paris_c_given = 0.0;
  std::string paris_units = "mm-MPa";
  std::string law_name = "strain_range";
  std::string model_name = "state_based";
  std::string plane_name = "plane_stress";
  std::string kernel_name = "constant";
  std::string rigid_model_name = "constraint";
  std::vector<double> check_factors{1.25, 1.5};
  PhaseOne phase_one;
};

std::string fatigue_snippet(const Inputs& in, const CalibrationResult& cal,
                            const std::vector<LifeComparison>& checks) {
  const CalibrationSetup& s = in.setup;
  const auto& law = in.phase_one.law;
  const auto& fit = cal.runs.back().life;
  const auto& m = s.coupon.material;
  std::string t;
  t += "# peritwin-calibrate: A2 by 000 App. A (integral form) on an ASTM E647 CT coupon\n";
  t += format("#   W = %g mm, B = %g mm, a0 = %g mm, at P_max = %g N, R = %g\n",
              s.coupon.width * 1e3, s.coupon.thickness * 1e3, s.coupon.initial_crack * 1e3, s.p_max,
              s.r);
  t += format(
      "#   material E = %g Pa, nu = %g, K_c = %g Pa*sqrt(m); Paris C = %g mm/cycle "
      "(dK in MPa*sqrt(m)), M = %g\n",
      m.youngs_modulus, m.poisson_ratio, m.fracture_toughness, s.paris.c, s.paris.m);
  t += format(
      "#   valid for [detail.grid] dx = %g, horizon_ratio = %g and [detail.model] kind = "
      "\"%s\", plane = \"%s\", kernel = \"%s\"%s\n",
      s.dx, s.model.horizon_ratio, in.model_name.c_str(), in.plane_name.c_str(),
      in.kernel_name.c_str(),
      s.model.options.surface_correction ? "" : ", surface_correction = false");
  t += "#   (another horizon at the same ratio: rescale A2 by 000 Eq. 29; otherwise recalibrate)\n";
  t += format(
      "#   fit: PD life %.0f vs Paris life %.0f cycles (%+.2f %%) to a = %.2f mm "
      "(K_max = K_c)\n",
      fit.pd_life, fit.paris_life, 100 * fit.relative_error(), fit.a_end * 1e3);
  for (const auto& c : checks) {
    t += format("#   check: P_max = %g N, R = %g: PD %.0f vs Paris %.0f cycles (%+.2f %%)\n",
                c.p_max, c.r, c.pd_life, c.paris_life, 100 * c.relative_error());
  }
  t += "[detail.fatigue]\n";
  t += format("law = \"%s\"\n", in.law_name.c_str());
  t += format("phi0 = %s  # phase I -> II switch (000 Sec. 4.4) used in the calibration\n",
              toml_number(s.model.phase_switch_damage).c_str());
  t += "static_failure = \"critical_stretch\"  # phase III as calibrated (000 Eq. 7-8)\n";
  t += format("A1 = %s  # %s\n", toml_number(law.A1).c_str(), in.phase_one.source.c_str());
  t += format("m1 = %s\n", toml_number(law.m1).c_str());
  t += format("eps_inf = %s  # phase I fatigue limit (000 Eq. 17)\n",
              toml_number(law.eps_inf).c_str());
  t += format("A2 = %s  # calibrated with the A1, m1 above: change them, recalibrate A2\n",
              toml_number(cal.a2).c_str());
  t += format("m2 = %s  # = Paris M (000 Eq. 25)\n", toml_number(law.m2).c_str());
  t += "eps_inf_prop = 0.0  # propagation-phase limit (002 Eq. 12) off, as calibrated\n";
  return t;
}

core::JsonLine life_json(const LifeComparison& l) {
  core::JsonLine j;
  j["p_max"] = core::significant(l.p_max, 6);
  j["r"] = core::fixed(l.r, 4);
  j["critical_crack_m"] = core::fixed(l.a_end, 6);
  j["pd_life"] = core::whole(l.pd_life);
  j["paris_life"] = core::whole(l.paris_life);
  j["rel_error"] = core::fixed(l.relative_error(), 4);
  j["wall_s"] = core::fixed(l.wall_s, 1);
  return j;
}

core::JsonLine result_json(const Inputs& in, const CalibrationResult& cal,
                           const std::vector<LifeComparison>& checks, double wall_s,
                           const std::string& snippet) {
  const CalibrationSetup& s = in.setup;
  const auto& law = in.phase_one.law;
  core::JsonLine j;
  j["tool"] = "peritwin-calibrate";
  j["youngs_modulus_pa"] = s.coupon.material.youngs_modulus;
  j["poisson_ratio"] = s.coupon.material.poisson_ratio;
  j["fracture_toughness_pa_sqrt_m"] = s.coupon.material.fracture_toughness;
  j["paris_c_given"] = in.paris_c_given;
  j["paris_units"] = in.paris_units;
  j["paris_c_mm_mpa"] = s.paris.c;
  j["paris_m"] = s.paris.m;
  j["dx_m"] = s.dx;
  j["horizon_ratio"] = s.model.horizon_ratio;
  j["model"] = in.model_name;
  j["plane"] = in.plane_name;
  j["kernel"] = in.kernel_name;
  j["surface_correction"] = s.model.options.surface_correction;
  j["law"] = in.law_name;
  j["width_m"] = s.coupon.width;
  j["thickness_m"] = s.coupon.thickness;
  j["initial_crack_m"] = s.coupon.initial_crack;
  j["p_max"] = s.p_max;
  j["r"] = s.r;
  j["tolerance"] = s.tolerance;
  j["converged"] = cal.converged;
  j["a2"] = core::significant(cal.a2, 7);
  j["a1"] = law.A1;
  j["m1"] = law.m1;
  j["eps_inf"] = law.eps_inf;
  j["m2"] = law.m2;
  j["phi0"] = s.model.phase_switch_damage;
  j["a1_m1_source"] = in.phase_one.source;
  core::JsonLine runs = core::JsonLine::array();
  for (const auto& run : cal.runs) {
    core::JsonLine r = life_json(run.life);
    r["a2"] = core::significant(run.a2, 7);
    runs.push_back(r);
  }
  j["runs"] = runs;
  if (!cal.runs.empty()) j["fit"] = life_json(cal.runs.back().life);
  core::JsonLine check = core::JsonLine::array();
  for (const auto& c : checks) check.push_back(life_json(c));
  j["checks"] = check;
  j["failure"] = cal.failure;
  j["wall_s"] = core::fixed(wall_s, 1);
  j["fatigue_toml"] = snippet;
  return j;
}

/// The command line: the inputs, and what only steers the run.
struct Options {
  Inputs in;
  double paris_c = 0.0, phi0 = 0.0, thickness = 0.0, p_max = 0.0;
  std::vector<std::string> sn_points;
  double m1 = 0.0, a1 = 0.0, intercept = 0.0;
  CLI::Option *m1_opt = nullptr, *a1_opt = nullptr, *intercept_opt = nullptr, *limit_opt = nullptr;
  double a2_trial = 0.0;
  bool no_check = false, dry_run = false, json = false;
};

void add_options(CLI::App& app, Options& o) {
  Inputs& in = o.in;
  CalibrationSetup& s = in.setup;
  model::Material& mat = s.coupon.material;
  // Material.
  app.add_option("-E,--youngs-modulus", mat.youngs_modulus, "Young's modulus E (Pa)")
      ->required()
      ->check(core::finite_positive());
  app.add_option("--nu,--poisson-ratio", mat.poisson_ratio, "Poisson's ratio (-1 < nu < 0.5)")
      ->required()
      ->check(finite_open(-1.0, 0.5));
  app.add_option("--K-c,--fracture-toughness", mat.fracture_toughness,
                 "fracture toughness K_c (Pa*sqrt(m)); the lives run to K_max = K_c")
      ->required()
      ->check(core::finite_positive());
  // Paris law.
  app.add_option("--paris-c", o.paris_c,
                 "Paris constant C of da/dN = C dK^M, in the units of --paris-units")
      ->required()
      ->check(core::finite_positive());
  app.add_option("--paris-m", s.paris.m, "Paris exponent M (dimensionless; m2 = M)")
      ->required()
      ->check(core::finite_in(1.0, 10.0));
  app.add_option("--paris-units", in.paris_units,
                 "units of C: mm-MPa (default; mm/cycle with dK in MPa*sqrt(m), as 000 Eq. A4), "
                 "m-Pa (m/cycle with dK in Pa*sqrt(m), SI), m-MPa (m/cycle with dK in "
                 "MPa*sqrt(m))")
      ->check(CLI::IsMember({"mm-MPa", "m-Pa", "m-MPa"}));
  // Grid and model.
  app.add_option("--dx", s.dx, "grid spacing dx (m) of the detail the parameters are for")
      ->required()
      ->check(core::finite_in(1e-5, 0.01));
  app.add_option("--horizon-ratio", s.model.horizon_ratio,
                 "horizon over grid spacing delta/dx (default 3.015; the config's bounds)")
      ->check(core::finite_in(config::kMinHorizonRatio, config::kMaxHorizonRatio));
  app.add_option("--model", in.model_name, "PD model: state_based (default) | bond_based")
      ->check(CLI::IsMember({"state_based", "bond_based"}));
  app.add_option("--plane", in.plane_name, "plane_stress (default) | plane_strain")
      ->check(CLI::IsMember({"plane_stress", "plane_strain"}));
  app.add_option("--kernel", in.kernel_name,
                 "bond-based micromodulus kernel: constant (default) | conical | gaussian")
      ->check(CLI::IsMember({"constant", "conical", "gaussian"}));
  app.add_option("--rigid-model", in.rigid_model_name,
                 "the coupon's pins: constraint (default; rigid-body ties, any nu) | "
                 "stiff_material (000 Sec. 6.1's 200*E, B1's documented A2; state-based only "
                 "for nu near 1/3 and above)")
      ->check(CLI::IsMember({"constraint", "stiff_material"}));
  app.add_flag_callback(
      "--no-surface-correction", [&] { s.model.options.surface_correction = false; },
      "[detail.model] surface_correction = false");
  app.add_option("--law", in.law_name,
                 "fatigue law the parameters are for: strain_range (default) | energy (000 Sec. 4, "
                 "same A1, m1, A2, m2)")
      ->check(CLI::IsMember({"strain_range", "energy"}));
  app.add_option("--phi0", o.phi0,
                 "phase-switch damage (default: the config's, the split damage at the horizon "
                 "ratio, 0.398 at 3.015)")
      ->check(core::finite_in(0.01, 0.99));
  // Coupon and load.
  app.add_option("--width", s.coupon.width, "CT coupon width W (m), default 0.050 as B1; a0 = 0.3W")
      ->check(core::finite_in(0.005, 1.0));
  app.add_option("--thickness", o.thickness, "CT coupon thickness B (m), default 0.2W (B1: 10 mm)")
      ->check(core::finite_in(1e-4, 1.0));
  app.add_option("--p-max", o.p_max,
                 "calibration P_max (N); default: K_max at a0 at B1's fraction of K_c (0.206), "
                 "i.e. 4 kN * (K_c/48.7 MPa*sqrt(m)) * (B/10 mm) * sqrt(W/50 mm)")
      ->check(core::finite_positive());
  app.add_option("--r", s.r, "calibration load ratio R = P_min/P_max (default 0.1)")
      ->check(core::finite_in(0.0, 0.9));
  // Phase I.
  app.add_option("--sn-curve", o.sn_points,
                 "strain-life point EPS:N (cyclic strain range, cycles to failure), repeated or "
                 "comma-separated, >= 2: A1, m1 by the least squares of 000 Eq. (23)")
      ->delimiter(',');
  o.m1_opt = app.add_option("--m1", o.m1, "phase I exponent m1 (with --a1 or --sn-intercept)")
                 ->check(core::finite_positive());
  o.a1_opt = app.add_option("--a1", o.a1, "phase I coefficient A1 (with --m1)")
                 ->check(core::finite_positive());
  o.intercept_opt =
      app.add_option("--sn-intercept", o.intercept,
                     "000 Eq. (48b): the fitted log10 intercept -log10(A1)/m1 (with --m1)")
          ->check(core::finite_in(-100, 100));
  o.limit_opt = app.add_option("--fatigue-limit", s.law.eps_inf,
                               "phase I fatigue limit eps_inf (000 Eq. 17, 23b; default 0)")
                    ->check(core::finite_in(0.0, 0.5));
  // Calibration.
  app.add_option("--a2-trial", o.a2_trial,
                 "first A2 (default: B1's 1301 scaled by C, E, M and the horizon)")
      ->check(core::finite_positive());
  app.add_option("--tolerance", s.tolerance,
                 "stop when |PD life / Paris life - 1| <= this (default 0.005)")
      ->check(core::finite_in(1e-4, 0.2));
  app.add_option("--max-runs", s.max_runs, "PD runs at most (default 8)")->check(CLI::Range(1, 50));
  app.add_option("--check-loads", in.check_factors,
                 "prediction checks at these multiples of P_max (default 1.25,1.5)")
      ->delimiter(',')
      ->check(core::finite_in(0.2, 5.0));
  app.add_flag("--no-check", o.no_check, "skip the prediction checks");
  app.add_flag("--dry-run", o.dry_run,
               "check the inputs, print what would be run (A1, m1, load, Paris life, first A2) "
               "and stop before the PD runs");
  app.add_flag("--json", o.json, "print one JSON line (inputs, runs, results, the TOML) instead");
}

int usage(const std::string& what) {
  std::fprintf(stderr, "peritwin-calibrate: %s\n", what.c_str());
  return core::kExitUsage;
}

/// What prepare() found: the crack length at K_max = K_c and the Paris life to it.
struct Plan {
  double a_end = 0.0, n_paris = 0.0;
};

/// The setup of the calibration from the options (model, coupon, Paris law, phase I, load),
/// checked; an exit code when the input is bad.
std::optional<int> prepare(Options& o, Plan& plan) {
  Inputs& in = o.in;
  CalibrationSetup& s = in.setup;
  model::Material& mat = s.coupon.material;
  const double paris_c = o.paris_c, phi0 = o.phi0, thickness = o.thickness, p_max = o.p_max;
  const double m1 = o.m1, a1 = o.a1, intercept = o.intercept, a2_trial = o.a2_trial;
  const std::vector<std::string>& sn_points = o.sn_points;
  const CLI::Option *m1_opt = o.m1_opt, *a1_opt = o.a1_opt, *intercept_opt = o.intercept_opt,
                    *limit_opt = o.limit_opt;

  // Model options (the config's rules: state-based takes the constant kernel only).
  model::ModelOptions& options = s.model.options;
  options.kind =
      in.model_name == "bond_based" ? model::ModelKind::bond_based : model::ModelKind::state_based;
  options.plane = in.plane_name == "plane_strain" ? model::PlaneCondition::plane_strain
                                                  : model::PlaneCondition::plane_stress;
  options.kernel = in.kernel_name == "conical"    ? model::Kernel::conical
                   : in.kernel_name == "gaussian" ? model::Kernel::gaussian
                                                  : model::Kernel::constant;
  if (const core::Status st = validate(mat, options); !st) return usage(core::message_of(st));
  s.coupon.rigid_model = in.rigid_model_name == "stiff_material" ? mesh::RigidModel::stiff_material
                                                                 : mesh::RigidModel::constraint;
  if (s.coupon.rigid_model == mesh::RigidModel::stiff_material) {
    if (const core::Status st =
            model::check_stiff_rigid_material(mat, options, mesh::DetailGeometry{}.rigid_factor);
        !st) {
      return usage(core::message_of(st));
    }
  }
  s.model.law =
      in.law_name == "energy" ? fatigue::FatigueLaw::energy : fatigue::FatigueLaw::strain_range;
  s.model.phase_switch_damage =
      phi0 > 0 ? phi0 : fatigue::phase_switch_damage_for_horizon(s.model.horizon_ratio);

  // Coupon: B1's proportions at W.
  s.coupon.initial_crack = 0.3 * s.coupon.width;
  s.coupon.thickness = thickness > 0 ? thickness : s.coupon.width / 5;
  if (const auto problem = coupon_grid_problem(s.coupon, s.dx)) return usage(*problem);

  // Paris law in ParisLaw's units.
  in.paris_c_given = paris_c;
  const ParisUnits units = in.paris_units == "m-Pa"    ? ParisUnits::m_per_cycle_pa
                           : in.paris_units == "m-MPa" ? ParisUnits::m_per_cycle_mpa
                                                       : ParisUnits::mm_per_cycle_mpa;
  s.paris.c = paris_c_in_mm_mpa(paris_c, s.paris.m, units);

  // Phase I: A1, m1, ε∞.
  PhaseOne& one = in.phase_one;
  const double eps_inf = s.law.eps_inf;
  if (!sn_points.empty()) {
    if (m1_opt->count() + a1_opt->count() + intercept_opt->count() > 0) {
      return usage("--sn-curve fits A1 and m1: leave out --m1, --a1 and --sn-intercept");
    }
    std::string error;
    const auto points = parse_points(sn_points, error);
    if (!points) return usage(error);
    std::vector<double> eps, cycles;
    for (const auto& [e, n] : *points) {
      eps.push_back(e);
      cycles.push_back(n);
    }
    const fatigue::Phase1Fit fit = fatigue::fit_phase1(eps, cycles, eps_inf);
    if (!fit.ok) {
      return usage(
          "--sn-curve: no fit of 000 Eq. (23): give >= 2 points with distinct N, every strain "
          "range above --fatigue-limit, and strain falling as N grows");
    }
    one.law.A1 = fit.A1;
    one.law.m1 = fit.m1;
    one.source = format("fitted to %zu strain-life points (000 Eq. 23%s)", points->size(),
                        eps_inf > 0 ? "b" : "a");
    one.from_b1 = false;
  } else if (m1_opt->count() > 0) {
    if (a1_opt->count() + intercept_opt->count() != 1) {
      return usage("--m1 goes with exactly one of --a1 and --sn-intercept");
    }
    one.law.m1 = m1;
    one.law.A1 = a1_opt->count() > 0 ? a1 : fatigue::a1_from_log_intercept(m1, intercept);
    one.source = a1_opt->count() > 0 ? "given" : "000 Eq. (48b) from m1 and the log10 intercept";
    one.from_b1 = false;
  } else if (a1_opt->count() + intercept_opt->count() > 0) {
    return usage("--a1 and --sn-intercept need --m1");
  } else {
    if (limit_opt->count() > 0) {
      return usage("--fatigue-limit belongs to your strain-life data: give --sn-curve or --m1 too");
    }
    one.source = "B1's (Al 6061-T6, 000 Eq. 48c/48a): no strain-life data given";
  }
  one.law.eps_inf = eps_inf;
  one.law.m2 = fatigue::m2_from_paris_exponent(s.paris.m);
  one.law.eps_inf_prop = 0.0;
  one.law.A2 =
      a2_trial > 0 ? a2_trial : a2_first_trial(s.coupon, s.paris, s.dx, s.model.horizon_ratio);
  if (const core::Status st = fatigue::validate(one.law); !st) return usage(core::message_of(st));
  s.law = one.law;

  // Load; the Paris life there tells a C in the wrong units.
  s.p_max = p_max > 0 ? p_max : default_calibration_load(s.coupon);
  const double a_end = critical_crack_length(s.coupon, s.p_max);
  if (!(a_end > s.coupon.initial_crack + 5 * s.dx)) {
    return usage(
        format("at P_max = %g N the crack reaches K_max = K_c after %.3g m of growth, "
               "less than 5 dx: lower --p-max",
               s.p_max, a_end - s.coupon.initial_crack));
  }
  const double n_paris = paris_life(s.coupon, s.paris, s.p_max, s.r, a_end);
  if (!(n_paris >= 100 && n_paris <= 1e9)) {
    return usage(
        format("the Paris law gives %.3g cycles at P_max = %g N, R = %g (from a0 to "
               "K_max = K_c): outside 100 to 1e9 — check --paris-c and --paris-units "
               "(C = %g %s is %g mm/cycle with dK in MPa*sqrt(m))",
               n_paris, s.p_max, s.r, paris_c, in.paris_units.c_str(), s.paris.c));
  }
  s.record_every = std::max<std::int64_t>(250, static_cast<std::int64_t>(n_paris / 200));
  plan.a_end = a_end;
  plan.n_paris = n_paris;
  return std::nullopt;
}

/// --dry-run: what would be run, as JSON.
int print_dry_run(const Options& o, const Plan& plan) {
  const Inputs& in = o.in;
  const CalibrationSetup& s = in.setup;
  const double n_paris = plan.n_paris, a_end = plan.a_end;
  const bool json = o.json;
  CalibrationResult none;
  none.a2 = s.law.A2;
  core::JsonLine line = result_json(in, none, {}, 0.0, "");
  line["a2"] = nullptr;  // not calibrated
  line["dry_run"] = true;
  line["first_a2"] = core::significant(s.law.A2, 7);
  line["paris_life"] = core::whole(n_paris);
  line["critical_crack_m"] = core::fixed(a_end, 6);
  line["record_every"] = s.record_every;
  if (json) {
    core::print_line(line);
  } else {
    std::printf("%s\n", line.dump(2).c_str());
  }
  return core::kExitOk;
}

/// The PD runs of the calibration and the checks; the TOML snippet (or the JSON line).
int calibrate(Options& o, const Plan& plan) {
  Inputs& in = o.in;
  const CalibrationSetup& s = in.setup;
  const PhaseOne& one = in.phase_one;
  const double n_paris = plan.n_paris;
  const bool json = o.json, no_check = o.no_check;
  const auto t0 = std::chrono::steady_clock::now();
  std::fprintf(stderr,
               "peritwin-calibrate: CT W = %g mm, B = %g mm, dx = %g mm (about %.0f nodes), "
               "P_max = %g N, R = %g, Paris life %.0f cycles; first A2 %.6g\n",
               s.coupon.width * 1e3, s.coupon.thickness * 1e3, s.dx * 1e3,
               1.5 * s.coupon.width * s.coupon.width / (s.dx * s.dx), s.p_max, s.r, n_paris,
               s.law.A2);
  int run_index = 0;
  CalibrationResult cal = calibrate_a2(s, [&](const CalibrationRun& run) {
    std::fprintf(stderr,
                 "run %d: A2 %.6g: PD life %.0f vs Paris life %.0f (%+.2f %%), %.1f s, %lld "
                 "bonds broken\n",
                 ++run_index, run.a2, run.life.pd_life, run.life.paris_life,
                 100 * run.life.relative_error(), run.life.wall_s,
                 static_cast<long long>(run.life.broken_bonds));
  });
  if (!cal.converged && cal.failure.empty()) {
    cal.failure = format(
        "no A2 within %g of the Paris life after %d runs (next A2 would be %.6g)%s", s.tolerance,
        s.max_runs, cal.a2,
        one.from_b1 ? "" : "; if A2 keeps growing, phase I (A1, m1) alone outlasts the Paris life");
  }
  std::vector<LifeComparison> checks;
  if (cal.converged && !no_check) {
    fatigue::StrainLawParams law = s.law;
    law.A2 = cal.a2;
    for (const double f : in.check_factors) {
      checks.push_back(compare_lives(s, law, f * s.p_max, s.r));
      const auto& c = checks.back();
      std::fprintf(stderr,
                   "check: P_max %g N: PD life %.0f vs Paris life %.0f (%+.2f %%), %.1f s\n",
                   c.p_max, c.pd_life, c.paris_life, 100 * c.relative_error(), c.wall_s);
    }
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string snippet = cal.converged ? fatigue_snippet(in, cal, checks) : std::string{};
  if (json) core::print_line(result_json(in, cal, checks, wall_s, snippet));
  if (!cal.converged) {
    std::fprintf(stderr, "peritwin-calibrate: calibration failed: %s\n", cal.failure.c_str());
    return kExitFailed;
  }
  if (!json) {
    std::printf("%s", snippet.c_str());
    std::printf("# calibration: %zu PD runs, %.1f s in all\n", cal.runs.size(), wall_s);
  }
  return core::kExitOk;
}

// ---------------------------------------------------------------- --kinetic (004 Fig. 4a, 8b)

struct KineticOptions {
  std::vector<std::string> sn_stress;
  bool nureg = false;
  std::vector<double> bounds;
  double step = 2e6;
  double r = -1.0;
  fatigue::KineticParams law;         // λ, n0, T, f
  double psi = 0.0, loop_area = 0.0;  // θ of Eq. (26)
  double n0 = 0.0;
};

void add_kinetic_options(CLI::App& app, KineticOptions& o) {
  app.add_flag("--kinetic")->description("this mode");
  app.add_option("--sn-stress", o.sn_stress,
                 "S-N point SA:N (stress amplitude in Pa, cycles), repeated or comma-separated")
      ->delimiter(',');
  app.add_flag("--nureg-6909-ss", o.nureg,
               "004's curve instead: NUREG/CR-6909 Rev. 0 austenitic SS through 004's 316L "
               "tensile curve, a point every --step within each segment");
  app.add_option("--segment-bounds", o.bounds,
                 "stress-amplitude bounds (Pa) of 1-3 segments, ascending; default: the points' "
                 "range (one segment), with --nureg-6909-ss 210e6,250e6,290e6,294e6 (004)")
      ->delimiter(',')
      ->check(core::finite_positive());
  app.add_option("--step", o.step, "--nureg-6909-ss spacing (Pa, default 2e6)")
      ->check(core::finite_positive());
  app.add_option("--r", o.r, "load ratio of the S-N data (default -1)")
      ->check(core::finite_in(-10.0, 0.99));
  app.add_option("--lambda", o.law.lambda, "λ (default 9, 004)")->check(core::finite_positive());
  app.add_option("--n0", o.n0, "n0 (default: unit life for λ, 1.771 at 9)")
      ->check(core::finite_in(1.0 + 1e-9, 1e6));
  app.add_option("--temperature", o.law.temperature, "T (K, default 293)")
      ->check(core::finite_positive());
  app.add_option("--frequency", o.law.frequency, "f (Hz, default 0.56)")
      ->check(core::finite_positive());
  app.add_option("--psi", o.psi, "ψ (m^3) of Eq. (26), with --loop-area (default 0)")
      ->check(core::finite_in(0.0, 1e-20));
  app.add_option("--loop-area", o.loop_area, "A (J/m^3) of Eq. (26) (default 0)")
      ->check(core::finite_in(0.0, 1e12));
}

/// The S-N points of the mode, or a usage message.
std::optional<std::vector<fatigue::SnPoint>> kinetic_points(KineticOptions& o, std::string& error) {
  std::vector<fatigue::SnPoint> pts;
  if (o.nureg == !o.sn_stress.empty()) {
    error = "--kinetic needs exactly one of --sn-stress and --nureg-6909-ss";
    return std::nullopt;
  }
  if (o.nureg) {
    if (o.bounds.empty()) o.bounds = {210e6, 250e6, 290e6, 294e6};
    if (!(o.bounds.back() < 295e6)) {
      error = "--nureg-6909-ss: the 316L curve saturates at 295 MPa: bounds must stay below";
      return std::nullopt;
    }
    const auto n =
        static_cast<int>(std::floor((o.bounds.back() - o.bounds.front()) / o.step + 1e-9));
    for (int k = 0; k <= n; ++k) {
      const double sa = o.bounds.front() + k * o.step;
      pts.push_back({sa, validation::nureg_6909_ss_life(
                             validation::curve_strain(model::PowerLawCurve{}, sa))});
    }
    return pts;
  }
  for (const auto& item : o.sn_stress) {
    const auto colon = item.find(':');
    fatigue::SnPoint p;
    if (colon == std::string::npos ||
        !core::parse_double(item.substr(0, colon), p.stress_amplitude) ||
        !core::parse_double(item.substr(colon + 1), p.cycles)) {
      error = "--sn-stress " + item + ": expected SA:N (e.g. 230e6:1.39e5)";
      return std::nullopt;
    }
    pts.push_back(p);
  }
  if (pts.size() < 2) {
    error = "--sn-stress: give at least 2 points (U and gamma are two unknowns)";
    return std::nullopt;
  }
  if (o.bounds.empty()) {
    double lo = pts.front().stress_amplitude, hi = lo;
    for (const auto& p : pts) {
      lo = std::min(lo, p.stress_amplitude);
      hi = std::max(hi, p.stress_amplitude);
    }
    o.bounds = {lo, hi};
  }
  return pts;
}

int run_kinetic(int argc, char** argv) {
  CLI::App app{
      "peritwin-calibrate --kinetic: U and gamma of the kinetic law (004 Eq. 15) per stress "
      "segment from an S-N curve (004 Fig. 4a, 8b): least squares on ln N of the single-bond "
      "life, printed as a [detail.fatigue] table. SI units. Exit codes: 0 fitted, 2 bad input, 3 "
      "no fit."};
  KineticOptions o;
  add_kinetic_options(app, o);
  if (const auto rc = core::parse_options(app, argc, argv)) return *rc;
  std::string error;
  const auto pts = kinetic_points(o, error);
  if (!pts) return usage(error);
  const std::size_t segments = o.bounds.size() - 1;
  if (segments < 1 || segments > fatigue::kMaxKineticSegments ||
      !std::is_sorted(o.bounds.begin(), o.bounds.end(), std::less_equal<>())) {
    return usage("--segment-bounds: 2 to 4 ascending stresses (1 to 3 segments)");
  }
  fatigue::KineticParams& law = o.law;
  law.n0 = o.n0 > 0 ? o.n0 : fatigue::kt_n0_for_unit_life(law.lambda);
  const double theta = fatigue::kt_thermal_energy(law.temperature, o.psi, o.loop_area, 0.0);
  constexpr double kEv = 1.602176634e-19;
  std::string head, keys;
  for (std::size_t i = 0; i < segments; ++i) {
    const double lo = o.bounds[i], hi = o.bounds[i + 1];
    std::vector<fatigue::SnPoint> seg;
    for (const auto& p : *pts) {
      if (p.stress_amplitude >= lo * (1 - 1e-12) && p.stress_amplitude <= hi * (1 + 1e-12)) {
        seg.push_back(p);
      }
    }
    const auto fit = fatigue::kt_calibrate_segment(seg, o.r, law, theta);
    if (!fit) {
      std::fprintf(stderr, "peritwin-calibrate: segment %zu (%g-%g Pa): %s\n", i + 1, lo, hi,
                   fit.error().message().c_str());
      return kExitFailed;
    }
    const std::string n = i == 0 ? "" : std::to_string(i + 1);
    head += format(
        "#   segment %zu: sigma_a %g-%g MPa, %zu points: U = %.4f eV (%.2f theta), gamma = %.4g "
        "m^3, max |dlnN| = %.3f\n",
        i + 1, lo / 1e6, hi / 1e6, seg.size(), fit->U / kEv, fit->U / theta, fit->gamma,
        fit->max_abs_log_error);
    keys += format("U%s = %s  # J\ngamma%s = %s  # m^3\n", n.c_str(), toml_number(fit->U).c_str(),
                   n.c_str(), toml_number(fit->gamma).c_str());
    if (i + 1 < segments) {  // the bond's σ_max at the upper amplitude: σ_max = 2σ_a/(1 − R)
      keys += format("sigma_upper%zu = %s  # Pa, bond sigma_max\n", i + 1,
                     toml_number(2 * hi / (1 - o.r)).c_str());
    }
  }
  std::printf(
      "# peritwin-calibrate --kinetic: U, gamma per segment, 004 Eq. (15) single-bond life\n");
  std::printf(
      "#   on %s at R = %g, theta = %.6g J (kT%s)\n",
      o.nureg ? "NUREG/CR-6909 Rev. 0 austenitic SS via 004's 316L curve" : "the given points", o.r,
      theta, o.psi * o.loop_area > 0 ? " + psi*A, Eq. 26" : "");
  std::printf("%s[detail.fatigue]\nlaw = \"kinetic\"\n%s", head.c_str(), keys.c_str());
  std::printf("lambda = %s\nn0 = %s\ntemperature = %s\nfrequency = %s\n",
              toml_number(law.lambda).c_str(), toml_number(law.n0).c_str(),
              toml_number(law.temperature).c_str(), toml_number(law.frequency).c_str());
  if (o.psi * o.loop_area > 0) {
    std::printf("psi = %s\nloop_area = %s\n", toml_number(o.psi).c_str(),
                toml_number(o.loop_area).c_str());
  }
  return core::kExitOk;
}

bool kinetic_mode(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--kinetic") == 0) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  if (kinetic_mode(argc, argv)) return run_kinetic(argc, argv);
  CLI::App app{
      "peritwin-calibrate: the strain-range fatigue law's parameters (000 Eq. 14-20) for your "
      "material, grid and PD model, as a [detail.fatigue] table to paste into a detail config.\n"
      "A2 (phase II, depends on dx and the horizon) is calibrated by 000 App. A: PD runs of an "
      "ASTM E647 compact-tension coupon (B1's, scaled to --width, with your material) at the "
      "calibration load, A2 rescaled until the PD life to K_max = K_c equals the life the Paris "
      "law gives (integral form, docs/validation.md). m2 = Paris M (000 Eq. 25). A1, m1 (phase I) "
      "come from strain-life data (000 Eq. 23) if you give any, else B1's Al 6061-T6 values (000 "
      "Eq. 48). Then the PD and Paris lives at other loads as a check.\n"
      "Units: SI (Pa, m, N) except the Paris constant C, whose units --paris-units states.\n"
      "Exit codes: 0 calibrated, 2 bad input, 3 calibration failed.\n"
      "--kinetic: the kinetic law's U, gamma on an S-N curve instead (--kinetic --help)."};
  Options o;
  add_options(app, o);
  if (const auto rc = core::parse_options(app, argc, argv)) return *rc;
  Plan plan;
  if (const auto rc = prepare(o, plan)) return *rc;
  return o.dry_run ? print_dry_run(o, plan) : calibrate(o, plan);
}
