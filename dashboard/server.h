// The dashboard's HTTP routes (cpp-httplib), all read-only: nothing here publishes on the bus.
//   /                         the page (embedded in the binary, dashboard/page.html)
//   /chart.js                 Chart.js from Debian's libjs-chart.js (read at run time)
//   /api/details              every detail with its latest summary
//   /api/details/{id}         the latest state of one detail, 404 {"error"} if unknown
//   /api/details/{id}/history its bounded history, 404 {"error"} if unknown
//   /api/details/{id}/mesh    its reassembled MESH, 404 {"error"} if unknown or none yet
//   /api/details/{id}/field   its newest complete FIELD, 404 {"error"} if unknown or none yet
//   /api/events               Server-Sent Events: one per STATE/STATUS/REJECT, complete MESH/FIELD
//                             after the event Last-Event-ID or ?after=ID names (X-Last-Event-Id of
//                             /api/details: the newest its snapshot includes), else from now;
//                             written by one thread for all (event_fanout.h); at most the
//                             fan-out's max_streams open at once, 503 (text/plain reason,
//                             Retry-After) beyond
#pragma once

#include <httplib.h>

#include <string>

#include "dashboard/event_fanout.h"
#include "dashboard/store.h"

namespace peritwin::dashboard {

/// The page (generated from dashboard/page.html at build time).
extern const char* const kPageHtml;

/// Installs the routes on `server` (a BoundedServer: /api/events hands its connections to
/// `events`, take_connection); `chartjs` is the path of chart.min.js.
void install_routes(httplib::Server& server, Store& store, const std::string& chartjs,
                    EventFanout& events);

}  // namespace peritwin::dashboard
