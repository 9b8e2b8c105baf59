// dashboard::Store: decoding with the codec, counting what does not decode, and the JSON it
// builds from a state (state_json's fields first), its history and its health.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "dashboard/store.h"
#include "messages/channels.h"
#include "messages/codec.h"

namespace peritwin::dashboard {
namespace {

using messages::channel;
using messages::Kind;
using nlohmann::json;

template <typename Message>
std::vector<unsigned char> encode(const Message& m) {
  std::vector<unsigned char> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

peritwin_msgs::damage_state_t state(std::int64_t seq, std::int64_t cycles, double crack) {
  peritwin_msgs::damage_state_t s{};
  s.utime = 1;
  s.detail_id = "b1-ct";
  s.state_seq = seq;
  s.num_sources = 1;
  s.source_ids = {"replay"};
  s.applied_seq = {seq};
  s.checkpointed_seq = {0};
  s.total_cycles = cycles;
  s.broken_bonds = 7 * seq;
  s.max_damage = 0.25;
  s.crack_count = 1;
  s.crack_length_m = crack;
  s.num_cracks = 1;
  peritwin_msgs::crack_t c{};
  c.id = 1;
  c.origin = "notch 0";
  c.length_m = crack;
  c.num_tips = 1;
  peritwin_msgs::crack_tip_t tip{};
  tip.x = 0.03;
  tip.k_i = 12.5e6;
  tip.k_ii = std::numeric_limits<double>::quiet_NaN();
  tip.k_status = 0;
  c.tips = {tip};
  c.num_absorbed = 0;
  s.cracks = {c};
  s.k_i = 12.5e6;
  s.k_ii = std::numeric_limits<double>::quiet_NaN();
  s.remaining_cycles =
      seq == 0 ? std::numeric_limits<double>::quiet_NaN() : 1000.0 * static_cast<double>(seq);
  s.remaining_cycles_low = s.remaining_cycles * 0.8;
  s.remaining_cycles_high = s.remaining_cycles * 1.2;
  s.remaining_life_seq = seq;
  s.remaining_life_source = "replay";
  s.failure = 0;
  s.end_of_life_cycle = -1;
  s.state_hash = "00112233aabbccdd";
  s.engine_hash = "ffeeddccbbaa0099";
  s.tag_length = 0;
  return s;
}

const auto kT0 = Clock::time_point{} + std::chrono::hours(1);

void feed(Store& store, const std::string& ch, const std::vector<unsigned char>& bytes,
          Clock::time_point at = kT0) {
  store.on_message(ch, bytes.data(), bytes.size(), at);
}

TEST(DashboardStore, DetailJsonStartsWithTheStateJsonFields) {
  Store store;
  const auto s = state(3, 3000, 0.0021);
  feed(store, channel("b1-ct", Kind::kState), encode(s));
  const auto text = store.detail_json("b1-ct", kT0);
  ASSERT_TRUE(text);
  const auto j = json::parse(*text);
  const auto expected = json::parse(messages::state_json(s));
  // The state_json fields, same values, and in the same order at the top.
  const auto ordered = nlohmann::ordered_json::parse(*text);
  const auto expected_ordered = nlohmann::ordered_json::parse(messages::state_json(s));
  std::vector<std::string> keys, expected_keys;
  for (auto it = ordered.begin(); keys.size() < expected_ordered.size(); ++it) {
    keys.push_back(it.key());
  }
  for (auto it = expected_ordered.begin(); it != expected_ordered.end(); ++it) {
    expected_keys.push_back(it.key());
  }
  EXPECT_EQ(keys, expected_keys);
  for (const auto& [key, value] : expected.items()) EXPECT_EQ(j.at(key), value) << key;
  EXPECT_EQ(j["cycles"], 3000);
  EXPECT_EQ(j["state_hash"], "00112233aabbccdd");
  EXPECT_EQ(j["engine_hash"], "ffeeddccbbaa0099");
  EXPECT_TRUE(j["k_ii"].is_null());  // NaN
  EXPECT_EQ(j["tip"]["k_i"], 12.5e6);
  EXPECT_EQ(j["signed"], false);
  EXPECT_EQ(j["health"], "waiting");  // no STATUS yet, and not for 5 s
  EXPECT_TRUE(j["status"].is_null());
  EXPECT_EQ(j["rejects"], 0);
  EXPECT_FALSE(store.detail_json("nope", kT0));
  EXPECT_FALSE(store.history_json("nope"));
}

TEST(DashboardStore, HistoryHasOnePointPerStateAndNullForNoEstimate) {
  Store store;
  for (int seq = 0; seq <= 4; ++seq) {
    feed(store, channel("b1-ct", Kind::kState), encode(state(seq, 1000 * seq, 0.001 * seq)));
  }
  // The daemon answers a duplicate batch with the same STATE again: no new point.
  feed(store, channel("b1-ct", Kind::kState), encode(state(4, 4000, 0.004)));
  const auto h = json::parse(*store.history_json("b1-ct"));
  EXPECT_EQ(h["state_seq"], json({0, 1, 2, 3, 4}));
  EXPECT_EQ(h["cycles"], json({0, 1000, 2000, 3000, 4000}));
  EXPECT_EQ(h["crack_length_m"].size(), 5u);
  EXPECT_TRUE(h["remaining"][0].is_null());
  EXPECT_EQ(h["remaining"][4], 4000.0);
  EXPECT_EQ(h["low"][4], 3200.0);
  EXPECT_EQ(h["high"][4], 4800.0);
  EXPECT_EQ(json::parse(*store.detail_json("b1-ct", kT0))["states_received"], 6);
}

TEST(DashboardStore, UndecodableMessagesAreCountedAndIgnored) {
  Store store;
  const auto good = encode(state(1, 1000, 0.0));
  feed(store, channel("b1-ct", Kind::kState), good);
  // Truncated, garbage, another type on the STATE channel, a forged count, a wrong detail.
  feed(store, channel("b1-ct", Kind::kState),
       std::vector<unsigned char>(good.begin(), good.end() - 3));
  feed(store, channel("b1-ct", Kind::kStatus), std::vector<unsigned char>(40, 0xff));
  feed(store, channel("b1-ct", Kind::kReject), good);
  feed(store, channel("b1-ct", Kind::kField), std::vector<unsigned char>{1, 2, 3});
  feed(store, channel("other", Kind::kState), good);  // detail_id b1-ct on OTHER's channel
  feed(store, "PERITWIN_bad", good);
  EXPECT_EQ(store.undecodable_total(), 6);
  const auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["undecodable"], 4);
  EXPECT_EQ(j["cycles"], 1000);
  EXPECT_FALSE(store.detail_json("other", kT0));
  EXPECT_EQ(json::parse(store.details_json(kT0))["undecodable"], 6);
}

TEST(DashboardStore, StatusRejectFieldAndStaleness) {
  Store store;
  peritwin_msgs::status_t st{};
  st.detail_id = "b1-ct";
  st.health = "degraded";
  st.last_seq = 2;
  feed(store, channel("b1-ct", Kind::kStatus), encode(st));
  peritwin_msgs::reject_t r = messages::reject_message(
      "b1-ct", "replay", 9, {messages::Verdict::gap, "seq", "seq 9 skips 3..8"}, 1);
  feed(store, channel("b1-ct", Kind::kReject), encode(r));
  peritwin_msgs::damage_field_t f{};
  f.detail_id = "b1-ct";
  f.num_chunks = 1;
  f.total_nodes = 2;
  f.num_nodes = 2;
  f.damage = {0.0F, 0.5F};
  feed(store, channel("b1-ct", Kind::kField), encode(f));
  auto j = json::parse(*store.detail_json("b1-ct", kT0 + std::chrono::seconds(1)));
  EXPECT_EQ(j["health"], "degraded");
  EXPECT_EQ(j["status_age_s"], 1.0);
  EXPECT_EQ(j["rejects"], 1);
  EXPECT_EQ(j["last_reject"]["why"], "seq 9 skips 3..8");
  EXPECT_EQ(j["fields"], 1);
  EXPECT_TRUE(j["state_seq"].is_null());
  j = json::parse(*store.detail_json("b1-ct", kT0 + std::chrono::seconds(6)));
  EXPECT_EQ(j["health"], "stale");
  // Events: one per STATUS and REJECT (FIELD is only counted).
  const auto events = store.events_after(0, std::chrono::milliseconds(0));
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, "status");
  EXPECT_EQ(events[1].kind, "reject");
  EXPECT_EQ(json::parse(events[1].data)["detail"], "b1-ct");
}

}  // namespace
}  // namespace peritwin::dashboard
