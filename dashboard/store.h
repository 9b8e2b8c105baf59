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
//   history_json(id) {"detail", "pushed", "backfilled", "cycles": [], "crack_length_m": [],
//                    "remaining": [], "low": [], "high": [], "state_seq": []} (non-finite numbers
//                    as null)
//   mesh_json(id)    the reassembled MESH: {"detail", "mesh_hash", "total_nodes", "dx", "horizon",
//                    "box": [x_min, y_min, x_max, y_max], "x": [], "y": [], "polylines":
//                    [{"kind": "outline"|"hole"|"notch", "index", "closed", "x": [], "y": []}]}
//   field_json(id)   the newest complete FIELD: {"detail", "state_seq", "mesh_hash",
//                    "total_nodes", "damage": []}
//
// Meshes: a detail seen without a mesh, or whose FIELD names a mesh_hash other than the mesh's, is
// due a mesh request (take_mesh_requests, at most every kMeshRequestPeriodS per detail): the LCM
// thread publishes a mesh_request_t for it, the daemon answers on PERITWIN_<DETAIL>_MESH.
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
#include <peritwin_msgs/damage_field_t.hpp>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/reject_t.hpp>
#include <peritwin_msgs/status_t.hpp>
#include <string>
#include <vector>

#include "dashboard/history.h"
#include "messages/mesh.h"

namespace peritwin::dashboard {

using Clock = std::chrono::steady_clock;

/// A detail is stale when its last STATUS (or, without one, its first message) is older than this.
inline constexpr double kStaleAfterS = 5.0;
/// Points kept per detail and series.
inline constexpr std::size_t kHistoryPoints = 10000;
/// A detail without its mesh is asked for it again after this long.
inline constexpr double kMeshRequestPeriodS = 5.0;

/// One point of a detail's history (a STATE, or a row of its results file).
struct HistoryPoint {
  std::int64_t state_seq = 0;
  std::int64_t cycles = 0;
  double crack_length_m = 0.0;
  double remaining = 0.0;
  double low = 0.0;
  double high = 0.0;
};

/// A complete damage field (all FIELD chunks of one state).
struct Field {
  std::int64_t state_seq = 0;
  std::string mesh_hash;
  std::vector<float> damage;
};

/// FIELD chunks of one state, waiting for the rest.
struct PartialField {
  std::int64_t state_seq = -1;
  std::string mesh_hash;
  std::int32_t num_chunks = 0;
  std::int32_t total_nodes = 0;
  std::map<std::int32_t, peritwin_msgs::damage_field_t> chunks;
};

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
  std::size_t backfilled = 0;  ///< points read from a results file
  std::optional<messages::Mesh> mesh;
  std::string mesh_hash;       ///< of `mesh`
  std::string mesh_error;      ///< why the last refused MESH chunk was refused
  std::optional<Field> field;  ///< the newest complete one
  PartialField partial_field;
  Clock::time_point mesh_requested{};  ///< last request sent; {} = never
};

/// One event for /api/events.
struct Event {
  std::uint64_t id = 0;
  std::string kind;  // "state", "status", "reject", "mesh", "field"
  std::string data;  // JSON
};

class Store {
 public:
  /// A message received on `channel` (any of the subscribed kinds) at `now`.
  void on_message(const std::string& channel, const void* data, std::size_t size,
                  Clock::time_point now);

  /// JSON texts as described above; nullopt for an unknown detail.
  /// `last_event` (when given): the id of the newest event the snapshot includes.
  [[nodiscard]] std::string details_json(Clock::time_point now,
                                         std::uint64_t* last_event = nullptr) const;
  [[nodiscard]] std::optional<std::string> detail_json(const std::string& id,
                                                       Clock::time_point now) const;
  [[nodiscard]] std::optional<std::string> history_json(const std::string& id) const;
  /// nullopt for an unknown detail; "" for a known one without a mesh (or complete field) yet.
  [[nodiscard]] std::optional<std::string> mesh_json(const std::string& id) const;
  [[nodiscard]] std::optional<std::string> field_json(const std::string& id) const;

  /// The details due a mesh request at `now` (seen without their mesh, or a FIELD names another
  /// mesh; last asked kMeshRequestPeriodS ago or never), marked as asked.
  std::vector<std::string> take_mesh_requests(Clock::time_point now);

  /// Points of a detail's history from before the bus (its results file, in state order): the
  /// points with a state_seq below the first one received live go first; the rest are ignored.
  /// Creates the detail (it then shows "waiting" until it publishes). Returns the points taken.
  std::size_t backfill(const std::string& id, const std::vector<HistoryPoint>& points,
                       Clock::time_point now);

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
  void on_mesh_chunk(const std::string& token, const void* data, std::size_t size,
                     Clock::time_point now);
  void on_field(const std::string& id, DetailRecord& d, peritwin_msgs::damage_field_t field,
                Clock::time_point now);
  [[nodiscard]] std::string detail_json_locked(const std::string& id, const DetailRecord& d,
                                               Clock::time_point now) const;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::map<std::string, DetailRecord> details_;
  std::map<std::string, std::int64_t> undecodable_;  // by channel token
  std::int64_t undecodable_total_ = 0;
  messages::MeshAssembler meshes_;
  std::deque<Event> events_;  // the newest kMaxEvents
  std::uint64_t next_event_ = 1;
  bool closed_ = false;
};

}  // namespace peritwin::dashboard
