#include "dashboard/server.h"

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <tuple>

#include "dashboard/http_server.h"

namespace peritwin::dashboard {
namespace {

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
                    EventFanout& events) {
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
  for (const auto& entry :
       {std::tuple<const char*, Getter, const char*>{"mesh", &Store::mesh_json, "mesh"},
        std::tuple<const char*, Getter, const char*>{"field", &Store::field_json,
                                                     "complete field"}}) {
    // Named copies, not structured bindings: clang (the fuzz build) cannot capture those.
    const char* const route = std::get<0>(entry);
    const Getter getter = std::get<1>(entry);
    const char* const what = std::get<2>(entry);
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
  // An event stream: a slot of the fan-out (none left: 503), the SSE headers written by httplib,
  // then the connection handed to the fan-out's thread, which writes every event to it. No worker
  // is held beyond that.
  server.Get("/api/events", [&store, &events](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    if (!events.reserve()) {
      // Answered at once (an EventSource stops on a 503).
      res.status = 503;
      res.set_header("Retry-After", std::to_string(kStreamRetryAfterS));
      res.set_content("too many open event streams (" + std::to_string(events.max_streams()) +
                          ", --max-event-streams): try again later\n",
                      "text/plain; charset=utf-8");
      return;
    }
    // The slot, given back when httplib drops the content provider holding it unless the
    // connection went to the fan-out (which gives it back when the stream closes): a HEAD, or
    // headers that could not be written.
    class Slot {
     public:
      explicit Slot(EventFanout& fanout) : fanout_(fanout) {}
      ~Slot() {
        if (!adopted) fanout_.release();
      }
      Slot(const Slot&) = delete;
      Slot& operator=(const Slot&) = delete;
      bool adopted = false;

     private:
      EventFanout& fanout_;
    };
    auto slot = std::make_shared<Slot>(events);
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
    res.set_chunked_content_provider(
        "text/event-stream", [&events, slot, start](std::size_t, httplib::DataSink&) {
          // Called once the response headers are written: the connection goes to the fan-out.
          const int sock = take_connection();
          if (sock >= 0) {
            slot->adopted = true;
            events.adopt(sock, start);
          }
          return false;  // httplib writes nothing more; the server lets go of the connection
        });
  });
  server.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (res.status == 404 && res.body.empty()) not_found(res, "no such route");
  });
}

}  // namespace peritwin::dashboard
