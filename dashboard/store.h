// What the dashboard knows of every detail on the bus, fed by the LCM thread and read by the HTTP
// threads (one mutex). Every message is decoded with the project's codec (messages/codec.h, layout
// checked first); an undecodable one, or one whose detail_id does not belong to its channel, is
// counted (per channel token and in total) and otherwise ignored. Auth tags of signed messages
// are read past, not verified.
//
// The JSON it builds:
//   detail_json(id)  the latest STATE's fields in messages::state_json's order at the top level
//                    (plus k_ii, remaining_life_source, signed), then "health", "status_age_s",
//                    "status" {...}, "rejects", "last_reject" {...}, "fields", "undecodable".
//   details_json()   {"details": [detail_json of each, by id], "undecodable": total}
//   history_json(id) {"detail", "pushed", "cycles": [], "crack_length_m": [], "remaining": [],
//                    "low": [], "high": [], "state_seq": []} (non-finite numbers as null)
//   events           one line of JSON per STATE/STATUS/REJECT: {"kind", "detail", "summary"}
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/reject_t.hpp>
#include <peritwin_msgs/status_t.hpp>
#include <string>

#include "dashboard/history.h"

namespace peritwin::dashboard {

using Clock = std::chrono::steady_clock;

/// A detail is stale when its last STATUS (or, without one, its first message) is older than this.
inline constexpr double kStaleAfterS = 5.0;
/// Points kept per detail and series.
inline constexpr std::size_t kHistoryPoints = 10000;

/// History columns: cycles, crack_length_m, remaining, low, high, state_seq.
using History = BoundedHistory<6>;

struct DetailRecord {
  std::optional<peritwin_msgs::damage_state_t> state;
  std::optional<peritwin_msgs::status_t> status;
  Clock::time_point first_seen{};
  Clock::time_point status_at{};
  std::int64_t states = 0;
  std::int64_t rejects = 0;
  std::optional<peritwin_msgs::reject_t> last_reject;
  std::int64_t fields = 0;
  History history{kHistoryPoints};
};

/// One event for /api/events.
struct Event {
  std::uint64_t id = 0;
  std::string kind;  // "state", "status", "reject"
  std::string data;  // JSON
};

class Store {
 public:
  /// A message received on `channel` (any of the subscribed kinds) at `now`.
  void on_message(const std::string& channel, const void* data, std::size_t size,
                  Clock::time_point now);

  /// JSON texts as described above; nullopt for an unknown detail.
  [[nodiscard]] std::string details_json(Clock::time_point now) const;
  [[nodiscard]] std::optional<std::string> detail_json(const std::string& id,
                                                       Clock::time_point now) const;
  [[nodiscard]] std::optional<std::string> history_json(const std::string& id) const;

  [[nodiscard]] std::int64_t undecodable_total() const;

  /// Events with an id > `after`, waiting up to `wait` for one; the last event id seen so far in
  /// `last_id` (0 when none). Returns at once after close().
  std::deque<Event> events_after(std::uint64_t after, std::chrono::milliseconds wait) const;
  /// Id of the newest event (0 before the first).
  [[nodiscard]] std::uint64_t last_event_id() const;
  /// Wakes every waiter for good (shutdown).
  void close();
  [[nodiscard]] bool closed() const;

 private:
  void push_event(const std::string& kind, const std::string& detail, Clock::time_point now);
  void count_undecodable(const std::string& token);
  [[nodiscard]] std::string detail_json_locked(const std::string& id, const DetailRecord& d,
                                               Clock::time_point now) const;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::map<std::string, DetailRecord> details_;
  std::map<std::string, std::int64_t> undecodable_;  // by channel token
  std::int64_t undecodable_total_ = 0;
  std::deque<Event> events_;  // the newest kMaxEvents
  std::uint64_t next_event_ = 1;
  bool closed_ = false;
};

}  // namespace peritwin::dashboard
