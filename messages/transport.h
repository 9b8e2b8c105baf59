// The LCM transport as the tools see it: where a tcpq:// URL's hub is, whether LCM's connection to
// it is up, a probe of the hub that bypasses LCM, and the daemon's reconnection backoff.
//
// Why the tools need this (LCM 1.3.1, lcm/lcm_tcpq.c): the tcpq provider's lcm_create succeeds even
// when the hub is unreachable (lcm.good() is true) and leaves its socket at -1; getFileno() then
// returns -1, and lcm_handle_timeout FD_SETs it, which _FORTIFY_SOURCE turns into an abort ("bit
// out of range 0 - FD_SETSIZE on fd_set", exit 134). When the hub closes the connection, handle()
// or publish() returns -1 and the socket goes back to -1. Every later handle(), publish(),
// subscribe() or unsubscribe() on a closed socket tries one reconnect (printing three lines to
// stderr when it fails); a reconnect re-sends every subscription of the instance, so the same
// lcm::LCM, with its subscriptions, works again once the hub is back. UDP multicast (udpm), memq
// and the log provider have no connection to lose: their getFileno() is never negative.
#pragma once

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>

#include "core/expected.h"

namespace peritwin::messages {

/// The hub of a tcpq:// URL as LCM 1.3.1 reads it: "tcpq://HOST:PORT?options", HOST a numeric
/// IPv4 address (default 127.0.0.1), PORT default 7700. Any other host means 0.0.0.0, i.e. this
/// machine: the provider's name lookup never runs (it tests `inet_aton(...) < 0`, which never
/// holds), so a host name is not resolved — the probe connects where LCM will.
struct TcpqHub {
  std::string host;           ///< as written in the URL
  std::uint32_t address = 0;  ///< where LCM connects, network byte order
  std::uint16_t port = 7700;  ///< host byte order
};

/// The hub of `url` (empty: $LCM_DEFAULT_URL, as lcm_create reads it), or nullopt when the URL is
/// not tcpq:// (or is malformed: lcm::LCM then fails and says so itself).
std::optional<TcpqHub> tcpq_hub(const std::string& url);

/// OK when something accepts TCP connections at the hub within `timeout_s`, else why not
/// ("Connection refused", "no answer within 2 s"). A plain connect and close, not through LCM:
/// nothing is printed and no lcm::LCM changes state (the Java hub drops a client that closes before
/// its handshake without a word).
core::Status probe_hub(const TcpqHub& hub, double timeout_s = 2.0);

/// Whether `lcm` has its transport: false while a tcpq instance has no connection to its hub.
/// Always true for udpm, memq and file URLs.
bool transport_up(lcm::LCM& lcm);

/// Makes a tcpq instance without a connection connect again, publishing nothing: a subscription
/// made while the socket is closed connects (lcm_tcpq_subscribe), the connection re-sends every
/// subscription of the instance, and the probe subscription is dropped again. OK when `lcm` has
/// its transport afterwards (then at once for other transports); otherwise LCM has printed its
/// three lines, so probe the hub first (probe_hub).
core::Status reconnect(lcm::LCM& lcm);

/// `url`, or "(LCM default)" when it is empty.
std::string shown_url(const std::string& url);

/// Reconnection delays: first_s, then doubling up to max_s (0.1 s, 0.2 s, ... 5 s); reset() after
/// a success.
class Backoff {
 public:
  explicit Backoff(double first_s = 0.1, double max_s = 5.0) : first_s_(first_s), max_s_(max_s) {}
  /// The delay before the next attempt; each call doubles the following one (capped).
  double next() {
    const double d = next_s_ > 0.0 ? next_s_ : first_s_;
    next_s_ = d * 2.0 < max_s_ ? d * 2.0 : max_s_;
    return d;
  }
  void reset() { next_s_ = 0.0; }
  [[nodiscard]] double first_s() const { return first_s_; }
  [[nodiscard]] double max_s() const { return max_s_; }

 private:
  double first_s_, max_s_;
  double next_s_ = 0.0;
};

}  // namespace peritwin::messages
