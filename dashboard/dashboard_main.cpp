// peritwin-dashboard: a read-only web dashboard of every detail on the bus. See README.md,
// "Dashboard", and dashboard/store.h, dashboard/server.h.
//
//   peritwin-dashboard --lcm-url URL [--listen 127.0.0.1:8080] [--results DIR]
//                      [--max-event-streams 4096] [--log-level L]
//
// It publishes one thing only: a mesh_request_t on PERITWIN_<DETAIL>_MESH_REQUEST for a detail it
// has no mesh of (every 5 s at most per detail), which its daemon answers on the MESH channel.
// --results DIR back-fills each detail's history from the daemon's results files under DIR.
// --max-event-streams N caps the open /api/events streams (503 beyond). They are all written by one
// thread (dashboard/event_fanout.h); the server's 8 workers answer requests only, so the page and
// the API are always answered (dashboard/http_server.h). N is lowered (with a warning) when the
// file-descriptor limit, raised to its hard limit at start, leaves no room for it.
//
// Prints "peritwin-dashboard: http://HOST:PORT/" on stdout once it serves (port 0: any free
// port, the one chosen is printed). Exit codes: 0 clean stop (SIGTERM/SIGINT, also while waiting
// for the hub), 2 bad usage (nothing started), 3 runtime failure (the address cannot be bound,
// LCM cannot open the URL, the HTTP server stops accepting connections). A tcpq hub that is down is
// waited for, as the daemon does.
#include <netinet/tcp.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "core/exit_codes.h"
#include "core/program.h"
#include "core/stop_signal.h"
#include "dashboard/backfill.h"
#include "dashboard/event_fanout.h"
#include "dashboard/http_server.h"
#include "dashboard/server.h"
#include "dashboard/store.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/hub_connection.h"

#ifndef PERITWIN_CHARTJS
#define PERITWIN_CHARTJS "/usr/share/javascript/chart.js/chart.min.js"
#endif

namespace {

using peritwin::core::kExitOk;
using peritwin::core::kExitRuntime;
using peritwin::core::kExitUsage;

struct Listen {
  std::string host;
  int port = 0;
};

/// "HOST:PORT" (PORT 0..65535, 0 = any free port), or nullopt.
std::optional<Listen> parse_listen(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) return std::nullopt;
  Listen l;
  l.host = text.substr(0, colon);
  if (l.host.size() > 2 && l.host.front() == '[' && l.host.back() == ']') {
    l.host = l.host.substr(1, l.host.size() - 2);
  }
  const std::string port = text.substr(colon + 1);
  if (port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  l.port = std::atoi(port.c_str());
  if (l.port > 65535) return std::nullopt;
  return l;
}

bool is_loopback(const std::string& host) {
  return host.rfind("127.", 0) == 0 || host == "localhost" || host == "::1";
}

/// Raw subscription handler: every message goes to the store, decoded there.
class Feed {
 public:
  explicit Feed(peritwin::dashboard::Store& store) : store_(store) {}
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    try {
      store_.on_message(channel, rbuf->data, rbuf->data_size, peritwin::dashboard::Clock::now());
    } catch (const std::exception& e) {  // e.g. out of memory: drop the message, keep serving
      spdlog::warn("message on {} dropped: {}", channel, e.what());
    }
  }

 private:
  peritwin::dashboard::Store& store_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-dashboard: read-only web dashboard of the details on the bus"};
  std::string lcm_url, listen = "127.0.0.1:8080", log_level = "info", results;
  app.add_option("--lcm-url", lcm_url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's default)");
  app.add_option("--listen", listen,
                 "HTTP address HOST:PORT (default 127.0.0.1:8080; port 0: any)");
  app.add_option("--results", results,
                 "back-fill each detail's history from the daemon's results files under DIR "
                 "(<DIR>/<id>.h5 or <DIR>/*/<id>.h5)");
  std::size_t max_event_streams = peritwin::dashboard::kDefaultMaxEventStreams;
  app.add_option("--max-event-streams", max_event_streams,
                 "open /api/events streams at most (one thread writes them all); HTTP 503 "
                 "beyond (default 4096)")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 20));
  app.add_option("--log-level", log_level, "trace|debug|info|warn|error|critical|off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
  if (const auto rc = peritwin::core::parse_options(app, argc, argv)) return *rc;
  const auto address = parse_listen(listen);
  if (!address) {
    std::fprintf(stderr, "--listen: expected HOST:PORT (e.g. 127.0.0.1:8080), got \"%s\"\n",
                 listen.c_str());
    return peritwin::core::kExitUsage;
  }

  peritwin::core::set_up_logging("peritwin-dashboard", log_level);
  lcm_url = peritwin::core::lcm_url_or_default(lcm_url);

  peritwin::core::install_stop_handler();
  // A browser that goes away mid-write must not kill the process.
  signal(SIGPIPE, SIG_IGN);

  peritwin::dashboard::Store store;
  peritwin::dashboard::ServerLimits limits;
  // Every open stream, every connection waiting for its headers and every request being answered
  // holds a file descriptor: their number stays below the descriptor limit (raised to the hard
  // limit if it can be), leaving room for LCM and files, so that accept() does not fail with
  // EMFILE. The streams get at most half of the room, the waiting connections the rest.
  rlimit files{};
  if (getrlimit(RLIMIT_NOFILE, &files) == 0) {
    if (files.rlim_cur < files.rlim_max) {
      files.rlim_cur = files.rlim_max;
      if (setrlimit(RLIMIT_NOFILE, &files) != 0) getrlimit(RLIMIT_NOFILE, &files);
    }
    constexpr rlim_t kOtherFiles = 128;
    const rlim_t room = files.rlim_cur > limits.workers + kOtherFiles
                            ? files.rlim_cur - limits.workers - kOtherFiles
                            : 0;
    if (max_event_streams > room / 2) {
      const std::size_t lowered = std::max<std::size_t>(1, room / 2);
      spdlog::warn(
          "--max-event-streams {} lowered to {}: the file-descriptor limit is {} (raise it, "
          "e.g. ulimit -n, for more)",
          max_event_streams, lowered, static_cast<unsigned long long>(files.rlim_cur));
      max_event_streams = lowered;
    }
    limits.max_waiting = std::max<std::size_t>(
        16, std::min<rlim_t>(limits.max_waiting,
                             room > max_event_streams ? room - max_event_streams : 0));
  }
  spdlog::info(
      "HTTP: {} event streams at most (one thread), {} workers, {} connections waiting "
      "at most",
      max_event_streams, limits.workers, limits.max_waiting);
  peritwin::dashboard::FanoutLimits fanout_limits;
  fanout_limits.max_streams = max_event_streams;
  // Declared before the server, whose routes use it: destroyed after the server stopped.
  peritwin::dashboard::EventFanout events(store, fanout_limits);
  peritwin::dashboard::BoundedServer server(limits);
  peritwin::dashboard::install_routes(server, store, PERITWIN_CHARTJS, events);
  // httplib's default also sets SO_REUSEPORT, which lets a second dashboard share a port in use
  // (requests then go to either): SO_REUSEADDR only, so that is refused.
  server.set_socket_options([](int sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    setsockopt(sock, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof yes);
  });
  int port = address->port;
  if (port == 0) {
    port = server.bind_to_any_port(address->host);
  } else if (!server.bind_to_port(address->host, port)) {
    port = -1;
  }
  if (port <= 0) {
    spdlog::critical("cannot listen on {}: address in use or not available here", listen);
    return peritwin::core::kExitRuntime;
  }
  // A burst of connections waits in the accept queue instead of having its SYNs dropped.
  constexpr int kListenBacklog = 1024;
  if (!server.set_backlog(kListenBacklog)) spdlog::warn("listen backlog not raised: {}", errno);
  if (!is_loopback(address->host)) {
    spdlog::warn(
        "listening on {} (not loopback): anyone who can reach it sees every detail's "
        "state; there is no authentication",
        address->host);
  }
  const std::string host =
      address->host.find(':') != std::string::npos ? "[" + address->host + "]" : address->host;
  // httplib 0.11.4's accept loop ends for good on an accept() failure other than EMFILE, EINTR or
  // EAGAIN (ENFILE, ENOBUFS, ECONNABORTED, ...; read from its listen_internal): the page would
  // then be gone while the process lives on. That stops the dashboard with exit code 3 instead,
  // for whoever supervises it to restart it.
  std::atomic<bool> http_failed{false};
  std::thread http([&server, &http_failed] {
    if (!server.listen_after_bind()) {
      spdlog::critical("the HTTP server stopped accepting connections: stopping");
      http_failed = true;
    }
  });
  const auto keep_serving = [&http_failed] {
    return peritwin::core::keep_running() && !http_failed;
  };
  std::printf("peritwin-dashboard: http://%s:%d/\n", host.c_str(), port);
  std::fflush(stdout);
  spdlog::info("serving http://{}:{}/ (read-only), LCM \"{}\"", host, port,
               peritwin::messages::shown_url(lcm_url));

  if (!results.empty()) {
    if (!std::filesystem::is_directory(results)) {
      spdlog::warn("--results {}: not a directory, nothing back-filled", results);
    }
    for (const auto& file : peritwin::dashboard::find_results_files(results)) {
      try {
        auto content = peritwin::dashboard::read_results(file.path);
        const auto now = peritwin::dashboard::Clock::now();
        const std::size_t taken = store.backfill(file.detail_id, content.points, now);
        // The card's numbers and the map from the file's last state and snapshot, until the
        // detail publishes newer ones.
        if (content.last) {
          store.backfill_latest(file.detail_id, *content.last, std::move(content.snapshot), now);
        }
        spdlog::info("[{}] back-filled {} of {} state(s) from {}", file.detail_id, taken,
                     content.points.size(), file.path.string());
      } catch (const std::exception& e) {
        spdlog::warn("[{}] {}: not back-filled: {}", file.detail_id, file.path.string(), e.what());
      }
    }
  }

  int rc = peritwin::core::kExitOk;
  try {
    peritwin::messages::HubConnection hub(lcm_url, keep_serving);
    const std::unique_ptr<lcm::LCM> connection = hub.open();
    if (!connection) {
      if (!hub.error().empty()) {
        spdlog::critical("{}", hub.error());
        rc = peritwin::core::kExitRuntime;
      }
    } else {
      lcm::LCM& lcm = *connection;
      Feed feed(store);
      for (const peritwin::messages::Kind kind :
           {peritwin::messages::Kind::kState, peritwin::messages::Kind::kStatus,
            peritwin::messages::Kind::kReject, peritwin::messages::Kind::kField,
            peritwin::messages::Kind::kMesh}) {
        lcm.subscribe(peritwin::messages::channel_regex(kind), &Feed::on_message, &feed);
      }
      spdlog::info("subscribed to STATE, STATUS, REJECT, FIELD and MESH of every detail");
      // Mesh requests are looked for every 0.1 s, not after every message (at 1100 messages/s
      // that was 1100 passes over every detail under the store's mutex).
      auto requests_due = peritwin::dashboard::Clock::time_point{};
      while (keep_serving()) {
        if (!hub.connected()) {
          hub.reconnect(lcm);
        } else {
          peritwin::messages::handle_lcm(lcm, 100);  // -1: the hub went away (check says so)
          hub.check(lcm);
          const auto now = peritwin::dashboard::Clock::now();
          if (now < requests_due) continue;
          requests_due = now + std::chrono::milliseconds(100);
          for (const auto& id : store.take_mesh_requests(now)) {
            const auto request = peritwin::messages::mesh_request_message(
                id, "peritwin-dashboard", peritwin::messages::now_utime());
            lcm.publish(peritwin::messages::channel(id, peritwin::messages::Kind::kMeshRequest),
                        &request);
            spdlog::debug("[{}] mesh requested", id);
          }
        }
      }
    }
  } catch (const std::exception& e) {
    spdlog::critical("runtime failure: {}", e.what());
    rc = peritwin::core::kExitRuntime;
  }
  if (const int s = peritwin::core::stop_signal(); s != 0)
    spdlog::info("signal {} received: stopping", s);
  store.close();
  server.stop();
  http.join();
  events.stop();
  const auto streams = events.stats();
  spdlog::info("event streams: {} served, {} closed as slow readers, {} refused (503)",
               streams.adopted, streams.closed_slow, streams.refused);
  if (http_failed) rc = peritwin::core::kExitRuntime;
  return rc;
}
