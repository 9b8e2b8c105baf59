// A detail never has two twins (issue 18): every STATUS names the daemon that sent it (host, pid,
// start time; status_t, message set version 7), and a daemon about to start listens to the STATUS
// channels of its details for a heartbeat and a half first. If another daemon's STATUS arrives for
// one of them, it refuses to start (exit 2, a usage error: the fleet's configuration gives the
// detail to two daemons), naming the detail and the other daemon.
#pragma once

#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <vector>

namespace peritwin::service {

/// This process as its STATUS names it.
struct DaemonIdentity {
  std::string host;
  std::int32_t pid = 0;
  std::int64_t started_utime = 0;
  /// The identity of this process (computed once, at the first call).
  static const DaemonIdentity& self();
};

/// What another daemon's STATUS said about itself.
struct OtherTwin {
  std::string detail_id;
  DaemonIdentity daemon;
  std::string health;
  double uptime_s = 0.0;
  /// "detail \"b1-ct\" already has a twin: peritwin pid 4242 on host \"deck-pc\" (up 812 s,
  /// health ok)".
  [[nodiscard]] std::string describe() const;
};

/// Listens to the STATUS channels of `detail_ids` for `window_s` (STATUS is sent every second:
/// 1.5 s sees at least one heartbeat of a running daemon) and returns the first STATUS from
/// another daemon than this process that is not stopping (health "stopping": its last STATUS
/// after SIGTERM), or nothing. Undecodable messages are ignored.
std::optional<OtherTwin> find_other_twin(lcm::LCM& lcm, const std::vector<std::string>& detail_ids,
                                         double window_s);

}  // namespace peritwin::service
