// The dashboard's HTTP server: cpp-httplib's Server whose workers only ever serve complete
// requests (issue 30 item 4: eight open event streams, or 200 idle connections, locked the page
// out, because httplib gives each accepted connection a worker of its 8 for as long as it is open,
// idle or not).
//
// A connection waits for its request headers in one gate thread (poll), not on a worker: only
// once "\r\n\r\n" has arrived does a worker read and answer it, and between keep-alive requests it
// goes back to the gate. A connection whose headers do not arrive within `header_timeout` (idle,
// or a slowloris dribbling half a request line) is closed there, as is one idle for
// `keep_alive_timeout` after a request. An event stream holds no worker either: once its
// response headers are written, the route takes the connection from the server
// (take_connection) and gives it to the one thread that writes every stream (event_fanout.h).
// So workers are held only by requests being answered, and a few of them always answer the page
// and the API, whatever number of streams and idle connections is open.
#pragma once

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstddef>

namespace peritwin::dashboard {

struct ServerLimits {
  /// Worker threads: requests being answered (an event stream only until its headers are out).
  std::size_t workers = 8;
  /// A new connection's request headers must have arrived within this, or it is closed.
  std::chrono::milliseconds header_timeout{10000};
  /// A connection idle this long after a request (keep-alive) is closed.
  std::chrono::milliseconds keep_alive_timeout{5000};
  /// Requests per connection; the last one is answered with "Connection: close".
  std::size_t keep_alive_max_count = 100;
  /// Connections waiting for their headers at most; beyond, the oldest waiting are closed.
  std::size_t max_waiting = 4096;
  /// A request's body must be read within this after a worker takes it; a write (response,
  /// event) waits this long at most for the client to take some.
  std::chrono::seconds read_timeout{5};
  std::chrono::seconds write_timeout{5};
};

/// Inside a route's content provider, on a BoundedServer worker: the connection being answered is
/// taken from the server, which then neither reads, writes nor closes it (the provider returns
/// false: httplib writes nothing more). Its socket, whose response headers are written; -1 when
/// not called on a BoundedServer worker, or a second time.
[[nodiscard]] int take_connection();

class BoundedServer : public httplib::Server {
 public:
  explicit BoundedServer(const ServerLimits& limits);

  /// After bind_to_port/bind_to_any_port: the listening socket's accept queue takes `backlog`
  /// connections (httplib listens with 5, so a burst of connections, e.g. 200 at once, had SYNs
  /// dropped and the clients' connects waited a second or more for the retransmission).
  bool set_backlog(int backlog);

 private:
  class Pool;
  friend class Pool;
  /// Called by httplib's accept loop for each new connection: hands it to the gate.
  bool process_and_close_socket(socket_t sock) override;
  /// Gives `sock` (its request headers there) to a worker.
  void dispatch(Pool& pool, socket_t sock, std::size_t served);
  /// On a worker: answers the one request whose headers are there, then back to the gate.
  void serve(socket_t sock, std::size_t served);

  ServerLimits limits_;
  std::atomic<Pool*> pool_{nullptr};
};

}  // namespace peritwin::dashboard
