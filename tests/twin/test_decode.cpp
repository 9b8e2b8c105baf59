// Decoding load batches defensively: wrong fingerprint, truncation, oversize, malformed lengths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "twin/messages_io.h"

namespace peritwin::twin {
namespace {

std::vector<std::uint8_t> encode(const peritwin_msgs::load_batch_t& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

peritwin_msgs::load_batch_t sample(int blocks = 3) {
  messages::Batch b{"b1-ct", "replay", 7, {}};
  for (int i = 0; i < blocks; ++i) b.blocks.push_back({4000.0 + i, 0.1, 0.25, 10 + i});
  return messages::batch_message(b, 123);
}

TEST(DecodeBatch, RoundTrip) {
  const auto bytes = encode(sample());
  const messages::Decoded d = messages::decode_batch(bytes.data(), bytes.size());
  ASSERT_TRUE(d.batch.has_value()) << d.error.why;
  EXPECT_EQ(d.batch->detail_id, "b1-ct");
  EXPECT_EQ(d.batch->source_id, "replay");
  EXPECT_EQ(d.batch->seq, 7);
  ASSERT_EQ(d.batch->blocks.size(), 3u);
  EXPECT_EQ(d.batch->blocks[2].p_max, 4002.0);
  EXPECT_EQ(d.batch->blocks[2].count, 12);
}

TEST(DecodeBatch, EveryTruncationIsRejected) {
  const auto bytes = encode(sample());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const messages::Decoded d = messages::decode_batch(bytes.data(), n);
    EXPECT_FALSE(d.batch.has_value()) << n;
    EXPECT_EQ(d.error.verdict, messages::Verdict::decode);
    EXPECT_EQ(d.error.what, "message");
    EXPECT_FALSE(d.error.why.empty());
  }
}

TEST(DecodeBatch, WrongFingerprint) {
  auto bytes = encode(sample());
  bytes[3] ^= 0x40;
  const messages::Decoded d = messages::decode_batch(bytes.data(), bytes.size());
  EXPECT_FALSE(d.batch.has_value());
  EXPECT_NE(d.error.why.find("fingerprint"), std::string::npos) << d.error.why;
  // Another type's bytes.
  peritwin_msgs::reject_t r{};
  r.detail_id = "b1-ct";
  std::vector<std::uint8_t> other(static_cast<std::size_t>(r.getEncodedSize()));
  r.encode(other.data(), 0, static_cast<int>(other.size()));
  EXPECT_FALSE(messages::decode_batch(other.data(), other.size()).batch.has_value());
}

TEST(DecodeBatch, OversizedPayloads) {
  auto bytes = encode(sample());
  bytes.push_back(0);
  messages::Decoded d = messages::decode_batch(bytes.data(), bytes.size());
  EXPECT_FALSE(d.batch.has_value());
  EXPECT_NE(d.error.why.find("oversized"), std::string::npos) << d.error.why;
  std::vector<std::uint8_t> huge(messages::kMaxBatchPayload + 1, 0);
  d = messages::decode_batch(huge.data(), huge.size());
  EXPECT_FALSE(d.batch.has_value());
  EXPECT_NE(d.error.why.find("oversized"), std::string::npos) << d.error.why;
}

TEST(DecodeBatch, MalformedLengthsDoNotAllocate) {
  const auto good = encode(sample(1));
  // num_blocks sits right before the 32 bytes of the one block, which the 4 bytes of an empty
  // auth tag's tag_length follow.
  const std::size_t at = good.size() - 4 - 32 - 4;
  for (const std::uint32_t n : {0x7fffffffu, 0x80000000u, 2u}) {
    auto bytes = good;
    for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
    const messages::Decoded d = messages::decode_batch(bytes.data(), bytes.size());
    EXPECT_FALSE(d.batch.has_value()) << n;
  }
  // detail_id length (after fingerprint and utime): negative, zero, past the end.
  for (const std::uint32_t n : {0xffffffffu, 0u, 0x10000u}) {
    auto bytes = good;
    for (int i = 0; i < 4; ++i) bytes[16 + i] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
    EXPECT_FALSE(messages::decode_batch(bytes.data(), bytes.size()).batch.has_value()) << n;
  }
  // A string without its NUL.
  auto bytes = good;
  bytes[16 + 4 + 5] = 'x';  // "b1-ct" + NUL: the NUL is at offset 5
  EXPECT_FALSE(messages::decode_batch(bytes.data(), bytes.size()).batch.has_value());
}

TEST(DecodeBatch, AuthTagIsCarriedAndItsCoverageIsEverythingBeforeTagLength) {
  auto msg = sample(2);
  const auto unsigned_bytes = encode(msg);
  const messages::Decoded plain =
      messages::decode_batch(unsigned_bytes.data(), unsigned_bytes.size());
  ASSERT_TRUE(plain.batch.has_value()) << plain.error.why;
  EXPECT_TRUE(plain.auth_tag.empty());
  EXPECT_EQ(plain.signed_size, unsigned_bytes.size() - 4);

  msg.auth_tag.assign(messages::kAuthTagBytes, 0xC3);
  msg.tag_length = static_cast<std::int32_t>(messages::kAuthTagBytes);
  const auto signed_bytes = encode(msg);
  const messages::Decoded tagged = messages::decode_batch(signed_bytes.data(), signed_bytes.size());
  ASSERT_TRUE(tagged.batch.has_value()) << tagged.error.why;
  EXPECT_EQ(tagged.auth_tag, msg.auth_tag);
  // The covered bytes are the same whether the message carries a tag or not.
  EXPECT_EQ(tagged.signed_size, plain.signed_size);
  EXPECT_TRUE(std::equal(unsigned_bytes.begin(),
                         unsigned_bytes.begin() + static_cast<std::ptrdiff_t>(plain.signed_size),
                         signed_bytes.begin()));

  // A tag of any other length than 0 or 32 is refused before the generated decoder sees it.
  msg.auth_tag.assign(5, 0x01);
  msg.tag_length = 5;
  const auto odd = encode(msg);
  const messages::Decoded refused = messages::decode_batch(odd.data(), odd.size());
  EXPECT_FALSE(refused.batch.has_value());
  EXPECT_NE(refused.error.why.find("tag_length 5"), std::string::npos) << refused.error.why;
}

TEST(Json, NonFiniteIsNull) {
  peritwin_msgs::damage_state_t s{};
  s.detail_id = "d\"x";
  s.total_cycles = 0;
  s.broken_bonds = 0;
  s.remaining_cycles = std::numeric_limits<double>::infinity();
  s.end_of_life_cycle = -1;
  s.state_hash = "00ff";
  s.engine_hash = "11ee";
  const std::string j = messages::summary_json(s);
  EXPECT_EQ(j,
            "{\"detail\":\"d\\\"x\",\"cycles\":0,\"broken_bonds\":0,\"crack_length_m\":0.0,"
            "\"remaining_cycles\":null,\"end_of_life_cycle\":-1,\"state_hash\":\"00ff\","
            "\"engine_hash\":\"11ee\"}");
}

TEST(Json, StateJsonKeysInDocumentedOrderAndNaNIsNull) {
  // messages_io.h documents the keys of state_json in this order; NaN and ±∞ print as null.
  peritwin_msgs::damage_state_t s{};
  s.detail_id = "b1-ct";
  s.state_seq = 12;
  s.total_cycles = 34567;
  s.broken_bonds = 89;
  s.max_damage = 0.25;
  peritwin_msgs::crack_t crack{};
  crack.length_m = 0.0125;
  s.cracks = {crack};
  s.num_cracks = 1;
  s.crack_count = 3;
  s.crack_length_m = 0.0125;
  s.k_i = std::numeric_limits<double>::quiet_NaN();
  s.remaining_cycles = 1.5e6;
  s.remaining_cycles_low = -std::numeric_limits<double>::infinity();
  s.remaining_cycles_high = std::numeric_limits<double>::infinity();
  s.remaining_life_seq = -1;
  s.failure = peritwin_msgs::damage_state_t::FAILURE_SINGULAR;
  s.end_of_life_cycle = 34000;
  s.state_hash = "0123abcd";
  s.engine_hash = "4567ef";
  const std::string text = messages::state_json(s);
  EXPECT_EQ(text,
            "{\"detail\":\"b1-ct\",\"state_seq\":12,\"cycles\":34567,\"broken_bonds\":89,"
            "\"crack_length_m\":0.0125,\"crack_count\":3,\"max_damage\":0.25,\"k_i\":null,"
            "\"remaining_cycles\":1500000.0,\"remaining_low\":null,\"remaining_high\":null,"
            "\"remaining_life_seq\":-1,\"failure\":2,\"end_of_life_cycle\":34000,"
            "\"state_hash\":\"0123abcd\",\"engine_hash\":\"4567ef\"}");
  const auto j = nlohmann::ordered_json::parse(text);
  const std::vector<std::string> documented = {
      "detail",           "state_seq",         "cycles",         "broken_bonds",
      "crack_length_m",   "crack_count",       "max_damage",     "k_i",
      "remaining_cycles", "remaining_low",     "remaining_high", "remaining_life_seq",
      "failure",          "end_of_life_cycle", "state_hash",     "engine_hash"};
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  EXPECT_EQ(keys, documented);
  EXPECT_TRUE(j["k_i"].is_null());
  EXPECT_TRUE(j["remaining_low"].is_null());
  EXPECT_TRUE(j["remaining_high"].is_null());
  EXPECT_EQ(j["crack_length_m"].get<double>(), 0.0125);  // the double read back bit for bit
  EXPECT_EQ(j["remaining_cycles"].get<double>(), 1.5e6);
  EXPECT_EQ(j["cycles"].get<std::int64_t>(), 34567);
}

}  // namespace
}  // namespace peritwin::twin
