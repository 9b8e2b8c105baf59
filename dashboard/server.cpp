#include "dashboard/server.h"

#include <atomic>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>
#include <tuple>

namespace peritwin::dashboard {
namespace {

/// How long an event stream gathers events after a write before the next one.
constexpr std::chrono::milliseconds kEventCoalesce{5};

/// Retry-After of the 503 to an event stream beyond the cap, in seconds.
constexpr int kStreamRetryAfterS = 10;

void not_found(httplib::Response& res, const std::string& what) {
  res.status = 404;
  res.set_content(nlohmann::json{{"error", what}}.dump(), "application/json");
}

/// A decimal event id of at most 19 digits, or nullopt.
std::optional<std::uint64_t> parse_event_id(const std::string& text) {
  if (text.empty() || text.size() > 19 || text.find_first_not_of("0123456789") != std::string::npos)
    return std::nullopt;
  return std::stoull(text);
}

void json(httplib::Response& res, const std::string& body) {
  res.set_header("Cache-Control", "no-store");
  res.set_content(body, "application/json");
}

}  // namespace

void install_routes(httplib::Server& server, Store& store, const std::string& chartjs,
                    std::size_t max_event_streams) {
  server.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content(kPageHtml, "text/html; charset=utf-8");
  });
  server.Get("/chart.js", [chartjs](const httplib::Request&, httplib::Response& res) {
    std::ifstream in(chartjs, std::ios::binary);
    if (!in) return not_found(res, "Chart.js not found at " + chartjs + " (libjs-chart.js)");
    std::ostringstream text;
    text << in.rdbuf();
    res.set_header("Cache-Control", "max-age=3600");
    res.set_content(text.str(), "application/javascript");
  });
  server.Get("/api/details", [&store](const httplib::Request&, httplib::Response& res) {
    std::uint64_t last_event = 0;
    const std::string body = store.details_json(Clock::now(), &last_event);
    // The newest event in this snapshot: /api/events?after=ID follows on without a gap.
    res.set_header("X-Last-Event-Id", std::to_string(last_event));
    json(res, body);
  });
  server.Get(R"(/api/details/([A-Za-z0-9_-]+))",
             [&store](const httplib::Request& req, httplib::Response& res) {
               const std::string id = req.matches[1];
               if (const auto body = store.detail_json(id, Clock::now())) return json(res, *body);
               not_found(res, "unknown detail \"" + id + "\"");
             });
  server.Get(R"(/api/details/([A-Za-z0-9_-]+)/history)",
             [&store](const httplib::Request& req, httplib::Response& res) {
               const std::string id = req.matches[1];
               if (const auto body = store.history_json(id)) return json(res, *body);
               not_found(res, "unknown detail \"" + id + "\"");
             });
  // The mesh and the newest complete field: 404 for an unknown detail or none yet.
  using Getter = std::optional<std::string> (Store::*)(const std::string&) const;
  for (const auto& [route, getter, what] :
       {std::tuple<const char*, Getter, const char*>{"mesh", &Store::mesh_json, "mesh"},
        std::tuple<const char*, Getter, const char*>{"field", &Store::field_json,
                                                     "complete field"}}) {
    server.Get(std::string(R"(/api/details/([A-Za-z0-9_-]+)/)") + route,
               [&store, getter, what](const httplib::Request& req, httplib::Response& res) {
                 const std::string id = req.matches[1];
                 const auto body = (store.*getter)(id);
                 if (!body) return not_found(res, "unknown detail \"" + id + "\"");
                 if (body->empty()) {
                   return not_found(res, std::string("no ") + what + " of \"" + id + "\" yet");
                 }
                 json(res, *body);
               });
  }
  // The open event streams, each holding a worker while open: at most max_event_streams, so that
  // the workers beyond them (dashboard_main.cpp) always serve the page and the API.
  auto open_streams = std::make_shared<std::atomic<std::size_t>>(0);
  server.Get("/api/events", [&store, open_streams, max_event_streams](const httplib::Request& req,
                                                                      httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    if (open_streams->fetch_add(1) >= max_event_streams) {
      open_streams->fetch_sub(1);
      // Answered at once, holding no worker beyond this answer (an EventSource stops on a 503).
      res.status = 503;
      res.set_header("Retry-After", std::to_string(kStreamRetryAfterS));
      res.set_content("too many open event streams (" + std::to_string(max_event_streams) +
                          ", --max-event-streams): try again later\n",
                      "text/plain; charset=utf-8");
      return;
    }
    // The slot, given back when httplib drops the content provider holding it (the stream
    // ended: client gone, a write failed or timed out, the dashboard stopping).
    std::shared_ptr<void> slot(nullptr, [open_streams](void*) { open_streams->fetch_sub(1); });
    // Events after the one a reconnecting EventSource names (Last-Event-ID), else after ?after=ID
    // (the X-Last-Event-Id of the /api/details snapshot the page drew), else after the newest at
    // connection time. An id this process has not reached yet (another dashboard's) counts as
    // the newest; events older than the 1000 kept are gone.
    const std::uint64_t newest = store.last_event_id();
    std::uint64_t start = newest;
    const std::string named = req.has_header("Last-Event-ID")
                                  ? req.get_header_value("Last-Event-ID")
                              : req.has_param("after") ? req.get_param_value("after")
                                                       : std::string();
    if (const auto id = parse_event_id(named); id && *id < newest) start = *id;
    struct Stream {
      std::uint64_t cursor;
      bool wrote_events = false;
    };
    auto stream = std::make_shared<Stream>(Stream{start});
    res.set_chunked_content_provider(
        "text/event-stream", [&store, stream, slot](std::size_t, httplib::DataSink& sink) {
          if (store.closed()) return false;
          // After a write of events, the next ones are gathered for kEventCoalesce first: one
          // wake-up and one send per 5 ms at most instead of one per event (at 1100 events/s
          // the wake-ups, futexes and sends were a third of the dashboard's CPU,
          // docs/benchmarks.md "Dashboard"). An event after a quiet spell goes out at once.
          if (stream->wrote_events) std::this_thread::sleep_for(kEventCoalesce);
          const auto events = store.events_after(stream->cursor, std::chrono::milliseconds(1000));
          if (store.closed()) return false;
          std::string out;
          for (const auto& e : events) {
            out +=
                "id: " + std::to_string(e.id) + "\nevent: " + e.kind + "\ndata: " + e.data + "\n\n";
            stream->cursor = e.id;
          }
          stream->wrote_events = !out.empty();
          if (out.empty()) out = ": keep-alive\n\n";  // notices a client that went away
          return sink.write(out.data(), out.size());
        });
  });
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (res.status == 404 && res.body.empty()) not_found(res, "no such route");
  });
}

}  // namespace peritwin::dashboard
