// peritwin: the twin daemon. See README.md and twin/service/daemon.h.
//
//   peritwin --config detail.toml [--lcm-url URL] [--state-dir DIR] [--log-level L]
//            [--deterministic] [--no-results] [--fresh-start] [--max-memory BYTES]
//            [--details ID,ID,...] [--twin-check-seconds S]
//
// Exit codes: 0 clean stop (SIGTERM/SIGINT: checkpoint, results, exit), 2 bad usage or config
// (nothing started; also: another daemon's STATUS names one of its details, duplicate_twin.h), 3
// runtime failure (LCM, checkpoint or model I/O, an internal error while applying a batch; the last
// checkpoint is left as it was; checkpoints exist and none is valid, without --fresh-start; the
// state dir is not writable). A tcpq hub that is down is not a failure: the daemon waits for it and
// reconnects with backoff (twin/service/hub_connection.h).
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <iostream>

#include "messages/auth.h"
#include "twin/config/config.h"
#include "twin/service/daemon.h"
#include "twin/service/duplicate_twin.h"
#include "twin/service/hub_connection.h"

namespace {

std::atomic<int> g_signal{0};

extern "C" void on_signal(int signal) { g_signal.store(signal); }

constexpr int kExitOk = 0;
constexpr int kExitUsage = 2;
constexpr int kExitRuntime = 3;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin: structural-health-monitoring digital twin daemon (LCM in/out)"};
  std::string config_file, lcm_url, state_dir = "state", log_level = "info";
  bool deterministic = false, no_results = false, fresh_start = false;
  app.add_option("--config", config_file, "detail configuration (TOML)")->required();
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's default)");
  app.add_option("--state-dir", state_dir, "checkpoint directory (default: state)");
  app.add_option("--log-level", log_level, "trace|debug|info|warn|error|critical|off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  app.add_flag("--deterministic", deterministic,
               "remaining life synchronously at fixed state_seq points (reproducible outputs; "
               "use with a lockstep replay)");
  app.add_flag("--no-results", no_results, "write no HDF5 results or PNG pictures");
  app.add_flag("--fresh-start", fresh_start,
               "start from the virgin state when checkpoints exist but none is valid (by "
               "default the daemon then refuses to start, naming each file and why)");
  std::vector<std::string> served_details;
  app.add_option("--details", served_details,
                 "serve only these details of --config (ids, comma-separated): several daemons "
                 "share one config, each detail served by one of them (default: every detail)")
      ->delimiter(',');
  double twin_check_s = 1.5;
  app.add_option("--twin-check-seconds", twin_check_s,
                 "listen this long to the STATUS of this daemon's details before starting; "
                 "another daemon's STATUS for one of them: refuse to start (exit 2). 0 = no check "
                 "(default 1.5: STATUS comes every second)")
      ->check(CLI::Range(0.0, 60.0));
  int worker_threads = 0;
  app.add_option("--worker-threads", worker_threads,
                 "threads that apply the details' batches and build them at start (default 0: "
                 "the machine's cores, at least 2; never more than the details served)")
      ->check(CLI::Range(0, 1024));
  int life_threads = 0;
  app.add_option("--life-threads", life_threads,
                 "threads that compute the remaining-life estimates of all details (default 0: "
                 "half the machine's cores, at least 1; never more than the details with "
                 "estimates); each running estimate holds a copy of its detail's factor")
      ->check(CLI::Range(0, 1024));
  std::string max_memory;
  app.add_option("--max-memory", max_memory,
                 "refuse a config whose estimated memory exceeds this: bytes, suffix K/M/G/T "
                 "(e.g. 8G; default 75 % of physical memory)")
      ->check([](const std::string& s) {
        return peritwin::twin::parse_byte_size(s) ? "" : "not a byte size > 0 (e.g. 8G): " + s;
      });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitUsage;
  }

  auto logger = spdlog::stderr_color_mt("peritwin");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
  spdlog::set_level(spdlog::level::from_str(log_level));

  // Remaining-life simulations run at most this many details at once: on the shared life
  // threads, or in deterministic mode on the worker threads (docs/limits.md).
  const int concurrent_life_estimates = deterministic
                                            ? peritwin::twin::default_worker_threads(worker_threads)
                                            : peritwin::twin::default_life_threads(life_threads);
  const auto loaded = peritwin::twin::load_config(
      config_file, {peritwin::twin::parse_byte_size(max_memory).value_or(0), served_details,
                    concurrent_life_estimates});
  if (!loaded.ok()) {
    for (const auto& e : loaded.errors) spdlog::error("config: {}", e.message());
    return kExitUsage;
  }
  for (const auto& detail : loaded.config->details) {
    // e.g. bilinear parameters out of range
    if (const auto settings = peritwin::twin::solver_settings(detail); !settings) {
      spdlog::error("config: {}", settings.error().message());
      return kExitUsage;
    }
  }
  if (const auto& auth = loaded.config->auth) {
    // A key file that is missing, open to others or malformed is a config error: nothing starts.
    if (const auto keys = peritwin::messages::KeyRing::load(auth->key_file); !keys) {
      spdlog::error("config: [auth] key_file: {}", keys.error().message());
      return kExitUsage;
    }
  }
  if (lcm_url.empty()) {
    if (const char* env = std::getenv("LCM_DEFAULT_URL")) lcm_url = env;
  }

  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);

  try {
    peritwin::twin::HubConnection hub(lcm_url, [] { return g_signal.load() == 0; });
    const std::unique_ptr<lcm::LCM> connection = hub.open();
    if (!connection) {
      if (!hub.error().empty()) {
        spdlog::critical("{}", hub.error());
        return kExitRuntime;
      }
      spdlog::info("signal {} received while waiting for the LCM hub: stopping", g_signal.load());
      return kExitOk;
    }
    lcm::LCM& lcm = *connection;
    if (twin_check_s > 0) {
      std::vector<std::string> ids;
      for (const auto& d : loaded.config->details) ids.push_back(d.id);
      if (const auto other = peritwin::twin::find_other_twin(lcm, ids, twin_check_s)) {
        spdlog::error(
            "{}: refusing to start a second twin of it (give each detail to one daemon: "
            "--details, README \"A fleet\")",
            other->describe());
        return kExitUsage;
      }
    }
    peritwin::twin::DaemonOptions options;
    options.state_dir = state_dir;
    options.deterministic = deterministic;
    options.results = !no_results;
    options.fresh_start = fresh_start;
    options.worker_threads = worker_threads;
    options.life_threads = life_threads;
    peritwin::twin::Daemon daemon(lcm, *loaded.config, options);
    spdlog::info("peritwin: {} detail(s) from {}, LCM \"{}\", state in {}, {} mode",
                 loaded.config->details.size(), config_file,
                 lcm_url.empty() ? "(LCM default)" : lcm_url, state_dir,
                 deterministic ? "deterministic" : "asynchronous-life");
    if (const peritwin::Status started = daemon.start(); !started) {
      spdlog::critical("start-up failed: {}", started.error().message());
      return kExitRuntime;
    }
    spdlog::info("ready");
    while (g_signal.load() == 0) {
      if (!hub.connected()) {
        hub.reconnect(lcm);
      } else if (!daemon.poll(100)) {
        break;
      } else {
        hub.check(lcm);
      }
    }
    if (const int s = g_signal.load(); s != 0) {
      spdlog::info("signal {} received: checkpointing and stopping", s);
    }
    daemon.stop();
    if (!daemon.error().empty()) {
      spdlog::critical("stopped after a runtime failure: {}", daemon.error());
      return kExitRuntime;
    }
    return kExitOk;
  } catch (const std::exception& e) {
    spdlog::critical("runtime failure: {}", e.what());
    return kExitRuntime;
  }
}
