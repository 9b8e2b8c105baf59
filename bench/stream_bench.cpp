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
#include "bench/percentile.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/transport.h"
#include "stream/stream_tool.h"
#include "tests/support/loopback_port.h"
#include "tools/json_line.h"
#include "twin/config/config.h"

namespace {

namespace fs = std::filesystem;
using namespace peritwin;
using bench::Clock;
using bench::percentile;
using bench::since;

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-stream: sensor samples -> peritwin-stream -> daemon, latency"};
  std::string config_file = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml";
  double seconds = 20.0, rate = 10'000.0, cycle_hz = 30.0, warm_up_s = 2.0;
  app.add_option("--config", config_file, "detail config (default: the demo's B1 detail)");
  app.add_option("--seconds", seconds, "seconds of samples measured after the warm-up (20)")
      ->check(CLI::PositiveNumber);
  app.add_option("--rate", rate, "samples per second (10000)")->check(CLI::PositiveNumber);
  app.add_option("--cycle-hz", cycle_hz, "load cycles per second (30)")->check(CLI::PositiveNumber);
  app.add_option("--warm-up", warm_up_s, "seconds of samples not measured first (2)")
      ->check(CLI::NonNegativeNumber);
  CLI11_PARSE(app, argc, argv);

  const auto loaded = twin::load_config(config_file);
  if (!loaded.ok()) {
    std::cerr << loaded.error_text() << "\n";
    return 2;
  }
  const twin::DetailConfig& detail = loaded.config->details.at(0);
  const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
  const fs::path work =
      fs::temp_directory_path() / ("peritwin_bench_stream_" + std::to_string(::getpid()));
  fs::create_directories(work);

  pid_t hub = -1, daemon = -1, stream = -1;
  int pipe_fd[2] = {-1, -1};
  std::unique_ptr<lcm::LCM> lcm;
  std::unique_ptr<StateWatch> watch;
  auto cleanup = [&](int code) {
    if (pipe_fd[1] >= 0) close(pipe_fd[1]);
    if (stream > 0) bench::stop_child(stream, 60.0);
    watch.reset();
    lcm.reset();
    if (daemon > 0) bench::stop_child(daemon, 300.0);
    if (hub > 0) bench::stop_child(hub, 60.0);
    if (code == 0 || code == 1) fs::remove_all(work);
    return code;
  };
  const int port = twin::free_loopback_port();
  hub = bench::spawn(
      {"java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", std::to_string(port)},
      "/dev/null", (work / "hub.log").string());
  if (hub < 0 || !twin::wait_for_loopback_port(port, 60.0)) {
    std::cerr << "peritwin-bench-stream: the LCM hub did not come up on port " << port << "\n";
    return cleanup(3);
  }
  const std::string url = "tcpq://127.0.0.1:" + std::to_string(port);
  lcm = std::make_unique<lcm::LCM>(url);
  if (!lcm->good() || !messages::transport_up(*lcm)) {
    std::cerr << "peritwin-bench-stream: cannot open LCM at " << url << "\n";
    return cleanup(3);
  }
  watch = std::make_unique<StateWatch>(*lcm, detail.id);
  daemon = bench::spawn(
      {(bin / "peritwin").string(), "--config", config_file, "--lcm-url", url, "--state-dir",
       (work / "state").string(), "--no-results", "--log-level", "warn"},
      "/dev/null", (work / "daemon.log").string());
  const auto t_start = Clock::now();
  while (!watch->seen_state && since(t_start) < 600.0 && waitpid(daemon, nullptr, WNOHANG) == 0) {
    messages::handle_lcm(*lcm, 50);
  }
  if (!watch->seen_state) {
    std::cerr << "peritwin-bench-stream: no STATE from the daemon (see " << (work / "daemon.log")
              << ")\n";
    return cleanup(3);
  }
  // O_CLOEXEC: the stream must not inherit the write end, or it never sees the end of its input.
  if (pipe2(pipe_fd, O_CLOEXEC) != 0) return cleanup(3);
  stream = bench::spawn({(bin / "peritwin-stream").string(), "--config", config_file, "--input",
                         "-", "--lcm-url", url, "--batch-seconds", "0.1", "--json"},
                        (work / "stream.out").string(), (work / "stream.err").string(), pipe_fd[0]);
  close(pipe_fd[0]);
  pipe_fd[0] = -1;
  if (stream < 0) return cleanup(3);

  // The shadow pipeline: which sample closes which batch (the stream's own options).
  replay::BatchingOptions batching;
  batching.max_seconds = 0.1;
  batching.merge_identical = true;
  stream::Pipeline shadow(detail, kSource, batching, 1);
  std::vector<twin::Batch> closed;
  std::vector<Clock::time_point> closed_at(1);  // [k]: when batch k's closing sample was written
  const auto total = static_cast<std::int64_t>((warm_up_s + seconds) * rate);
  const auto t0 = Clock::now();
  std::string chunk;
  std::int64_t written = 0;
  while (written < total) {
    const auto due = std::min<std::int64_t>(total, static_cast<std::int64_t>(since(t0) * rate) + 1);
    chunk.clear();
    for (; written < due; ++written) {
      const double t = static_cast<double>(written) / rate;
      const double p = 2200.0 + 1800.0 * std::sin(2.0 * std::numbers::pi * cycle_hz * t);
      char line[64];
      const int n = std::snprintf(line, sizeof line, "%.6f,%.6f\n", t, p);
      chunk.append(line, static_cast<std::size_t>(n));
      // The shadow sees the value the stream will parse from the text.
      double tp = 0, pp = 0;
      std::sscanf(line, "%lf,%lf", &tp, &pp);
      shadow.sample(tp, pp, 0.0, closed);
    }
    for (std::size_t off = 0; off < chunk.size();) {
      const ssize_t w = write(pipe_fd[1], chunk.data() + off, chunk.size() - off);
      if (w <= 0) {
        std::cerr << "peritwin-bench-stream: the stream closed its input\n";
        return cleanup(3);
      }
      off += static_cast<std::size_t>(w);
    }
    const auto now = Clock::now();
    closed_at.resize(closed.size() + 1, now);
    messages::handle_lcm(*lcm, 0);
    while (messages::handle_lcm(*lcm, 0) > 0) {
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  close(pipe_fd[1]);
  pipe_fd[1] = -1;
  const int stream_exit = bench::wait_child(stream, 600.0);
  stream = -1;
  const auto last_batch = static_cast<std::int64_t>(closed.size());
  const auto wait_from = Clock::now();
  while (static_cast<std::int64_t>(watch->applied_at.size()) <= last_batch &&
         since(wait_from) < 60.0) {
    messages::handle_lcm(*lcm, 50);
  }

  // Latencies of the batches closed after the warm-up (in sample time).
  std::vector<double> latency_ms;
  const auto first_measured = static_cast<std::size_t>(std::ceil(warm_up_s / 0.1)) + 1;
  for (std::size_t k = first_measured; k < closed_at.size() && k < watch->applied_at.size(); ++k) {
    latency_ms.push_back(
        std::chrono::duration<double, std::milli>(watch->applied_at[k] - closed_at[k]).count());
  }
  std::uint64_t counted = 0;
  {
    std::ifstream out(work / "stream.out");
    std::string line, last;
    while (std::getline(out, line)) last = line;
    const auto summary = nlohmann::json::parse(last, nullptr, false);
    if (summary.is_object() && summary.contains("stream")) {
      counted = summary["stream"].value("samples", std::uint64_t{0});
    }
  }
  tools::JsonLine line;
  line["bench"] = "stream";
  line["rate_hz"] = rate;
  line["batch_seconds"] = 0.1;
  line["seconds"] = seconds;
  line["samples_written"] = written;
  line["samples_counted"] = counted;
  line["dropped"] = written - static_cast<std::int64_t>(counted);
  line["batches"] = last_batch;
  line["batches_measured"] = latency_ms.size();
  const double p99 = percentile(latency_ms, 0.99);
  line["latency_ms"] = {{"p50", tools::fixed(percentile(latency_ms, 0.5), 2)},
                        {"p90", tools::fixed(percentile(latency_ms, 0.9), 2)},
                        {"p99", tools::fixed(p99, 2)},
                        {"max", tools::fixed(percentile(latency_ms, 1.0), 2)}};
  line["goal_p99_ms"] = 50;
  line["ratio_p99_to_goal"] = tools::fixed(p99 / 50.0, 3);
  line["broken_bonds"] = watch->broken_bonds;
  line["stream_exit"] = stream_exit;
  line["transport"] = "tcpq";
  tools::print_line(line);
  const bool complete =
      static_cast<std::int64_t>(watch->applied_at.size()) > last_batch && stream_exit == 0;
  if (!complete) {
    std::cerr << "peritwin-bench-stream: not every batch was applied (see " << work << ")\n";
    return cleanup(3);
  }
  return cleanup(watch->broken_bonds > 0 ? 1 : 0);
}
