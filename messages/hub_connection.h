// The daemon's connection to a tcpq hub that comes and goes (see messages/transport.h for what
// LCM 1.3.1 does without one). peritwin_main.cpp drives it around Daemon::poll():
//
//   - open(): waits until the hub accepts connections before creating the lcm::LCM (one warning
//     line, then a probe per backoff delay, 0.1 s doubling to 5 s), so the daemon builds its models
//     and says "ready" only once it is connected; other transports open at once.
//   - after every poll(), check(): when the hub has closed the connection, one warning line.
//   - while disconnected, reconnect(): waits the next backoff delay, probes the hub without LCM
//     (so LCM prints nothing and stays as it is), and when the hub answers, makes the same
//     lcm::LCM connect again (messages::reconnect: LCM re-sends its subscriptions, so the Daemon
//     keeps its instance and its models). One line when it is back. The next Daemon::poll()
//     publishes what the detail workers queued meanwhile (the STATEs of batches received before
//     the loss). No STATE is made up here: the daemon publishes the next one (signed, with its
//     checkpointed seqs) when a producer resumes — a resent batch is a duplicate, which is
//     answered with the STATE.
//
// While disconnected the daemon is not polled: no STATUS (it could not be delivered); its detail
// workers go on applying the batches received before the loss (their STATEs wait in the outbox)
// and write their checkpoints; SIGTERM still stops it with its checkpoint. All LCM calls run on
// the thread that polls the daemon.
#pragma once

#include <chrono>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>

#include "messages/transport.h"

namespace peritwin::messages {

class HubConnection {
 public:
  /// `url` as given to lcm::LCM (empty: LCM's default); `keep_going` turns false to give up
  /// waiting (a signal).
  HubConnection(std::string url, std::function<bool()> keep_going);

  /// A connected lcm::LCM; nullptr when keep_going() turned false first or when LCM cannot open
  /// the URL at all (then error() says why).
  std::unique_ptr<lcm::LCM> open();
  /// After Daemon::poll(): false, with one warning line, once the hub has closed the connection.
  bool check(lcm::LCM& lcm);
  /// While disconnected: waits the next backoff delay and tries once; true when reconnected.
  bool reconnect(lcm::LCM& lcm);

  [[nodiscard]] bool connected() const { return connected_; }
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  bool wait(double seconds) const;

  std::string url_, shown_;
  std::function<bool()> keep_going_;
  std::optional<messages::TcpqHub> hub_;
  messages::Backoff backoff_;
  bool connected_ = false;
  std::chrono::steady_clock::time_point since_;
  std::string error_;
};

}  // namespace peritwin::messages
