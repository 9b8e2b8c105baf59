// peritwin-bench-soak (also `peritwin-bench soak`): does the daemon's memory stay flat over many
// batches? Issue 14 item 8's goal: RSS flat within 5 % over 10^7 single-block batches.
//
// Starts LCM's Java TCP hub on a free loopback port (unless --lcm-url is given) and the daemon
// binary (build/bin/peritwin, as deployed: a child process, so that its RSS is its own) on a
// detail where every batch is cheap and nothing breaks: by default the B1 example coarsened to
// dx = 2.5 mm (about 600 nodes), remaining-life estimates and field snapshots off, no results,
// checkpoints every 1000 batches (and every 300 s); --config runs a config file of yours as it
// is. It publishes --batches single-block batches of one cycle each (P_max cycling over 20..35 N,
// R = 0.1: far below any bond's fatigue life over 10^7 cycles) on PERITWIN_<DETAIL>_LOAD, with
// --window batches beyond the last applied one in flight, follows the applied seq in the
// daemon's STATE, and resends from it when nothing moves for 3 s. It stops after the last batch
// or after --max-seconds.
//
// The daemon's VmRSS (/proc/<pid>/status) is sampled after the first batch, after the warm-up
// (--warm-up batches, by default 10^4 = ten checkpoints: the allocator's, LCM's and HDF5's
// buffers are in place; this is the start), every 10 % of the rest, and at the end; VmHWM is its
// peak. One JSON line:
//   {"bench":"soak","batches":…,"warm_up_batches":…,"complete":…,"seconds":…,"batches_per_s":…,
//    "rss_first_batch_kb":…,"rss_start_kb":…,"rss_end_kb":…,"rss_peak_kb":…,"growth_percent":…,
//    "growth_kb_per_million_batches":…,"rss_max_per_tenth_kb":[…],"envelope_growth_percent":…,
//    "samples":[{"batches":…,"rss_kb":…},…],"broken_bonds":…,"resends":…,"daemon_exit":…,
//    "transport":"tcpq"}
// seconds, batches_per_s and growth_* cover the batches after the warm-up; growth_* is
// end - start. rss_max_per_tenth_kb: the highest VmRSS of each tenth after the warm-up (sampled
// every second), envelope_growth_percent the highest of the second half of the tenths against
// the highest of the first half — the measure for a daemon whose RSS swings (asynchronous life
// estimates copy the model for each estimate, so two samples can fall anywhere on the swing).
// daemon_exit: the daemon's exit status after SIGTERM (0: checkpointed and stopped cleanly). Exit 0
// when the run completed and nothing broke, 1 when a bond broke (the detail is not in steady
// state), 3 on a runtime failure.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <thread>

#include "bench/child_process.h"
#include "config/config.h"
#include "core/json_line.h"
#include "core/loopback_port.h"
#include "core/proc_files.h"
#include "core/program.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/transport.h"

namespace {

namespace fs = std::filesystem;
using namespace peritwin;
using peritwin::bench::Clock;
using peritwin::bench::since;
using peritwin::bench::spawn;
using peritwin::bench::stop_child;
using peritwin::core::proc_status_kb;

/// The B1 example made cheap per batch: each edit's first string must occur once.
std::string soak_config_text(const std::string& example) {
  std::ifstream in(example);
  std::stringstream buffer;
  buffer << in.rdbuf();
  std::string text = buffer.str();
  const std::vector<std::pair<std::string, std::string>> edits{
      {"dx = 0.001 ", "dx = 0.0025 "},
      {"field_every_batches = 10\n", "field_every_batches = 0\n"},
      {"png = true\n", "png = false\n"},
      {"\nevery_batches = 10\n", "\nevery_batches = 0\n"},     // [detail.life]
      {"\nevery_batches = 100\n", "\nevery_batches = 1000\n"}  // [detail.checkpoint]
  };
  for (const auto& [from, to] : edits) {
    const auto p = text.find(from);
    if (p == std::string::npos) return {};
    text.replace(p, from.size(), to);
  }
  return text;
}

/// The publishing side: single-block batches generated on demand (10^7 of them would not fit in
/// memory as a vector), a window beyond the applied seq, resends after 3 s without progress.
class Producer {
 public:
  Producer(lcm::LCM& lcm, std::string detail, std::int64_t window)
      : lcm_(lcm),
        detail_(std::move(detail)),
        load_channel_(peritwin::messages::channel(detail_, peritwin::messages::Kind::kLoad)),
        window_(window) {
    sub_ = lcm_.subscribe(peritwin::messages::channel(detail_, peritwin::messages::Kind::kState),
                          &Producer::on_state, this);
    sub_->setQueueCapacity(100'000);
  }
  ~Producer() { lcm_.unsubscribe(sub_); }
  Producer(const Producer&) = delete;
  Producer& operator=(const Producer&) = delete;

  /// Publishes and follows STATE until seq `last` is applied, `keep_going()` turns false or
  /// nothing progresses for `give_up_s`; false with error() on failure.
  bool run_to(std::int64_t last, double give_up_s, const std::function<bool()>& keep_going) {
    auto progress = Clock::now(), sent = Clock::now();
    while (applied_ < last) {
      const std::int64_t limit = std::min(last, applied_ + window_);
      while (next_ <= limit && peritwin::messages::transport_up(lcm_)) {
        publish(next_++);
        sent = Clock::now();
      }
      const std::int64_t before = applied_;
      errno = 0;
      if (peritwin::messages::handle_lcm(lcm_, 20) < 0 && errno != EINTR) {
        error_ = "LCM failed while receiving";
        return false;
      }
      if (!peritwin::messages::transport_up(lcm_)) {
        error_ = "connection to the LCM hub lost";
        return false;
      }
      if (applied_ != before) progress = Clock::now();
      if (since(progress) > give_up_s) {
        error_ = "no progress from the daemon for " + std::to_string(give_up_s) +
                 " s (applied seq " + std::to_string(applied_) + ")";
        return false;
      }
      if (since(progress) > 3.0 && since(sent) > 3.0) {
        next_ = applied_ + 1;  // go back: resend what is not applied
        ++resends_;
      }
      if (keep_going && !keep_going()) return true;
    }
    return true;
  }

  [[nodiscard]] std::int64_t applied() const { return applied_; }
  [[nodiscard]] std::int64_t broken_bonds() const { return broken_bonds_; }
  [[nodiscard]] std::int64_t resends() const { return resends_; }
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  void on_state(const lcm::ReceiveBuffer*, const std::string&,
                const peritwin_msgs::damage_state_t* s) {
    applied_ = std::max(applied_, peritwin::messages::applied_seq(*s, kSource));
    next_ = std::max(next_, applied_ + 1);
    broken_bonds_ = s->broken_bonds;
  }
  void publish(std::int64_t seq) {
    peritwin::messages::Batch b;
    b.detail_id = detail_;
    b.source_id = kSource;
    b.seq = seq;
    b.blocks.push_back({20.0 + 5.0 * static_cast<double>(seq % 4), 0.1, 0.0, 1});
    const auto m = peritwin::messages::batch_message(b, peritwin::messages::now_utime());
    lcm_.publish(load_channel_, &m);
  }

  static constexpr const char* kSource = "soak";
  lcm::LCM& lcm_;
  std::string detail_, load_channel_;
  std::int64_t window_;
  lcm::Subscription* sub_ = nullptr;
  std::int64_t applied_ = 0, next_ = 1, broken_bonds_ = -1, resends_ = 0;
  std::string error_;
};

/// The command line.
struct Options {
  std::int64_t batches = 1'000'000;
  std::int64_t window = 256;
  double max_seconds = 3600.0;
  std::string config_file, lcm_url;
  std::string daemon_bin = (fs::read_symlink("/proc/self/exe").parent_path() / "peritwin").string();
  bool keep = false;
  std::int64_t warm_up = 10'000;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--batches", o.batches, "single-block batches to publish (default 1000000)")
      ->check(CLI::PositiveNumber);
  app.add_option("--window", o.window, "batches in flight beyond the applied one (default 256)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-seconds", o.max_seconds, "stop publishing after this long (default 3600)")
      ->check(CLI::PositiveNumber);
  app.add_option("--config", o.config_file,
                 "detail configuration, used as it is (default: the B1 example at dx = 2.5 mm, "
                 "no life estimates, no fields, checkpoints every 1000 batches)");
  app.add_option("--lcm-url", o.lcm_url, "use this tcpq/udpm URL instead of starting a hub");
  app.add_option("--daemon", o.daemon_bin, "the peritwin binary (default: next to this one)");
  app.add_option("--warm-up", o.warm_up,
                 "batches before the start sample (default 10000, at most a tenth of --batches)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--keep", o.keep, "keep the work directory (config, daemon log, checkpoints)");
}

/// The daemon's RSS over the run: the samples and the numbers of the JSON line.
struct Measurement {
  core::JsonLine samples = core::JsonLine::array();
  std::int64_t rss_first = -1, rss_start = -1, rss_end = -1, rss_peak = -1, applied = 0;
  std::vector<std::int64_t> tenth_max;
  double seconds = 0.0;
  bool ok = false, alive = false;
};

/// Publishes the batches after the first one (applied), sampling the daemon's VmRSS.
Measurement measure(Options& o, Producer& producer, pid_t daemon,
                    const std::function<bool()>& daemon_alive) {
  Measurement m;
  auto sample = [&] {
    const std::int64_t rss = core::proc_status_kb("VmRSS", std::to_string(daemon));
    m.samples.push_back({{"batches", producer.applied()}, {"rss_kb", rss}});
    return rss;
  };
  m.rss_first = sample();
  // Warm-up: the allocator's and LCM's buffers, HDF5's on the first checkpoints.
  o.warm_up = std::clamp<std::int64_t>(o.warm_up, 1, std::max<std::int64_t>(1, o.batches / 10));
  m.ok = producer.run_to(o.warm_up, 120.0, daemon_alive);
  m.rss_start = m.ok && producer.applied() >= o.warm_up ? sample() : -1;
  const auto t0 = Clock::now();
  // The highest RSS of each tenth, from a sample every second: a daemon whose RSS swings (a life
  // estimate's model copy comes and goes) is compared by its upper envelope, not by two samples
  // that may fall on a swing.
  auto last_poll = Clock::now();
  for (int tenth = 1; tenth <= 10 && m.ok && m.rss_start >= 0; ++tenth) {
    const std::int64_t target = o.warm_up + (o.batches - o.warm_up) * tenth / 10;
    m.tenth_max.push_back(-1);
    auto note = [&](std::int64_t rss) { m.tenth_max.back() = std::max(m.tenth_max.back(), rss); };
    m.ok = producer.run_to(target, 120.0, [&] {
      if (since(last_poll) >= 1.0) {
        last_poll = Clock::now();
        note(core::proc_status_kb("VmRSS", std::to_string(daemon)));
      }
      return since(t0) < o.max_seconds && daemon_alive();
    });
    if (producer.applied() < target) break;  // --max-seconds, or the daemon is gone
    if (target > o.warm_up) note(sample());
  }
  while (!m.tenth_max.empty() && m.tenth_max.back() < 0) m.tenth_max.pop_back();
  m.seconds = since(t0);
  m.applied = producer.applied();
  m.alive = daemon_alive();
  m.rss_end = m.alive ? core::proc_status_kb("VmRSS", std::to_string(daemon)) : -1;
  m.rss_peak = m.alive ? core::proc_status_kb("VmHWM", std::to_string(daemon)) : -1;
  if (m.alive && m.samples.back()["batches"] != m.applied) {
    m.samples.push_back({{"batches", m.applied}, {"rss_kb", m.rss_end}});
  }
  return m;
}

/// The JSON line of the run.
core::JsonLine soak_line(const Options& o, const Measurement& m, const Producer& producer,
                         int daemon_exit) {
  const std::vector<std::int64_t>& tenth_max = m.tenth_max;
  const double measured = static_cast<double>(std::max<std::int64_t>(0, m.applied - o.warm_up));
  const double growth_kb = static_cast<double>(m.rss_end - m.rss_start);
  core::JsonLine line;
  line["bench"] = "soak";
  line["batches"] = m.applied;
  line["warm_up_batches"] = o.warm_up;
  line["complete"] = m.applied >= o.batches;
  line["seconds"] = core::fixed(m.seconds, 1);
  line["batches_per_s"] = core::fixed(measured / std::max(m.seconds, 1e-9), 1);
  line["rss_first_batch_kb"] = m.rss_first;
  line["rss_start_kb"] = m.rss_start;
  line["rss_end_kb"] = m.rss_end;
  line["rss_peak_kb"] = m.rss_peak;
  const bool measured_rss = m.rss_start > 0 && m.rss_end > 0 && measured > 0;
  line["growth_percent"] =
      measured_rss
          ? core::JsonLine(core::fixed(100.0 * growth_kb / static_cast<double>(m.rss_start), 2))
          : core::JsonLine(nullptr);
  line["growth_kb_per_million_batches"] =
      measured_rss ? core::JsonLine(core::fixed(1e6 * growth_kb / measured, 1))
                   : core::JsonLine(nullptr);
  line["rss_max_per_tenth_kb"] = tenth_max;
  // The highest RSS of the second half of the tenths against the first half's.
  const auto half = static_cast<std::ptrdiff_t>(tenth_max.size() / 2);
  line["envelope_growth_percent"] =
      half >= 1 && tenth_max.front() > 0
          ? core::JsonLine(core::fixed(
                100.0 *
                    static_cast<double>(
                        *std::max_element(tenth_max.begin() + half, tenth_max.end()) -
                        *std::max_element(tenth_max.begin(), tenth_max.begin() + half)) /
                    static_cast<double>(
                        *std::max_element(tenth_max.begin(), tenth_max.begin() + half)),
                2))
          : core::JsonLine(nullptr);
  line["samples"] = m.samples;
  line["broken_bonds"] = producer.broken_bonds();
  line["resends"] = producer.resends();
  line["daemon_exit"] = daemon_exit;
  line["transport"] = o.lcm_url.rfind("tcpq://", 0) == 0 ? "tcpq" : o.lcm_url;
  return line;
}

/// The config file to run (the B1 example edited, written to `work`, unless --config); the
/// detail's id, or "" (said on stderr) when it cannot be had.
std::string prepare_config(Options& o, const fs::path& work) {
  if (o.config_file.empty()) {
    const std::string text =
        soak_config_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
    if (text.empty()) {
      std::cerr << "peritwin-bench-soak: the B1 example no longer has the lines this bench edits\n";
      return {};
    }
    o.config_file = (work / "soak.toml").string();
    std::ofstream(o.config_file) << text;
  }
  const auto loaded = config::load_config(o.config_file);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text();
    return {};
  }
  return loaded.config->details.front().id;
}

/// The soak run; the exit code.
int run(Options o) {
  const fs::path work =
      fs::temp_directory_path() / ("peritwin_bench_soak_" + std::to_string(getpid()));
  fs::create_directories(work);
  const std::string detail = prepare_config(o, work);
  if (detail.empty()) return 2;

  pid_t hub = -1, daemon = -1;
  std::unique_ptr<lcm::LCM> lcm;
  std::unique_ptr<Producer> producer_owner;
  auto cleanup = [&] {
    producer_owner.reset();  // unsubscribes while the hub is still there
    lcm.reset();
    if (daemon > 0) stop_child(daemon, 600.0);
    if (hub > 0) stop_child(hub, 60.0);
    if (!o.keep) fs::remove_all(work);
  };
  if (o.lcm_url.empty()) {
    const int port = core::free_loopback_port();
    hub = spawn(
        {"java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", std::to_string(port)},
        "/dev/null", (work / "hub.log").string());
    if (hub < 0 || !core::wait_for_loopback_port(port, 60.0)) {
      std::cerr << "peritwin-bench-soak: the LCM hub did not come up on port " << port << "\n";
      cleanup();
      return 3;
    }
    o.lcm_url = "tcpq://127.0.0.1:" + std::to_string(port);
  }
  const std::string daemon_log = (work / "daemon.log").string();
  daemon = spawn({o.daemon_bin, "--config", o.config_file, "--lcm-url", o.lcm_url, "--state-dir",
                  (work / "state").string(), "--no-results", "--log-level", "warn"},
                 "/dev/null", daemon_log);
  if (daemon < 0) {
    std::cerr << "peritwin-bench-soak: cannot start " << o.daemon_bin << "\n";
    cleanup();
    return 3;
  }

  lcm = std::make_unique<lcm::LCM>(o.lcm_url);
  if (!lcm->good() || !messages::transport_up(*lcm)) {
    std::cerr << "peritwin-bench-soak: cannot open LCM at " << o.lcm_url << "\n";
    cleanup();
    return 3;
  }
  producer_owner = std::make_unique<Producer>(*lcm, detail, o.window);
  Producer& producer = *producer_owner;
  const std::function<bool()> daemon_alive = [&] { return waitpid(daemon, nullptr, WNOHANG) == 0; };
  // Warm-up: batch 1 alone, resent until applied (the daemon builds its model meanwhile).
  if (!producer.run_to(1, 600.0, daemon_alive) || producer.applied() < 1) {
    std::cerr << "peritwin-bench-soak: the daemon did not apply the first batch: "
              << producer.error() << " (see " << daemon_log << ")\n";
    o.keep = true;
    cleanup();
    return 3;
  }
  const Measurement m = measure(o, producer, daemon, daemon_alive);
  const int daemon_exit = m.alive ? stop_child(daemon, 600.0) : -1;
  daemon = -1;
  if (!m.ok || !m.alive) {
    std::cerr << "peritwin-bench-soak: "
              << (!m.alive ? "the daemon died (see " + daemon_log + ")" : producer.error()) << "\n";
    o.keep = true;
  }
  core::print_line(soak_line(o, m, producer, daemon_exit));
  const std::int64_t broken = producer.broken_bonds();
  cleanup();
  if (!m.ok || !m.alive || daemon_exit != 0) return 3;
  return broken == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-soak: the daemon's RSS over many single-block batches (tcpq)"};
  Options o;
  add_options(app, o);
  if (const auto rc =
          peritwin::core::parse_options(app, argc, argv, peritwin::core::ParseErrors::cli11)) {
    return *rc;
  }
  return run(std::move(o));
}
