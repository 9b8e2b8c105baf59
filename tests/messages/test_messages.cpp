// Tests of the generated LCM types (peritwin_msgs) and of the channel naming rule.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <peritwin_msgs/crack_t.hpp>
#include <peritwin_msgs/damage_field_t.hpp>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/load_batch_t.hpp>
#include <peritwin_msgs/load_block_t.hpp>
#include <peritwin_msgs/load_samples_t.hpp>
#include <peritwin_msgs/reject_t.hpp>
#include <peritwin_msgs/status_t.hpp>
#include <regex>
#include <string>
#include <vector>

#include "messages/channels.h"

namespace peritwin {
namespace {

namespace msgs = ::peritwin_msgs;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int64_t kI64Max = std::numeric_limits<std::int64_t>::max();
constexpr std::int64_t kI64Min = std::numeric_limits<std::int64_t>::min();

// LCM_SHORT_MESSAGE_MAX_SIZE of LCM's UDP multicast transport on Linux: channel name, its NUL and
// the payload of a message sent as one datagram (no LCM fragmentation) fit in this many bytes.
constexpr std::size_t kLcmShortMessageMax = 65499;

// ---- encode / decode helpers ---------------------------------------------------------------

template <class T>
std::vector<std::uint8_t> encode(const T& msg) {
  const int size = msg.getEncodedSize();
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(size));
  EXPECT_EQ(msg.encode(buf.data(), 0, size), size);
  return buf;
}

template <class T>
T decode(const std::vector<std::uint8_t>& buf) {
  T msg;
  EXPECT_EQ(msg.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return msg;
}

// Decodes the first `len` bytes of `buf` from a heap block of exactly that size (so that a
// sanitizer would catch a read past the end) and returns decode()'s result.
template <class T>
int decode_prefix(const std::vector<std::uint8_t>& buf, std::size_t len) {
  auto block = std::make_unique<std::uint8_t[]>(len == 0 ? 1 : len);
  std::memcpy(block.get(), buf.data(), len);
  T msg;
  return msg.decode(block.get(), 0, static_cast<int>(len));
}

// Number-for-number equality: doubles and floats compare bit for bit (NaN, -0.0, Inf included).
void expect_same(double a, double b, const char* what) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a), std::bit_cast<std::uint64_t>(b)) << what;
}
void expect_same(float a, float b, const char* what) {
  EXPECT_EQ(std::bit_cast<std::uint32_t>(a), std::bit_cast<std::uint32_t>(b)) << what;
}

#define EXPECT_SAME_FIELD(a, b, field) expect_same((a).field, (b).field, #field)

// ---- field-by-field comparisons --------------------------------------------------------------

void expect_equal(const msgs::load_block_t& a, const msgs::load_block_t& b) {
  EXPECT_SAME_FIELD(a, b, p_max);
  EXPECT_SAME_FIELD(a, b, r);
  EXPECT_SAME_FIELD(a, b, alpha);
  EXPECT_EQ(a.count, b.count);
}

void expect_equal(const msgs::load_batch_t& a, const msgs::load_batch_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.detail_id, b.detail_id);
  EXPECT_EQ(a.source_id, b.source_id);
  EXPECT_EQ(a.seq, b.seq);
  EXPECT_EQ(a.num_blocks, b.num_blocks);
  ASSERT_EQ(a.blocks.size(), b.blocks.size());
  for (std::size_t i = 0; i < a.blocks.size(); ++i) {
    SCOPED_TRACE("block " + std::to_string(i));
    expect_equal(a.blocks[i], b.blocks[i]);
  }
  EXPECT_EQ(a.tag_length, b.tag_length);
  EXPECT_EQ(a.auth_tag, b.auth_tag);
}

void expect_equal(const msgs::crack_t& a, const msgs::crack_t& b) {
  EXPECT_EQ(a.notch_index, b.notch_index);
  EXPECT_SAME_FIELD(a, b, origin_x);
  EXPECT_SAME_FIELD(a, b, origin_y);
  EXPECT_SAME_FIELD(a, b, tip_x);
  EXPECT_SAME_FIELD(a, b, tip_y);
  EXPECT_SAME_FIELD(a, b, length_m);
  EXPECT_SAME_FIELD(a, b, projected_length_m);
  EXPECT_SAME_FIELD(a, b, kink_angle_rad);
  EXPECT_EQ(a.num_nodes, b.num_nodes);
  EXPECT_EQ(a.phase, b.phase);
  EXPECT_EQ(a.id, b.id);
  EXPECT_EQ(a.origin_kind, b.origin_kind);
  EXPECT_EQ(a.origin, b.origin);
  EXPECT_EQ(a.birth_cycle, b.birth_cycle);
  EXPECT_EQ(a.num_tips, b.num_tips);
  ASSERT_EQ(a.tips.size(), b.tips.size());
  for (std::size_t t = 0; t < a.tips.size(); ++t) {
    EXPECT_SAME_FIELD(a.tips[t], b.tips[t], x);
    EXPECT_SAME_FIELD(a.tips[t], b.tips[t], y);
    EXPECT_SAME_FIELD(a.tips[t], b.tips[t], angle_rad);
    EXPECT_SAME_FIELD(a.tips[t], b.tips[t], k_i);
    EXPECT_SAME_FIELD(a.tips[t], b.tips[t], k_ii);
    EXPECT_EQ(a.tips[t].k_status, b.tips[t].k_status);
  }
  EXPECT_EQ(a.num_absorbed, b.num_absorbed);
  EXPECT_EQ(a.absorbed_ids, b.absorbed_ids);
}

void expect_equal(const msgs::damage_state_t& a, const msgs::damage_state_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.detail_id, b.detail_id);
  EXPECT_EQ(a.state_seq, b.state_seq);
  EXPECT_EQ(a.num_sources, b.num_sources);
  EXPECT_EQ(a.source_ids, b.source_ids);
  EXPECT_EQ(a.applied_seq, b.applied_seq);
  EXPECT_EQ(a.checkpointed_seq, b.checkpointed_seq);
  EXPECT_EQ(a.history, b.history);
  EXPECT_EQ(a.history_start, b.history_start);
  EXPECT_EQ(a.total_cycles, b.total_cycles);
  EXPECT_EQ(a.broken_bonds, b.broken_bonds);
  EXPECT_SAME_FIELD(a, b, max_damage);
  EXPECT_EQ(a.crack_count, b.crack_count);
  EXPECT_SAME_FIELD(a, b, crack_length_m);
  EXPECT_EQ(a.num_cracks, b.num_cracks);
  ASSERT_EQ(a.cracks.size(), b.cracks.size());
  for (std::size_t i = 0; i < a.cracks.size(); ++i) {
    SCOPED_TRACE("crack " + std::to_string(i));
    expect_equal(a.cracks[i], b.cracks[i]);
  }
  EXPECT_SAME_FIELD(a, b, k_i);
  EXPECT_SAME_FIELD(a, b, k_ii);
  EXPECT_SAME_FIELD(a, b, remaining_cycles);
  EXPECT_SAME_FIELD(a, b, remaining_cycles_low);
  EXPECT_SAME_FIELD(a, b, remaining_cycles_high);
  EXPECT_EQ(a.remaining_life_seq, b.remaining_life_seq);
  EXPECT_EQ(a.remaining_life_source, b.remaining_life_source);
  EXPECT_EQ(a.failure, b.failure);
  EXPECT_EQ(a.state_hash, b.state_hash);
  EXPECT_EQ(a.tag_length, b.tag_length);
  EXPECT_EQ(a.auth_tag, b.auth_tag);
}

void expect_equal(const msgs::damage_field_t& a, const msgs::damage_field_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.detail_id, b.detail_id);
  EXPECT_EQ(a.state_seq, b.state_seq);
  EXPECT_EQ(a.mesh_hash, b.mesh_hash);
  EXPECT_EQ(a.chunk_index, b.chunk_index);
  EXPECT_EQ(a.num_chunks, b.num_chunks);
  EXPECT_EQ(a.total_nodes, b.total_nodes);
  EXPECT_EQ(a.first_node, b.first_node);
  EXPECT_EQ(a.num_nodes, b.num_nodes);
  ASSERT_EQ(a.damage.size(), b.damage.size());
  for (std::size_t i = 0; i < a.damage.size(); ++i) {
    expect_same(a.damage[i], b.damage[i], "damage");
  }
}

void expect_equal(const msgs::reject_t& a, const msgs::reject_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.detail_id, b.detail_id);
  EXPECT_EQ(a.source_id, b.source_id);
  EXPECT_EQ(a.seq, b.seq);
  EXPECT_EQ(a.code, b.code);
  EXPECT_EQ(a.what, b.what);
  EXPECT_EQ(a.why, b.why);
  EXPECT_EQ(a.tag_length, b.tag_length);
  EXPECT_EQ(a.auth_tag, b.auth_tag);
}

void expect_equal(const msgs::status_t& a, const msgs::status_t& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.detail_id, b.detail_id);
  EXPECT_EQ(a.health, b.health);
  EXPECT_EQ(a.last_seq, b.last_seq);
  EXPECT_EQ(a.pending, b.pending);
  EXPECT_SAME_FIELD(a, b, lag_s);
  EXPECT_SAME_FIELD(a, b, uptime_s);
  EXPECT_EQ(a.errors, b.errors);
  EXPECT_EQ(a.duplicates, b.duplicates);
  EXPECT_EQ(a.gaps, b.gaps);
  EXPECT_SAME_FIELD(a, b, busy_s);
  EXPECT_EQ(a.auth_rejects, b.auth_rejects);
  EXPECT_SAME_FIELD(a, b, reject_rate);
}

// ---- sample messages (awkward values on purpose) ---------------------------------------------

msgs::load_block_t make_block(int i) {
  msgs::load_block_t b;
  b.p_max = 1234.5678 + 0.1 * i;
  b.r = i % 2 == 0 ? 0.1 : -1.0;
  b.alpha = std::nextafter(0.7853981633974483, 1.0) * i;
  b.count = i == 2 ? kI64Max : 1000 * (i + 1);
  return b;
}

msgs::load_batch_t make_batch() {
  msgs::load_batch_t m{};
  m.utime = 1'700'000'000'123'456;
  m.detail_id = "b1-ct";
  m.source_id = "strain-gauge_3 \xc2\xb5";  // UTF-8 is carried as bytes
  m.seq = 42;
  for (int i = 0; i < 5; ++i) m.blocks.push_back(make_block(i));
  m.num_blocks = static_cast<std::int32_t>(m.blocks.size());
  for (int i = 0; i < 32; ++i) m.auth_tag.push_back(static_cast<std::uint8_t>(255 - 7 * i));
  m.tag_length = static_cast<std::int32_t>(m.auth_tag.size());
  return m;
}

msgs::crack_t make_crack(int i) {
  msgs::crack_t c{};
  c.id = 3 + i;
  c.origin_kind = i == 0 ? msgs::crack_t::ORIGIN_NOTCH : msgs::crack_t::ORIGIN_INTERIOR;
  c.origin = i == 0 ? "notch pre-crack" : "interior";
  c.notch_index = i == 0 ? 0 : -1;
  c.origin_x = 0.0125 * i;
  c.origin_y = -0.0;
  c.tip_x = 0.031415926535 + i;
  c.tip_y = -1e-300;
  c.length_m = 0.02 + 1e-17 * i;
  c.projected_length_m = 0.0199;
  c.kink_angle_rad = -1.2217304763960306;
  c.num_nodes = 123 + i;
  c.phase = i == 0 ? msgs::crack_t::PHASE_PROPAGATION : msgs::crack_t::PHASE_INITIATION;
  c.birth_cycle = kI64Max - i;
  for (int t = 0; t <= i; ++t) {  // one tip, or two (interior)
    msgs::crack_tip_t tip{};
    tip.x = 0.01 * t;
    tip.y = -0.0;
    tip.angle_rad = 3.14159 - t;
    tip.k_i = t == 0 ? 12.5e6 : std::numeric_limits<double>::quiet_NaN();
    tip.k_ii = -1e-310;
    tip.k_status = t == 0 ? msgs::crack_tip_t::K_OK : msgs::crack_tip_t::K_NEAR_SURFACE;
    c.tips.push_back(tip);
  }
  c.num_tips = static_cast<std::int32_t>(c.tips.size());
  c.absorbed_ids = std::vector<std::int32_t>(static_cast<std::size_t>(i), 7);
  c.num_absorbed = i;
  return c;
}

msgs::damage_state_t make_state() {
  msgs::damage_state_t m{};
  m.utime = -1;
  m.detail_id = "Weld_Toe-07";
  m.state_seq = 17;
  m.source_ids = {"", "live", "replay"};
  m.applied_seq = {0, kI64Max, 16};
  m.checkpointed_seq = {0, kI64Max - 1, 0};
  m.history = {0, -1, std::numeric_limits<std::int64_t>::min()};
  m.history_start = {0, 1, kI64Max};
  m.num_sources = static_cast<std::int32_t>(m.source_ids.size());
  m.total_cycles = 9'876'543'210;
  m.broken_bonds = 4321;
  m.max_damage = 0.5;
  m.crack_count = 11;
  m.crack_length_m = 0.02;
  m.cracks = {make_crack(0), make_crack(1)};
  m.num_cracks = static_cast<std::int32_t>(m.cracks.size());
  m.k_i = 1.7e7;
  m.k_ii = kNaN;
  m.remaining_cycles = kInf;
  m.remaining_cycles_low = std::numeric_limits<double>::denorm_min();
  m.remaining_cycles_high = -kInf;
  m.remaining_life_seq = 15;
  m.remaining_life_source = "replay";
  m.failure = msgs::damage_state_t::FAILURE_SINGULAR;
  m.state_hash = "0123456789abcdef0123456789abcdef";
  m.echo_source = "replay";
  m.echo_nonce = std::numeric_limits<std::int64_t>::min();
  m.auth_tag.assign(32, 0xA5);
  m.tag_length = 32;
  return m;
}

msgs::damage_field_t make_field(int num_nodes, std::string detail_id = "b1-ct") {
  msgs::damage_field_t m;
  m.utime = kI64Min;
  m.detail_id = std::move(detail_id);
  m.state_seq = 17;
  m.mesh_hash = "0123456789abcdef";
  m.chunk_index = 3;
  m.num_chunks = 9;
  m.total_nodes = 123'456;
  m.first_node = 45'000;
  m.damage.resize(static_cast<std::size_t>(num_nodes));
  for (std::size_t i = 0; i < m.damage.size(); ++i) {
    m.damage[i] = static_cast<float>(i % 1000) / 999.0f;
  }
  if (num_nodes > 2) {
    m.damage[1] = std::numeric_limits<float>::quiet_NaN();
    m.damage[2] = -0.0f;
  }
  m.num_nodes = num_nodes;
  return m;
}

msgs::reject_t make_reject() {
  msgs::reject_t m{};
  m.utime = 1;
  m.detail_id = "b1-ct";
  m.source_id = "replay";
  m.seq = 7;
  m.code = msgs::reject_t::CODE_INVALID;
  m.what = "blocks[3].r";
  m.why = "r = 1.2 must be < 1";
  m.auth_tag.assign(32, 0x5A);
  m.tag_length = 32;
  return m;
}

msgs::status_t make_status() {
  msgs::status_t m{};
  m.utime = 2;
  m.detail_id = "b1-ct";
  m.health = "degraded";
  m.last_seq = 17;
  m.pending = 3;
  m.lag_s = 0.25;
  m.uptime_s = 86400.000001;
  m.errors = 1;
  m.duplicates = 2;
  m.gaps = kI64Max;
  m.busy_s = 61.5;
  m.auth_rejects = 12;
  m.reject_rate = 0.1;
  return m;
}

// Round trip: encode -> decode gives equal fields, and re-encoding gives the same bytes.
template <class T>
void check_round_trip(const T& original) {
  const std::vector<std::uint8_t> bytes = encode(original);
  const T decoded = decode<T>(bytes);
  expect_equal(original, decoded);
  EXPECT_EQ(encode(decoded), bytes);
}

// Every strict prefix of an encoded message fails to decode.
template <class T>
void check_truncated_fails(const T& original) {
  const std::vector<std::uint8_t> bytes = encode(original);
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    ASSERT_LT(decode_prefix<T>(bytes, len), 0) << "prefix of " << len << " of " << bytes.size();
  }
  EXPECT_EQ(decode_prefix<T>(bytes, bytes.size()), static_cast<int>(bytes.size()));
}

// Any change of the leading 64-bit type fingerprint fails to decode.
template <class T>
void check_wrong_fingerprint_fails(const T& original) {
  const std::vector<std::uint8_t> bytes = encode(original);
  for (std::size_t i = 0; i < 8; ++i) {
    std::vector<std::uint8_t> bad = bytes;
    bad[i] ^= 0x01;
    T msg;
    EXPECT_LT(msg.decode(bad.data(), 0, static_cast<int>(bad.size())), 0) << "byte " << i;
  }
}

// ---- round trips -----------------------------------------------------------------------------

TEST(MessagesRoundTrip, LoadBlock) { check_round_trip(make_block(2)); }
TEST(MessagesRoundTrip, LoadBatch) { check_round_trip(make_batch()); }
TEST(MessagesRoundTrip, Crack) { check_round_trip(make_crack(1)); }
TEST(MessagesRoundTrip, DamageState) { check_round_trip(make_state()); }
TEST(MessagesRoundTrip, DamageField) { check_round_trip(make_field(1000)); }
TEST(MessagesRoundTrip, Reject) { check_round_trip(make_reject()); }
TEST(MessagesRoundTrip, Status) { check_round_trip(make_status()); }

TEST(MessagesRoundTrip, EmptyArraysAndStrings) {
  msgs::load_batch_t batch{};
  batch.utime = 0;
  batch.seq = 0;
  batch.num_blocks = 0;
  check_round_trip(batch);

  msgs::damage_state_t state{};
  state.num_sources = 0;
  state.num_cracks = 0;
  check_round_trip(state);

  check_round_trip(make_field(0));
}

TEST(MessagesRoundTrip, FieldOfFullChunk) {
  check_round_trip(make_field(msgs::damage_field_t::MAX_NODES_PER_CHUNK));
}

// ---- malformed input -------------------------------------------------------------------------

TEST(MessagesDecode, TruncatedBufferFails) {
  check_truncated_fails(make_block(1));
  check_truncated_fails(make_batch());
  check_truncated_fails(make_crack(0));
  check_truncated_fails(make_state());
  check_truncated_fails(make_field(7));
  check_truncated_fails(make_reject());
  check_truncated_fails(make_status());
}

TEST(MessagesDecode, TruncatedFullChunkFails) {
  const auto bytes = encode(make_field(msgs::damage_field_t::MAX_NODES_PER_CHUNK));
  for (const std::size_t len : {std::size_t{0}, std::size_t{8}, std::size_t{40}, bytes.size() / 2,
                                bytes.size() - 4, bytes.size() - 1}) {
    EXPECT_LT(decode_prefix<msgs::damage_field_t>(bytes, len), 0) << len;
  }
}

TEST(MessagesDecode, WrongFingerprintFails) {
  check_wrong_fingerprint_fails(make_block(1));
  check_wrong_fingerprint_fails(make_batch());
  check_wrong_fingerprint_fails(make_crack(0));
  check_wrong_fingerprint_fails(make_state());
  check_wrong_fingerprint_fails(make_field(7));
  check_wrong_fingerprint_fails(make_reject());
  check_wrong_fingerprint_fails(make_status());
}

TEST(MessagesDecode, OtherTypeFails) {
  // A message decoded as another type is rejected by the fingerprint, even when it would fit.
  const auto reject_bytes = encode(make_reject());
  msgs::status_t status{};
  EXPECT_LT(status.decode(reject_bytes.data(), 0, static_cast<int>(reject_bytes.size())), 0);
  const auto batch_bytes = encode(make_batch());
  msgs::reject_t reject{};
  EXPECT_LT(reject.decode(batch_bytes.data(), 0, static_cast<int>(batch_bytes.size())), 0);
}

TEST(MessagesDecode, FingerprintsAreDistinct) {
  const std::vector<std::int64_t> hashes = {
      msgs::load_block_t::getHash(),   msgs::load_batch_t::getHash(),
      msgs::crack_t::getHash(),        msgs::crack_tip_t::getHash(),
      msgs::damage_state_t::getHash(), msgs::damage_field_t::getHash(),
      msgs::reject_t::getHash(),       msgs::status_t::getHash(),
      msgs::load_samples_t::getHash()};
  for (std::size_t i = 0; i < hashes.size(); ++i) {
    for (std::size_t j = i + 1; j < hashes.size(); ++j) EXPECT_NE(hashes[i], hashes[j]);
  }
}

// ---- size limit of damage_field_t ------------------------------------------------------------

TEST(MessagesSize, FullFieldChunkStaysBelow64KB) {
  EXPECT_EQ(msgs::damage_field_t::MAX_NODES_PER_CHUNK, 15000);
  const std::string longest_id(messages::kMaxDetailIdLength, 'x');
  const auto field = make_field(msgs::damage_field_t::MAX_NODES_PER_CHUNK, longest_id);
  const auto size = static_cast<std::size_t>(field.getEncodedSize());
  EXPECT_EQ(encode(field).size(), size);
  EXPECT_EQ(size, 60'102u);  // messages/README.md
  EXPECT_LT(size, std::size_t{64} * 1024);
  // Sent by UDP multicast as one datagram, never as LCM fragments.
  EXPECT_LE(messages::channel(longest_id, messages::Kind::kField).size() + 1 + size,
            kLcmShortMessageMax);
}

// ---- channel names ---------------------------------------------------------------------------

TEST(Channels, NamesOfEveryKind) {
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kLoad), "PERITWIN_B1_CT_LOAD");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kState), "PERITWIN_B1_CT_STATE");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kField), "PERITWIN_B1_CT_FIELD");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kReject), "PERITWIN_B1_CT_REJECT");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kStatus), "PERITWIN_B1_CT_STATUS");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kSamples), "PERITWIN_B1_CT_SAMPLES");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kMesh), "PERITWIN_B1_CT_MESH");
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kMeshRequest),
            "PERITWIN_B1_CT_MESH_REQUEST");
}

TEST(Channels, DetailTokenIsUpperCaseWithUnderscores) {
  EXPECT_EQ(messages::detail_token("b1-ct"), "B1_CT");
  EXPECT_EQ(messages::detail_token("Weld_Toe-07a"), "WELD_TOE_07A");
  EXPECT_EQ(messages::detail_token("X"), "X");
  EXPECT_EQ(messages::detail_token("-_-"), "___");
  // Not injective: these share channels, so one deployment must not use both.
  EXPECT_EQ(messages::detail_token("b1-ct"), messages::detail_token("B1_CT"));
}

TEST(Channels, InvalidDetailIdsAreRejected) {
  using namespace std::string_view_literals;
  const std::string_view bad[] = {""sv,         "b1.ct"sv, "b1/ct"sv,
                                  "b1 ct"sv,    "b1*"sv,   "a$"sv,
                                  "\xc3\xa9"sv, "a\0b"sv,  "PERITWIN_.*_LOAD"sv,
                                  "b1\n"sv};
  for (const std::string_view id : bad) {
    EXPECT_FALSE(messages::is_valid_detail_id(id)) << id;
    EXPECT_THROW(messages::detail_token(id), std::invalid_argument) << id;
    EXPECT_THROW(messages::channel(id, messages::Kind::kLoad), std::invalid_argument) << id;
  }
  const std::string too_long(messages::kMaxDetailIdLength + 1, 'a');
  EXPECT_FALSE(messages::is_valid_detail_id(too_long));
  EXPECT_THROW(messages::channel(too_long, messages::Kind::kState), std::invalid_argument);
}

TEST(Channels, LongestDetailIdFitsLcmChannelLimit) {
  static_assert(messages::is_valid_detail_id("b1-ct"));
  static_assert(!messages::is_valid_detail_id("b1.ct"));
  const std::string longest(messages::kMaxDetailIdLength, 'z');
  ASSERT_TRUE(messages::is_valid_detail_id(longest));
  for (const messages::Kind kind : messages::kAllKinds) {
    EXPECT_LE(messages::channel(longest, kind).size(), messages::kMaxChannelLength);
  }
}

TEST(Channels, RegexMatchesEveryDetailOfOneKind) {
  for (const messages::Kind kind : messages::kAllKinds) {
    const std::regex re(messages::channel_regex(kind));
    for (const messages::Kind other : messages::kAllKinds) {
      EXPECT_EQ(std::regex_match(messages::channel("b1-ct", other), re), other == kind);
      EXPECT_EQ(std::regex_match(messages::channel("Weld_Toe-07", other), re), other == kind);
    }
    EXPECT_FALSE(std::regex_match("OTHER_B1_" + std::string(messages::suffix(kind)), re));
  }
}

TEST(Channels, ParseIsInverseUpToToken) {
  for (const messages::Kind kind : messages::kAllKinds) {
    const auto parts = messages::parse_channel(messages::channel("weld_toe-7", kind));
    ASSERT_TRUE(parts.has_value());
    EXPECT_EQ(parts->token, "WELD_TOE_7");
    EXPECT_EQ(parts->kind, kind);
  }
  const auto state = messages::parse_channel("PERITWIN_LOAD_STATE");
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->token, "LOAD");
  EXPECT_EQ(state->kind, messages::Kind::kState);
  for (const char* name :
       {"PERITWIN_LOAD", "PERITWIN__LOAD", "PERITWIN_b1_LOAD", "OTHER_B1_LOAD",
        "PERITWIN_B1_CT_FOO", "PERITWIN_B1.CT_LOAD", "PERITWIN_B1CT_XLOAD", ""}) {
    EXPECT_FALSE(messages::parse_channel(name).has_value()) << name;
  }
}

// ---- LCM publish / subscribe in one process (memq://) ----------------------------------------

class BatchCatcher {
 public:
  void on_batch(const lcm::ReceiveBuffer* /*rbuf*/, const std::string& chan,
                const msgs::load_batch_t* msg) {
    channels.push_back(chan);
    batches.push_back(*msg);
  }
  std::vector<std::string> channels;
  std::vector<msgs::load_batch_t> batches;
};

TEST(MessagesLcm, MemqPublishSubscribeRoundTrip) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());

  const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
  BatchCatcher exact;
  BatchCatcher every_detail;
  BatchCatcher other_detail;
  BatchCatcher other_kind;
  ASSERT_NE(lcm.subscribe(load, &BatchCatcher::on_batch, &exact), nullptr);
  ASSERT_NE(lcm.subscribe(messages::channel_regex(messages::Kind::kLoad), &BatchCatcher::on_batch,
                          &every_detail),
            nullptr);
  ASSERT_NE(lcm.subscribe(messages::channel("b1-ct2", messages::Kind::kLoad),
                          &BatchCatcher::on_batch, &other_detail),
            nullptr);
  ASSERT_NE(lcm.subscribe(messages::channel("b1-ct", messages::Kind::kState),
                          &BatchCatcher::on_batch, &other_kind),
            nullptr);

  const msgs::load_batch_t sent = make_batch();
  ASSERT_EQ(lcm.publish(load, &sent), 0);
  EXPECT_TRUE(exact.batches.empty()) << "memq delivers in handle(), not in publish()";

  ASSERT_GT(lcm.handleTimeout(1000), 0);
  ASSERT_EQ(exact.batches.size(), 1u);
  EXPECT_EQ(exact.channels.front(), load);
  expect_equal(sent, exact.batches.front());
  ASSERT_EQ(every_detail.batches.size(), 1u);
  expect_equal(sent, every_detail.batches.front());
  EXPECT_TRUE(other_detail.batches.empty());
  EXPECT_TRUE(other_kind.batches.empty());

  // Nothing else is queued.
  EXPECT_EQ(lcm.handleTimeout(10), 0);
}

}  // namespace
}  // namespace peritwin
