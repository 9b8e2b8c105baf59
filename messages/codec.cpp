#include "messages/codec.h"

#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "messages/mesh.h"

namespace peritwin::messages {

namespace {

std::uint64_t read_be(const unsigned char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

Outcome decode_error(std::string why) { return {Verdict::decode, "message", std::move(why)}; }

/// Walks the load_batch_t layout without allocating; empty when the generated decoder can be
/// given the bytes safely and will consume exactly all of them. `signed_size` is set to the
/// number of leading bytes the auth tag covers (everything before tag_length).
std::string check_layout(const unsigned char* p, std::size_t size, std::size_t& signed_size) {
  std::size_t pos = 0;
  auto need = [&](std::size_t n, const char* what) -> std::string {
    if (size - pos < n) {
      return std::string("truncated payload: ") + std::to_string(size) + " bytes end inside " +
             what;
    }
    return {};
  };
  if (auto e = need(8, "the fingerprint"); !e.empty()) return e;
  if (static_cast<std::int64_t>(read_be(p, 8)) != peritwin_msgs::load_batch_t::getHash()) {
    return "wrong fingerprint: not a peritwin_msgs.load_batch_t of this version";
  }
  pos = 8;
  if (auto e = need(8, "utime"); !e.empty()) return e;
  pos += 8;
  for (const char* field : {"detail_id", "source_id"}) {
    if (auto e = need(4, field); !e.empty()) return e;
    const auto len = static_cast<std::int32_t>(read_be(p + pos, 4));
    pos += 4;
    if (len < 1) return std::string("malformed ") + field + " length " + std::to_string(len);
    if (auto e = need(static_cast<std::size_t>(len), field); !e.empty()) return e;
    if (p[pos + static_cast<std::size_t>(len) - 1] != 0) {
      return std::string(field) + " is not NUL-terminated";
    }
    if (std::memchr(p + pos, 0, static_cast<std::size_t>(len) - 1) != nullptr) {
      return std::string(field) + " contains a NUL byte";
    }
    pos += static_cast<std::size_t>(len);
  }
  if (auto e = need(4 * 8 + 4, "seq, nonce, history, history_start and num_blocks"); !e.empty()) {
    return e;
  }
  pos += 4 * 8;
  const auto blocks = static_cast<std::int32_t>(read_be(p + pos, 4));
  pos += 4;
  if (blocks < 0) return "malformed num_blocks " + std::to_string(blocks);
  std::size_t expected = pos + 32 * static_cast<std::size_t>(blocks) + 4;
  if (size < expected) {
    return "truncated payload: " + std::to_string(size) +
           " bytes, num_blocks = " + std::to_string(blocks) + " needs " + std::to_string(expected) +
           " with the tag length";
  }
  signed_size = expected - 4;
  const auto tag_length = static_cast<std::int32_t>(read_be(p + signed_size, 4));
  if (tag_length != 0 && tag_length != static_cast<std::int32_t>(kAuthTagBytes)) {
    return "malformed tag_length " + std::to_string(tag_length) + " (0 or " +
           std::to_string(kAuthTagBytes) + ")";
  }
  expected += static_cast<std::size_t>(tag_length);
  if (size < expected) {
    return "truncated payload: " + std::to_string(size) + " bytes end inside auth_tag";
  }
  if (size > expected) {
    return "oversized payload: " + std::to_string(size - expected) +
           " bytes after the message's end";
  }
  return {};
}

/// Walks an encoded message field by field; every count and length is checked against the bytes
/// left before anything is skipped.
class LayoutWalker {
 public:
  LayoutWalker(const unsigned char* p, std::size_t size) : p_(p), size_(size) {}
  bool fingerprint(std::int64_t hash) {
    if (!skip(8)) return false;
    return static_cast<std::int64_t>(read_be(p_, 8)) == hash;
  }
  bool skip(std::size_t n) {
    if (!ok_ || size_ - pos_ < n) return ok_ = false;
    pos_ += n;
    return true;
  }
  /// An int32 count of elements of at least `min_element_bytes` each that the rest can hold.
  bool count(std::size_t min_element_bytes, std::int32_t& n) {
    if (!ok_ || size_ - pos_ < 4) return ok_ = false;
    n = static_cast<std::int32_t>(read_be(p_ + pos_, 4));
    pos_ += 4;
    if (n < 0 || static_cast<std::size_t>(n) > (size_ - pos_) / min_element_bytes) {
      return ok_ = false;
    }
    return true;
  }
  /// A string: NUL-terminated, no NUL inside (LCM's encoder stops at the first NUL, so only
  /// such strings re-encode to the bytes they were decoded from).
  bool string() {
    std::int32_t len = 0;
    if (!count(1, len) || len < 1) return ok_ = false;
    const unsigned char* s = p_ + pos_;
    const auto n = static_cast<std::size_t>(len);
    if (s[n - 1] != 0 || std::memchr(s, 0, n - 1) != nullptr) return ok_ = false;
    return skip(n);
  }
  [[nodiscard]] bool at_end() const { return ok_ && pos_ == size_; }
  [[nodiscard]] std::size_t pos() const { return pos_; }

 private:
  const unsigned char* p_;
  std::size_t size_, pos_ = 0;
  bool ok_ = true;
};

/// Encoded bytes of one crack_tip_t: 5 doubles, int8.
constexpr std::size_t kCrackTipBytes = 5 * 8 + 1;
/// Fewest encoded bytes of one crack_t (empty origin, no tips, none absorbed): id, origin_kind,
/// origin, notch_index, 7 doubles, num_nodes, phase, birth_cycle, num_tips, num_absorbed.
constexpr std::size_t kMinCrackBytes = 4 + 1 + (4 + 1) + 4 + 7 * 8 + 4 + 1 + 8 + 4 + 4;

/// One crack_t inside a damage_state_t.
bool crack_layout(LayoutWalker& w) {
  std::int32_t tips = 0, absorbed = 0;
  return w.skip(4 + 1) && w.string() && w.skip(4 + 7 * 8 + 4 + 1 + 8) &&
         w.count(kCrackTipBytes, tips) && w.skip(kCrackTipBytes * static_cast<std::size_t>(tips)) &&
         w.count(4, absorbed) && w.skip(4 * static_cast<std::size_t>(absorbed));
}

bool state_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  std::int32_t sources = 0, cracks = 0, tag = 0;
  if (!w.fingerprint(peritwin_msgs::damage_state_t::getHash()) || !w.skip(8) || !w.string() ||
      !w.skip(8) || !w.count(4 + 1 + 4 * 8, sources)) {
    return false;
  }
  for (std::int32_t i = 0; i < sources; ++i) {
    if (!w.string()) return false;
  }
  // applied_seq, checkpointed_seq, history, history_start; total_cycles, broken_bonds,
  // max_damage, crack_count, crack_length_m, then the cracks.
  if (!w.skip(4 * 8 * static_cast<std::size_t>(sources)) || !w.skip(3 * 8 + 4 + 8) ||
      !w.count(kMinCrackBytes, cracks)) {
    return false;
  }
  for (std::int32_t i = 0; i < cracks; ++i) {
    if (!crack_layout(w)) return false;
  }
  // k_i, k_ii, the remaining life and its seq, its source, failure, end_of_life_cycle,
  // state_hash, engine_hash.
  if (!w.skip(2 * 8 + 3 * 8 + 8) || !w.string() || !w.skip(1 + 8) || !w.string() || !w.string()) {
    return false;
  }
  // The ensemble (version 9): num_particles, ensemble_estimate_cycle, effective_sample_size, the
  // percentiles (3 doubles each), horizon and its probability, the parameters, the observations,
  // the observation sources.
  std::int32_t n = 0;
  if (!w.skip(4 + 8 + 8) || !w.count(3 * 8, n) || !w.skip(3 * 8 * static_cast<std::size_t>(n)) ||
      !w.skip(2 * 8) || !w.count(4 + 1 + 2 * 8, n)) {
    return false;
  }
  for (std::int32_t i = 0; i < n; ++i) {
    if (!w.string()) return false;
  }
  if (!w.skip(2 * 8 * static_cast<std::size_t>(n)) || !w.skip(4) || !w.count(8 + 1 + 4 * 8, n) ||
      !w.skip((8 + 1 + 4 * 8) * static_cast<std::size_t>(n)) || !w.count(4 + 1 + 8, n)) {
    return false;
  }
  for (std::int32_t i = 0; i < n; ++i) {
    if (!w.string()) return false;
  }
  // observation_applied_seq; the gauges (version 10): ids, 4 doubles, residual, its sigma, the
  // alarm count, then gauge_alarm_sigmas and gauge_alarm_after.
  if (!w.skip(8 * static_cast<std::size_t>(n)) || !w.count(2 + 6 * 8 + 4, n)) return false;
  for (std::int32_t i = 0; i < n; ++i) {
    if (!w.string()) return false;
  }
  if (!w.skip((6 * 8 + 4) * static_cast<std::size_t>(n)) || !w.skip(8 + 4)) return false;
  // echo_source, echo_nonce, the tag.
  if (!w.string() || !w.skip(8) || !w.count(1, tag) || !w.skip(static_cast<std::size_t>(tag))) {
    return false;
  }
  return w.at_end();
}

bool reject_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  std::int32_t tag = 0;
  // utime, detail_id, source_id, seq, nonce, code, what, why, the tag.
  return w.fingerprint(peritwin_msgs::reject_t::getHash()) && w.skip(8) && w.string() &&
         w.string() && w.skip(8 + 8 + 1) && w.string() && w.string() && w.count(1, tag) &&
         w.skip(static_cast<std::size_t>(tag)) && w.at_end();
}

/// The end of a signed message from where the walker stands: tag_length (0 or kAuthTagBytes), the
/// tag, nothing after; `signed_size` = the bytes before tag_length. Empty when so, else why not.
std::string signed_tail(LayoutWalker& w, std::size_t& signed_size) {
  signed_size = w.pos();
  std::int32_t tag = 0;
  if (!w.count(1, tag) || !w.skip(static_cast<std::size_t>(tag))) {
    return "malformed or truncated tag_length / auth_tag";
  }
  if (tag != 0 && tag != static_cast<std::int32_t>(kAuthTagBytes)) {
    return "malformed tag_length " + std::to_string(tag) + " (0 or " +
           std::to_string(kAuthTagBytes) + ")";
  }
  if (!w.at_end()) return "oversized payload: bytes after the message's end";
  return {};
}

/// load_samples_t: the layout (every count against the bytes left), and the size the tag covers.
std::string samples_layout(const unsigned char* p, std::size_t size, std::size_t& signed_size) {
  LayoutWalker w(p, size);
  if (!w.fingerprint(peritwin_msgs::load_samples_t::getHash())) {
    return size < 8 ? "truncated payload: " + std::to_string(size) + " bytes"
                    : "wrong fingerprint: not a peritwin_msgs.load_samples_t of this version";
  }
  if (!w.skip(8) || !w.string() || !w.string()) {
    return "malformed or truncated utime, detail_id or source_id";
  }
  std::int32_t n = 0;
  if (!w.skip(3 * 8)) return "truncated payload: ends inside seq, t0 or sample_period";
  for (const char* array : {"p", "t", "alpha"}) {
    if (!w.count(8, n) || !w.skip(8 * static_cast<std::size_t>(n))) {
      return std::string("malformed or truncated ") + array + " (its count exceeds the payload)";
    }
  }
  return signed_tail(w, signed_size);
}

/// observation_t: the layout, and the size the tag covers; empty when it decodes safely.
std::string observation_layout(const unsigned char* p, std::size_t size, std::size_t& signed_size) {
  LayoutWalker w(p, size);
  if (!w.fingerprint(peritwin_msgs::observation_t::getHash())) {
    return size < 8 ? "truncated payload: " + std::to_string(size) + " bytes"
                    : "wrong fingerprint: not a peritwin_msgs.observation_t of this version";
  }
  // utime, detail_id, source_id, seq, nonce, cycle, kind, origin, 4 doubles.
  if (!w.skip(8) || !w.string() || !w.string() || !w.skip(3 * 8 + 1) || !w.string() ||
      !w.skip(4 * 8)) {
    return "malformed or truncated: a string length or the payload's end";
  }
  // The gauges (version 10): ids, then compliance, sigma and model per gauge, whether it
  // identifies, then the angle.
  std::int32_t gauges = 0;
  if (!w.count(2 + 3 * 8 + 1, gauges)) return "malformed or truncated num_gauges";
  for (std::int32_t i = 0; i < gauges; ++i) {
    if (!w.string()) return "malformed or truncated gauge_ids";
  }
  if (!w.skip((3 * 8 + 1) * static_cast<std::size_t>(gauges)) || !w.skip(8)) {
    return "truncated payload: ends inside the gauges' values";
  }
  return signed_tail(w, signed_size);
}

bool status_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  // utime, detail_id, health, last_seq, pending, lag_s, uptime_s, errors, duplicates, gaps,
  // busy_s, auth_rejects, reject_rate, host, pid, started_utime.
  return w.fingerprint(peritwin_msgs::status_t::getHash()) && w.skip(8) && w.string() &&
         w.string() && w.skip(8 + 4 + 8 + 8 + 3 * 8 + 8 + 8 + 8) && w.string() && w.skip(4 + 8) &&
         w.at_end();
}

bool field_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  std::int32_t nodes = 0;
  // utime, detail_id, state_seq, mesh_hash, chunk_index, num_chunks, total_nodes, first_node,
  // the damage.
  return w.fingerprint(peritwin_msgs::damage_field_t::getHash()) && w.skip(8) && w.string() &&
         w.skip(8) && w.string() && w.skip(4 * 4) && w.count(4, nodes) &&
         w.skip(4 * static_cast<std::size_t>(nodes)) && w.at_end();
}

/// Fewest encoded bytes of one mesh_polyline_t: kind, index, closed, num_points.
constexpr std::size_t kMinPolylineBytes = 1 + 4 + 1 + 4;

bool mesh_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  std::int32_t nodes = 0, lines = 0;
  // utime, detail_id, mesh_hash, chunk_index, num_chunks, total_nodes, dx, horizon, the box,
  // first_node, x and y, the polylines.
  if (!w.fingerprint(peritwin_msgs::detail_mesh_t::getHash()) || !w.skip(8) || !w.string() ||
      !w.string() || !w.skip(3 * 4 + 6 * 8 + 4) || !w.count(2 * 8, nodes) ||
      !w.skip(2 * 8 * static_cast<std::size_t>(nodes)) || !w.count(kMinPolylineBytes, lines)) {
    return false;
  }
  for (std::int32_t i = 0; i < lines; ++i) {
    std::int32_t points = 0;
    if (!w.skip(1 + 4 + 1) || !w.count(2 * 8, points) ||
        !w.skip(2 * 8 * static_cast<std::size_t>(points))) {
      return false;
    }
  }
  return w.at_end();
}

bool mesh_request_layout(const unsigned char* p, std::size_t size) {
  LayoutWalker w(p, size);
  return w.fingerprint(peritwin_msgs::mesh_request_t::getHash()) && w.skip(8) && w.string() &&
         w.string() && w.at_end();
}

/// A signed message's payload against its size bound and its layout (`layout` returns why not, and
/// the bytes the tag covers): the DECODE outcome, or nothing when the decoder can be given it.
std::optional<Outcome> payload_error(const void* data, std::size_t size, std::size_t max_size,
                                     std::string (*layout)(const unsigned char*, std::size_t,
                                                           std::size_t&),
                                     std::size_t& signed_size) {
  if (size > max_size) {
    return decode_error("oversized payload: " + std::to_string(size) + " bytes > " +
                        std::to_string(max_size));
  }
  if (std::string e = layout(static_cast<const unsigned char*>(data), size, signed_size);
      !e.empty()) {
    return decode_error(std::move(e));
  }
  return std::nullopt;
}

template <typename Message>
std::optional<Message> decode_checked(const void* data, std::size_t size,
                                      bool (*layout)(const unsigned char*, std::size_t)) {
  if (size > static_cast<std::size_t>(std::numeric_limits<int>::max()) ||
      !layout(static_cast<const unsigned char*>(data), size)) {
    return std::nullopt;
  }
  Message m{};
  if (m.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) return std::nullopt;
  return m;
}

}  // namespace

std::optional<peritwin_msgs::damage_state_t> decode_state(const void* data, std::size_t size) {
  return decode_checked<peritwin_msgs::damage_state_t>(data, size, state_layout);
}

std::optional<peritwin_msgs::reject_t> decode_reject(const void* data, std::size_t size) {
  return decode_checked<peritwin_msgs::reject_t>(data, size, reject_layout);
}

std::optional<peritwin_msgs::status_t> decode_status(const void* data, std::size_t size) {
  return decode_checked<peritwin_msgs::status_t>(data, size, status_layout);
}

std::optional<peritwin_msgs::damage_field_t> decode_field(const void* data, std::size_t size) {
  return decode_checked<peritwin_msgs::damage_field_t>(data, size, field_layout);
}

std::optional<peritwin_msgs::detail_mesh_t> decode_mesh(const void* data, std::size_t size) {
  return decode_checked<peritwin_msgs::detail_mesh_t>(data, size, mesh_layout);
}

std::optional<peritwin_msgs::mesh_request_t> decode_mesh_request(const void* data,
                                                                 std::size_t size) {
  auto request = decode_checked<peritwin_msgs::mesh_request_t>(data, size, mesh_request_layout);
  if (!request || !is_valid_detail_id(request->detail_id) ||
      request->requester.size() > kMaxRequesterLength) {
    return std::nullopt;
  }
  return request;
}

int handle_lcm(lcm::LCM& lcm, int timeout_ms) {
  const int fd = lcm.getFileno();
  if (fd < 0) {  // tcpq without a hub (see messages/transport.h): nothing to wait on
    std::this_thread::sleep_for(std::chrono::milliseconds(std::max(0, timeout_ms)));
    return 0;
  }
  int type = 0;
  socklen_t len = sizeof type;
  if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &len) == 0 && type == SOCK_STREAM) {
    const int on = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    setsockopt(fd, IPPROTO_TCP, TCP_QUICKACK, &on, sizeof on);
  }
  // lcm.handleTimeout() as LCM 1.3.1 does it, with poll() instead of select(): FD_SET of a
  // descriptor >= FD_SETSIZE aborts as a negative one does.
  pollfd p{fd, POLLIN, 0};
  const int ready = poll(&p, 1, std::max(0, timeout_ms));
  if (ready <= 0) return ready;  // 0: timeout; -1: errno (EINTR: a signal)
  if (lcm.handle() == 0) return 1;
  // The hub closed the connection (the provider's socket is -1 now): not this call's failure.
  return lcm.getFileno() < 0 ? 0 : -1;
}

std::int64_t now_utime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

DecodedObservation decode_observation(const void* data, std::size_t size) {
  DecodedObservation out;
  std::size_t signed_size = 0;
  if (auto e = payload_error(data, size, kMaxObservationPayload, observation_layout, signed_size)) {
    out.error = std::move(*e);
    return out;
  }
  peritwin_msgs::observation_t m{};
  if (m.decode(data, 0, static_cast<int>(size)) != static_cast<int>(size)) {
    out.error = decode_error("not decodable as peritwin_msgs.observation_t");
    return out;
  }
  if (m.kind != peritwin_msgs::observation_t::KIND_CRACK_LENGTH &&
      m.kind != peritwin_msgs::observation_t::KIND_NO_CRACK &&
      m.kind != peritwin_msgs::observation_t::KIND_GAUGE_COMPLIANCE) {
    out.error = {Verdict::invalid, "observation.kind",
                 "kind = " + std::to_string(m.kind) + " is none of KIND_CRACK_LENGTH (1), " +
                     "KIND_NO_CRACK (2), KIND_GAUGE_COMPLIANCE (3)"};
    out.source_id = m.source_id;
    out.seq = m.seq;
    out.nonce = static_cast<std::uint64_t>(m.nonce);
    return out;
  }
  // gauge_identifies is a flag: a byte other than 0 or 1 would not encode back to itself.
  for (const std::int8_t flag : m.gauge_identifies) {
    if (flag != 0 && flag != 1) {
      out.error = decode_error("gauge_identifies holds " + std::to_string(flag) + " (0 or 1)");
      return out;
    }
  }
  Observation o;
  o.detail_id = m.detail_id;
  o.source_id = m.source_id;
  o.seq = m.seq;
  o.nonce = static_cast<std::uint64_t>(m.nonce);
  o.cycle = m.cycle;
  o.kind = m.kind == peritwin_msgs::observation_t::KIND_NO_CRACK ? ObservationKind::no_crack
           : m.kind == peritwin_msgs::observation_t::KIND_GAUGE_COMPLIANCE
               ? ObservationKind::gauge_compliance
               : ObservationKind::crack_length;
  o.origin = m.origin;
  o.length_m = m.length_m;
  o.sigma_m = m.sigma_m;
  o.pod_a50_m = m.pod_a50_m;
  o.pod_slope = m.pod_slope;
  for (std::size_t g = 0; g < m.gauge_ids.size(); ++g) {
    o.gauges.push_back({m.gauge_ids[g], m.gauge_compliance[g], m.gauge_sigma[g], m.gauge_model[g],
                        m.gauge_identifies[g] != 0});
  }
  o.gauge_angle_rad = m.gauge_angle_rad;
  out.source_id = o.source_id;
  out.seq = o.seq;
  out.nonce = o.nonce;
  out.observation = std::move(o);
  out.signed_size = signed_size;
  out.auth_tag = std::move(m.auth_tag);
  return out;
}

peritwin_msgs::observation_t observation_message(const Observation& o, std::int64_t utime) {
  peritwin_msgs::observation_t m{};
  m.utime = utime;
  m.detail_id = o.detail_id;
  m.source_id = o.source_id;
  m.seq = o.seq;
  m.nonce = static_cast<std::int64_t>(o.nonce);
  m.cycle = o.cycle;
  m.kind = o.kind == ObservationKind::no_crack ? peritwin_msgs::observation_t::KIND_NO_CRACK
           : o.kind == ObservationKind::gauge_compliance
               ? peritwin_msgs::observation_t::KIND_GAUGE_COMPLIANCE
               : peritwin_msgs::observation_t::KIND_CRACK_LENGTH;
  m.origin = o.origin;
  m.length_m = o.length_m;
  m.sigma_m = o.sigma_m;
  m.pod_a50_m = o.pod_a50_m;
  m.pod_slope = o.pod_slope;
  for (const GaugeCompliance& g : o.gauges) {
    m.gauge_ids.push_back(g.id);
    m.gauge_compliance.push_back(g.compliance);
    m.gauge_sigma.push_back(g.sigma);
    m.gauge_model.push_back(g.model);
    m.gauge_identifies.push_back(g.identifies ? 1 : 0);
  }
  m.num_gauges = static_cast<std::int32_t>(m.gauge_ids.size());
  m.gauge_angle_rad = o.gauge_angle_rad;
  m.tag_length = 0;
  return m;
}

Decoded decode_batch(const void* data, std::size_t size) {
  Decoded out;
  std::size_t signed_size = 0;
  if (auto e = payload_error(data, size, kMaxBatchPayload, check_layout, signed_size)) {
    out.error = std::move(*e);
    return out;
  }
  peritwin_msgs::load_batch_t msg{};
  const int used = msg.decode(data, 0, static_cast<int>(size));
  if (used < 0 || static_cast<std::size_t>(used) != size) {
    out.error = decode_error("not decodable as peritwin_msgs.load_batch_t");
    return out;
  }
  Batch b;
  b.detail_id = msg.detail_id;
  b.source_id = msg.source_id;
  b.seq = msg.seq;
  b.nonce = static_cast<std::uint64_t>(msg.nonce);
  b.history = static_cast<std::uint64_t>(msg.history);
  b.history_start = msg.history_start;
  b.blocks.reserve(msg.blocks.size());
  for (const auto& k : msg.blocks) b.blocks.push_back({k.p_max, k.r, k.alpha, k.count});
  out.auth_tag = std::move(msg.auth_tag);
  out.batch = std::move(b);
  out.signed_size = signed_size;
  return out;
}

Outcome check_samples(const Samples& s, std::string_view detail_id) {
  const auto invalid = [](std::string what, std::string why) {
    return Outcome{Verdict::invalid, std::move(what), std::move(why)};
  };
  // detail_id, source_id and seq by the batches' rules.
  const Outcome ids = check_batch(
      {s.detail_id, s.source_id, s.seq, {core::LoadBlock{1.0, 0.0, 0.0, 1}}}, detail_id);
  if (!ids.applied()) return ids;
  const auto n = s.p.size();
  if (n < 1 || n > static_cast<std::size_t>(kMaxSamplesPerMessage)) {
    return invalid("num_samples", "num_samples = " + std::to_string(n) + " must be 1 to " +
                                      std::to_string(kMaxSamplesPerMessage));
  }
  if (!std::isfinite(s.t0)) return invalid("t0", "t0 must be finite");
  if (!s.t.empty() && s.t.size() != n) {
    return invalid("num_t", "num_t = " + std::to_string(s.t.size()) +
                                " must be 0 or num_samples (" + std::to_string(n) + ")");
  }
  if (!s.alpha.empty() && s.alpha.size() != n) {
    return invalid("num_alpha", "num_alpha = " + std::to_string(s.alpha.size()) +
                                    " must be 0 or num_samples (" + std::to_string(n) + ")");
  }
  if (s.t.empty() ? !(std::isfinite(s.sample_period) && s.sample_period > 0.0)
                  : s.sample_period != 0.0) {
    return invalid("sample_period", s.t.empty() ? "sample_period must be finite and > 0 without t"
                                                : "sample_period must be 0 when t gives the times");
  }
  for (std::size_t i = 0; i < s.t.size(); ++i) {
    if (!std::isfinite(s.t[i]) || (i > 0 && !(s.t[i] > s.t[i - 1]))) {
      return invalid("t[" + std::to_string(i) + "]",
                     "sample times must be finite and strictly increasing");
    }
  }
  for (std::size_t i = 0; i < s.alpha.size(); ++i) {
    if (!std::isfinite(s.alpha[i])) {
      return invalid("alpha[" + std::to_string(i) + "]", "alpha must be finite");
    }
  }
  return {};
}

DecodedSamples decode_samples(const void* data, std::size_t size) {
  DecodedSamples out;
  if (size > kMaxSamplesPayload) {
    out.error = decode_error("oversized payload: " + std::to_string(size) + " bytes > " +
                             std::to_string(kMaxSamplesPayload));
    return out;
  }
  std::size_t signed_size = 0;
  if (const std::string e =
          samples_layout(static_cast<const unsigned char*>(data), size, signed_size);
      !e.empty()) {
    out.error = decode_error(e);
    return out;
  }
  peritwin_msgs::load_samples_t msg{};
  const int used = msg.decode(data, 0, static_cast<int>(size));
  if (used < 0 || static_cast<std::size_t>(used) != size) {
    out.error = decode_error("not decodable as peritwin_msgs.load_samples_t");
    return out;
  }
  Samples s;
  s.detail_id = msg.detail_id;
  s.source_id = msg.source_id;
  s.seq = msg.seq;
  s.t0 = msg.t0;
  s.sample_period = msg.sample_period;
  s.p = std::move(msg.p);
  s.t = std::move(msg.t);
  s.alpha = std::move(msg.alpha);
  out.samples = std::move(s);
  out.auth_tag = std::move(msg.auth_tag);
  out.signed_size = signed_size;
  return out;
}

peritwin_msgs::load_samples_t samples_message(const Samples& s, std::int64_t utime) {
  peritwin_msgs::load_samples_t m{};
  m.utime = utime;
  m.detail_id = s.detail_id;
  m.source_id = s.source_id;
  m.seq = s.seq;
  m.t0 = s.t0;
  m.sample_period = s.sample_period;
  m.p = s.p;
  m.num_samples = static_cast<std::int32_t>(m.p.size());
  m.t = s.t;
  m.num_t = static_cast<std::int32_t>(m.t.size());
  m.alpha = s.alpha;
  m.num_alpha = static_cast<std::int32_t>(m.alpha.size());
  return m;
}

peritwin_msgs::load_batch_t batch_message(const Batch& batch, std::int64_t utime) {
  peritwin_msgs::load_batch_t m{};
  m.utime = utime;
  m.detail_id = batch.detail_id;
  m.source_id = batch.source_id;
  m.seq = batch.seq;
  m.nonce = static_cast<std::int64_t>(batch.nonce);
  m.history = static_cast<std::int64_t>(batch.history);
  m.history_start = batch.history_start;
  for (const auto& b : batch.blocks) {
    peritwin_msgs::load_block_t k;
    k.p_max = b.p_max;
    k.r = b.r;
    k.alpha = b.alpha;
    k.count = b.count;
    m.blocks.push_back(k);
  }
  m.num_blocks = static_cast<std::int32_t>(m.blocks.size());
  return m;
}

peritwin_msgs::reject_t reject_message(const std::string& detail_id, const std::string& source,
                                       std::int64_t seq, const Outcome& outcome, std::int64_t utime,
                                       std::uint64_t nonce) {
  peritwin_msgs::reject_t m{};
  m.utime = utime;
  m.detail_id = detail_id;
  m.source_id = source;
  m.seq = seq;
  m.nonce = static_cast<std::int64_t>(nonce);
  m.code = static_cast<std::int8_t>(outcome.verdict);
  m.what = outcome.what;
  m.why = outcome.why;
  return m;
}

double crack_length(const peritwin_msgs::damage_state_t& state) { return state.crack_length_m; }

std::int64_t applied_seq(const peritwin_msgs::damage_state_t& state, const std::string& source) {
  for (std::size_t i = 0; i < state.source_ids.size() && i < state.applied_seq.size(); ++i) {
    if (state.source_ids[i] == source) return state.applied_seq[i];
  }
  return 0;
}

SourceHistory source_history(const peritwin_msgs::damage_state_t& state,
                             const std::string& source) {
  for (std::size_t i = 0;
       i < state.source_ids.size() && i < state.history.size() && i < state.history_start.size();
       ++i) {
    if (state.source_ids[i] == source) {
      return {static_cast<std::uint64_t>(state.history[i]), state.history_start[i]};
    }
  }
  return {};
}

bool answers(const peritwin_msgs::damage_state_t& state, const std::string& source,
             std::uint64_t nonce) {
  return nonce != 0 && state.echo_source == source &&
         static_cast<std::uint64_t>(state.echo_nonce) == nonce;
}

/// "p05", "p50", "p95", "p97.5".
std::string percentile_key(double q) {
  char buf[32];
  // Whole percentiles of [0, 100] as two digits at least; anything else (a forged STATE's too) as
  // %g, never cast.
  if (q >= 0.0 && q <= 100.0 && q == std::floor(q)) {
    std::snprintf(buf, sizeof buf, "p%02d", static_cast<int>(q));
  } else {
    std::snprintf(buf, sizeof buf, "p%g", q);
  }
  return buf;
}

namespace {

/// A learning twin's keys (message set version 9), as peritwin-replay --observations prints them:
/// end_of_life_percentiles and remaining_percentiles (whole cycles, null beyond the horizon or
/// before an estimate), probability_within_horizon, horizon_cycles, posterior, and the count of
/// observations taken in. Nothing without an ensemble.
void add_ensemble(nlohmann::ordered_json& j, const peritwin_msgs::damage_state_t& s) {
  if (s.num_particles <= 0) return;
  const auto cycles = [](double v) -> nlohmann::ordered_json {
    if (!std::isfinite(v) || std::abs(v) >= 0x1p53) return nullptr;
    return static_cast<std::int64_t>(std::llround(v));
  };
  nlohmann::ordered_json eol = nlohmann::ordered_json::object();
  nlohmann::ordered_json rem = nlohmann::ordered_json::object();
  const std::size_t n = std::min(
      {s.percentiles.size(), s.end_of_life_percentiles.size(), s.remaining_percentiles.size()});
  for (std::size_t k = 0; k < n; ++k) {
    eol[percentile_key(s.percentiles[k])] = cycles(s.end_of_life_percentiles[k]);
    rem[percentile_key(s.percentiles[k])] = cycles(s.remaining_percentiles[k]);
  }
  j["end_of_life_percentiles"] = eol;
  j["remaining_percentiles"] = rem;
  j["probability_within_horizon"] = s.probability_within_horizon;
  j["horizon_cycles"] = s.horizon_cycles;
  nlohmann::ordered_json posterior = nlohmann::ordered_json::object();
  const std::size_t m =
      std::min({s.parameter_names.size(), s.parameter_medians.size(), s.parameter_covs.size()});
  for (std::size_t k = 0; k < m; ++k) {
    posterior[s.parameter_names[k]] = {{"median", s.parameter_medians[k]},
                                       {"cov", s.parameter_covs[k]}};
  }
  j["posterior"] = posterior;
  j["observations"] = s.observation_count;
}

/// The strain gauges (message set version 10): per gauge id its influence coefficients (strain
/// per N: constant, cos α, sin α) and the last compliance residual with its sigma and the
/// observations in a row beyond the alarm bound (null before one). Nothing without gauges.
void add_gauges(nlohmann::ordered_json& j, const peritwin_msgs::damage_state_t& s) {
  const std::size_t n =
      std::min({s.gauge_ids.size(), s.gauge_per_constant.size(), s.gauge_per_cos.size(),
                s.gauge_per_sin.size(), s.gauge_residuals.size(), s.gauge_residual_sigmas.size(),
                s.gauge_alarm_counts.size()});
  if (n == 0) return;
  const auto number = [](double v) -> nlohmann::ordered_json {
    if (!std::isfinite(v)) return nullptr;
    return v;
  };
  nlohmann::ordered_json gauges = nlohmann::ordered_json::object();
  for (std::size_t k = 0; k < n; ++k) {
    gauges[s.gauge_ids[k]] = {
        {"per_n",
         {number(s.gauge_per_constant[k]), number(s.gauge_per_cos[k]), number(s.gauge_per_sin[k])}},
        {"residual", number(s.gauge_residuals[k])},
        {"residual_sigma", number(s.gauge_residual_sigmas[k])},
        {"in_a_row", s.gauge_alarm_counts[k]}};
  }
  j["gauges"] = gauges;
}

}  // namespace

std::string state_json(const peritwin_msgs::damage_state_t& s) {
  nlohmann::ordered_json j;
  j["detail"] = s.detail_id;
  j["state_seq"] = s.state_seq;
  j["cycles"] = s.total_cycles;
  j["broken_bonds"] = s.broken_bonds;
  j["crack_length_m"] = crack_length(s);
  j["crack_count"] = s.crack_count;
  j["max_damage"] = s.max_damage;
  j["k_i"] = s.k_i;
  j["remaining_cycles"] = s.remaining_cycles;
  j["remaining_low"] = s.remaining_cycles_low;
  j["remaining_high"] = s.remaining_cycles_high;
  j["remaining_life_seq"] = s.remaining_life_seq;
  j["failure"] = static_cast<int>(s.failure);
  j["end_of_life_cycle"] = s.end_of_life_cycle;
  j["state_hash"] = s.state_hash;
  j["engine_hash"] = s.engine_hash;
  add_ensemble(j, s);
  add_gauges(j, s);
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string summary_json(const peritwin_msgs::damage_state_t& s,
                         const std::vector<SummaryObject>& extra) {
  nlohmann::ordered_json j;
  j["detail"] = s.detail_id;
  j["cycles"] = s.total_cycles;
  j["broken_bonds"] = s.broken_bonds;
  j["crack_length_m"] = crack_length(s);
  j["remaining_cycles"] = s.remaining_cycles;
  j["end_of_life_cycle"] = s.end_of_life_cycle;
  j["state_hash"] = s.state_hash;
  j["engine_hash"] = s.engine_hash;
  add_ensemble(j, s);
  add_gauges(j, s);
  for (const SummaryObject& object : extra) {
    nlohmann::ordered_json o = nlohmann::ordered_json::object();
    for (const auto& [key, value] : object.numbers) {
      // Whole numbers as integers ("3", not "3.0"); halves and the rest as doubles.
      if (std::abs(value) < 0x1p53 && value == std::floor(value)) {
        o[key] = static_cast<std::int64_t>(value);
      } else {
        o[key] = value;
      }
    }
    j[object.name] = std::move(o);
  }
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace peritwin::messages
