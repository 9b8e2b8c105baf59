// peritwin-validate: builds the benchmarks of docs/benchmarks.md and prints one JSON
// line per result. Long-running: not part of the default test run.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "core/cli_checks.h"
#include "core/json_line.h"
#include "validation/b1_compact_tension.h"
#include "validation/b2_compact_tension_shear.h"
#include "validation/b3_ct_with_hole.h"
#include "validation/b4_analytical.h"
#include "validation/b5_run.h"
#include "validation/b6_dcb.h"
#include "validation/b7_dcb_paris.h"
#include "validation/c1_compression.h"
#include "validation/ct_calibration.h"
#include "validation/d_dynamics.h"

namespace {

using namespace peritwin;
using namespace peritwin::validation;

void write_csv(const std::filesystem::path& path, const CrackHistory& h) {
  std::ofstream out(path);
  out << "cycles,crack_length_m\n";
  for (std::size_t i = 0; i < h.cycles.size(); ++i) {
    out << static_cast<long long>(h.cycles[i]) << ',' << h.crack_length[i] << '\n';
  }
}

int run_b1(double dx, const std::filesystem::path& out_dir, double a2_trial, int iterations) {
  // Calibration at 4 kN, R = 0.1 (000 App. A): Eq. (26b) in integral form after each of
  // `iterations` runs (validation/ct_calibration.h, the loop peritwin-calibrate runs too).
  CalibrationSetup setup;
  setup.dx = dx;
  setup.law = fatigue::al6061_t6_strain_params();
  setup.law.A2 = a2_trial;
  setup.step = A2Step::eq26b;
  setup.tolerance = 0.0;
  setup.max_runs = iterations;
  const CompactTensionSpec& spec = setup.coupon;
  const ParisLaw& paris = setup.paris;
  int it = 0;
  const CalibrationResult calibration = calibrate_a2(setup, [&](const CalibrationRun& run) {
    const double c_rate = fitted_paris_constant(spec, run.history, setup.p_max, setup.r, paris.m,
                                                spec.initial_crack + 0.001, run.life.a_end - 0.001);
    std::fprintf(stderr,
                 "calibration %d: A2 %.6g C_trial %.4g (rate fit over the growth only: %.4g) "
                 "(%.1f s, %lld bonds)\n",
                 it++, run.a2, paris.c * run.life.paris_life / run.life.pd_life, c_rate,
                 run.life.wall_s, static_cast<long long>(run.life.broken_bonds));
  });
  if (!std::isfinite(calibration.a2)) return 1;
  auto law = setup.law;
  law.A2 = calibration.a2;
  CrackHistory h;
  struct Case {
    double p_max, r;
    bool calibration;
  };
  for (const Case c : {Case{4000, 0.1, true}, Case{5000, 0.1, false}, Case{6000, 0.1, false},
                       Case{5000, 0.3, false}}) {
    const LifeComparison life = compare_lives(setup, law, c.p_max, c.r, &h);
    char name[64];
    std::snprintf(name, sizeof name, "b1_p%.0f_r%.1f.csv", c.p_max, c.r);
    write_csv(out_dir / name, h);
    core::JsonLine line;
    line["case"] = "B1";
    line["p_max"] = core::whole(c.p_max);
    line["r"] = core::fixed(c.r, 2);
    line["calibration"] = c.calibration;
    line["a2"] = core::significant(law.A2, 6);
    line["dx_m"] = core::significant(dx, 6);
    line["critical_crack_m"] = core::fixed(life.a_end, 6);
    line["pd_life"] = core::whole(life.pd_life);
    line["paris_life"] = core::whole(life.paris_life);
    line["rel_error"] = core::fixed(life.relative_error(), 4);
    line["wall_s"] = core::fixed(h.wall_s, 1);
    core::print_line(line);
    std::fflush(stdout);
  }
  return 0;
}

/// B2's fatigue parameters: B1's material with A2 calibrated on B1 at Δx = 1 mm
/// (peritwin-validate --case B1), scaled to the horizon at `dx` by 000 Eq. (29).
fatigue::StrainLawParams b2_law_params(double dx, double a2_at_1mm, double horizon_ratio = 3.015) {
  auto law = fatigue::al6061_t6_strain_params();
  law.A2 = fatigue::a2_scaled(a2_at_1mm, 3.015e-3, horizon_ratio * dx, law.m2);
  return law;
}

int run_b2(KinkRun run, double alpha_deg, double a2_at_1mm, const std::filesystem::path& out_dir) {
  run.dx = compact_tension_shear_grid_spacing(CompactTensionShearSpec{}, run.dx);  // printed
  run.law = b2_law_params(run.dx, a2_at_1mm, run.horizon_ratio);
  const double pi = std::numbers::pi;
  run.alpha = alpha_deg * pi / 180;
  char name[64];
  std::snprintf(name, sizeof name, "b2_alpha%g.csv", alpha_deg);
  run.snapshot_csv = (out_dir / name).string();
  const KinkResult r = run_compact_tension_shear(run);
  if (!r.failure.empty()) {
    std::fprintf(stderr, "B2 (dx = %g m): %s\n", run.dx, r.failure.c_str());
    return 1;
  }
  const bool loaded_lower = !run.lower_holes_fixed;
  core::JsonLine line;
  line["case"] = "B2";
  line["model"] = run.model == model::ModelKind::bond_based ? "bond_based" : "state_based";
  line["law"] = run.fatigue_law == fatigue::FatigueLaw::energy ? "energy" : "strain_range";
  line["lower_holes"] = loaded_lower ? "loaded" : "fixed";
  line["pin_forces"] = run.rigid_fixtures ? "rigid_fixture" : "eq51";
  line["compressed_bonds_fatigue"] = run.compressed_bonds_fatigue;
  line["alpha_deg"] = core::fixed(alpha_deg, 2);
  line["beta_deg"] = core::fixed(r.beta * 180 / pi, 2);
  line["kii_over_ki"] = core::fixed(r.kii_over_ki, 4);
  line["t_over_ki"] = core::significant(r.t_over_ki, 4);
  line["kii_over_ki_fit"] = core::fixed(r.kii_over_ki_fit, 4);
  line["t_over_ki_fit"] = core::fixed(r.t_over_ki_fit, 4);
  line["ki_over_richard"] = core::fixed(r.ki_over_richard, 4);
  line["kii_over_richard"] = core::fixed(r.kii_over_richard, 4);
  line["mts_beta_deg"] = core::fixed(r.mts_beta * 180 / pi, 2);
  line["growth_m"] = core::fixed(r.growth, 4);
  line["cycles"] = static_cast<long long>(r.cycles);
  line["dx_m"] = core::significant(run.dx, 6);
  line["horizon_ratio"] = core::significant(run.horizon_ratio, 4);
  line["phase_switch_damage"] = core::fixed(r.phase_switch_damage, 3);
  line["grid_perturbation"] = core::fixed(run.grid.amplitude, 3);
  line["grid_seed"] = static_cast<unsigned long long>(run.grid.seed);
  line["wall_s"] = core::fixed(r.wall_s, 1);
  line["snapshot"] = run.snapshot_csv;
  core::print_line(line);
  return 0;
}

int run_b2_k_field(KFieldRun run, double a2_at_1mm, const std::filesystem::path& out_dir) {
  run.law = b2_law_params(run.dx, a2_at_1mm);
  char name[96];
  std::snprintf(name, sizeof name, "b2_k_field_%g_t%g_p%g.csv", run.kii_over_ki, run.t_over_ki,
                run.grid.amplitude);
  run.snapshot_csv = (out_dir / name).string();
  const KinkResult r = run_k_field_plate(run);
  if (!r.failure.empty()) {
    std::fprintf(stderr, "B2 K field (dx = %g m): %s\n", run.dx, r.failure.c_str());
    return 1;
  }
  const double deg = 180 / std::numbers::pi;
  core::JsonLine line;
  line["case"] = "B2-K-field";
  line["kii_over_ki_applied"] = core::fixed(run.kii_over_ki, 4);
  line["t_over_ki"] = core::significant(run.t_over_ki, 4);
  line["beta_deg"] = core::fixed(r.beta * deg, 2);
  line["kii_over_ki"] = core::fixed(r.kii_over_ki, 4);
  line["t_over_ki_measured"] = core::significant(r.t_over_ki, 4);
  line["kii_over_ki_fit"] = core::fixed(r.kii_over_ki_fit, 4);
  line["t_over_ki_fit"] = core::fixed(r.t_over_ki_fit, 4);
  line["mts_beta_deg"] = core::fixed(r.mts_beta * deg, 2);
  line["growth_m"] = core::fixed(r.growth, 4);
  line["cycles"] = static_cast<long long>(r.cycles);
  line["dx_m"] = core::significant(run.dx, 6);
  line["grid_perturbation"] = core::fixed(run.grid.amplitude, 3);
  line["grid_seed"] = static_cast<unsigned long long>(run.grid.seed);
  line["wall_s"] = core::fixed(r.wall_s, 1);
  line["snapshot"] = run.snapshot_csv;
  core::print_line(line);
  return 0;
}

int run_b3(double dx, bool limit, const std::filesystem::path& out_dir, double max_cycles) {
  // P_max at a0 giving ΔK ≈ 20 MPa·√m (000 Eq. A2), the ΔK of 002 Eq. (13); the load then follows
  // the crack to hold that ΔK, and after the entry into the hole follows 002 Sec. 7's protocol
  // (run_ct_with_hole, HoleProtocol).
  const double p_max = 5500;
  const auto prefix = (out_dir / (limit ? "b3_limit" : "b3_no_limit")).string();
  const double a2 = calibrate_b3_a2(dx, p_max, 1000.0, 0.002);
  std::fprintf(stderr, "B3: A2 calibrated to %.6g per cycle\n", a2);
  const auto r =
      run_ct_with_hole(dx, p_max, limit, a2, prefix, static_cast<std::int64_t>(max_cycles));
  for (const auto& e : r.events) {
    core::JsonLine line;
    line["case"] = "B3";
    line["propagation_limit"] = limit;
    line["event"] = e.what;
    line["cycle"] = static_cast<long long>(e.cycle);
    line["x_m"] = core::fixed(e.where.x, 5);
    line["y_m"] = core::fixed(e.where.y, 5);
    line["p_max"] = core::fixed(e.p_max, 1);
    line["eps_inf_prop"] = core::significant(e.eps_inf_prop, 4);
    core::print_line(line);
  }
  for (const auto& [when, d] : {std::pair{"entry", r.entry}, std::pair{"settled", r.settled}}) {
    core::JsonLine line;
    line["case"] = "B3";
    line["propagation_limit"] = limit;
    line["race"] = when;
    line["old_path_max_range"] = core::significant(d.old_path_max_range, 4);
    line["old_path_min_life"] = core::significant(d.old_path_min_life, 4);
    line["old_path_cycles_no_limit"] = core::significant(d.old_path_cycles, 4);
    line["old_path_cycles_limited"] = core::significant(d.old_path_cycles_limited, 4);
    line["far_side_max_range"] = core::significant(d.far_side_max_range, 4);
    line["far_side_cycles"] = core::significant(d.far_side_cycles, 4);
    core::print_line(line);
  }
  core::JsonLine line;
  line["case"] = "B3";
  line["propagation_limit"] = limit;
  line["cycles"] = static_cast<long long>(r.cycles);
  line["broken_bonds"] = static_cast<long long>(r.broken_bonds);
  line["breaks_old_path"] = static_cast<long long>(r.breaks_old_path);
  line["breaks_far_side"] = static_cast<long long>(r.breaks_far_side);
  line["breaks_other"] = static_cast<long long>(r.breaks_other);
  line["a2"] = core::significant(a2, 6);
  line["delta_k"] = core::significant(r.delta_k, 4);
  line["eps_bar"] = core::significant(r.eps_bar, 4);
  line["eps_inf_prop"] = core::significant(r.eps_inf_prop, 4);
  line["p_entry"] = core::fixed(r.p_entry, 1);
  line["p_final"] = core::fixed(r.p_final, 1);
  line["dx_m"] = core::significant(dx, 6);
  line["wall_s"] = core::fixed(r.wall_s, 1);
  line["snapshots"] = prefix + "_*.csv";
  core::print_line(line);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-validate: benchmark validations as JSON lines"};
  std::string which = "B1";
  double dx = 0.001;
  double a2_trial = 1055;
  int iterations = 2;
  std::string out = "results/validation";
  app.add_option("--case", which, "B1 | B2 | B3 | B4 | B5 | B6 | B7 | C1 | D1 | D2 | D3 | D4")
      ->check(
          CLI::IsMember({"B1", "B2", "B3", "B4", "B5", "B6", "B7", "C1", "D1", "D2", "D3", "D4"}));
  validation::B5RunOptions b5;
  app.add_option("--b5-loading", b5.loadings, "B5: all | symmetric | pol | pul")
      ->check(CLI::IsMember({"all", "symmetric", "pol", "pul"}));
  app.add_option("--b5-model", b5.models, "B5: all | conventional | modified")
      ->check(CLI::IsMember({"all", "conventional", "modified"}));
  app.add_option("--b5-points", b5.points_across, "B5: points across the 5 mm gauge (004: 17)")
      ->check(CLI::Range(5, 65));
  app.add_option("--psi", b5.psi, "B5: ψ of 004 Eq. (26) in m^3 (default 1.85e-28)")
      ->check(peritwin::core::finite_in(0.0, 1e-20));
  app.add_option("--k-u", b5.k_u, "B5: k_U of 004 step 6 (default 1.2)")
      ->check(peritwin::core::finite_in(0.1, 10.0));
  app.add_flag("--b5-own-loops", b5.own_loops,
               "B5: the modified model with each bond's own loop area, not 004's measured ones");
  int b6_law = 0;
  double b6_m = 3.0, b6_horizon = 3.75e-4, b6_coefficient = 0.0;
  std::int64_t b6_dn = 1000;
  bool quick = false;
  double b7_ratio = 0.0;
  int b6_only_law = 0;
  std::string b6_plot_from;
  app.add_option("--plot-from", b6_plot_from,
                 "B6: draw OUT/b6_slopes.png from these JSON lines instead of running");
  app.add_option("--only-law", b6_only_law, "B6: the study of this law alone (1, 2, 3)")
      ->check(CLI::Range(1, 3));
  app.add_option("--g-over-gc", b7_ratio, "B7: run this G/Gc alone")
      ->check(peritwin::core::finite_in(0.01, 1.0));
  app.add_option("--b6-law", b6_law, "B6: run one configuration with this law (1, 2, 3)")
      ->check(CLI::Range(1, 3));
  app.add_option("--b6-m", b6_m, "B6 single: horizon ratio m")->check(CLI::Range(1.5, 6.0));
  app.add_option("--b6-dn", b6_dn, "B6 single: cycle increment")->check(CLI::Range(1, 1000000));
  app.add_option("--b6-horizon", b6_horizon, "B6 single: horizon (m)")
      ->check(peritwin::core::finite_in(1e-5, 1e-2));
  app.add_option("--b6-coefficient", b6_coefficient, "B6 single: the law's A, C or B")
      ->check(peritwin::core::finite_positive());
  app.add_flag("--quick", quick, "B6, B7: the short versions (coarse grid) the tests run");
  std::string c1_ct = PERITWIN_EXAMPLES_DIR "/b1-ct-al6061.toml";
  std::string c1_panel = PERITWIN_EXAMPLES_DIR "/mt-panel-al6061.toml";
  app.add_option("--ct-config", c1_ct, "C1: the CT detail (default the demo's B1)");
  app.add_option("--panel-config", c1_panel,
                 "C1: the middle-crack panel (default examples/mt-panel-al6061.toml; \"\" = none)");
  int threads = 2;
  app.add_option("--threads", threads, "D1, D3, D4: bond-force threads")->check(CLI::Range(1, 64));
  bool no_limit = false;
  double max_cycles = 5e6;
  app.add_flag("--no-propagation-limit", no_limit, "B3: without 002 Eq. (12)");
  app.add_option("--max-cycles", max_cycles, "B3: stop after this many cycles")
      ->check(peritwin::core::finite_in(1.0, 1e12));
  double alpha = 45;
  double a2_at_1mm = 1301;
  double growth = 0.010;
  app.add_option("--alpha", alpha, "B2: load angle (degrees, 0 <= alpha < 90)")
      ->check(peritwin::core::finite_in(0.0, 89.999));
  app.add_option("--a2", a2_at_1mm, "B2: A2 calibrated on B1 at dx = 1 mm")
      ->check(peritwin::core::finite_positive());
  // Default: the lower holes carry the point reflection of the upper forces, as Richard's device
  // does. Fixed lower holes (the benchmarks README) break the CTS's half-turn symmetry: at α = 0
  // they give K_II/K_I = −0.13 and β = 13.6° where the specimen is in pure mode I (loaded: 0.02,
  // 0.0°), and at 45° K_II/K_I = 0.62 against Richard's 0.495 (loaded: 0.466).
  std::string lower_holes = "loaded";
  app.add_option("--lower-holes", lower_holes,
                 "B2: loaded (mirrored forces, default) | fixed (benchmarks README)")
      ->check(CLI::IsMember({"loaded", "fixed"}));
  app.add_flag_callback(
      "--loaded-lower-holes", [&] { lower_holes = "loaded"; }, "B2: same as --lower-holes loaded");
  std::string pin_forces = "eq51";
  app.add_option("--pin-forces", pin_forces,
                 "B2: eq51 (each pin its 000 Eq. 51 force, default) | rigid-fixture (the pins of "
                 "each half joined by a rigid loading fixture, as in Richard's device)")
      ->check(CLI::IsMember({"eq51", "rigid-fixture"}));
  app.add_option("--growth", growth, "B2: crack growth at which beta is measured (m)")
      ->check(peritwin::core::finite_in(1e-4, 0.04));
  KinkRun b2;
  app.add_flag_callback(
      "--tension-only-fatigue", [&] { b2.compressed_bonds_fatigue = false; },
      "B2: only bonds in tension at P_max fatigue (000 Eq. 15 takes |s|: compressed ones too)");
  std::string b2_law = "energy";
  app.add_option("--law", b2_law, "B2: energy (000 Sec. 6.2) | strain_range")
      ->check(CLI::IsMember({"energy", "strain_range"}));
  mesh::GridPerturbation& grid = b2.grid;
  app.add_option("--grid-perturbation", grid.amplitude,
                 "B2: move each node off its grid point by up to this fraction of dx")
      ->check(peritwin::core::finite_in(0.0, 0.249));
  app.add_option("--grid-seed", grid.seed, "B2: seed of the grid perturbation");
  std::string b2_model = "state_based";
  app.add_option("--model", b2_model,
                 "B2: state_based (000 Sec. 6.2) | bond_based (nu = 1/3, about 6x faster)")
      ->check(CLI::IsMember({"state_based", "bond_based"}));
  app.add_option("--phi0", b2.phase_switch_damage,
                 "B2: phase-switch damage (default: a straight split's damage at the horizon)")
      ->check(peritwin::core::finite_in(0.01, 0.99));
  app.add_option("--horizon-ratio", b2.horizon_ratio,
                 "B2: horizon over grid spacing (default 3.015; 000 Fig. 15 compares 2, 3, 4)")
      ->check(peritwin::core::finite_in(1.5, 6.0));
  KFieldRun k_field;
  auto* k_field_option =
      app.add_option("--k-field", k_field.kii_over_ki,
                     "B2: instead of the CTS, a square plate under the tractions of a pure "
                     "near-tip field with this |K_II|/K_I")
          ->check(peritwin::core::finite_in(0.0, 10.0));
  app.add_option("--t-over-ki", k_field.t_over_ki, "B2 --k-field: T-stress over K_I (1/sqrt(m))")
      ->check(peritwin::core::finite_in(-1e3, 1e3));
  auto* dx_option = app.add_option("--dx", dx, "grid spacing (m); default 1 mm, B3 0.25 mm")
                        ->check(peritwin::core::finite_in(1e-5, 0.01));
  app.add_option("--a2-trial", a2_trial, "B1: trial A2 for the calibration")
      ->check(peritwin::core::finite_positive());
  app.add_option("--iterations", iterations, "B1: calibration iterations")
      ->check(CLI::Range(1, 10));
  app.add_option("--out", out, "directory for CSV output");
  CLI11_PARSE(app, argc, argv);
  std::filesystem::create_directories(out);
  if (which == "B1") return run_b1(dx, out, a2_trial, iterations);
  const fatigue::FatigueLaw b2_fatigue_law =
      b2_law == "energy" ? fatigue::FatigueLaw::energy : fatigue::FatigueLaw::strain_range;
  if (which == "B2" && k_field_option->count() > 0) {
    k_field.dx = dx_option->count() > 0 ? dx : 0.0005;
    k_field.growth = growth;
    k_field.fatigue_law = b2_fatigue_law;
    k_field.grid = grid;
    return run_b2_k_field(k_field, a2_at_1mm, out);
  }
  if (which == "B2") {
    b2.dx = dx;
    b2.growth = growth;
    b2.lower_holes_fixed = lower_holes == "fixed";
    b2.rigid_fixtures = pin_forces == "rigid-fixture";
    b2.fatigue_law = b2_fatigue_law;
    b2.model =
        b2_model == "bond_based" ? model::ModelKind::bond_based : model::ModelKind::state_based;
    return run_b2(b2, alpha, a2_at_1mm, out);
  }
  // B3's default is finer: at 0.5 mm the grid's step where the path turns into the hole leaves a
  // strain range above ε̃∞ and both settings grow 002 Fig. 9's crack; at 0.25 mm they part as in
  // Figs. 9-10 (docs/validation.md).
  if (which == "B3")
    return run_b3(dx_option->count() > 0 ? dx : 0.00025, !no_limit, out, max_cycles);
  if (which == "B4") return validation::run_b4();
  if (which == "B5") return validation::run_b5(b5, out);
  if (which == "B6" && b6_law > 0) {
    return validation::run_b6_single(b6_law, b6_m, b6_dn, b6_horizon, b6_coefficient, max_cycles);
  }
  if (which == "B6" && !b6_plot_from.empty()) {
    return validation::plot_b6_slopes(b6_plot_from, out + "/b6_slopes.png");
  }
  if (which == "B6") return validation::run_b6(out, quick, b6_only_law);
  if (which == "B7") return validation::run_b7(out, quick, b7_ratio);
  if (which == "C1") return validation::run_c1_compression(c1_ct, c1_panel, out);
  if (which == "D1") return validation::run_d1(out, threads);
  if (which == "D2") return validation::run_d2(out);
  if (which == "D3") return validation::run_d3(out, threads);
  if (which == "D4") return validation::run_d4(out, threads, dx_option->count() > 0 ? dx : 0.0);
  return 2;
}
