// The open /api/events streams, all written by one thread (issue 30 item 4: each stream used to
// hold a worker thread of its own, so the cap on streams was the number of workers, 64).
//
// The route (server.cpp) reserves a slot (none left: 503), httplib writes the SSE response's
// headers, and the route's content provider takes the connection from the server
// (take_connection, http_server.h) and gives it here with the id of the event it starts after.
// From then on this thread owns the socket: it polls every stream (epoll), writes each event
// (chunked transfer coding, as httplib started it) to every stream without blocking, and closes
// a stream whose client hung up (noticed at once: EPOLLRDHUP), or reads too slowly: more than
// `max_pending_bytes` queued for it behind what is being sent, or queued data that made no
// progress for `stall_timeout`.
// Events are formatted and framed once per write and shared by every stream (a stream's queue
// holds shared pieces): a slow reader costs its queue's pointers, not a copy of the events.
//
// Event content and order are those of the thread-per-stream design: "id: N\nevent: KIND\ndata:
// JSON\n\n" for every event after the one named, in id order, the events that arrived within
// `coalesce` of a write gathered into the next one (an event after a quiet spell goes out at
// once), and ": keep-alive\n\n" to a stream that got nothing for `keep_alive`.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "dashboard/store.h"

namespace peritwin::dashboard {

/// The default cap on open event streams (--max-event-streams).
constexpr std::size_t kDefaultMaxEventStreams = 4096;

struct FanoutLimits {
  /// Open (or reserved) streams at most; one more is refused (the route answers 503).
  std::size_t max_streams = kDefaultMaxEventStreams;
  /// Bytes queued for one stream at most behind the piece being sent (beyond its socket's send
  /// buffer; a new stream's catch-up is one piece, which may be larger): a client that reads
  /// slower than the events come is closed beyond this (it reconnects with Last-Event-ID).
  std::size_t max_pending_bytes = std::size_t{1} << 20;
  /// A stream whose queued bytes made no progress for this long is closed.
  std::chrono::milliseconds stall_timeout{5000};
  /// A stream that was sent nothing for this long gets a ": keep-alive" comment.
  std::chrono::milliseconds keep_alive{1000};
  /// After a write of events, the next ones are gathered this long (one send per stream per
  /// `coalesce` at most instead of one per event; docs/benchmarks.md "Dashboard").
  std::chrono::milliseconds coalesce{5};
};

/// Counts since the start, and the streams open now.
struct FanoutStats {
  std::size_t open = 0;           ///< streams open (or reserved) now
  std::uint64_t adopted = 0;      ///< streams taken over
  std::uint64_t refused = 0;      ///< reservations refused (503)
  std::uint64_t closed_gone = 0;  ///< closed: the client hung up or reset
  std::uint64_t closed_slow = 0;  ///< closed: too much queued, or no progress (slow reader)
  std::uint64_t events_sent = 0;  ///< events queued, summed over the streams
  std::uint64_t writes = 0;       ///< event writes (each to every stream up to date)
};

class EventFanout {
 public:
  /// Starts the thread; streams start after store.last_event_id() at the latest.
  EventFanout(Store& store, const FanoutLimits& limits);
  ~EventFanout();
  EventFanout(const EventFanout&) = delete;
  EventFanout& operator=(const EventFanout&) = delete;

  /// A slot for one stream: false (and counted as refused) when max_streams are open or
  /// reserved. A slot taken is given back by adopt (when its stream closes) or release.
  bool reserve();
  /// Gives back a slot reserved and not adopted.
  void release();
  /// Takes over `sock` (its SSE response headers sent, a slot reserved for it): events with an
  /// id above `after` are written to it from now on, older ones kept by the store first. Closed
  /// (and its slot given back) at once after stop().
  void adopt(int sock, std::uint64_t after);
  /// Closes every stream and stops the thread (the destructor does too).
  void stop();

  [[nodiscard]] std::size_t max_streams() const { return limits_.max_streams; }
  [[nodiscard]] FanoutStats stats() const;

 private:
  struct Client;
  struct Arrival {
    int sock;
    std::uint64_t after;
  };
  void run();
  void wake();

  Store& store_;
  FanoutLimits limits_;
  int epoll_ = -1;
  int wake_ = -1;
  /// True while the thread waits for an event (the store's listener then wakes it, once).
  std::atomic<bool> armed_{false};
  std::atomic<std::size_t> slots_{0};
  std::atomic<std::uint64_t> adopted_{0}, refused_{0}, closed_gone_{0}, closed_slow_{0},
      events_sent_{0}, writes_{0};
  std::mutex mutex_;  // arrivals_, stopping_
  std::vector<Arrival> arrivals_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace peritwin::dashboard
