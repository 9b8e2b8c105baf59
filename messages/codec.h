// The LCM message codec (peritwin_msgs, messages/*.lcm): decoding load batches defensively,
// building batch and reject messages, reading state messages, the JSON lines the replay tool
// prints, and LCM's receive loop tuned for the TCP hub. No model here: the state and field
// messages of a twin are built in twin/messages_io.h. The replay tool's producer side links
// this alone (no HDF5, no libpng).
#pragma once

#include <cstddef>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <peritwin_msgs/damage_field_t.hpp>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/load_batch_t.hpp>
#include <peritwin_msgs/load_samples_t.hpp>
#include <peritwin_msgs/observation_t.hpp>
#include <peritwin_msgs/reject_t.hpp>
#include <peritwin_msgs/status_t.hpp>
#include <string>
#include <utility>
#include <vector>

#include "messages/batch.h"
#include "messages/channels.h"
#include "messages/observation.h"

namespace peritwin::messages {

/// Largest load_batch_t payload accepted (a full batch of kMaxBlocksPerBatch blocks with two
/// maximal ids fits).
inline constexpr std::size_t kMaxBatchPayload = 32 * kMaxBlocksPerBatch + 4096;

/// Largest load_samples_t payload accepted: one UDP datagram of LCM 1.3.1 (65 499 bytes with the
/// channel name and its NUL; a fragmented message is lost when its fragments arrive out of order,
/// see damage_field_t) with the longest channel name: about 8 100 samples of p alone, 2 700 with t
/// and alpha. And at most kMaxSamplesPerMessage samples whatever the payload.
inline constexpr std::size_t kMaxSamplesPayload = 65'499 - kMaxChannelLength - 1;
inline constexpr std::int32_t kMaxSamplesPerMessage = 65536;

/// Raw load samples of one detail from one source (load_samples_t, message set version 5).
struct Samples {
  std::string detail_id;
  std::string source_id;
  std::int64_t seq = 0;
  double t0 = 0.0;
  double sample_period = 0.0;  ///< > 0 without t, 0 with it
  std::vector<double> p;
  std::vector<double> t;      ///< empty or one per sample
  std::vector<double> alpha;  ///< empty or one per sample
  /// Time of sample i: t[i], or t0 + i * sample_period.
  [[nodiscard]] double time(std::size_t i) const {
    return t.empty() ? t0 + static_cast<double>(i) * sample_period : t[i];
  }
};

/// Every field of a samples message against its rules (load_samples_t.lcm), as check_batch: the
/// verdict (wrong_detail or invalid), the field ("num_t", "t[3]", ...) and the reason.
Outcome check_samples(const Samples& samples, std::string_view detail_id);

/// A decoded samples message (layout checked first, never allocating beyond the payload; not yet
/// checked by check_samples), or (verdict decode) why not; the signed bytes and the tag as Decoded.
struct DecodedSamples {
  std::optional<Samples> samples;
  Outcome error;
  std::size_t signed_size = 0;
  std::vector<std::uint8_t> auth_tag;
};
DecodedSamples decode_samples(const void* data, std::size_t size);

peritwin_msgs::load_samples_t samples_message(const Samples& samples, std::int64_t utime);

/// lcm.handleTimeout(timeout_ms) with the socket tuned for LCM's TCP hub. LCM 1.3.1's Java hub
/// (lcm.lcm.TCPService) writes every relayed message in five small unbuffered writes without
/// TCP_NODELAY, and the C client writes a published one in several too; Nagle's algorithm then
/// holds each message's tail until the peer ACKs its head, which Linux delays by up to 40 ms:
/// a lockstep round trip took ~90 ms. Before each receive we disable Nagle on our end and ask
/// for immediate ACKs (TCP_QUICKACK is not sticky, hence every call); both are no-ops on the
/// memq and UDP transports.
/// Returns 1 when a message was handled, 0 after the timeout, -1 on failure (errno; EINTR is a
/// signal). Without a transport (a tcpq hub that is down or has just closed the connection, see
/// messages/transport.h) it returns 0, after waiting timeout_ms when it was down already, and
/// never lets LCM select() on a negative descriptor: callers check transport_up() to tell.
int handle_lcm(lcm::LCM& lcm, int timeout_ms);

/// Microseconds since the Unix epoch (the informational utime of every message).
std::int64_t now_utime();

/// A decoded batch, or (verdict decode) why not: wrong fingerprint, truncated, oversized,
/// malformed string or array length. Never allocates more than the payload justifies.
struct Decoded {
  std::optional<Batch> batch;
  Outcome error;
  /// Leading bytes of the payload the batch's auth tag covers (messages/README.md), and the tag:
  /// empty (unsigned) or kAuthTagBytes bytes.
  std::size_t signed_size = 0;
  std::vector<std::uint8_t> auth_tag;
};
Decoded decode_batch(const void* data, std::size_t size);

/// A STATE or REJECT decoded from untrusted bytes, or nullopt: wrong fingerprint, truncated,
/// bytes after the end, or a string length or array count the payload cannot hold. The layout is
/// walked first, so LCM's decoder (which sizes its arrays from the counts before reading them) is
/// never asked to allocate more than the payload justifies: a forged num_sources of 2^30 would
/// otherwise cost gigabytes in any receiver that subscribes with the typed handler.
std::optional<peritwin_msgs::damage_state_t> decode_state(const void* data, std::size_t size);
std::optional<peritwin_msgs::reject_t> decode_reject(const void* data, std::size_t size);

/// A STATUS or FIELD chunk decoded from untrusted bytes the same way, or nullopt (a FIELD's
/// num_nodes is checked against the payload before LCM sizes its damage array).
std::optional<peritwin_msgs::status_t> decode_status(const void* data, std::size_t size);
std::optional<peritwin_msgs::damage_field_t> decode_field(const void* data, std::size_t size);

peritwin_msgs::load_batch_t batch_message(const Batch& batch, std::int64_t utime);

/// Largest observation_t payload accepted: two maximal ids, an origin of 64 characters, a tag,
/// and up to kMaxObservedGauges gauges (an id of 32 characters and three doubles each).
inline constexpr std::size_t kMaxObservationPayload = 1024 + kMaxObservedGauges * (4 + 33 + 3 * 8);

/// A decoded observation message (layout checked first; not yet checked by
/// check_observation_message), or why not: verdict decode, or invalid for a kind that is none of
/// the KIND_* constants (then source_id, seq and nonce are known). The signed bytes and the tag as
/// Decoded.
struct DecodedObservation {
  std::optional<Observation> observation;
  Outcome error;
  std::string source_id;  ///< "" when it did not decode
  std::int64_t seq = -1;
  std::uint64_t nonce = 0;
  std::size_t signed_size = 0;
  std::vector<std::uint8_t> auth_tag;
};
DecodedObservation decode_observation(const void* data, std::size_t size);
/// The message of an observation (unsigned: messages::sign it with the source's key).
peritwin_msgs::observation_t observation_message(const Observation& observation,
                                                 std::int64_t utime);

/// REJECT for a batch that was not applied (source "" / seq -1 / nonce 0 when it did not
/// decode); `nonce` is the batch's (load_batch_t.nonce), echoed for its producer.
peritwin_msgs::reject_t reject_message(const std::string& detail_id, const std::string& source,
                                       std::int64_t seq, const Outcome& outcome, std::int64_t utime,
                                       std::uint64_t nonce = 0);

/// Length (m) of the longest crack of a state message (crack_length_m; 0 without cracks).
double crack_length(const peritwin_msgs::damage_state_t& state);
/// Last applied seq of `source` in a state message (0 when the source is unknown).
std::int64_t applied_seq(const peritwin_msgs::damage_state_t& state, const std::string& source);
/// The history of a source's last applied batch (damage_state_t.history, .history_start).
struct SourceHistory {
  std::uint64_t fingerprint = 0;  ///< 0: none (a stream, or the source is unknown)
  std::int64_t start = 0;         ///< seq of that history's first batch
  bool operator==(const SourceHistory&) const = default;
};
/// What a state message says of `source` ({0, 0} when the source is unknown).
SourceHistory source_history(const peritwin_msgs::damage_state_t& state, const std::string& source);
/// Whether a state message answers a batch of the producer run with this nonce (its echo_source
/// is `source` and its echo_nonce `nonce`, not 0): it was published after that run's start.
bool answers(const peritwin_msgs::damage_state_t& state, const std::string& source,
             std::uint64_t nonce);

/// The JSON key of a percentile: "p05", "p50", "p95", "p97.5".
std::string percentile_key(double percentile);

/// One JSON object per state: detail, state_seq, cycles, broken_bonds, crack_length_m,
/// crack_count, max_damage, k_i, remaining_cycles, remaining_low, remaining_high,
/// remaining_life_seq, failure, end_of_life_cycle, state_hash, engine_hash. Non-finite numbers are
/// written as null.
std::string state_json(const peritwin_msgs::damage_state_t& state);
/// An object of numbers a tool appends to its summary line: "name": {"key": value, ...} in the
/// given order (e.g. the replay's "skipped_cycles" for a series).
struct SummaryObject {
  std::string name;
  std::vector<std::pair<std::string, double>> numbers;
};
/// The final summary: {"detail","cycles","broken_bonds","crack_length_m","remaining_cycles",
/// "end_of_life_cycle","state_hash","engine_hash"}, then the `extra` objects in order.
std::string summary_json(const peritwin_msgs::damage_state_t& state,
                         const std::vector<SummaryObject>& extra = {});

}  // namespace peritwin::messages
