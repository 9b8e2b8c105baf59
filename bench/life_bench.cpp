// peritwin-bench-life (also `peritwin-bench life`): the cost of one remaining-life estimate
// (issue 18 item 3; goal: <= 60 s at 60k nodes).
//
// The detail is the B1 example (examples/b1-ct-al6061.toml) at the dx that gives about --nodes
// nodes, its A2 (calibrated at dx = 1 mm) rescaled to the horizon by 000 Eq. (29), its life
// criterion 8 mm of crack growth (--critical-length) under the reference spectrum (4 kN, R 0.1).
// A live engine is run at the reference load until the crack has grown --start-growth (exactly:
// a stop check after every group of breaks); from that state the estimate (central and the band
// A2·(1 ± 0.2), three forward simulations, concurrent unless --sequential) is made the way
// `--modes` lists:
//   fork    — each simulation continues from a copy of the live engine (FatigueEngine::fork);
//   rebuild — each simulation builds a fresh engine and imports the state (the path before
//             FatigueEngine::fork: first factorization, rebuild, replay of the re-solves);
//   coarse  — the estimate on a coarser grid of spacing --coarse-dx (twin/coarse_life.h:
//             the crack mapped, A2 calibrated to the fine model's recent growth), with
//             coarse_over_fine the ratio of its central life to the fine one's.
// With both, `identical` says whether the two gave the same three lives bit for bit.
// One JSON line:
//   {"bench":"life","nodes":…,"bonds":…,"dx_m":…,"model_build_s":…,"start":{"cycles":…,
//    "broken_bonds":…,"crack_length_m":…,"resolves":…,"live_s":…},"snapshot_fork_s":…,
//    "fork":{"wall_s":…,"rss_peak_mb":…,"central":…,"low":…,"high":…,"simulations":[{"a2_factor":…,
//    "build_s":…,"import_s":…,"fork_s":…,"stepping_s":…,"wall_s":…,"breaks":…,"updates":…},…]},
//    "rebuild":{…},"identical":…,"peak_rss_mb":…}
// Peak RSS per mode: VmHWM reset (/proc/self/clear_refs) before the mode, read after it; it
// includes the live engine (one factor) that stays in memory throughout, as in the daemon.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/cli_checks.h"
#include "core/json_line.h"
#include "core/proc_files.h"
#include "solver/fatigue/laws/strain_range.h"
#include "twin/coarse_life.h"
#include "twin/detail_model.h"
#include "twin/life.h"

namespace {

using namespace peritwin;
using namespace peritwin::twin;

void reset_peak_rss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Options {
  double nodes = 15000;
  double start_growth = 0.002;
  double critical_length = 0.008;
  std::string modes = "fork,rebuild";
  bool sequential = false;
  double coarse_dx = 0.0;
};

core::JsonLine run_coarse(const DetailModel& model, const fatigue::EngineState& state,
                          const std::vector<core::LoadBlock>& spectrum, double dx, bool sequential,
                          LifeEstimate& estimate) {
  reset_peak_rss();
  CoarseLifeReport rep;
  estimate = estimate_life_coarse(model, dx, state, spectrum, !sequential, nullptr, &rep);
  core::JsonLine out;
  out["dx_m"] = dx;
  out["wall_s"] = core::fixed(estimate.wall_s, 2);
  out["rss_peak_mb"] = core::fixed(core::proc_status_mb("VmHWM"), 1);
  out["central"] = core::whole(estimate.central);
  out["low"] = core::whole(estimate.low);
  out["high"] = core::whole(estimate.high);
  out["nodes"] = rep.coarse_nodes;
  out["bonds"] = static_cast<long long>(rep.coarse_bonds);
  out["mapped_bonds"] = static_cast<long long>(rep.mapped_bonds);
  out["fine_length_m"] = core::significant(rep.fine_length, 4);
  out["start_length_m"] = core::significant(rep.coarse_start_length, 4);
  out["critical_length_m"] = core::significant(rep.coarse_critical_length, 4);
  out["window_growth_m"] = core::significant(rep.window_growth, 4);
  out["fine_window_cycles"] = core::whole(rep.fine_window_cycles);
  out["coarse_window_cycles"] = core::whole(rep.coarse_window_cycles);
  out["a2_factor"] = core::significant(rep.a2_factor, 4);
  out["calibration_runs"] = rep.calibration_runs;
  out["calibrated"] = rep.calibrated;
  out["build_s"] = core::fixed(rep.build_s, 3);
  out["map_s"] = core::fixed(rep.map_s, 3);
  out["calibrate_s"] = core::fixed(rep.calibrate_s, 3);
  out["simulate_s"] = core::fixed(rep.simulate_s, 3);
  return out;
}

core::JsonLine run_mode(const DetailModel& model, const fatigue::FatigueEngine& live,
                        const fatigue::EngineState& state,
                        const std::vector<core::LoadBlock>& spectrum, bool fork, bool sequential,
                        LifeEstimate& estimate) {
  reset_peak_rss();
  std::vector<SimulationStats> stats;
  estimate =
      estimate_life(model, state, spectrum, !sequential, nullptr, fork ? &live : nullptr, &stats);
  core::JsonLine out;
  out["wall_s"] = core::fixed(estimate.wall_s, 2);
  out["rss_peak_mb"] = core::fixed(core::proc_status_mb("VmHWM"), 1);
  out["central"] = core::whole(estimate.central);
  out["low"] = core::whole(estimate.low);
  out["high"] = core::whole(estimate.high);
  const double s = model.config().life.a2_relative_scatter;
  const double factors[3] = {1.0, 1 + s, 1 - s};
  out["simulations"] = core::JsonLine::array();
  for (std::size_t i = 0; i < stats.size(); ++i) {
    core::JsonLine sim;
    sim["a2_factor"] = factors[i];
    sim["build_s"] = core::fixed(stats[i].build_s, 3);
    sim["import_s"] = core::fixed(stats[i].import_s, 3);
    sim["fork_s"] = core::fixed(stats[i].fork_s, 3);
    sim["stepping_s"] = core::fixed(stats[i].stepping_s, 3);
    sim["wall_s"] = core::fixed(stats[i].wall_s, 3);
    sim["breaks"] = static_cast<long long>(stats[i].breaks);
    sim["updates"] = stats[i].updates;
    out["simulations"].push_back(sim);
  }
  return out;
}

int run(const Options& o) {
  config::ConfigLimits limits;
  limits.max_memory_bytes = UINT64_MAX;
  auto loaded =
      config::load_config(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml", limits);
  if (!loaded.ok()) {
    std::fprintf(stderr, "peritwin-bench life: %s\n", loaded.error_text().c_str());
    return 3;
  }
  config::DetailConfig config = loaded.config->details.at(0);
  // B1 is 62.5 mm x 60 mm: nodes ~ 3750 mm^2 / dx^2 (as the fleet bench).
  const double dx = std::sqrt(0.0625 * 0.060 / o.nodes);
  const double dx0 = config.dx;
  config.dx = dx;
  auto& strain = config.fatigue.strain;
  strain.A2 = fatigue::a2_scaled(strain.A2, config.horizon_ratio * dx0, config.horizon_ratio * dx,
                                 strain.m2);  // 000 Eq. (29)
  config.life.critical_crack_length = o.critical_length;
  auto t0 = std::chrono::steady_clock::now();
  auto built = DetailModel::build(config);
  if (!built) {
    std::fprintf(stderr, "peritwin-bench life: %s\n", built.error().message().c_str());
    return 3;
  }
  const DetailModel& model = **built;
  const double build_s = seconds_since(t0);
  const std::vector<core::LoadBlock> spectrum = config.life.reference_spectrum;

  // The live engine, run at the reference load until the crack has grown start_growth.
  t0 = std::chrono::steady_clock::now();
  const auto live = model.make_engine();
  if (!live->initialize()) {
    std::fprintf(stderr, "peritwin-bench life: %s\n", live->failure_reason().c_str());
    return 3;
  }
  const auto length = [&](const fatigue::FatigueEngine& e) {
    return criterion_crack_length(model, e.node_damage(), e.solver().intact());
  };
  const fatigue::FatigueEngine::StopCheck grown = [&](const fatigue::FatigueEngine& e) {
    return length(e) >= o.start_growth || end_of_life(model, e) != Failure::none;
  };
  while (length(*live) < o.start_growth) {
    if (live->apply(spectrum.front(), grown) == fatigue::EngineStatus::final_failure) {
      std::fprintf(stderr, "peritwin-bench life: final failure before the start growth\n");
      return 3;
    }
  }
  const double live_s = seconds_since(t0);
  const double live_peak_mb = core::proc_status_mb("VmHWM");  // build and live run
  const fatigue::EngineState state = live->export_state();

  core::JsonLine line;
  line["bench"] = "life";
  line["nodes"] = model.disc().num_nodes();
  line["bonds"] = model.disc().num_bonds();
  line["dx_m"] = core::significant(dx, 4);
  line["a2"] = core::significant(strain.A2, 6);
  line["critical_length_m"] = o.critical_length;
  line["model_build_s"] = core::fixed(build_s, 2);
  core::JsonLine start;
  start["cycles"] = static_cast<long long>(state.total_cycles);
  start["broken_bonds"] = static_cast<long long>(live->broken_bonds() - model.precut_bonds());
  start["crack_length_m"] = core::significant(length(*live), 4);
  start["resolves"] = static_cast<long long>(state.resolve_groups.size());
  start["rebuilds"] = live->rebuilds();
  start["live_s"] = core::fixed(live_s, 2);
  start["rss_peak_mb"] = core::fixed(live_peak_mb, 1);
  start["factor_nnz"] = core::whole(live->solver().factor().factor_nonzeros());
  line["start"] = start;
  // What the daemon's worker path adds on the ingest thread: one fork for the job's snapshot.
  t0 = std::chrono::steady_clock::now();
  { const auto snapshot = live->fork(model.engine_settings()); }
  line["snapshot_fork_s"] = core::fixed(seconds_since(t0), 3);
  line["sequential"] = o.sequential;

  LifeEstimate by_fork, by_rebuild;
  const bool fork = o.modes.find("fork") != std::string::npos;
  const bool rebuild = o.modes.find("rebuild") != std::string::npos;
  if (fork) line["fork"] = run_mode(model, *live, state, spectrum, true, o.sequential, by_fork);
  if (rebuild) {
    line["rebuild"] = run_mode(model, *live, state, spectrum, false, o.sequential, by_rebuild);
  }
  const bool coarse = o.modes.find("coarse") != std::string::npos;
  LifeEstimate by_coarse;
  if (coarse) {
    line["coarse"] = run_coarse(model, state, spectrum, o.coarse_dx, o.sequential, by_coarse);
    const LifeEstimate& fine = fork ? by_fork : by_rebuild;
    if (fork || rebuild) {
      line["coarse_over_fine"] = core::fixed(by_coarse.central / fine.central, 4);
    }
  }
  if (fork && rebuild) {
    line["identical"] = by_fork.central == by_rebuild.central && by_fork.low == by_rebuild.low &&
                        by_fork.high == by_rebuild.high;
  }
  double peak = live_peak_mb;
  for (const char* mode : {"fork", "rebuild", "coarse"}) {
    if (line.contains(mode)) peak = std::max(peak, line[mode]["rss_peak_mb"].get<double>());
  }
  line["peak_rss_mb"] = core::fixed(peak, 1);
  core::print_line(line);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench life: the wall time of one remaining-life estimate"};
  Options o;
  app.add_option("--nodes", o.nodes, "approximate number of nodes (B1 example)")
      ->check(peritwin::core::finite_in(500.0, 1e7));
  app.add_option("--start-growth", o.start_growth,
                 "crack growth (m) of the live state the estimate starts from (default 0.002)")
      ->check(peritwin::core::finite_in(0.0, 0.03));
  app.add_option("--critical-length", o.critical_length,
                 "the life criterion's crack length (m, default 0.008)")
      ->check(peritwin::core::finite_in(0.0005, 0.03));
  app.add_option("--modes", o.modes,
                 "comma-separated: fork, rebuild, coarse (needs --coarse-dx); default fork,rebuild")
      ->check([](const std::string& v) {
        std::stringstream list(v);
        std::string item;
        while (std::getline(list, item, ',')) {
          if (item != "fork" && item != "rebuild" && item != "coarse") {
            return "unknown mode \"" + item + "\" (fork, rebuild, coarse)";
          }
        }
        return std::string();
      });
  app.add_option("--coarse-dx", o.coarse_dx,
                 "grid spacing (m) of the coarse estimate model ([detail.life] dx) for mode coarse")
      ->check(peritwin::core::finite_in(0.0, 0.01));
  app.add_flag("--sequential", o.sequential,
               "the three simulations one after another (default: concurrently)");
  CLI11_PARSE(app, argc, argv);
  if ((o.modes.find("coarse") != std::string::npos) != (o.coarse_dx > 0)) {
    std::fprintf(stderr, "peritwin-bench life: mode coarse needs --coarse-dx and vice versa\n");
    return 2;
  }
  if (o.start_growth >= o.critical_length) {
    std::fprintf(stderr, "peritwin-bench life: --start-growth must be below --critical-length\n");
    return 2;
  }
  return run(o);
}
