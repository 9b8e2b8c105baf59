// peritwin: the twin daemon. See README.md and service/daemon.h.
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
// reconnects with backoff (messages/hub_connection.h).
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "config/config.h"
#include "core/exit_codes.h"
#include "core/program.h"
#include "core/stop_signal.h"
#include "messages/auth.h"
#include "messages/hub_connection.h"
#include "service/daemon.h"
#include "service/duplicate_twin.h"

namespace {

using peritwin::core::kExitOk;
using peritwin::core::kExitRuntime;
using peritwin::core::kExitUsage;

/// The command line.
struct Options {
  std::string config_file, lcm_url, state_dir = "state", log_level = "info";
  bool deterministic = false, no_results = false, fresh_start = false;
  std::vector<std::string> served_details;
  double twin_check_s = 1.5;
  int worker_threads = 0;
  int life_threads = 0;
  std::string max_memory;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--config", o.config_file, "detail configuration (TOML)")->required();
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's default)");
  app.add_option("--state-dir", o.state_dir, "checkpoint directory (default: state)");
  app.add_option("--log-level", o.log_level, "trace|debug|info|warn|error|critical|off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  app.add_flag("--deterministic", o.deterministic,
               "remaining life synchronously at fixed state_seq points (reproducible outputs; "
               "use with a lockstep replay)");
  app.add_flag("--no-results", o.no_results, "write no HDF5 results or PNG pictures");
  app.add_flag("--fresh-start", o.fresh_start,
               "start from the virgin state when checkpoints exist but none is valid (by "
               "default the daemon then refuses to start, naming each file and why)");
  app.add_option("--details", o.served_details,
                 "serve only these details of --config (ids, comma-separated): several daemons "
                 "share one config, each detail served by one of them (default: every detail)")
      ->delimiter(',');
  app.add_option("--twin-check-seconds", o.twin_check_s,
                 "listen this long to the STATUS of this daemon's details before starting; "
                 "another daemon's STATUS for one of them: refuse to start (exit 2). 0 = no check "
                 "(default 1.5: STATUS comes every second)")
      ->check(CLI::Range(0.0, 60.0));
  app.add_option("--worker-threads", o.worker_threads,
                 "threads that apply the details' batches and build them at start (default 0: "
                 "the machine's cores, at least 2; never more than the details served)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--life-threads", o.life_threads,
                 "threads that compute the remaining-life estimates of all details (default 0: "
                 "half the machine's cores, at least 1; never more than the details with "
                 "estimates); each running estimate holds a copy of its detail's factor")
      ->check(CLI::Range(0, 1024));
  app.add_option("--max-memory", o.max_memory,
                 "refuse a config whose estimated memory exceeds this: bytes, suffix K/M/G/T "
                 "(e.g. 8G; default 75 % of physical memory)")
      ->check([](const std::string& s) {
        return peritwin::config::parse_byte_size(s) ? "" : "not a byte size > 0 (e.g. 8G): " + s;
      });
}

/// The config, every detail's solver settings and the key file checked: nothing starts when one
/// is wrong (logged; the exit code then).
std::optional<int> load_config(const Options& o, peritwin::config::ConfigResult& loaded) {
  // Remaining-life simulations run at most this many details at once: on the shared life
  // threads, or in deterministic mode on the worker threads (docs/limits.md).
  const int concurrent_life_estimates =
      o.deterministic ? peritwin::service::default_worker_threads(o.worker_threads)
                      : peritwin::service::default_life_threads(o.life_threads);
  loaded = peritwin::config::load_config(
      o.config_file, {peritwin::config::parse_byte_size(o.max_memory).value_or(0), o.served_details,
                      concurrent_life_estimates});
  if (!loaded.ok()) {
    for (const auto& e : loaded.errors) spdlog::error("config: {}", e.message());
    return peritwin::core::kExitUsage;
  }
  for (const auto& detail : loaded.config->details) {
    // e.g. bilinear parameters out of range
    if (const auto settings = peritwin::twin::solver_settings(detail); !settings) {
      spdlog::error("config: {}", settings.error().message());
      return peritwin::core::kExitUsage;
    }
  }
  if (const auto& auth = loaded.config->auth) {
    // A key file that is missing, open to others or malformed is a config error: nothing starts.
    if (const auto keys = peritwin::messages::KeyRing::load(auth->key_file); !keys) {
      spdlog::error("config: [auth] key_file: {}", keys.error().message());
      return peritwin::core::kExitUsage;
    }
  }
  return std::nullopt;
}

/// The daemon on `lcm` until a signal or a runtime failure; the exit code.
int serve(const Options& o, const std::string& lcm_url, const peritwin::config::TwinConfig& config,
          peritwin::messages::HubConnection& hub, lcm::LCM& lcm) {
  if (o.twin_check_s > 0) {
    std::vector<std::string> ids;
    for (const auto& d : config.details) ids.push_back(d.id);
    if (const auto other = peritwin::service::find_other_twin(lcm, ids, o.twin_check_s)) {
      spdlog::error(
          "{}: refusing to start a second twin of it (give each detail to one daemon: "
          "--details, README \"A fleet\")",
          other->describe());
      return peritwin::core::kExitUsage;
    }
  }
  peritwin::service::DaemonOptions options;
  options.state_dir = o.state_dir;
  options.deterministic = o.deterministic;
  options.results = !o.no_results;
  options.fresh_start = o.fresh_start;
  options.worker_threads = o.worker_threads;
  options.life_threads = o.life_threads;
  peritwin::service::Daemon daemon(lcm, config, options);
  spdlog::info("peritwin: {} detail(s) from {}, LCM \"{}\", state in {}, {} mode",
               config.details.size(), o.config_file, lcm_url.empty() ? "(LCM default)" : lcm_url,
               o.state_dir, o.deterministic ? "deterministic" : "asynchronous-life");
  if (const peritwin::core::Status started = daemon.start(); !started) {
    spdlog::critical("start-up failed: {}", started.error().message());
    return peritwin::core::kExitRuntime;
  }
  spdlog::info("ready");
  while (peritwin::core::keep_running()) {
    if (!hub.connected()) {
      hub.reconnect(lcm);
    } else if (!daemon.poll(100)) {
      break;
    } else {
      hub.check(lcm);
    }
  }
  if (const int s = peritwin::core::stop_signal(); s != 0) {
    spdlog::info("signal {} received: checkpointing and stopping", s);
  }
  daemon.stop();
  if (!daemon.error().empty()) {
    spdlog::critical("stopped after a runtime failure: {}", daemon.error());
    return peritwin::core::kExitRuntime;
  }
  return peritwin::core::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin: structural-health-monitoring digital twin daemon (LCM in/out)"};
  Options o;
  add_options(app, o);
  if (const auto rc = peritwin::core::parse_options(app, argc, argv)) return *rc;
  peritwin::core::set_up_logging("peritwin", o.log_level);
  peritwin::config::ConfigResult loaded;
  if (const auto rc = load_config(o, loaded)) return *rc;
  const std::string lcm_url = peritwin::core::lcm_url_or_default(o.lcm_url);
  peritwin::core::install_stop_handler();
  try {
    peritwin::messages::HubConnection hub(lcm_url, peritwin::core::keep_running);
    const std::unique_ptr<lcm::LCM> connection = hub.open();
    if (!connection) {
      if (!hub.error().empty()) {
        spdlog::critical("{}", hub.error());
        return peritwin::core::kExitRuntime;
      }
      spdlog::info("signal {} received while waiting for the LCM hub: stopping",
                   peritwin::core::stop_signal());
      return peritwin::core::kExitOk;
    }
    return serve(o, lcm_url, *loaded.config, hub, *connection);
  } catch (const std::exception& e) {
    spdlog::critical("runtime failure: {}", e.what());
    return peritwin::core::kExitRuntime;
  }
}
