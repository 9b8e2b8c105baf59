// peritwin-bench-stream (also `peritwin-bench stream`): end-to-end latency of a live sensor stream.
// Issue 16's goal: samples at 10 kHz, batches every 100 ms of sample time, p99 latency from the
// last sample of a batch to the STATE that shows it applied <= 50 ms while no bond breaks, and no
// sample dropped.
//
// Starts LCM's Java TCP hub on a free loopback port, the daemon binary (as deployed, no
// --deterministic: remaining-life estimates run on its worker thread) on --config (default the
// demo's B1 detail) and peritwin-stream --input - --batch-seconds 0.1 on a pipe. After the
// daemon's first STATE it writes samples in real time at --rate Hz: P(t) = 2200 + 1800 sin(2π f t)
// N (4 kN, R 0.1 at --cycle-hz f, 30 Hz by default: 3 cycles per batch), paced by the wall clock
// in 1 ms steps. The same samples go through a shadow of the stream's pipeline (stream::Pipeline,
// the same library) to know which sample closes which batch; the latency of batch k is the time
// from writing its closing sample to receiving the first STATE whose applied seq of the stream's
// source is >= k. The first --warm-up-s of batches are not counted (the daemon's first
// remaining-life estimate and the JIT of the hub). At the end the pipe is closed, the stream
// finishes (residue half) and prints its summary; dropped = samples written - samples it counted.
// One JSON line:
//   {"bench":"stream","rate_hz":…,"batch_seconds":0.1,"seconds":…,"samples_written":…,
//    "samples_counted":…,"dropped":…,"batches":…,"batches_measured":…,"latency_ms":{"p50":…,
//    "p90":…,"p99":…,"max":…},"goal_p99_ms":50,"ratio_p99_to_goal":…,"broken_bonds":…,
//    "transport":"tcpq"}
// Exit 0 when every batch was applied and nothing broke, 1 when a bond broke (the measure is not
// "while no bond breaks"), 3 on a runtime failure.
// With --gauges [--gauge-samples N]: instead, in-process, the rate of strain gauges -> P, α
// (bench/gauge_bench.h; one JSON line per form of the load, "bench":"gauge_identification").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <thread>

#include "bench/child_process.h"
#include "bench/gauge_bench.h"
#include "config/config.h"
#include "core/json_line.h"
#include "core/loopback_port.h"
#include "core/percentile.h"
#include "core/program.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/transport.h"
#include "stream/stream_tool.h"

namespace {

namespace fs = std::filesystem;
using namespace peritwin;
using bench::Clock;
using bench::since;
using peritwin::core::percentile;

constexpr const char* kSource = "stream";

/// Follows the detail's STATE: the arrival time of the first state showing each applied seq.
class StateWatch {
 public:
  StateWatch(lcm::LCM& lcm, const std::string& detail) : lcm_(lcm) {
    sub_ = lcm_.subscribe(messages::channel(detail, messages::Kind::kState), &StateWatch::on_state,
                          this);
    sub_->setQueueCapacity(100'000);
  }
  ~StateWatch() { lcm_.unsubscribe(sub_); }
  StateWatch(const StateWatch&) = delete;
  StateWatch& operator=(const StateWatch&) = delete;

  std::vector<Clock::time_point> applied_at;  ///< [k]: first STATE with applied seq >= k
  bool seen_state = false;
  std::int64_t broken_bonds = 0;

 private:
  void on_state(const lcm::ReceiveBuffer*, const std::string&,
                const peritwin_msgs::damage_state_t* s) {
    const auto now = Clock::now();
    seen_state = true;
    broken_bonds = s->broken_bonds;
    const std::int64_t applied = messages::applied_seq(*s, kSource);
    while (static_cast<std::int64_t>(applied_at.size()) <= applied) applied_at.push_back(now);
  }
  lcm::LCM& lcm_;
  lcm::Subscription* sub_ = nullptr;
};

/// The command line.
struct Options {
  std::string config_file = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml";
  double seconds = 20.0, rate = 10'000.0, cycle_hz = 30.0, warm_up_s = 2.0;
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--config", o.config_file, "detail config (default: the demo's B1 detail)");
  app.add_option("--seconds", o.seconds, "seconds of samples measured after the warm-up (20)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rate", o.rate, "samples per second (10000)")->check(CLI::PositiveNumber);
  app.add_option("--cycle-hz", o.cycle_hz, "load cycles per second (30)")
      ->check(CLI::PositiveNumber);
  app.add_option("--warm-up", o.warm_up_s, "seconds of samples not measured first (2)")
      ->check(CLI::NonNegativeNumber);
}

/// The samples written to the stream, and when each batch's closing sample was written.
struct Feed {
  std::int64_t written = 0;
  std::vector<Clock::time_point> closed_at =
      std::vector<Clock::time_point>(1);  ///< [k]: when batch k's closing sample was written
  std::int64_t last_batch = 0;
};

/// The summary's "stream".samples of the stream's output (0 when there is none).
std::uint64_t counted_samples(const fs::path& out_file) {
  std::uint64_t counted = 0;
  std::ifstream out(out_file);
  std::string line, last;
  while (std::getline(out, line)) last = line;
  const auto summary = nlohmann::json::parse(last, nullptr, false);
  if (summary.is_object() && summary.contains("stream")) {
    counted = summary["stream"].value("samples", std::uint64_t{0});
  }
  return counted;
}

/// One run: the hub, the daemon and peritwin-stream as child processes, the STATE watched.
class Run {
 public:
  Run(const Options& o, const config::DetailConfig& detail)
      : o_(o),
        detail_(detail),
        work_(fs::temp_directory_path() / ("peritwin_bench_stream_" + std::to_string(::getpid()))) {
    fs::create_directories(work_);
  }
  /// Stops what runs, removes the work directory unless `code` is a failure; returns `code`.
  int cleanup(int code) {
    if (pipe_fd_[1] >= 0) close(pipe_fd_[1]);
    pipe_fd_[1] = -1;
    if (stream_ > 0) bench::stop_child(stream_, 60.0);
    stream_ = -1;
    watch_.reset();
    lcm_.reset();
    if (daemon_ > 0) bench::stop_child(daemon_, 300.0);
    daemon_ = -1;
    if (hub_ > 0) bench::stop_child(hub_, 60.0);
    hub_ = -1;
    if (code == 0 || code == 1) fs::remove_all(work_);
    return code;
  }
  /// The hub, the daemon (up to its first STATE) and the stream; false (said) when one fails.
  bool start();
  /// The samples at --rate into the stream, a shadow pipeline telling which closes each batch;
  /// false when the stream closed its input.
  bool feed(Feed& f);
  /// Closes the stream's input and waits for it and for the daemon to apply the last batch; the
  /// JSON line; the exit code.
  int finish(const Feed& f);

 private:
  const Options& o_;
  const config::DetailConfig& detail_;
  fs::path work_;
  pid_t hub_ = -1, daemon_ = -1, stream_ = -1;
  int pipe_fd_[2] = {-1, -1};
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<StateWatch> watch_;
};

bool Run::start() {
  const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  const int port = core::free_loopback_port();
  hub_ = bench::spawn(
      {"java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", std::to_string(port)},
      "/dev/null", (work_ / "hub.log").string());
  if (hub_ < 0 || !core::wait_for_loopback_port(port, 60.0)) {
    std::cerr << "peritwin-bench-stream: the LCM hub did not come up on port " << port << "\n";
    return false;
  }
  const std::string url = "tcpq://127.0.0.1:" + std::to_string(port);
  lcm_ = std::make_unique<lcm::LCM>(url);
  if (!lcm_->good() || !messages::transport_up(*lcm_)) {
    std::cerr << "peritwin-bench-stream: cannot open LCM at " << url << "\n";
    return false;
  }
  watch_ = std::make_unique<StateWatch>(*lcm_, detail_.id);
  daemon_ = bench::spawn(
      {(bin / "peritwin").string(), "--config", o_.config_file, "--lcm-url", url, "--state-dir",
       (work_ / "state").string(), "--no-results", "--log-level", "warn"},
      "/dev/null", (work_ / "daemon.log").string());
  const auto t_start = Clock::now();
  while (!watch_->seen_state && since(t_start) < 600.0 && waitpid(daemon_, nullptr, WNOHANG) == 0) {
    messages::handle_lcm(*lcm_, 50);
  }
  if (!watch_->seen_state) {
    std::cerr << "peritwin-bench-stream: no STATE from the daemon (see " << (work_ / "daemon.log")
              << ")\n";
    return false;
  }
  // O_CLOEXEC: the stream must not inherit the write end, or it never sees the end of its input.
  if (pipe2(pipe_fd_, O_CLOEXEC) != 0) return false;
  stream_ =
      bench::spawn({(bin / "peritwin-stream").string(), "--config", o_.config_file, "--input", "-",
                    "--lcm-url", url, "--batch-seconds", "0.1", "--json"},
                   (work_ / "stream.out").string(), (work_ / "stream.err").string(), pipe_fd_[0]);
  close(pipe_fd_[0]);
  pipe_fd_[0] = -1;
  return stream_ >= 0;
}

bool Run::feed(Feed& f) {
  // The shadow pipeline: which sample closes which batch (the stream's own options).
  loads::BatchingOptions batching;
  batching.max_seconds = 0.1;
  batching.merge_identical = true;
  stream::Pipeline shadow(detail_, kSource, batching, 1);
  std::vector<messages::Batch> closed;
  const auto total = static_cast<std::int64_t>((o_.warm_up_s + o_.seconds) * o_.rate);
  const auto t0 = Clock::now();
  std::string chunk;
  while (f.written < total) {
    const auto due =
        std::min<std::int64_t>(total, static_cast<std::int64_t>(since(t0) * o_.rate) + 1);
    chunk.clear();
    for (; f.written < due; ++f.written) {
      const double t = static_cast<double>(f.written) / o_.rate;
      const double p = 2200.0 + 1800.0 * std::sin(2.0 * std::numbers::pi * o_.cycle_hz * t);
      char line[64];
      const int n = std::snprintf(line, sizeof line, "%.6f,%.6f\n", t, p);
      chunk.append(line, static_cast<std::size_t>(n));
      // The shadow sees the value the stream will parse from the text.
      double tp = 0, pp = 0;
      std::sscanf(line, "%lf,%lf", &tp, &pp);
      shadow.sample(tp, pp, 0.0, closed);
    }
    for (std::size_t off = 0; off < chunk.size();) {
      const ssize_t w = write(pipe_fd_[1], chunk.data() + off, chunk.size() - off);
      if (w <= 0) {
        std::cerr << "peritwin-bench-stream: the stream closed its input\n";
        return false;
      }
      off += static_cast<std::size_t>(w);
    }
    const auto now = Clock::now();
    f.closed_at.resize(closed.size() + 1, now);
    messages::handle_lcm(*lcm_, 0);
    while (messages::handle_lcm(*lcm_, 0) > 0) {
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  f.last_batch = static_cast<std::int64_t>(closed.size());
  return true;
}

int Run::finish(const Feed& f) {
  close(pipe_fd_[1]);
  pipe_fd_[1] = -1;
  const int stream_exit = bench::wait_child(stream_, 600.0);
  stream_ = -1;
  const std::int64_t last_batch = f.last_batch;
  const auto wait_from = Clock::now();
  while (static_cast<std::int64_t>(watch_->applied_at.size()) <= last_batch &&
         since(wait_from) < 60.0) {
    messages::handle_lcm(*lcm_, 50);
  }

  // Latencies of the batches closed after the warm-up (in sample time).
  std::vector<double> latency_ms;
  const auto first_measured = static_cast<std::size_t>(std::ceil(o_.warm_up_s / 0.1)) + 1;
  for (std::size_t k = first_measured; k < f.closed_at.size() && k < watch_->applied_at.size();
       ++k) {
    latency_ms.push_back(
        std::chrono::duration<double, std::milli>(watch_->applied_at[k] - f.closed_at[k]).count());
  }
  const std::uint64_t counted = counted_samples(work_ / "stream.out");
  core::JsonLine line;
  line["bench"] = "stream";
  line["rate_hz"] = o_.rate;
  line["batch_seconds"] = 0.1;
  line["seconds"] = o_.seconds;
  line["samples_written"] = f.written;
  line["samples_counted"] = counted;
  line["dropped"] = f.written - static_cast<std::int64_t>(counted);
  line["batches"] = last_batch;
  line["batches_measured"] = latency_ms.size();
  const double p99 = core::percentile(latency_ms, 0.99);
  line["latency_ms"] = {{"p50", core::fixed(core::percentile(latency_ms, 0.5), 2)},
                        {"p90", core::fixed(core::percentile(latency_ms, 0.9), 2)},
                        {"p99", core::fixed(p99, 2)},
                        {"max", core::fixed(core::percentile(latency_ms, 1.0), 2)}};
  line["goal_p99_ms"] = 50;
  line["ratio_p99_to_goal"] = core::fixed(p99 / 50.0, 3);
  line["broken_bonds"] = watch_->broken_bonds;
  line["stream_exit"] = stream_exit;
  line["transport"] = "tcpq";
  core::print_line(line);
  const bool complete =
      static_cast<std::int64_t>(watch_->applied_at.size()) > last_batch && stream_exit == 0;
  if (!complete) {
    std::cerr << "peritwin-bench-stream: not every batch was applied (see " << work_ << ")\n";
    return cleanup(3);
  }
  return cleanup(watch_->broken_bonds > 0 ? 1 : 0);
}

/// The benchmark; the exit code.
int run(const Options& o) {
  const auto loaded = config::load_config(o.config_file);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text() << "\n";
    return 2;
  }
  Run r(o, loaded.config->details.at(0));
  if (!r.start()) return r.cleanup(3);
  Feed f;
  if (!r.feed(f)) return r.cleanup(3);
  return r.finish(f);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-stream: sensor samples -> peritwin-stream -> daemon, latency"};
  Options o;
  add_options(app, o);
  bool gauges = false;
  std::int64_t gauge_samples = 1'000'000;
  app.add_flag("--gauges", gauges,
               "instead: the rate of strain gauges -> P, α (stream/gauge_identification.h) for 8 "
               "gauges in each form of the load, in-process (bench/gauge_bench.h)");
  app.add_option("--gauge-samples", gauge_samples, "--gauges: identify() calls per form (1e6)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40));
  if (const auto rc = core::parse_options(app, argc, argv, core::ParseErrors::cli11)) return *rc;
  if (gauges) return bench::run_gauge_identification(gauge_samples);
  return run(o);
}
