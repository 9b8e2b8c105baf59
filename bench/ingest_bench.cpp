// peritwin-bench-ingest: how fast the daemon absorbs load cycles over LCM when no bond breaks.
//
// Starts LCM's Java TCP hub on a free loopback port (unless --lcm-url is given), runs the daemon
// service (service/daemon.h) on its own thread and LCM connection, and feeds it with the
// replay client (replay/replay_tool.h, lockstep off) histories of single-cycle blocks at loads far
// too low to break a bond (P_max cycling over 200..350 N, R = 0.1), batched as peritwin-replay
// batches them (1024 blocks or 1000 cycles per batch), after a one-batch lockstep warm-up:
//  1. latency phase: `--latency-cycles` with `--latency-window` (2) batches in flight — a
//     producer the daemon keeps up with, as sensors are;
//  2. throughput phase: `--cycles` with `--window` (64) batches in flight — the daemon saturated.
// Remaining-life estimates and checkpoints are off; results (HDF5 rows) are written unless
// --no-results. Prints one JSON line:
//   {"bench":"ingest","cycles_per_s":…,"p50_ms":…,"p99_ms":…,"latency_window":…,
//    "saturated_p50_ms":…,"saturated_p99_ms":…,"window":…,"batches":…,"cycles":…,
//    "blocks_per_batch":…,"broken_bonds":…,"transport":"tcpq","results":…,"resends":…}
// cycles_per_s: cycles of phase 2 / time from its first publish to the STATE showing its last
// batch applied. Latency: LCM's receive time of a batch at the daemon -> its STATE publish, which
// includes the wait in the daemon's inbox (p50/p99 of phase 1; saturated_* of phase 2, where it is
// mostly the queue of `window` batches).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "core/json_line.h"
#include "core/loopback_port.h"
#include "core/program.h"
#include "replay/replay_tool.h"
#include "service/daemon.h"

extern char** environ;

namespace {

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

using namespace peritwin;

/// The command line.
struct Options {
  std::string config_file = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml";
  std::string lcm_url;
  std::int64_t cycles = 1'000'000;
  std::size_t window = 64;
  std::int64_t latency_cycles = 100'000;
  std::size_t latency_window = 2;
  bool no_results = false;
  loads::BatchingOptions batching;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--config", o.config_file, "detail configuration (default: the B1 example)");
  app.add_option("--cycles", o.cycles, "single-cycle blocks to send (default 1000000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--window", o.window, "batches in flight in the throughput phase (default 64)")
      ->check(CLI::PositiveNumber);
  app.add_option("--latency-cycles", o.latency_cycles,
                 "single-cycle blocks of the latency phase (default 100000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--latency-window", o.latency_window,
                 "batches in flight in the latency phase (default 2)")
      ->check(CLI::PositiveNumber);
  app.add_option("--lcm-url", o.lcm_url, "use this LCM URL instead of starting a hub");
  app.add_flag("--no-results", o.no_results, "do not write the HDF5 results");
  app.add_option("--batch-blocks", o.batching.max_blocks, "blocks per batch at most")
      ->check(CLI::PositiveNumber);
  app.add_option("--batch-cycles", o.batching.max_cycles, "cycles per batch at most")
      ->check(CLI::PositiveNumber);
}

/// LCM's Java TCP hub on a free loopback port, `lcm_url` set to it; -1 (said on stderr) when it
/// does not come up.
pid_t start_hub(std::string& lcm_url) {
  pid_t hub = -1;
  const int port = core::free_loopback_port();
  const std::string port_text = std::to_string(port);
  const char* args[] = {
      "java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", port_text.c_str(), nullptr};
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  if (posix_spawnp(&hub, "java", &actions, nullptr, const_cast<char**>(args), environ) != 0) {
    std::cerr << "peritwin-bench-ingest: cannot start java (LCM hub)\n";
    return -1;
  }
  posix_spawn_file_actions_destroy(&actions);
  if (!core::wait_for_loopback_port(port, 30.0)) {
    std::cerr << "peritwin-bench-ingest: the LCM hub did not come up on port " << port << '\n';
    kill(hub, SIGTERM);
    waitpid(hub, nullptr, 0);
    return -1;
  }
  lcm_url = "tcpq://127.0.0.1:" + port_text;
  return hub;
}

/// What the producer side measured.
struct Phases {
  replay::ReplayResult result, latency_result;
  double seconds = 0.0;
  std::size_t num_latency_batches = 0, num_batches = 0;
};

/// The warm-up batch, the latency phase and the throughput phase, over their own LCM.
Phases run_phases(const Options& o, const std::string& detail_id) {
  auto history = [&](std::int64_t n, const char* source) {
    std::vector<core::LoadBlock> blocks;
    for (std::int64_t i = 0; i < n; ++i) {
      blocks.push_back({200.0 + 50.0 * static_cast<double>(i % 4), 0.1, 0.0, 1});
    }
    return loads::make_twin_batches(blocks, detail_id, source, o.batching);
  };
  auto latency_batches = history(o.latency_cycles, "bench-latency");
  auto batches = history(o.cycles, "bench");
  Phases out;
  out.num_latency_batches = latency_batches.size();
  out.num_batches = batches.size();
  lcm::LCM lcm(o.lcm_url);
  // Warm-up: one batch of another source in lockstep, so that both LCM clients are known to
  // the hub (a fresh subscription is registered asynchronously) before the clock starts.
  loads::ReplayOptions warm_options;
  warm_options.lockstep = true;
  warm_options.resend_after_s = 0.5;
  replay::LcmReplayer warm_up(
      lcm, loads::make_twin_batches({{200.0, 0.1, 0.0, 1}}, detail_id, "warm-up", o.batching),
      warm_options);
  if (!warm_up.run({}, {}).ok) {
    std::cerr << "peritwin-bench-ingest: no answer from the daemon\n";
  }
  // Latency phase: a producer that keeps `latency_window` batches in flight, so that the
  // latency is the daemon's and not a queue the benchmark builds on purpose.
  loads::ReplayOptions latency_options;
  latency_options.window = o.latency_window;
  replay::LcmReplayer latency_replayer(lcm, std::move(latency_batches), latency_options);
  out.latency_result = latency_replayer.run({}, {});
  // Throughput phase: `window` batches in flight; the daemon is saturated.
  loads::ReplayOptions options;
  options.window = o.window;
  replay::LcmReplayer replayer(lcm, std::move(batches), options);
  const auto t0 = std::chrono::steady_clock::now();
  out.result = replayer.run({}, {});
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

/// The JSON line: `latencies` in order of application (the warm-up batch, the latency phase,
/// the throughput phase).
core::JsonLine ingest_line(const Options& o, const Phases& p, const std::vector<double>& latencies,
                           std::int64_t broken) {
  const auto first = std::min<std::size_t>(1, latencies.size());
  const auto split = std::min(latencies.size(), first + p.num_latency_batches);
  const std::vector<double> paced(latencies.begin() + static_cast<std::ptrdiff_t>(first),
                                  latencies.begin() + static_cast<std::ptrdiff_t>(split));
  const std::vector<double> saturated(latencies.begin() + static_cast<std::ptrdiff_t>(split),
                                      latencies.end());
  core::JsonLine line;
  line["bench"] = "ingest";
  line["cycles_per_s"] = core::fixed(static_cast<double>(o.cycles) / p.seconds, 1);
  line["p50_ms"] = core::fixed(1e3 * percentile(paced, 0.50), 3);
  line["p99_ms"] = core::fixed(1e3 * percentile(paced, 0.99), 3);
  line["latency_window"] = o.latency_window;
  line["saturated_p50_ms"] = core::fixed(1e3 * percentile(saturated, 0.50), 3);
  line["saturated_p99_ms"] = core::fixed(1e3 * percentile(saturated, 0.99), 3);
  line["window"] = o.window;
  line["batches"] = p.num_batches;
  line["cycles"] = static_cast<long long>(o.cycles);
  line["blocks_per_batch"] =
      static_cast<std::size_t>(o.cycles) / std::max<std::size_t>(1, p.num_batches);
  line["broken_bonds"] = static_cast<long long>(broken);
  line["transport"] = "tcpq";
  line["results"] = !o.no_results;
  line["resends"] = static_cast<long long>(p.result.rewinds + p.latency_result.rewinds);
  return line;
}

/// The benchmark; the exit code.
int run(Options o) {
  spdlog::set_level(spdlog::level::warn);
  auto loaded = config::load_config(o.config_file);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return 2;
  }
  config::TwinConfig config = *loaded.config;
  config.details.resize(1);
  config::DetailConfig& detail = config.details[0];
  detail.life.every_batches = 0;
  detail.checkpoint = {0, 0.0};
  detail.output.field_every_batches = 0;
  const auto work = std::filesystem::temp_directory_path() /
                    ("peritwin_bench_ingest_" + std::to_string(getpid()));
  detail.output.directory = (work / "results").string();

  pid_t hub = -1;
  if (o.lcm_url.empty() && (hub = start_hub(o.lcm_url)) < 0) return 3;
  auto stop_hub = [&] {
    if (hub > 0) {
      kill(hub, SIGTERM);
      waitpid(hub, nullptr, 0);
    }
    std::filesystem::remove_all(work);
  };

  // The daemon on its own thread and LCM connection.
  std::atomic<bool> ready{false}, stop{false}, failed{false};
  std::vector<double> latencies;
  std::int64_t broken = -1;
  std::thread daemon_thread([&] {
    lcm::LCM lcm(o.lcm_url);
    service::DaemonOptions options;
    options.state_dir = work / "state";
    options.checkpoints = false;
    options.results = !o.no_results;
    options.record_latency = true;
    service::Daemon daemon(lcm, config, options);
    const core::Status started =
        lcm.good() ? daemon.start() : core::Status{core::failure("LCM is not good")};
    if (!started) {
      std::cerr << "peritwin-bench-ingest: daemon: " << started.error().message() << "\n";
      failed = true;
      ready = true;
      return;
    }
    ready = true;
    while (!stop) daemon.poll(20);
    latencies = daemon.latencies();
    broken = daemon.twin(0).broken_bonds();
    daemon.stop();
  });
  while (!ready) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  if (failed) {
    daemon_thread.join();
    stop_hub();
    return 3;
  }
  const Phases phases = run_phases(o, detail.id);
  stop = true;
  daemon_thread.join();
  stop_hub();
  if (!phases.latency_result.ok || !phases.result.ok) {
    std::cerr << "peritwin-bench-ingest: " << phases.latency_result.error << " "
              << phases.result.error << "\n";
    return 3;
  }
  core::print_line(ingest_line(o, phases, latencies, broken));
  return broken == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-ingest: load cycles absorbed per second by the daemon over tcpq"};
  Options o;
  add_options(app, o);
  if (const auto rc = core::parse_options(app, argc, argv, core::ParseErrors::cli11)) return *rc;
  return run(std::move(o));
}
