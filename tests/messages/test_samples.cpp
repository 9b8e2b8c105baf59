// load_samples_t (message set version 5): the codec's round trip, the layout checks on untrusted
// bytes, every validation rule with the field it names, the payload limit and the HMAC tag.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/codec.h"

namespace peritwin::messages {
namespace {

std::vector<std::uint8_t> encode(const peritwin_msgs::load_samples_t& m) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  return bytes;
}

messages::Samples even() {
  return {"b1-ct", "gauge-1", 1, 5.0, 0.001, {400.0, 4000.0, 400.0}, {}, {}};
}

TEST(Samples, RoundTripAndTimes) {
  messages::Samples timed{"b1-ct", "gauge-1", 7, 0.0, 0.0, {1.0, 2.0}, {0.5, 0.75}, {0.1, 0.2}};
  for (const messages::Samples& s : {even(), timed}) {
    const auto bytes = encode(messages::samples_message(s, 123));
    const auto d = messages::decode_samples(bytes.data(), bytes.size());
    ASSERT_TRUE(d.samples) << d.error.why;
    EXPECT_EQ(d.samples->p, s.p);
    EXPECT_EQ(d.samples->t, s.t);
    EXPECT_EQ(d.samples->alpha, s.alpha);
    EXPECT_EQ(d.samples->seq, s.seq);
    EXPECT_TRUE(messages::check_samples(*d.samples, "b1-ct").applied());
    EXPECT_EQ(d.signed_size + 4, bytes.size());
  }
  EXPECT_DOUBLE_EQ(even().time(2), 5.002);
  EXPECT_DOUBLE_EQ(timed.time(1), 0.75);
  EXPECT_EQ(messages::channel("b1-ct", messages::Kind::kSamples), "PERITWIN_B1_CT_SAMPLES");
}

TEST(Samples, EveryRuleNamesItsField) {
  const auto field_of = [](const messages::Samples& s) {
    return messages::check_samples(s, "b1-ct").what;
  };
  messages::Samples s = even();
  s.detail_id = "b2";
  EXPECT_EQ(messages::check_samples(s, "b1-ct").verdict, messages::Verdict::wrong_detail);
  s = even();
  s.source_id = "";
  EXPECT_EQ(field_of(s), "source_id");
  s = even();
  s.seq = 0;
  EXPECT_EQ(field_of(s), "seq");
  s = even();
  s.p.clear();
  EXPECT_EQ(field_of(s), "num_samples");
  s = even();
  s.p.assign(65537, 1.0);
  EXPECT_EQ(field_of(s), "num_samples");
  s = even();
  s.t0 = std::numeric_limits<double>::infinity();
  EXPECT_EQ(field_of(s), "t0");
  s = even();
  s.sample_period = 0.0;
  EXPECT_EQ(field_of(s), "sample_period");
  s = even();
  s.t = {1.0, 2.0, 3.0};  // with t the period must be 0
  EXPECT_EQ(field_of(s), "sample_period");
  s.sample_period = 0.0;
  EXPECT_TRUE(messages::check_samples(s, "b1-ct").applied());
  s.t = {1.0, 2.0};
  EXPECT_EQ(field_of(s), "num_t");
  s.t = {1.0, 3.0, 3.0};
  EXPECT_EQ(field_of(s), "t[2]");
  s = even();
  s.alpha = {0.0};
  EXPECT_EQ(field_of(s), "num_alpha");
  s.alpha = {0.0, std::nan(""), 0.0};
  EXPECT_EQ(field_of(s), "alpha[1]");
  s = even();
  s.p[1] = std::nan("");  // a dropout: taken, skipped and counted by the stream
  EXPECT_TRUE(messages::check_samples(s, "b1-ct").applied());
}

TEST(Samples, UntrustedBytesAreRefusedWithAReason) {
  const auto bytes = encode(messages::samples_message(even(), 1));
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    const auto d = messages::decode_samples(bytes.data(), cut);
    EXPECT_FALSE(d.samples) << cut;
    EXPECT_EQ(d.error.verdict, messages::Verdict::decode);
    EXPECT_FALSE(d.error.why.empty());
  }
  auto forged = bytes;
  // num_samples (after fingerprint, utime, two strings, seq, t0, period) set to 2^30.
  const std::size_t at = 8 + 8 + (4 + 6) + (4 + 8) + 3 * 8;
  forged[at] = 0x40;
  EXPECT_FALSE(messages::decode_samples(forged.data(), forged.size()).samples);
  messages::Samples big = even();
  big.p.assign(8200, 1.0);  // 65.6 kB: above the payload limit
  const auto too_big = encode(messages::samples_message(big, 1));
  ASSERT_GT(too_big.size(), messages::kMaxSamplesPayload);
  const auto d = messages::decode_samples(too_big.data(), too_big.size());
  EXPECT_FALSE(d.samples);
  EXPECT_NE(d.error.why.find("oversized"), std::string::npos) << d.error.why;
}

TEST(Samples, SignedLikeABatch) {
  messages::AuthKey key;
  for (std::size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<std::uint8_t>(i);
  auto m = messages::samples_message(even(), 1);
  messages::sign(m, key);
  EXPECT_TRUE(messages::verify(m, key).ok());
  const auto bytes = encode(m);
  EXPECT_TRUE(verify_encoded<peritwin_msgs::load_samples_t>(bytes.data(), bytes.size(), key).ok());
  const auto d = messages::decode_samples(bytes.data(), bytes.size());
  ASSERT_TRUE(d.samples);
  EXPECT_TRUE(messages::tag_matches(key, bytes.data(), d.signed_size, d.auth_tag));
  m.p[0] += 1.0;
  EXPECT_EQ(messages::verify(m, key).error().reason, "wrong tag");
}

}  // namespace
}  // namespace peritwin::messages
