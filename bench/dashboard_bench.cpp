// peritwin-bench-dashboard (also `peritwin-bench dashboard`): STATE-to-SSE-event latency of the
// web dashboard under load, with its CPU and memory. Issue 17's goal: with 100 details publishing
// 10 states/s each, the p99 from a STATE's publication to its Server-Sent Event is at most 20 ms,
// the dashboard uses at most 10 % of one core and its RSS stays below 200 MB with full histories.
//
// Starts LCM's Java TCP hub on a free loopback port (unless --lcm-url is given) and the
// `peritwin-dashboard` binary as a child process (--listen 127.0.0.1:0, the port read from its
// stdout), then plays --details daemons on one LCM connection (TCP_NODELAY, as the daemon's):
//   warm-up      --warmup states per detail as fast as the hub and the dashboard take them (LCM
//                tcpq blocks the publisher when they fall behind), then waits until /api/details
//                counts them all. The default, 10 000, is the dashboard's history bound
//                (dashboard/store.h, kHistoryPoints): every detail's history is then full, at
//                its cap, and the first state of the window makes each one decimate.
//   measurement  one SSE client on /api/events (a plain socket, as a browser: no TCP options),
//                then --seconds of STATE at --rate per detail, evenly staggered over the details,
//                and a STATUS per detail every second (the daemon's heartbeat), then 2 s for the
//                last events to arrive.
// Each STATE's publication time (taken just before lcm.publish) is matched with the arrival of
// its "state" event (detail and state_seq; the event's cycles are checked against the state's)
// at the SSE client (the time recv() returned the bytes that completed it). The dashboard's CPU is
// utime + stime from /proc/<pid>/stat over the window divided by the window's wall time; its RSS
// is VmRSS at the end of the window and VmHWM (peak) from /proc/<pid>/status. Between the warm-up
// and the window every detail's history is fetched once (/api/details/{id}/history, as the page
// does when it loads): its points (history_points_*) and the time of each request
// (history_get_ms; the store's mutex is held while the JSON is built). One JSON line:
//   {"bench":"dashboard","details":…,"states_per_s_per_detail":…,"states_per_s":…,"duration_s":…,
//    "warmup_states_per_detail":…,"warmup_s":…,"warmup_cpu_us_per_state":…,"history_points_min":…,
//    "history_points_max":…,"history_get_ms":{"mean":…,"max":…},"published":…,"events":…,
//    "missing_events":…,"cycle_mismatches":…,"status_events":…,
//    "sse_clients":…,"latency_ms":{"p50":…,"p90":…,"p99":…,"max":…,"over_goal_fraction":…},
//    ["lcm_reference_latency_ms":{"events":…,"p50":…,"p99":…,"max":…,"over_goal_fraction":…},]
//    "cpu_fraction_of_core":…,"cpu_us_per_state":…,
//    "rss_after_warmup_mb":…,"rss_mb":…,"rss_peak_mb":…,
//    "goals":{"p99_ms":20,"cpu_fraction_of_core":0.1,"rss_mb":200},
//    "pass":{"p99":…,"cpu":…,"rss":…},"load_average_1min":…,"sse_quickack":…,"dashboard_exit":…,
//    "transport":"tcpq"}
// over_goal_fraction: the events later than the goal (20 ms). --sse-clients N: N clients on
// /api/events (browser tabs), the first one timed. lcm_reference_latency_ms (--lcm-reference): the
// same states timed to a second LCM subscriber in this process, the hub's share. load_average_1min
// (/proc/loadavg at the end of the window) says how busy the machine was: on a shared machine the
// tail latency is mostly other processes' time slices. Exit 0 when measured (whatever the goals
// say: timings depend on the machine), 3 on a runtime failure (hub, dashboard, a dashboard that
// does not count the warm-up states).
//
// Issue 30 item 4, a dashboard that cannot be locked out: --streams N holds N more event streams
// open through the window (each counts the events it receives) and --idle M holds M idle
// connections (every other one has sent half a request line; one the dashboard closes after its
// header timeout is opened again), all on one thread of the bench, while GET / and GET
// /api/details are fetched every --fetch-period-ms (100) on a new connection each. The line then
// has "lockout": {"streams","streams_open" (answered 200),"streams_with_events",
// "stream_events_min","streams_closed_by_dashboard","idle","idle_reopened","connect_failures",
// "fetch_period_ms","page_ms":{n,p50,p99,max},"api_details_ms":{…},"fetch_failures",
// "threads_before","threads_max" (the dashboard's, /proc/<pid>/status, before the connections
// and at most during the window),"goal_p99_ms":50,"pass"}: pass when every stream was answered
// 200 and received events, no fetch failed and both p99 are at most 50 ms. With many streams the
// events are written to each of them: keep the rate modest (e.g. --details 10 --rate 1; at 1100
// events/s the 1000 streams would be 2 GB/s). --max-event-streams N is passed to the dashboard.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/child_process.h"
#include "core/json_line.h"
#include "core/loopback_port.h"
#include "core/percentile.h"
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
using peritwin::core::percentile;
using peritwin::core::proc_cpu_s;
using peritwin::core::proc_status_kb;
using peritwin::core::read_text;

// --- HTTP
// -----------------------------------------------------------------------------------------

int connect_loopback(int port, double recv_timeout_s) {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  if (s < 0) return -1;
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(recv_timeout_s);
  tv.tv_usec = static_cast<suseconds_t>((recv_timeout_s - std::floor(recv_timeout_s)) * 1e6);
  setsockopt(s, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  if (connect(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    close(s);
    return -1;
  }
  return s;
}

bool send_all(int s, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const auto n = send(s, text.data() + done, text.size() - done, MSG_NOSIGNAL);
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

/// GET `path` on 127.0.0.1:port (Connection: close): the body of a 200 answer, or nullopt.
/// The dashboard's JSON routes answer with a Content-Length body.
std::optional<std::string> http_get(int port, const std::string& path) {
  const int s = connect_loopback(port, 30.0);
  if (s < 0) return std::nullopt;
  std::string text;
  if (send_all(s, "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n")) {
    char buf[65536];
    ssize_t n = 0;
    while ((n = recv(s, buf, sizeof buf, 0)) > 0) text.append(buf, static_cast<std::size_t>(n));
  }
  close(s);
  const auto end = text.find("\r\n\r\n");
  if (text.rfind("HTTP/1.1 200", 0) != 0 || end == std::string::npos) return std::nullopt;
  return text.substr(end + 4);
}

// --- what is published
// ----------------------------------------------------------------------------

std::string detail_id(int i) {
  char id[24];
  std::snprintf(id, sizeof id, "bench-%03d", i);
  return id;
}

/// Cycles of state `seq` of detail `i`: 1000 cycles per batch, details offset.
std::int64_t cycles_of(int i, std::int64_t seq) { return 1000 * seq + 17 * i; }

std::string hex16(std::uint64_t v) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(v));
  return text;
}

/// A STATE as the daemon publishes it for a detail with one notch crack growing: one source, the
/// main crack with its tip and K, a remaining-life estimate with its band, both hashes.
peritwin_msgs::damage_state_t state_message(int i, std::int64_t seq) {
  peritwin_msgs::damage_state_t s{};
  s.utime = peritwin::messages::now_utime();
  s.detail_id = detail_id(i);
  s.state_seq = seq;
  s.num_sources = 1;
  s.source_ids = {"gauge-1"};
  s.applied_seq = {seq};
  s.checkpointed_seq = {seq - seq % 100};
  s.history = {0};
  s.history_start = {0};
  s.total_cycles = cycles_of(i, seq);
  const double growth = 1e-7 * static_cast<double>(seq);  // 0.1 µm per batch: 1 mm per 10^4
  s.broken_bonds = 40 + seq / 50;
  s.max_damage = std::min(1.0, 0.4 + 1e-5 * static_cast<double>(seq));
  s.crack_count = 1;
  s.crack_length_m = 0.002 + growth;
  s.num_cracks = 1;
  peritwin_msgs::crack_t c{};
  c.id = 1;
  c.origin_kind = peritwin_msgs::crack_t::ORIGIN_NOTCH;
  c.origin = "notch 0";
  c.notch_index = 0;
  c.origin_x = 0.0275;
  c.origin_y = 0.0;
  c.tip_x = 0.0275 + s.crack_length_m;
  c.tip_y = 1e-5;
  c.length_m = s.crack_length_m;
  c.projected_length_m = s.crack_length_m;
  c.kink_angle_rad = 0.0;
  c.num_nodes = 2 + static_cast<std::int32_t>(seq / 100);
  c.phase = peritwin_msgs::crack_t::PHASE_PROPAGATION;
  c.birth_cycle = 12000;
  c.num_tips = 1;
  peritwin_msgs::crack_tip_t tip{};
  tip.x = c.tip_x;
  tip.y = c.tip_y;
  tip.angle_rad = 0.0;
  tip.k_i = 9.5e6 * std::sqrt(1.0 + growth / 0.015);
  tip.k_ii = 1.0e4;
  tip.k_status = peritwin_msgs::crack_tip_t::K_OK;
  c.tips = {tip};
  c.num_absorbed = 0;
  s.cracks = {c};
  s.k_i = tip.k_i;
  s.k_ii = tip.k_ii;
  s.remaining_cycles = std::max(0.0, 4.0e7 - 1000.0 * static_cast<double>(seq));
  s.remaining_cycles_low = 0.8 * s.remaining_cycles;
  s.remaining_cycles_high = 1.25 * s.remaining_cycles;
  s.remaining_life_seq = std::max<std::int64_t>(0, seq - 3);
  s.remaining_life_source = "gauge-1";
  s.failure = peritwin_msgs::damage_state_t::FAILURE_NONE;
  s.end_of_life_cycle = -1;
  s.state_hash = hex16(0x9e3779b97f4a7c15ULL * static_cast<std::uint64_t>(seq + 1) +
                       static_cast<std::uint64_t>(i));
  s.engine_hash = hex16(0xc2b2ae3d27d4eb4fULL * static_cast<std::uint64_t>(seq + 7) +
                        static_cast<std::uint64_t>(i));
  s.tag_length = 0;
  return s;
}

peritwin_msgs::status_t status_message(int i, std::int64_t last_seq, double uptime_s) {
  peritwin_msgs::status_t st{};
  st.utime = peritwin::messages::now_utime();
  st.detail_id = detail_id(i);
  st.health = "ok";
  st.last_seq = last_seq;
  st.pending = 0;
  st.lag_s = 0.0;
  st.uptime_s = uptime_s;
  st.errors = 0;
  st.duplicates = 0;
  st.gaps = 0;
  st.busy_s = 0.0;
  st.auth_rejects = 0;
  st.reject_rate = 0.0;
  return st;
}

// --- the SSE client
// -------------------------------------------------------------------------------

/// Publication times of the measured states, by detail and seq (from first_seq), and the arrival
/// latencies of their events.
class Matcher {
 public:
  Matcher(int details, std::int64_t first_seq, std::int64_t per_detail)
      : first_seq_(first_seq),
        per_detail_(per_detail),
        published_(static_cast<std::size_t>(details) * static_cast<std::size_t>(per_detail)) {}

  void published(int i, std::int64_t seq, Clock::time_point at) {
    const std::lock_guard lock(mutex_);
    if (const auto k = slot(i, seq)) published_[*k] = at;
  }
  /// A state event of detail i, state seq, its cycles, arrived at `at`.
  void arrived(int i, std::int64_t seq, std::int64_t cycles, Clock::time_point at) {
    const std::lock_guard lock(mutex_);
    const auto k = slot(i, seq);
    if (!k || published_[*k] == Clock::time_point{}) {
      ++unmatched_;
      return;
    }
    if (cycles != cycles_of(i, seq)) ++cycle_mismatches_;
    latencies_ms_.push_back(std::chrono::duration<double, std::milli>(at - published_[*k]).count());
    published_[*k] = Clock::time_point{};  // one event per state
  }
  std::vector<double> latencies_ms() const {
    const std::lock_guard lock(mutex_);
    return latencies_ms_;
  }
  std::int64_t cycle_mismatches() const {
    const std::lock_guard lock(mutex_);
    return cycle_mismatches_;
  }

 private:
  std::optional<std::size_t> slot(int i, std::int64_t seq) const {
    const std::int64_t j = seq - first_seq_;
    if (i < 0 || j < 0 || j >= per_detail_) return std::nullopt;
    const auto k = static_cast<std::size_t>(i) * static_cast<std::size_t>(per_detail_) +
                   static_cast<std::size_t>(j);
    return k < published_.size() ? std::optional(k) : std::nullopt;
  }

  mutable std::mutex mutex_;
  std::int64_t first_seq_, per_detail_;
  std::vector<Clock::time_point> published_;
  std::vector<double> latencies_ms_;
  std::int64_t unmatched_ = 0, cycle_mismatches_ = 0;
};

/// The integer after `"key":` in `text` from `from`, or nullopt.
std::optional<std::int64_t> int_after(const std::string& text, const std::string& key,
                                      std::size_t from = 0) {
  const auto p = text.find("\"" + key + "\":", from);
  if (p == std::string::npos) return std::nullopt;
  return std::atoll(text.c_str() + p + key.size() + 3);
}

/// Reads /api/events (HTTP/1.1 chunked) until `stop`: every "state" event of a bench detail goes
/// to the matcher with the time its last bytes arrived.
class SseClient {
 public:
  /// `matcher` null: the events are read and counted, not timed.
  SseClient(int port, Matcher* matcher, bool quickack) : matcher_(matcher), quickack_(quickack) {
    socket_ = connect_loopback(port, 0.5);
    if (socket_ < 0 || !send_all(socket_,
                                 "GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                                 "Accept: text/event-stream\r\nCache-Control: no-cache\r\n\r\n")) {
      error_ = "cannot connect to /api/events";
      return;
    }
    thread_ = std::thread([this] { run(); });
  }
  ~SseClient() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (socket_ >= 0) close(socket_);
  }
  SseClient(const SseClient&) = delete;
  SseClient& operator=(const SseClient&) = delete;

  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] std::int64_t state_events() const { return state_events_.load(); }
  [[nodiscard]] std::int64_t status_events() const { return status_events_.load(); }
  [[nodiscard]] bool connected() const { return headers_done_.load(); }

 private:
  void run() {
    std::string raw;     // bytes not yet de-chunked
    std::string stream;  // the event stream (de-chunked)
    char buf[65536];
    while (!stop_) {
      if (quickack_) {  // not sticky: before every receive
        const int on = 1;
        setsockopt(socket_, IPPROTO_TCP, TCP_QUICKACK, &on, sizeof on);
      }
      const auto n = recv(socket_, buf, sizeof buf, 0);
      const auto at = Clock::now();
      if (n == 0) break;
      if (n < 0) {
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;
        break;
      }
      raw.append(buf, static_cast<std::size_t>(n));
      if (!headers_done_) {
        const auto end = raw.find("\r\n\r\n");
        if (end == std::string::npos) continue;
        raw.erase(0, end + 4);
        headers_done_ = true;
      }
      // Chunks: HEX\r\nDATA\r\n.
      while (true) {
        const auto eol = raw.find("\r\n");
        if (eol == std::string::npos) break;
        const auto size = std::strtoull(raw.substr(0, eol).c_str(), nullptr, 16);
        if (raw.size() < eol + 2 + size + 2) break;
        stream.append(raw, eol + 2, size);
        raw.erase(0, eol + 2 + size + 2);
      }
      // Events: blocks ending in a blank line.
      std::size_t start = 0;
      for (auto end = stream.find("\n\n"); end != std::string::npos;
           end = stream.find("\n\n", start)) {
        on_event(stream.substr(start, end - start), at);
        start = end + 2;
      }
      stream.erase(0, start);
    }
  }

  void on_event(const std::string& event, Clock::time_point at) {
    if (event.find("\nevent: status\n") != std::string::npos) {
      ++status_events_;
      return;
    }
    if (event.find("\nevent: state\n") == std::string::npos) return;
    ++state_events_;
    const auto d = event.find("\"detail\":\"bench-");
    if (d == std::string::npos) return;
    const int i = std::atoi(event.c_str() + d + 16);
    const auto summary = event.find("\"summary\":");
    if (summary == std::string::npos) return;
    const auto seq = int_after(event, "state_seq", summary);
    const auto cycles = int_after(event, "cycles", summary);
    if (seq && cycles && matcher_ != nullptr) matcher_->arrived(i, *seq, *cycles, at);
  }

  Matcher* matcher_;
  bool quickack_;
  int socket_ = -1;
  std::thread thread_;
  std::atomic<bool> stop_{false}, headers_done_{false};
  std::atomic<std::int64_t> state_events_{0}, status_events_{0};
  std::string error_;
};

/// A second LCM subscriber to every STATE, in this process: the hub's own share of the latency
/// (publication to delivery to a subscriber), the part no dashboard can remove.
class ReferenceSubscriber {
 public:
  ReferenceSubscriber(const std::string& url, Matcher& matcher) : matcher_(matcher) {
    lcm_ = std::make_unique<lcm::LCM>(url);
    if (!lcm_->good() || !peritwin::messages::transport_up(*lcm_)) {
      error_ = "the reference subscriber cannot open LCM at " + url;
      return;
    }
    lcm_->subscribeFunction(
        peritwin::messages::channel_regex(peritwin::messages::Kind::kState),
        +[](const lcm::ReceiveBuffer* rbuf, const std::string&, ReferenceSubscriber* self) {
          const auto at = Clock::now();
          const auto s = peritwin::messages::decode_state(rbuf->data, rbuf->data_size);
          if (!s || s->detail_id.rfind("bench-", 0) != 0) return;
          self->matcher_.arrived(std::atoi(s->detail_id.c_str() + 6), s->state_seq, s->total_cycles,
                                 at);
        },
        this);
    thread_ = std::thread([this] {
      while (!stop_) peritwin::messages::handle_lcm(*lcm_, 100);
    });
  }
  ~ReferenceSubscriber() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  ReferenceSubscriber(const ReferenceSubscriber&) = delete;
  ReferenceSubscriber& operator=(const ReferenceSubscriber&) = delete;
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  Matcher& matcher_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::string error_;
};

/// --streams event streams on /api/events and --idle idle connections (every other one has sent
/// half a request line), all held on one thread (epoll) for the window: each stream's status and
/// the events it received are counted; an idle connection the dashboard closes (its header
/// timeout) is opened again at once, so that --idle are open all the time.
class HeldConnections {
 public:
  HeldConnections(int port, int streams, int idle) : port_(port) {
    epoll_ = epoll_create1(EPOLL_CLOEXEC);
    for (int i = 0; i < streams; ++i) open(true, i);
    for (int i = 0; i < idle; ++i) open(false, i);
    thread_ = std::thread([this] { run(); });
  }
  ~HeldConnections() {
    stop();
    for (auto& [fd, c] : conns_) close(fd);
    if (epoll_ >= 0) close(epoll_);
  }
  HeldConnections(const HeldConnections&) = delete;
  HeldConnections& operator=(const HeldConnections&) = delete;

  /// Waits until every stream was answered (its status line read), `timeout_s` at most.
  bool wait_answered(std::size_t streams, double timeout_s) const {
    for (const auto t0 = Clock::now(); since(t0) < timeout_s;) {
      if (answered_.load() >= streams) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return answered_.load() >= streams;
  }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  /// After stop(): per stream, events received (-1: not answered 200).
  [[nodiscard]] std::vector<std::int64_t> stream_events() const {
    std::vector<std::int64_t> out;
    for (const auto& [fd, c] : conns_) {
      if (c.stream) out.push_back(c.status == 200 ? c.events : -1);
    }
    return out;
  }
  [[nodiscard]] std::int64_t streams_closed() const { return streams_closed_; }
  [[nodiscard]] std::int64_t idle_reopened() const { return idle_reopened_; }
  [[nodiscard]] std::int64_t open_failures() const { return open_failures_; }

 private:
  struct Conn {
    bool stream = false;
    int status = 0;    // of a stream's answer; 0 before its status line
    std::string head;  // a stream's bytes until its headers are complete
    std::string tail;  // the last bytes of its body (an event marker split between reads)
    std::int64_t events = 0;
  };

  void open(bool stream, int i) {
    const int s = connect_loopback(port_, 30.0);
    if (s < 0) {
      ++open_failures_;
      return;
    }
    const bool sent = stream ? send_all(s,
                                        "GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                                        "Accept: text/event-stream\r\n\r\n")
                             : (i % 2 == 0 || send_all(s, "GET / HT"));
    epoll_event e{};
    e.events = EPOLLIN | EPOLLRDHUP;
    e.data.fd = s;
    if (!sent || fcntl(s, F_SETFL, fcntl(s, F_GETFL) | O_NONBLOCK) != 0 ||
        epoll_ctl(epoll_, EPOLL_CTL_ADD, s, &e) != 0) {
      close(s);
      ++open_failures_;
      return;
    }
    conns_[s].stream = stream;
  }

  void run() {
    std::vector<epoll_event> ready(512);
    std::vector<char> buffer(1 << 16);
    static const std::string kMarker = "\nevent: ";
    while (!stop_) {
      const int n = epoll_wait(epoll_, ready.data(), static_cast<int>(ready.size()), 100);
      for (int k = 0; k < n; ++k) {
        const int fd = ready[static_cast<std::size_t>(k)].data.fd;
        auto it = conns_.find(fd);
        if (it == conns_.end()) continue;
        Conn& c = it->second;
        bool gone = false;
        for (;;) {
          const auto got = recv(fd, buffer.data(), buffer.size(), 0);
          if (got == 0 || (got < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
            gone = true;
            break;
          }
          if (got < 0) break;
          std::string text(buffer.data(), static_cast<std::size_t>(got));
          if (!c.stream) continue;  // an idle connection's answer (none expected): dropped
          if (c.status == 0) {
            c.head += text;
            const auto end = c.head.find("\r\n\r\n");
            if (end == std::string::npos) continue;
            c.status = c.head.rfind("HTTP/1.1 ", 0) == 0 ? std::atoi(c.head.c_str() + 9) : -1;
            ++answered_;
            text = c.head.substr(end + 4);
            c.head.clear();
          }
          // Every event has one "\nevent: " line (data is JSON: no raw newline in it).
          const std::string seen = c.tail + text;
          for (auto p = seen.find(kMarker); p != std::string::npos; p = seen.find(kMarker, p + 1)) {
            ++c.events;
          }
          c.tail = seen.substr(seen.size() - std::min(seen.size(), kMarker.size() - 1));
        }
        if (!gone) continue;
        epoll_ctl(epoll_, EPOLL_CTL_DEL, fd, nullptr);
        close(fd);
        const bool stream = c.stream;
        if (stream) {
          ++streams_closed_;
          closed_streams_.push_back(std::move(c));
        }
        conns_.erase(it);
        if (!stream) {
          ++idle_reopened_;
          open(false, static_cast<int>(idle_reopened_));
        }
      }
    }
    for (auto& c : closed_streams_) conns_[-1 - static_cast<int>(conns_.size())] = std::move(c);
    closed_streams_.clear();
  }

  int port_;
  int epoll_ = -1;
  std::map<int, Conn> conns_;         // by socket (closed streams: negative keys, after stop)
  std::vector<Conn> closed_streams_;  // streams the dashboard closed (their counts kept)
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<std::size_t> answered_{0};
  std::int64_t streams_closed_ = 0, idle_reopened_ = 0, open_failures_ = 0;
};

/// The page and the API fetched over and over (a new connection each time, as a browser opening
/// the dashboard), every `period`: the time of each answer, and the dashboard's threads.
class Fetcher {
 public:
  Fetcher(int port, pid_t dashboard, std::chrono::milliseconds period)
      : port_(port), pid_(std::to_string(dashboard)), period_(period) {
    thread_ = std::thread([this] { run(); });
  }
  ~Fetcher() { stop(); }
  Fetcher(const Fetcher&) = delete;
  Fetcher& operator=(const Fetcher&) = delete;
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  std::vector<double> page_ms, api_ms;
  std::int64_t failures = 0, threads_max = -1;

 private:
  void run() {
    auto next = Clock::now();
    while (!stop_) {
      for (const auto& [path, times] :
           {std::pair<const char*, std::vector<double>*>{"/", &page_ms},
            std::pair<const char*, std::vector<double>*>{"/api/details", &api_ms}}) {
        const auto t0 = Clock::now();
        if (http_get(port_, path)) {
          times->push_back(1e3 * since(t0));
        } else {
          ++failures;
        }
      }
      threads_max = std::max(threads_max, core::proc_status_kb("Threads", pid_));
      next += period_;
      std::this_thread::sleep_until(next);
    }
  }
  int port_;
  std::string pid_;
  std::chrono::milliseconds period_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

/// The command line.
struct Options {
  int details = 100;
  double rate = 10.0, seconds = 30.0;
  std::int64_t warmup = static_cast<std::int64_t>(10000);
  std::string lcm_url;
  std::string dashboard_bin =
      (fs::read_symlink("/proc/self/exe").parent_path() / "peritwin-dashboard").string();
  bool keep = false, sse_quickack = false, reference = false;
  int sse_clients = 1;
  int streams = 0, idle = 0;  // held open during the window (issue 30 item 4)
  int fetch_period_ms = 100;
  int max_event_streams = 0;  // > 0: passed to the dashboard
};

void add_options(CLI::App& app, Options& o) {
  app.add_option("--details", o.details, "details publishing (default 100)")
      ->check(CLI::Range(1, 999));
  app.add_option("--rate", o.rate, "states per second per detail (default 10)")
      ->check(CLI::Range(0.01, 10000.0));
  app.add_option("--seconds", o.seconds, "measurement window (default 30)")
      ->check(CLI::Range(0.5, 86400.0));
  app.add_option("--warmup", o.warmup,
                 "states per detail published before the window, as fast as they are taken "
                 "(default 10000: the history bound, full histories)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{10'000'000}));
  app.add_option("--lcm-url", o.lcm_url, "use this tcpq URL instead of starting a hub");
  app.add_option("--dashboard", o.dashboard_bin,
                 "the peritwin-dashboard binary (default: next to this one)");
  app.add_option("--sse-clients", o.sse_clients,
                 "clients on /api/events, the first one timed (default 1; 0: none, no latency)")
      ->check(CLI::Range(0, 100));
  app.add_flag("--sse-quickack", o.sse_quickack,
               "TCP_QUICKACK on the SSE client before every receive (a diagnosis: no delayed ACKs "
               "from the client, unlike a browser)");
  app.add_flag("--lcm-reference", o.reference,
               "also time each STATE to a second LCM subscriber in this process (the hub's share "
               "of the latency; the hub then relays every STATE twice)");
  app.add_option("--streams", o.streams,
                 "event streams held open during the window, each counting its events, while "
                 "the page and the API are fetched (default 0)")
      ->check(CLI::Range(0, 100000));
  app.add_option("--idle", o.idle,
                 "idle connections held open during the window (every other one sent half a "
                 "request line; reopened when the dashboard closes them), while the page and "
                 "the API are fetched (default 0)")
      ->check(CLI::Range(0, 100000));
  app.add_option("--fetch-period-ms", o.fetch_period_ms,
                 "with --streams or --idle: GET / and GET /api/details every this many ms "
                 "(default 100)")
      ->check(CLI::Range(1, 60000));
  app.add_option("--max-event-streams", o.max_event_streams,
                 "passed to the dashboard (default: its own default)")
      ->check(CLI::Range(1, 1 << 20));
  app.add_flag("--keep", o.keep, "keep the work directory (hub and dashboard logs)");
}

/// What the warm-up measured.
struct Warmup {
  double seconds = 0.0, cpu_s = 0.0;
  std::vector<double> history_ms;  // per request, as the client sees it
  std::int64_t history_min = -1, history_max = -1, rss_kb = -1;
};

/// What the window measured.
struct Window {
  double seconds = 0.0, cpu_s = 0.0, load_average = 0.0;
  std::int64_t published = 0, rss_end = -1, rss_peak = -1, cycle_mismatches = 0;
  std::int64_t status_events = 0;
  std::vector<double> latencies, lcm_latencies;
  int dashboard_exit = -1;
  // --streams / --idle
  std::vector<std::int64_t> stream_events;  // per stream (-1: not answered 200)
  std::int64_t streams_closed = 0, idle_reopened = 0, open_failures = 0, threads_max = -1;
  std::int64_t threads_before = -1, fetch_failures = 0;
  std::vector<double> page_ms, api_ms;
};

constexpr double kGoalP99Ms = 20.0, kGoalCpu = 0.10, kGoalRssMb = 200.0;
/// Issue 30 item 4: the page and the API with --streams and --idle open.
constexpr double kGoalFetchP99Ms = 50.0;

/// {"n", "p50", "p99", "max"} of `ms`.
core::JsonLine fetch_times(const std::vector<double>& ms) {
  return {{"n", static_cast<std::int64_t>(ms.size())},
          {"p50", core::fixed(core::percentile(ms, 0.50), 2)},
          {"p99", core::fixed(core::percentile(ms, 0.99), 2)},
          {"max", core::fixed(core::percentile(ms, 1.0), 2)}};
}

/// The JSON line of the run.
core::JsonLine dashboard_line(const Options& o, const Warmup& w, const Window& m) {
  const std::vector<double>& latencies = m.latencies;
  const double p99 = core::percentile(latencies, 0.99);
  auto over_goal = [&](const std::vector<double>& v) {
    return v.empty() ? std::nan("")
                     : static_cast<double>(std::count_if(
                           v.begin(), v.end(), [&](double x) { return x > kGoalP99Ms; })) /
                           static_cast<double>(v.size());
  };
  const double cpu_fraction = m.seconds > 0 ? m.cpu_s / m.seconds : 0.0;
  const double rss_mb = static_cast<double>(m.rss_end) / 1024.0;
  const double peak_mb = static_cast<double>(m.rss_peak) / 1024.0;
  const auto missing = m.published - static_cast<std::int64_t>(latencies.size());
  const auto total_warmup = static_cast<double>(o.warmup) * o.details;
  core::JsonLine line;
  line["bench"] = "dashboard";
  line["details"] = o.details;
  line["states_per_s_per_detail"] = o.rate;
  line["states_per_s"] = core::fixed(static_cast<double>(m.published) / m.seconds, 1);
  line["duration_s"] = core::fixed(m.seconds, 2);
  line["warmup_states_per_detail"] = o.warmup;
  line["warmup_s"] = core::fixed(w.seconds, 1);
  line["warmup_cpu_us_per_state"] =
      total_warmup > 0 ? core::JsonLine(core::fixed(1e6 * w.cpu_s / total_warmup, 1))
                       : core::JsonLine(nullptr);
  line["history_points_min"] = w.history_min;
  line["history_points_max"] = w.history_max;
  line["history_get_ms"] = {
      {"mean", core::fixed(std::accumulate(w.history_ms.begin(), w.history_ms.end(), 0.0) /
                               static_cast<double>(w.history_ms.size()),
                           2)},
      {"max", core::fixed(*std::max_element(w.history_ms.begin(), w.history_ms.end()), 2)}};
  line["published"] = m.published;
  line["events"] = static_cast<std::int64_t>(latencies.size());
  line["missing_events"] = o.sse_clients > 0 ? core::JsonLine(missing) : core::JsonLine(nullptr);
  line["cycle_mismatches"] = m.cycle_mismatches;
  line["sse_clients"] = o.sse_clients;
  line["status_events"] = m.status_events;
  core::JsonLine lat;
  lat["p50"] = core::fixed(core::percentile(latencies, 0.50), 2);
  lat["p90"] = core::fixed(core::percentile(latencies, 0.90), 2);
  lat["p99"] = core::fixed(p99, 2);
  lat["max"] = core::fixed(
      latencies.empty() ? std::nan("") : *std::max_element(latencies.begin(), latencies.end()), 2);
  lat["over_goal_fraction"] = core::fixed(over_goal(latencies), 4);
  line["latency_ms"] = lat;
  if (o.reference) {
    line["lcm_reference_latency_ms"] = {
        {"events", static_cast<std::int64_t>(m.lcm_latencies.size())},
        {"p50", core::fixed(core::percentile(m.lcm_latencies, 0.50), 2)},
        {"p99", core::fixed(core::percentile(m.lcm_latencies, 0.99), 2)},
        {"max", core::fixed(core::percentile(m.lcm_latencies, 1.0), 2)},
        {"over_goal_fraction", core::fixed(over_goal(m.lcm_latencies), 4)}};
  }
  line["cpu_fraction_of_core"] = core::fixed(cpu_fraction, 3);
  line["cpu_us_per_state"] =
      m.published > 0
          ? core::JsonLine(core::fixed(1e6 * m.cpu_s / static_cast<double>(m.published), 1))
          : core::JsonLine(nullptr);
  line["rss_after_warmup_mb"] = core::fixed(static_cast<double>(w.rss_kb) / 1024.0, 1);
  line["rss_mb"] = core::fixed(rss_mb, 1);
  line["rss_peak_mb"] = core::fixed(peak_mb, 1);
  line["goals"] = {
      {"p99_ms", kGoalP99Ms}, {"cpu_fraction_of_core", kGoalCpu}, {"rss_mb", kGoalRssMb}};
  line["pass"] = {{"p99", o.sse_clients > 0 ? core::JsonLine(missing == 0 && p99 <= kGoalP99Ms)
                                            : core::JsonLine(nullptr)},
                  {"cpu", cpu_fraction <= kGoalCpu},
                  {"rss", peak_mb <= kGoalRssMb}};
  if (o.streams > 0 || o.idle > 0) {
    const auto& ev = m.stream_events;
    const auto open = std::count_if(ev.begin(), ev.end(), [](std::int64_t e) { return e >= 0; });
    const auto with_events =
        std::count_if(ev.begin(), ev.end(), [](std::int64_t e) { return e > 0; });
    std::int64_t min_events = -1;
    for (const auto e : ev) {
      if (e >= 0) min_events = min_events < 0 ? e : std::min(min_events, e);
    }
    const double page_p99 = core::percentile(m.page_ms, 0.99);
    const double api_p99 = core::percentile(m.api_ms, 0.99);
    const bool pass = open == o.streams && with_events == o.streams && m.fetch_failures == 0 &&
                      !m.page_ms.empty() && !m.api_ms.empty() && page_p99 <= kGoalFetchP99Ms &&
                      api_p99 <= kGoalFetchP99Ms;
    line["lockout"] = {{"streams", o.streams},
                       {"streams_open", static_cast<std::int64_t>(open)},
                       {"streams_with_events", static_cast<std::int64_t>(with_events)},
                       {"stream_events_min", min_events},
                       {"streams_closed_by_dashboard", m.streams_closed},
                       {"idle", o.idle},
                       {"idle_reopened", m.idle_reopened},
                       {"connect_failures", m.open_failures},
                       {"fetch_period_ms", o.fetch_period_ms},
                       {"page_ms", fetch_times(m.page_ms)},
                       {"api_details_ms", fetch_times(m.api_ms)},
                       {"fetch_failures", m.fetch_failures},
                       {"threads_before", m.threads_before},
                       {"threads_max", m.threads_max},
                       {"goal_p99_ms", kGoalFetchP99Ms},
                       {"pass", pass}};
  }
  line["load_average_1min"] = m.load_average;
  line["sse_quickack"] = o.sse_quickack;
  line["dashboard_exit"] = m.dashboard_exit;
  line["transport"] = o.lcm_url.rfind("tcpq://", 0) == 0 ? "tcpq" : o.lcm_url;
  return line;
}

/// One run: the hub and the dashboard as child processes, the states published from here.
class Run {
 public:
  explicit Run(Options& o)
      : o_(o),
        work_(fs::temp_directory_path() /
              ("peritwin_bench_dashboard_" + std::to_string(getpid()))) {
    fs::create_directories(work_);
  }
  void cleanup() {
    lcm_.reset();
    if (dashboard_ > 0) stop_child(dashboard_, 30.0);
    if (hub_ > 0) stop_child(hub_, 30.0);
    if (!o_.keep) fs::remove_all(work_);
  }
  /// Says why, keeps the work directory, cleans up; the exit code 3.
  int fail(const std::string& why) {
    std::cerr << "peritwin-bench-dashboard: " << why << " (logs kept in " << work_.string()
              << ")\n";
    o_.keep = true;
    cleanup();
    return 3;
  }
  /// The hub (unless --lcm-url), the dashboard up to its HTTP port, LCM; an exit code on failure.
  std::optional<int> start();
  /// States 1..warmup of every detail as fast as they go, until the dashboard counted them all.
  std::optional<int> warm_up(Warmup& w);
  /// The SSE clients, then `rate` states per second per detail for `seconds`.
  std::optional<int> measure(Window& m);

 private:
  bool dashboard_alive() const { return waitpid(dashboard_, nullptr, WNOHANG) == 0; }
  void publish_status(int i, std::int64_t last_seq) {
    const auto st = status_message(i, last_seq, since(started_));
    lcm_->publish(status_channel_[static_cast<std::size_t>(i)], &st);
  }

  Options& o_;
  fs::path work_;
  pid_t hub_ = -1, dashboard_ = -1;
  std::unique_ptr<lcm::LCM> lcm_;
  int http_port_ = -1;
  std::vector<std::string> state_channel_, status_channel_;
  Clock::time_point started_;
};

std::optional<int> Run::start() {
  if (o_.lcm_url.empty()) {
    const int port = core::free_loopback_port();
    hub_ = spawn(
        {"java", "-cp", "/usr/share/java/lcm.jar", "lcm.lcm.TCPService", std::to_string(port)},
        "/dev/null", (work_ / "hub.log").string());
    if (hub_ < 0 || !core::wait_for_loopback_port(port, 60.0)) {
      return fail("the LCM hub did not come up on port " + std::to_string(port));
    }
    o_.lcm_url = "tcpq://127.0.0.1:" + std::to_string(port);
  }
  const fs::path out_file = work_ / "dashboard.out", log_file = work_ / "dashboard.log";
  std::vector<std::string> args{o_.dashboard_bin, "--lcm-url",   o_.lcm_url, "--listen",
                                "127.0.0.1:0",    "--log-level", "info"};
  if (o_.max_event_streams > 0) {
    args.insert(args.end(), {"--max-event-streams", std::to_string(o_.max_event_streams)});
  }
  dashboard_ = spawn(args, out_file.string(), log_file.string());
  if (dashboard_ < 0) return fail("cannot start " + o_.dashboard_bin);
  for (const auto t0 = Clock::now(); since(t0) < 60.0 && dashboard_alive();) {
    std::smatch m;
    const std::string out = core::read_text(out_file);
    if (std::regex_search(out, m, std::regex("http://127\\.0\\.0\\.1:([0-9]+)/")) &&
        read_text(log_file).find("subscribed to") != std::string::npos) {
      http_port_ = std::stoi(m[1]);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (http_port_ < 0) return fail("the dashboard did not come up");

  lcm_ = std::make_unique<lcm::LCM>(o_.lcm_url);
  if (!lcm_->good() || !messages::transport_up(*lcm_)) {
    return fail("cannot open LCM at " + o_.lcm_url);
  }
  messages::handle_lcm(*lcm_, 0);  // TCP_NODELAY on the publisher's socket, as the daemon's
  for (int i = 0; i < o_.details; ++i) {
    state_channel_.push_back(messages::channel(detail_id(i), messages::Kind::kState));
    status_channel_.push_back(messages::channel(detail_id(i), messages::Kind::kStatus));
  }
  started_ = Clock::now();
  return std::nullopt;
}

std::optional<int> Run::warm_up(Warmup& w) {
  const int details = o_.details;
  const std::int64_t warmup = o_.warmup;
  for (int i = 0; i < details; ++i) publish_status(i, 0);
  const double cpu_before_warmup = core::proc_cpu_s(dashboard_);
  const auto warmup_t0 = Clock::now();
  for (std::int64_t seq = 1; seq <= warmup; ++seq) {
    for (int i = 0; i < details; ++i) {
      const auto s = state_message(i, seq);
      lcm_->publish(state_channel_[static_cast<std::size_t>(i)], &s);
    }
    if (!messages::transport_up(*lcm_)) return fail("connection to the LCM hub lost");
    if (seq % 1000 == 0 && !dashboard_alive()) return fail("the dashboard died in the warm-up");
  }
  for (int i = 0; i < details; ++i) publish_status(i, warmup);
  const std::int64_t expected_details = details;
  bool counted = false;
  for (const auto t0 = Clock::now(); since(t0) < 600.0 && dashboard_alive();) {
    if (const auto body = http_get(http_port_, "/api/details")) {
      const auto j = nlohmann::json::parse(*body, nullptr, false);
      std::int64_t complete = 0;
      if (j.is_object() && j.contains("details")) {
        for (const auto& d : j["details"]) {
          if (d.value("states_received", std::int64_t{-1}) == warmup && !d["status"].is_null() &&
              d["status"].value("last_seq", -1) == warmup) {
            ++complete;
          }
        }
      }
      if (complete == expected_details) {
        counted = true;
        break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  w.seconds = since(warmup_t0);
  w.cpu_s = core::proc_cpu_s(dashboard_) - cpu_before_warmup;
  if (!counted) return fail("the dashboard did not count every warm-up state within 600 s");
  for (int i = 0; i < details; ++i) {
    const auto h0 = Clock::now();
    const auto body = http_get(http_port_, "/api/details/" + detail_id(i) + "/history");
    w.history_ms.push_back(1e3 * since(h0));
    if (!body) return fail("no history for " + detail_id(i));
    const auto j = nlohmann::json::parse(*body, nullptr, false);
    const auto n = j.is_object() ? static_cast<std::int64_t>(j["cycles"].size()) : -1;
    w.history_min = w.history_min < 0 ? n : std::min(w.history_min, n);
    w.history_max = std::max(w.history_max, n);
  }
  w.rss_kb = core::proc_status_kb("VmRSS", std::to_string(dashboard_));
  return std::nullopt;
}

std::optional<int> Run::measure(Window& m) {
  const int details = o_.details;
  const std::int64_t warmup = o_.warmup;
  const auto per_detail = static_cast<std::int64_t>(std::llround(o_.rate * o_.seconds));
  Matcher matcher(details, warmup + 1, per_detail);
  Matcher lcm_matcher(details, warmup + 1, per_detail);
  std::unique_ptr<ReferenceSubscriber> ref;
  if (o_.reference) {
    ref = std::make_unique<ReferenceSubscriber>(o_.lcm_url, lcm_matcher);
    if (!ref->error().empty()) return fail(ref->error());
  }
  std::vector<std::unique_ptr<SseClient>> sse;  // the first one timed
  for (int c = 0; c < o_.sse_clients; ++c) {
    sse.push_back(
        std::make_unique<SseClient>(http_port_, c == 0 ? &matcher : nullptr, o_.sse_quickack));
    if (!sse.back()->error().empty()) return fail(sse.back()->error());
    for (const auto t0 = Clock::now(); !sse.back()->connected() && since(t0) < 10.0;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (!sse.back()->connected()) return fail("no answer on /api/events");
  }
  // --streams / --idle: held open through the window while the page and the API are fetched.
  std::unique_ptr<HeldConnections> held;
  std::unique_ptr<Fetcher> fetcher;
  if (o_.streams > 0 || o_.idle > 0) {
    m.threads_before = core::proc_status_kb("Threads", std::to_string(dashboard_));
    held = std::make_unique<HeldConnections>(http_port_, o_.streams, o_.idle);
    if (!held->wait_answered(static_cast<std::size_t>(o_.streams), 120.0)) {
      return fail("the event streams were not all answered within 120 s");
    }
    fetcher = std::make_unique<Fetcher>(http_port_, dashboard_,
                                        std::chrono::milliseconds(o_.fetch_period_ms));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const double state_period_s = 1.0 / (o_.rate * static_cast<double>(details));
  const double status_period_s = 1.0 / static_cast<double>(details);
  const std::int64_t total_states = per_detail * details;
  const double cpu0 = core::proc_cpu_s(dashboard_);
  const auto t0 = Clock::now();
  std::int64_t k_state = 0, k_status = 0;
  auto due = [&](std::int64_t k, double period) {
    return t0 + std::chrono::duration_cast<Clock::duration>(
                    std::chrono::duration<double>(static_cast<double>(k) * period));
  };
  while (k_state < total_states) {
    const auto next_state = due(k_state, state_period_s);
    const auto next_status = due(k_status, status_period_s);
    const bool status_first = next_status < next_state;
    std::this_thread::sleep_until(status_first ? next_status : next_state);
    if (status_first) {
      const int i = static_cast<int>(k_status % details);
      publish_status(i, warmup + k_state / details);
      ++k_status;
      continue;
    }
    const int i = static_cast<int>(k_state % details);
    const std::int64_t seq = warmup + 1 + k_state / details;
    const auto s = state_message(i, seq);
    const auto at = Clock::now();
    matcher.published(i, seq, at);
    if (ref) lcm_matcher.published(i, seq, at);
    lcm_->publish(state_channel_[static_cast<std::size_t>(i)], &s);
    ++k_state;
    if (k_state % 1000 == 0 && (!messages::transport_up(*lcm_) || !dashboard_alive())) break;
  }
  m.seconds = since(t0);
  m.published = k_state;
  m.cpu_s = core::proc_cpu_s(dashboard_) - cpu0;
  m.rss_end = core::proc_status_kb("VmRSS", std::to_string(dashboard_));
  m.rss_peak = core::proc_status_kb("VmHWM", std::to_string(dashboard_));
  m.load_average = std::atof(core::read_text("/proc/loadavg").c_str());  // 1 min
  // The last events.
  for (const auto t1 = Clock::now();
       o_.sse_clients > 0 && since(t1) < 2.0 &&
       static_cast<std::int64_t>(matcher.latencies_ms().size()) < k_state;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  m.latencies = matcher.latencies_ms();
  if (fetcher) {
    fetcher->stop();
    m.page_ms = fetcher->page_ms;
    m.api_ms = fetcher->api_ms;
    m.fetch_failures = fetcher->failures;
    m.threads_max = fetcher->threads_max;
  }
  if (held) {
    held->stop();
    m.stream_events = held->stream_events();
    m.streams_closed = held->streams_closed();
    m.idle_reopened = held->idle_reopened();
    m.open_failures = held->open_failures();
  }
  ref.reset();
  m.lcm_latencies = lcm_matcher.latencies_ms();
  const bool alive = dashboard_alive();
  m.dashboard_exit = alive ? stop_child(dashboard_, 30.0) : -1;
  dashboard_ = -1;
  if (!alive) return fail("the dashboard died during the window");
  m.cycle_mismatches = matcher.cycle_mismatches();
  m.status_events = sse.empty() ? 0 : sse.front()->status_events();
  return std::nullopt;
}

/// The benchmark; the exit code.
int run(Options o) {
  Run r(o);
  if (auto rc = r.start()) return *rc;
  Warmup w;
  if (auto rc = r.warm_up(w)) return *rc;
  Window m;
  if (auto rc = r.measure(m)) return *rc;
  core::print_line(dashboard_line(o, w, m));
  r.cleanup();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench-dashboard: STATE-to-SSE latency, CPU and RSS of the dashboard"};
  Options o;
  add_options(app, o);
  if (const auto rc =
          peritwin::core::parse_options(app, argc, argv, peritwin::core::ParseErrors::cli11)) {
    return *rc;
  }
  // --streams and --idle hold a socket each.
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
    files.rlim_cur = files.rlim_max;
    setrlimit(RLIMIT_NOFILE, &files);
  }
  return run(std::move(o));
}
