// What the dashboard knows of every detail on the bus, fed by the LCM thread and read by the HTTP
// threads (one mutex). Every message is decoded with the project's codec (messages/codec.h, layout
// checked first); an undecodable one, or one whose detail_id does not belong to its channel, is
// counted (per channel token and in total) and otherwise ignored. Auth tags of signed messages
// are read past, not verified.
//
// The JSON it builds:
//   detail_json(id)  the latest STATE's fields in messages::state_json's order at the top level
//                    (plus k_ii, remaining_life_source, signed, tip, cracks, "from_results"),
//                    then "health", "status_age_s", "status" {...}, "rejects" (refusals only),
//                    "fields", ..., "undecodable", then "life" {state, remaining, low, high,
//                    end_cycle, estimate_cycle, estimate_source, estimate_seq, age_cycles, age_s}:
//                    the estimate counted down to this state, see Countdown), "last_reject" {...}
//                    (the last refusal), "protocol" {probes, duplicates, gaps, last}. Without a
//                    STATE since the start but with a results file (--results): its last row
//                    under the same keys ("from_results": true).
//                    64-bit integers (seq, cycles) are JSON numbers below 2^53 and decimal strings
//                    from there on: a browser's JSON.parse reads doubles.
//   details_json()   {"details": [detail_json of each, by id], "undecodable": total}
//                    With the learning ensemble (num_particles > 0), "ensemble" {particles,
//                    estimate_cycle, effective_sample_size, percentiles [], end_of_life [],
//                    remaining [], horizon_cycles, probability_within_horizon, posterior [{name,
//                    median, cov}], observation_count}; null without one.
//   history_json(id) {"detail", "pushed", "backfilled", "cycles": [], "crack_length_m": [],
//                    "remaining": [], "low": [], "high": [], "state_seq": [], "eol_low": [],
//                    "eol_median": [], "eol_high": [], "eol_percentiles": [low, median, high] (of
//                    the latest STATE with an ensemble; null before one), "observations": [{index,
//                    cycles, kind ("crack_length"|"no_crack"), length_m, sigma_m, pod_a50_m,
//                    predicted_m}]} (non-finite numbers as null). eol_*: the ensemble's predicted
//                    end-of-life cycle at each state, at the first, middle and last of the
//                    STATE's percentiles (5, 50, 95 by default); null without an ensemble or
//                    beyond its simulated horizon.
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
#include <functional>
#include <limits>
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

/// Batches remembered per detail to find the state a remaining-life estimate was made on (the
/// life worker lags the live state by the length of one forward simulation): 32 bytes each, so
/// at most 512 kB per detail (reached only while no estimate comes: each new one drops the
/// batches before its own). An estimate made further back is shown as published (unanchored).
inline constexpr std::size_t kBatchMemory = 16384;

/// One point of a detail's history (a STATE, or a row of its results file). remaining, low and
/// high are counted down to this point's cycles (see Countdown), not the estimate as published.
struct HistoryPoint {
  std::int64_t state_seq = 0;
  std::int64_t cycles = 0;
  double crack_length_m = 0.0;
  double remaining = 0.0;
  double low = 0.0;
  double high = 0.0;
  /// The ensemble's predicted end-of-life cycle (low, median, high percentile); NaN without one.
  double eol_low = std::numeric_limits<double>::quiet_NaN();
  double eol_median = std::numeric_limits<double>::quiet_NaN();
  double eol_high = std::numeric_limits<double>::quiet_NaN();
};

/// Observations kept per detail (the oldest dropped beyond).
inline constexpr std::size_t kObservationMemory = 4096;

/// An observation the detail's ensemble took in, as STATE carries it (observation_t.KIND_*).
struct ObservationPoint {
  std::int64_t index = 0;  ///< 0-based, in the order the ensemble took them in
  std::int64_t cycles = 0;
  std::int8_t kind = 0;
  double length_m = std::numeric_limits<double>::quiet_NaN();
  double sigma_m = std::numeric_limits<double>::quiet_NaN();
  double pod_a50_m = std::numeric_limits<double>::quiet_NaN();
  double predicted_m = std::numeric_limits<double>::quiet_NaN();
};

/// A remaining-life estimate seen at a later state. The STATE carries the estimate (central, low,
/// high: cycles left after the state it was computed on) and that state's batch
/// (remaining_life_source, remaining_life_seq), not its cycles: the store finds them among the
/// states it received. The end of life is then predicted at estimate_cycles + central, and at a
/// state of `cycles` the remaining life is that end − cycles (not below 0), for the band likewise.
struct Countdown {
  double remaining = std::numeric_limits<double>::quiet_NaN();
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
  double end_cycle = std::numeric_limits<double>::quiet_NaN();  ///< predicted (+Inf: never)
  std::int64_t age_cycles = 0;                                  ///< cycles − estimate_cycles
};

/// The countdown of an estimate (central, low, high) made at `estimate_cycles`, at `cycles`.
/// NaN stays NaN (no estimate), +Inf stays +Inf (the reference spectrum never ends the life).
[[nodiscard]] Countdown count_down(double central, double low, double high,
                                   std::int64_t estimate_cycles, std::int64_t cycles);

/// A complete damage field (all FIELD chunks of one state, or a results file's snapshot).
struct Field {
  std::int64_t state_seq = 0;
  std::string mesh_hash;  ///< "" for a snapshot from a results file until a mesh matches it
  std::vector<float> damage;
  /// A results file's snapshot: FNV-1a 64 of its /mesh/x and /mesh/y (mesh_coordinates_hash),
  /// compared with the bus's mesh to tell it is the same grid in the same node order.
  std::optional<std::uint64_t> file_coordinates;
};

/// FNV-1a 64 over the bytes of x then y: a results file's grid equals a MESH's when both agree.
[[nodiscard]] std::uint64_t mesh_coordinates_hash(const std::vector<double>& x,
                                                  const std::vector<double>& y);

/// The last state of a results file (its last /timeseries row), shown on the card of a detail
/// that has not published a STATE since the dashboard started.
struct FileState {
  std::int64_t state_seq = 0;
  std::int64_t cycles = 0;
  std::int64_t broken_bonds = 0;
  std::int64_t crack_count = 0;  ///< -1 unknown (a layout-1 file)
  double crack_length_m = 0.0;
  double k_i = std::numeric_limits<double>::quiet_NaN();
  double k_ii = std::numeric_limits<double>::quiet_NaN();
  double tip_x = std::numeric_limits<double>::quiet_NaN();
  double tip_y = std::numeric_limits<double>::quiet_NaN();
  double remaining = std::numeric_limits<double>::quiet_NaN();  ///< as estimated (not counted down)
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
  std::int64_t remaining_state_seq = -1;        ///< the state the estimate was made on; -1 none
  std::optional<std::int64_t> estimate_cycles;  ///< that state's cycles, when the file has its row
  double max_damage = std::numeric_limits<double>::quiet_NaN();  ///< of the snapshot of this state
};

/// The remaining-life estimate the detail's countdown runs from.
struct LifeAnchor {
  std::string source;       ///< remaining_life_source ("" with seq -1: the initial state)
  std::string source_json;  ///< `source` as JSON text (escaped once, written every event)
  std::int64_t seq = -1;    ///< remaining_life_seq
  bool keyed = true;        ///< false: from a results file, whose rows do not name the batch
  double central = std::numeric_limits<double>::quiet_NaN();
  double low = std::numeric_limits<double>::quiet_NaN();
  double high = std::numeric_limits<double>::quiet_NaN();
  std::optional<std::int64_t> cycles;  ///< of the state it was made on; nullopt: not seen
  std::int64_t utime = 0;              ///< that state's utime; 0: not seen
};

/// The batch that produced a state the store received (its predecessor received too).
struct BatchState {
  std::uint32_t source = 0;  ///< index into DetailRecord::batch_sources
  std::int64_t seq = 0;
  std::int64_t cycles = 0;
  std::int64_t utime = 0;
};

/// FIELD chunks of one state, waiting for the rest.
struct PartialField {
  std::int64_t state_seq = -1;
  std::string mesh_hash;
  std::int32_t num_chunks = 0;
  std::int32_t total_nodes = 0;
  std::map<std::int32_t, peritwin_msgs::damage_field_t> chunks;
};

/// History columns: cycles, crack_length_m, remaining, low, high, state_seq, eol_low, eol_median,
/// eol_high.
using History = BoundedHistory<9>;

struct DetailRecord {
  std::optional<peritwin_msgs::damage_state_t> state;
  std::optional<peritwin_msgs::status_t> status;
  Clock::time_point first_seen{};
  Clock::time_point status_at{};
  std::int64_t states = 0;
  /// Refusals: a batch the daemon would not take (INVALID, AUTH, LIMIT, FAILED, and DECODE,
  /// WRONG_DETAIL, INTERNAL): what an operator must look at.
  std::int64_t rejects = 0;
  std::string last_reject;  ///< the last refusal as JSON text; "" none
  /// Protocol events, the exactly-once handshake working as meant: a producer's probe (GAP with
  /// seq 2^63 − 1, answered with the STATE), a resend answered as DUPLICATE, a GAP asking for a
  /// resend. Counted apart; never in `rejects`.
  std::int64_t probes = 0;
  std::int64_t duplicates = 0;
  std::int64_t gaps = 0;
  std::string last_protocol;       ///< the last protocol event as JSON text; "" none
  std::optional<LifeAnchor> life;  ///< the estimate of the latest STATE (or results file)
  std::deque<BatchState> batches;  ///< newest last, at most kBatchMemory, none before `life`'s
  std::vector<std::string> batch_sources;  ///< the source ids `batches` index (seen, in order)
  std::int64_t initial_utime = 0;          ///< utime of state 0 when received (estimates on it)
  std::optional<FileState> file_state;     ///< the results file's last state (--results)
  std::int64_t fields = 0;
  History history{kHistoryPoints};
  std::size_t backfilled = 0;                 ///< points read from a results file
  std::deque<ObservationPoint> observations;  ///< by index, at most kObservationMemory
  std::vector<double> eol_percentiles;        ///< the latest ensemble's (low, median, high)
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
  /// The card's numbers and the damage map from a results file (--results): its last state and
  /// its newest snapshot, used until the detail publishes a newer STATE or FIELD. The snapshot is
  /// drawn on the bus's MESH when that mesh has the file's coordinates (mesh_coordinates_hash).
  void backfill_latest(const std::string& id, const FileState& state, std::optional<Field> snapshot,
                       Clock::time_point now);

  [[nodiscard]] std::int64_t undecodable_total() const;

  /// Events with an id > `after`, waiting up to `wait` for one; the last event id seen so far in
  /// `last_id` (0 when none). Returns at once after close().
  std::deque<Event> events_after(std::uint64_t after, std::chrono::milliseconds wait) const;
  /// Id of the newest event (0 before the first).
  [[nodiscard]] std::uint64_t last_event_id() const;
  /// `listener` (or none: nullptr) is called after every new event, under the store's lock: it
  /// must be quick and must not call the store (EventFanout's wakes its thread).
  void set_event_listener(std::function<void()> listener);
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
  static void on_state_life(DetailRecord& d, const peritwin_msgs::damage_state_t& s);
  static void on_state_ensemble(DetailRecord& d, const peritwin_msgs::damage_state_t& s);
  static void match_file_field(DetailRecord& d);
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
  std::function<void()> event_listener_;
  bool closed_ = false;
};

}  // namespace peritwin::dashboard
