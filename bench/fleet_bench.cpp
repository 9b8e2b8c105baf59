// peritwin-bench-fleet (also `peritwin-bench fleet`): one daemon holding a fleet of details on one
// bus (issue 18). Goals on a 2-core machine: 32 details x 4000 nodes in <= 1.5 GB RSS, the quiet
// details' STATE latency p99 <= 20 ms while a loud one breaks bonds, start-up <= 0.5 s per detail.
//
// Starts LCM's Java TCP hub on a free loopback port and the daemon binary (as deployed, a child
// process: its RSS is its own) on a generated config of --details copies of the B1 example
// (examples/b1-ct-al6061.toml) at the dx that gives about --nodes-per-detail nodes, ids d00, d01,
// ...; remaining-life estimates, field snapshots, pictures and results off (the bench measures the
// ingest, not the estimates: those are reported by `peritwin-bench fatigue`), checkpoints as in
// the example (every 100 batches). Detail d00 is loud: its producer sends 4 kN, R 0.1 blocks of
// --loud-cycles (50) cycles in lockstep (the next batch as soon as the previous one is applied),
// so that it breaks bonds throughout (the first at about 1900 cycles; loud_breaking_batches counts
// the batches that broke one; --loud-pre-cycles gives it that many cycles in one batch before the
// window). Every other detail is quiet: a batch of 10 cycles at 500 N (far below any
// bond's fatigue life) every 1/--quiet-rate s, the quiet details' phases spread evenly over that
// period as independent sensors' would be (--aligned-phases: all at the same instant, a burst of
// details-1 batches every period). The latency of a quiet batch is
// from its publication to the first STATE showing it applied. The measured window is --seconds,
// or shorter when the loud detail reaches its end-of-life criterion (8 mm of crack) before.
//
// The daemon applies the details' batches on a pool of worker threads (README "A fleet"): the run
// is made twice in one invocation, with the daemon's default pool (--worker-threads, default the
// cores) and with one worker thread (every detail then waits for the loud one's re-solves), and
// the quiet p99 of both and their ratio are reported (--no-one-thread skips the second). One
// JSON line:
//   {"bench":"fleet","details":…,"nodes_per_detail":…,"dx_m":…,"startup_s":…,
//    "startup_s_per_detail":…,"rss_mb":…,"rss_peak_mb":…,"rss_mb_per_detail":…,"cycles_per_s":…,
//    "quiet_batches":…,"quiet_p50_ms":…,"quiet_p99_ms":…,"loud_batches":…,"loud_broken_bonds":…,
//    "loud_cycles_before_window":…,"loud_breaking_batches":…,
//    "window_s":…,"loud_end_of_life":…,"worker_threads":…,"startup_s_one_thread":…,
//    "quiet_p50_ms_one_thread":…,"quiet_p99_ms_one_thread":…,"quiet_p99_one_thread_over_pool":…,
//    "goals":{…},"transport":"tcpq"}
// rss_mb is the daemon's VmRSS at the end of the run, rss_peak_mb its VmHWM. Exit 0 when the run
// completed, 3 on a runtime failure.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include "bench/child_process.h"
#include "core/json_line.h"
#include "core/loopback_port.h"
#include "core/percentile.h"
#include "core/proc_files.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/transport.h"

namespace {

namespace fs = std::filesystem;
using namespace peritwin;
using bench::Clock;
using bench::since;
using peritwin::core::percentile;

constexpr const char* kSource = "fleet";

/// `text` with the first `from` replaced by `to`; throws when it is not there (the example
/// changed: the bench must be updated).
std::string edit(std::string text, const std::string& from, const std::string& to) {
  const auto p = text.find(from);
  if (p == std::string::npos) throw std::runtime_error("examples/b1-ct-al6061.toml: no " + from);
  return text.replace(p, from.size(), to);
}

/// The fleet's config: `details` copies of the B1 example at grid spacing `dx`.
std::string fleet_config(int details, double dx, bool release_idle_factors) {
  const std::string b1 = core::read_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
  std::string out;
  for (int i = 0; i < details; ++i) {
    char id[16];
    std::snprintf(id, sizeof id, "d%02d", i);
    std::string d = edit(b1, "id = \"b1-ct\"", std::string("id = \"") + id + "\"");
    d = edit(d, "results/b1-ct", std::string("results/") + id);
    d = edit(d, "dx = 0.001 ", "dx = " + std::to_string(dx) + " ");
    d = edit(d, "field_every_batches = 10", "field_every_batches = 0");
    d = edit(d, "png = true", "png = false");
    d = edit(d, "\nevery_batches = 10\n", "\nevery_batches = 0\n");  // [detail.life]: no estimates
    if (release_idle_factors) {
      d = edit(d, "release_idle_factor = false", "release_idle_factor = true");
    }
    out += d + "\n";
  }
  return out;
}

/// One detail's producer and what its STATEs said.
struct Feed {
  std::string id;
  bool loud = false;
  std::int64_t next_seq = 1, applied = 0, broken_bonds = 0, cycles = 0, cycles_at_start = -1;
  std::int64_t breaking_states = 0;  ///< STATEs with more broken bonds than the one before
  bool seen = false;
  bool ended = false;  ///< its end-of-life criterion was met: it applies nothing more
  Clock::time_point ended_at{};
  Clock::time_point next_send{};
  struct Sent {
    Clock::time_point at;
    std::int64_t utime = 0;  ///< wall clock, as the STATE's utime (set when the daemon made it)
  };
  std::map<std::int64_t, Sent> in_flight;  ///< seq -> publication time
  std::vector<double> latency_ms;
  /// Of latency_ms: from publication to the daemon making the STATE (its utime), the rest being
  /// the STATE's way out through the daemon's LCM thread, the hub and this process.
  std::vector<double> to_state_ms;
};

/// Follows every detail's STATE on the bus.
class Fleet {
 public:
  Fleet(lcm::LCM& lcm, int details) : lcm_(lcm) {
    for (int i = 0; i < details; ++i) {
      char id[16];
      std::snprintf(id, sizeof id, "d%02d", i);
      Feed f;
      f.id = id;
      f.loud = i == 0;
      index_[f.id] = feeds_.size();
      feeds_.push_back(std::move(f));
    }
    sub_ = lcm_.subscribe("PERITWIN_.*_STATE", &Fleet::on_state, this);
    sub_->setQueueCapacity(100'000);
  }
  ~Fleet() { lcm_.unsubscribe(sub_); }
  Fleet(const Fleet&) = delete;
  Fleet& operator=(const Fleet&) = delete;

  std::vector<Feed>& feeds() { return feeds_; }
  [[nodiscard]] bool all_seen() const {
    return std::all_of(feeds_.begin(), feeds_.end(), [](const Feed& f) { return f.seen; });
  }
  void publish(Feed& f, double p_max, std::int64_t count) {
    messages::Batch b;
    b.detail_id = f.id;
    b.source_id = kSource;
    b.seq = f.next_seq++;
    b.blocks.push_back({p_max, 0.1, 0.0, count});
    const std::int64_t utime = messages::now_utime();
    const auto m = messages::batch_message(b, utime);
    f.in_flight[b.seq] = {Clock::now(), utime};
    lcm_.publish(messages::channel(f.id, messages::Kind::kLoad), &m);
  }

 private:
  void on_state(const lcm::ReceiveBuffer*, const std::string&,
                const peritwin_msgs::damage_state_t* s) {
    const auto now = Clock::now();
    const auto it = index_.find(s->detail_id);
    if (it == index_.end()) return;
    Feed& f = feeds_[it->second];
    f.seen = true;
    if (s->broken_bonds > f.broken_bonds) ++f.breaking_states;
    f.broken_bonds = s->broken_bonds;
    f.cycles = s->total_cycles;
    f.applied = std::max(f.applied, messages::applied_seq(*s, kSource));
    if (s->end_of_life_cycle >= 0 && !f.ended) {
      f.ended = true;
      f.ended_at = now;
    }
    while (!f.in_flight.empty() && f.in_flight.begin()->first <= f.applied) {
      const Feed::Sent& sent = f.in_flight.begin()->second;
      f.latency_ms.push_back(std::chrono::duration<double, std::milli>(now - sent.at).count());
      f.to_state_ms.push_back(1e-3 * static_cast<double>(s->utime - sent.utime));
      f.in_flight.erase(f.in_flight.begin());
    }
    if (f.ended) f.in_flight.clear();  // the rest is refused (FAILED)
  }
  lcm::LCM& lcm_;
  std::vector<Feed> feeds_;
  std::map<std::string, std::size_t> index_;
  lcm::Subscription* sub_ = nullptr;
};

struct RunResult {
  bool ok = false;
  std::string error;
  double startup_s = 0, rss_mb = 0, rss_peak_mb = 0, cycles_per_s = 0;
  std::vector<double> quiet_ms, quiet_to_state_ms;
  std::int64_t loud_batches = 0, loud_broken = 0, loud_breaking = 0;
  std::int64_t loud_cycles_before = 0;  ///< the loud detail's cycles when the window opened
  double window_s = 0;
  bool loud_ended = false;  ///< the loud detail reached its end of life (the window ended there)
};

struct Options {
  int details = 8;
  int nodes_per_detail = 4000;
  double seconds = 30.0, quiet_rate = 5.0;
  std::int64_t loud_cycles = 50;
  /// Cycles the loud detail gets in one batch before the window opens (0: none). The window
  /// then skips the first breaks, which are the heaviest batches: with release_idle_factor a
  /// detail that breaks a bond after a pause factorizes again.
  std::int64_t loud_pre_cycles = 0;
  int worker_threads = 0;  ///< the daemon's --worker-threads in the first run (0: its default)
  bool one_thread = true;  ///< the second run with --worker-threads 1
  bool release_idle_factors = false;  ///< [detail.limits] release_idle_factor in every detail
  /// The quiet producers' phases: spread evenly over one period (independent sensors), or all
  /// publishing at the same instant (a burst of details-1 batches every period).
  bool aligned_phases = false;
};

/// One daemon run on `url` with `extra` daemon arguments.
RunResult run(const Options& o, const std::string& url, const fs::path& config,
              const fs::path& work, const std::vector<std::string>& extra,
              const std::string& name) {
  RunResult out;
  const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  lcm::LCM lcm(url);
  if (!lcm.good() || !messages::transport_up(lcm)) {
    out.error = "cannot open LCM at " + url;
    return out;
  }
  Fleet fleet(lcm, o.details);
  std::vector<std::string> argv{(bin / "peritwin").string(),
                                "--config",
                                config.string(),
                                "--lcm-url",
                                url,
                                "--state-dir",
                                (work / ("state-" + name)).string(),
                                "--no-results",
                                "--log-level",
                                "warn"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  const pid_t daemon =
      bench::spawn(argv, "/dev/null", (work / ("daemon-" + name + ".log")).string());
  if (daemon < 0) {
    out.error = "cannot start the daemon";
    return out;
  }
  const auto t0 = Clock::now();
  bool daemon_exited = false;  // reaped here: stop_child would wait for it in vain
  while (!fleet.all_seen() && since(t0) < 1800.0 && !daemon_exited) {
    messages::handle_lcm(lcm, 20);
    daemon_exited = waitpid(daemon, nullptr, WNOHANG) != 0;
  }
  out.startup_s = since(t0);
  if (!fleet.all_seen()) {
    out.error = std::string(daemon_exited ? "the daemon exited before" : "not") +
                " every detail published its first STATE (see " +
                (work / ("daemon-" + name + ".log")).string() + ")";
    if (!daemon_exited) bench::stop_child(daemon, 300.0);
    return out;
  }
  Feed& loud = fleet.feeds().front();
  if (o.loud_pre_cycles > 0) {
    fleet.publish(loud, 4000.0, o.loud_pre_cycles);
    const auto t_pre = Clock::now();
    while (!loud.in_flight.empty() && since(t_pre) < 600.0) messages::handle_lcm(lcm, 20);
    loud.latency_ms.clear();
    loud.to_state_ms.clear();
    loud.breaking_states = 0;
  }
  out.loud_cycles_before = loud.cycles;
  const auto start = Clock::now();
  const auto quiet_period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / o.quiet_rate));
  const auto quiet = static_cast<std::int64_t>(fleet.feeds().size()) - 1;
  std::int64_t quiet_index = 0;
  for (Feed& f : fleet.feeds()) {
    f.cycles_at_start = f.cycles;
    f.next_send = start;
    if (!f.loud && !o.aligned_phases) f.next_send += quiet_period * quiet_index++ / quiet;
  }
  std::int64_t loud_sent = 0;
  // The window ends after --seconds, or when the loud detail reaches its end of life (it breaks
  // no more bonds then).
  while (since(start) < o.seconds && !loud.ended) {
    const auto now = Clock::now();
    for (Feed& f : fleet.feeds()) {
      if (f.loud) {
        if (f.in_flight.empty() && !f.ended) {
          fleet.publish(f, 4000.0, o.loud_cycles);
          ++loud_sent;
        }
      } else if (now >= f.next_send) {
        fleet.publish(f, 500.0, 10);
        f.next_send += quiet_period;
      }
    }
    messages::handle_lcm(lcm, 1);
  }
  // The batches in flight: wait for them (at most 5 min), then stop.
  const auto drain = Clock::now();
  const auto pending = [&] {
    return std::any_of(fleet.feeds().begin(), fleet.feeds().end(),
                       [](const Feed& f) { return !f.in_flight.empty(); });
  };
  while (pending() && since(drain) < 300.0) messages::handle_lcm(lcm, 20);
  const double window =
      std::chrono::duration<double>(
          (loud.ended ? std::min(loud.ended_at, Clock::now()) : Clock::now()) - start)
          .count();
  out.window_s = window;
  out.loud_ended = loud.ended;
  out.rss_mb = core::proc_status_mb("VmRSS", std::to_string(daemon), std::nan(""));
  out.rss_peak_mb = core::proc_status_mb("VmHWM", std::to_string(daemon), std::nan(""));
  std::int64_t cycles = 0;
  for (const Feed& f : fleet.feeds()) {
    cycles += f.cycles - f.cycles_at_start;
    if (f.loud) {
      out.loud_batches = static_cast<std::int64_t>(f.latency_ms.size());
      out.loud_broken = f.broken_bonds;
      out.loud_breaking = f.breaking_states;
    } else {
      out.quiet_ms.insert(out.quiet_ms.end(), f.latency_ms.begin(), f.latency_ms.end());
      out.quiet_to_state_ms.insert(out.quiet_to_state_ms.end(), f.to_state_ms.begin(),
                                   f.to_state_ms.end());
    }
  }
  out.cycles_per_s = static_cast<double>(cycles) / window;
  (void)loud_sent;
  const int exit = bench::stop_child(daemon, 300.0);
  out.ok = !pending() && exit == 0;
  if (!out.ok) {
    out.error = pending() ? "batches still unapplied 300 s after the window"
                          : "the daemon exited with " + std::to_string(exit);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-fleet: one daemon, many details, one quiet/loud load"};
  Options o;
  app.add_option("--details", o.details, "details in the daemon (default 8; the goal: 32)")
      ->check(CLI::Range(2, 99));
  app.add_option("--nodes-per-detail", o.nodes_per_detail, "about this many nodes each (4000)")
      ->check(CLI::Range(200, 1'000'000));
  app.add_option("--seconds", o.seconds, "measured seconds per run (30)")
      ->check(CLI::PositiveNumber);
  app.add_option("--quiet-rate", o.quiet_rate, "batches per second of each quiet detail (5)")
      ->check(CLI::PositiveNumber);
  app.add_option("--loud-cycles", o.loud_cycles, "cycles per batch of the loud detail (50)")
      ->check(CLI::PositiveNumber);
  app.add_option("--worker-threads", o.worker_threads,
                 "the daemon's --worker-threads in the first run (default 0: its default)")
      ->check(CLI::Range(0, 1024));
  app.add_option("--loud-pre-cycles", o.loud_pre_cycles,
                 "cycles the loud detail gets in one batch before the window (default 0; B1 at 4 "
                 "kN breaks its first bond at about 1900)")
      ->check(CLI::NonNegativeNumber);
  bool no_one_thread = false;
  app.add_flag("--no-one-thread", no_one_thread, "skip the comparison run with one worker thread");
  app.add_flag("--release-idle-factors", o.release_idle_factors,
               "every detail frees its Cholesky factor while it breaks no bond ([detail.limits] "
               "release_idle_factor)");
  app.add_flag("--aligned-phases", o.aligned_phases,
               "every quiet detail publishes at the same instant (default: phases spread evenly "
               "over the period, as independent sensors)");
  CLI11_PARSE(app, argc, argv);
  o.one_thread = !no_one_thread;

  // B1 is 62.5 mm x 60 mm: nodes ~ 3750 mm^2 / dx^2.
  const double dx = std::sqrt(0.0625 * 0.060 / o.nodes_per_detail);
  const fs::path work =
      fs::temp_directory_path() / ("peritwin_bench_fleet_" + std::to_string(::getpid()));
  fs::create_directories(work);
  const fs::path config = work / "fleet.toml";
  try {
    std::ofstream(config) << fleet_config(o.details, dx, o.release_idle_factors);
  } catch (const std::exception& e) {
    std::cerr << "peritwin-bench-fleet: " << e.what() << "\n";
    return 3;
  }
  const int port = core::free_loopback_port();
  const pid_t hub = bench::spawn(
      {"java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", std::to_string(port)},
      "/dev/null", (work / "hub.log").string());
  if (hub < 0 || !core::wait_for_loopback_port(port, 60.0)) {
    std::cerr << "peritwin-bench-fleet: the LCM hub did not come up on port " << port << "\n";
    return 3;
  }
  const std::string url = "tcpq://127.0.0.1:" + std::to_string(port);
  const RunResult pool =
      run(o, url, config, work, {"--worker-threads", std::to_string(o.worker_threads)}, "pool");
  RunResult single;
  if (pool.ok && o.one_thread) {
    single = run(o, url, config, work, {"--worker-threads", "1"}, "one-thread");
  }
  bench::stop_child(hub, 60.0);
  for (const RunResult* r : std::initializer_list<const RunResult*>{&pool, &single}) {
    if (!r->ok && (r == &pool || o.one_thread)) {
      std::cerr << "peritwin-bench-fleet: " << r->error << " (in " << work << ")\n";
      return 3;
    }
  }
  fs::remove_all(work);

  const double p99 = core::percentile(pool.quiet_ms, 0.99);
  core::JsonLine line;
  line["bench"] = "fleet";
  line["details"] = o.details;
  line["release_idle_factors"] = o.release_idle_factors;
  line["quiet_phases"] = o.aligned_phases ? "aligned" : "spread";
  line["nodes_per_detail"] = o.nodes_per_detail;
  line["dx_m"] = core::fixed(dx, 6);
  line["startup_s"] = core::fixed(pool.startup_s, 2);
  line["startup_s_per_detail"] = core::fixed(pool.startup_s / o.details, 3);
  line["rss_mb"] = core::fixed(pool.rss_mb, 1);
  line["rss_peak_mb"] = core::fixed(pool.rss_peak_mb, 1);
  line["rss_mb_per_detail"] = core::fixed(pool.rss_mb / o.details, 2);
  line["cycles_per_s"] = core::fixed(pool.cycles_per_s, 0);
  line["quiet_batches"] = pool.quiet_ms.size();
  line["quiet_p50_ms"] = core::fixed(core::percentile(pool.quiet_ms, 0.5), 2);
  // The part until the daemon made the STATE (wall clock, its utime): receipt, the wait for a
  // worker and the batch; the rest of quiet_p*_ms is the STATE's way back over the bus.
  line["quiet_p50_ms_to_state"] = core::fixed(core::percentile(pool.quiet_to_state_ms, 0.5), 2);
  line["quiet_p99_ms_to_state"] = core::fixed(core::percentile(pool.quiet_to_state_ms, 0.99), 2);
  line["quiet_p99_ms"] = core::fixed(p99, 2);
  line["loud_batches"] = pool.loud_batches;
  line["loud_broken_bonds"] = pool.loud_broken;
  line["loud_cycles_before_window"] = pool.loud_cycles_before;
  // Loud batches whose STATE shows more broken bonds than the one before (each a re-solve).
  line["loud_breaking_batches"] = pool.loud_breaking;
  line["window_s"] = core::fixed(pool.window_s, 1);
  line["loud_end_of_life"] = pool.loud_ended;
  line["worker_threads"] = o.worker_threads;  // 0: the daemon's default (the cores, at least 2)
  if (o.one_thread) {
    const double p99_one = core::percentile(single.quiet_ms, 0.99);
    line["startup_s_one_thread"] = core::fixed(single.startup_s, 2);
    line["quiet_batches_one_thread"] = single.quiet_ms.size();
    line["quiet_p50_ms_one_thread"] = core::fixed(core::percentile(single.quiet_ms, 0.5), 2);
    line["quiet_p99_ms_one_thread"] = core::fixed(p99_one, 2);
    line["quiet_p99_one_thread_over_pool"] = core::fixed(p99_one / p99, 2);
    line["loud_batches_one_thread"] = single.loud_batches;
    line["loud_breaking_batches_one_thread"] = single.loud_breaking;
    line["rss_mb_one_thread"] = core::fixed(single.rss_mb, 1);
  }
  line["goals"] = {{"rss_mb_at_32x4000", 1536},
                   {"quiet_p99_ms", 20},
                   {"startup_s_per_detail", 0.5},
                   {"quiet_p99_ok", p99 <= 20.0},
                   {"startup_ok", pool.startup_s / o.details <= 0.5}};
  line["transport"] = "tcpq";
  core::print_line(line);
  return 0;
}
