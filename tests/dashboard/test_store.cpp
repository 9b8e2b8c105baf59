// dashboard::Store: decoding with the codec, counting what does not decode, and the JSON it
// builds from a state (state_json's fields first), its history and its health.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <vector>

#include "dashboard/backfill.h"
#include "dashboard/store.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/mesh.h"
#include "outputs/results_writer.h"
#include "tests/support/state_messages.h"

namespace peritwin::dashboard {
namespace {

using nlohmann::json;

template <typename Message>
std::vector<unsigned char> encode(const Message& m) {
  std::vector<unsigned char> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

peritwin_msgs::damage_state_t state(std::int64_t seq, std::int64_t cycles, double crack) {
  auto s = testing::minimal_state("b1-ct", seq, cycles, "replay");
  s.utime = 1;
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

void feed(dashboard::Store& store, const std::string& ch, const std::vector<unsigned char>& bytes,
          Clock::time_point at = kT0) {
  store.on_message(ch, bytes.data(), bytes.size(), at);
}

TEST(DashboardStore, DetailJsonStartsWithTheStateJsonFields) {
  dashboard::Store store;
  const auto s = state(3, 3000, 0.0021);
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(s));
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

/// Top-level keys of a JSON object text as written (a duplicate counted twice), by SAX.
std::vector<std::string> top_level_keys(const std::string& text) {
  struct Keys : nlohmann::json_sax<json> {
    std::vector<std::string> keys;
    int depth = 0;
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(number_integer_t) override { return true; }
    bool number_unsigned(number_unsigned_t) override { return true; }
    bool number_float(number_float_t, const string_t&) override { return true; }
    bool string(string_t&) override { return true; }
    bool binary(binary_t&) override { return true; }
    bool start_object(std::size_t) override { return ++depth, true; }
    bool end_object() override { return --depth, true; }
    bool start_array(std::size_t) override { return ++depth, true; }
    bool end_array() override { return --depth, true; }
    bool key(string_t& k) override {
      if (depth == 1) keys.push_back(k);
      return true;
    }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
      return false;
    }
  } sax;
  if (!json::sax_parse(text, &sax)) return {};
  return sax.keys;
}

// The summary is state_json's text spliced with the dashboard's fields (no parse): it must be the
// bytes a parse of the whole and a dump give (what the dashboard served before the splice), and
// hold no key twice (a field state_json gains one day that the dashboard also adds). With the
// awkward values: NaN and infinities (null), -0.0, tiny and huge numbers, a non-ASCII and a
// control character in strings, and before any state (no splice).
TEST(DashboardStore, DetailJsonIsTheDumpOfItsOwnParseWithNoKeyTwice) {
  dashboard::Store store;
  auto s = state(5, 5000, 1.0e-300);
  s.max_damage = -0.0;
  s.k_i = std::numeric_limits<double>::infinity();
  s.remaining_cycles = 1.0e300;
  s.remaining_cycles_low = 0.1 + 0.2;
  s.remaining_life_source = "r\xc3\xa9play\x01\"";
  s.state_hash = "\t";
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(s));
  feed(store, messages::channel("b1-dg", messages::Kind::kStatus), encode([] {
         peritwin_msgs::status_t st{};
         st.detail_id = "b1-dg";
         st.health = "ok";
         return st;
       }()));
  // A counted-down estimate (the life part is written as text, not dumped): whole, fractional,
  // past 1e15 (dump() writes 1e+15) and -0.0 numbers; a refusal and a probe with awkward text.
  const auto cd = messages::channel("b1-cd", messages::Kind::kState);
  auto s0 = state(0, 0, 0.0);
  s0.detail_id = "b1-cd";
  s0.remaining_cycles = 1.0e15;
  s0.remaining_cycles_low = 0.5;
  s0.remaining_cycles_high = -0.0;
  s0.remaining_life_seq = -1;
  s0.remaining_life_source = "";
  s0.utime = 1'000'001;
  auto s1 = s0;
  s1.state_seq = 1;
  s1.applied_seq = {1};
  s1.total_cycles = 3;
  s1.utime = 2'500'000;
  feed(store, cd, encode(s0));
  feed(store, cd, encode(s1));
  feed(store, messages::channel("b1-cd", messages::Kind::kReject),
       encode(messages::reject_message("b1-cd", "r\xc3\xa9\x01\"", 4,
                                       {messages::Verdict::invalid, "x\"", "\t\xc3\xa9"}, 1)));
  feed(store, messages::channel("b1-cd", messages::Kind::kReject),
       encode(messages::reject_message("b1-cd", "p", std::numeric_limits<std::int64_t>::max(),
                                       {messages::Verdict::gap, "seq", "probe"}, 1)));
  ASSERT_EQ(json::parse(*store.detail_json("b1-cd", kT0))["life"]["state"], "countdown");
  ASSERT_EQ(top_level_keys(R"({"a": {"b": 1}, "a": 2})"), (std::vector<std::string>{"a", "a"}));
  for (const std::string id : {"b1-ct", "b1-dg", "b1-cd"}) {
    const auto text = store.detail_json(id, kT0);
    ASSERT_TRUE(text) << id;
    const auto ordered = nlohmann::ordered_json::parse(*text);
    EXPECT_EQ(ordered.dump(-1, ' ', false, json::error_handler_t::replace), *text) << id;
    const auto keys = top_level_keys(*text);
    EXPECT_EQ(keys.size(), ordered.size()) << id << ": a key appears twice in " << *text;
  }
}

TEST(DashboardStore, HistoryHasOnePointPerStateAndNullForNoEstimate) {
  dashboard::Store store;
  for (int seq = 0; seq <= 4; ++seq) {
    feed(store, messages::channel("b1-ct", messages::Kind::kState),
         encode(state(seq, 1000 * seq, 0.001 * seq)));
  }
  // The daemon answers a duplicate batch with the same STATE again: no new point.
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(state(4, 4000, 0.004)));
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
  dashboard::Store store;
  const auto good = encode(state(1, 1000, 0.0));
  feed(store, messages::channel("b1-ct", messages::Kind::kState), good);
  // Truncated, garbage, another type on the STATE channel, a forged count, a wrong detail.
  feed(store, messages::channel("b1-ct", messages::Kind::kState),
       std::vector<unsigned char>(good.begin(), good.end() - 3));
  feed(store, messages::channel("b1-ct", messages::Kind::kStatus),
       std::vector<unsigned char>(40, 0xff));
  feed(store, messages::channel("b1-ct", messages::Kind::kReject), good);
  feed(store, messages::channel("b1-ct", messages::Kind::kField),
       std::vector<unsigned char>{1, 2, 3});
  feed(store, messages::channel("other", messages::Kind::kState),
       good);  // detail_id b1-ct on OTHER's channel
  feed(store, "PERITWIN_bad", good);
  EXPECT_EQ(store.undecodable_total(), 6);
  const auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["undecodable"], 4);
  EXPECT_EQ(j["cycles"], 1000);
  EXPECT_FALSE(store.detail_json("other", kT0));
  EXPECT_EQ(json::parse(store.details_json(kT0))["undecodable"], 6);
}

TEST(DashboardStore, StatusRejectFieldAndStaleness) {
  dashboard::Store store;
  peritwin_msgs::status_t st{};
  st.detail_id = "b1-ct";
  st.health = "degraded";
  st.last_seq = 2;
  feed(store, messages::channel("b1-ct", messages::Kind::kStatus), encode(st));
  peritwin_msgs::reject_t r = messages::reject_message(
      "b1-ct", "replay", 9, {messages::Verdict::invalid, "blocks[0].r", "r = 1.2 must be < 1"}, 1);
  feed(store, messages::channel("b1-ct", messages::Kind::kReject), encode(r));
  peritwin_msgs::damage_field_t f{};
  f.detail_id = "b1-ct";
  f.mesh_hash = "0123456789abcdef";
  f.num_chunks = 1;
  f.total_nodes = 2;
  f.num_nodes = 2;
  f.damage = {0.0F, 0.5F};
  feed(store, messages::channel("b1-ct", messages::Kind::kField), encode(f));
  auto j = json::parse(*store.detail_json("b1-ct", kT0 + std::chrono::seconds(1)));
  EXPECT_EQ(j["health"], "degraded");
  EXPECT_EQ(j["status_age_s"], 1.0);
  EXPECT_EQ(j["rejects"], 1);
  EXPECT_EQ(j["last_reject"]["why"], "r = 1.2 must be < 1");
  EXPECT_EQ(j["fields"], 1);
  EXPECT_TRUE(j["state_seq"].is_null());
  j = json::parse(*store.detail_json("b1-ct", kT0 + std::chrono::seconds(6)));
  EXPECT_EQ(j["health"], "stale");
  // Events: one per STATUS and REJECT, one per complete FIELD.
  const auto events = store.events_after(0, std::chrono::milliseconds(0));
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].kind, "status");
  EXPECT_EQ(events[1].kind, "reject");
  EXPECT_EQ(events[2].kind, "field");
  EXPECT_EQ(json::parse(events[2].data)["summary"]["field_seq"], 0);
  EXPECT_EQ(json::parse(events[1].data)["detail"], "b1-ct");
}

/// A 100 x 60 grid on 1 mm (6000 nodes: two MESH chunks) with its outline and a notch.
messages::Mesh grid_mesh() {
  messages::Mesh m;
  m.detail_id = "b1-ct";
  m.dx = 1e-3;
  m.horizon = 3.015e-3;
  m.x_max = 0.1;
  m.y_max = 0.06;
  for (int j = 0; j < 60; ++j) {
    for (int i = 0; i < 100; ++i) {
      m.x.push_back((i + 0.5) * 1e-3);
      m.y.push_back((j + 0.5) * 1e-3);
    }
  }
  m.polylines.push_back({peritwin_msgs::mesh_polyline_t::KIND_OUTLINE,
                         0,
                         true,
                         {0, 0.1, 0.1, 0},
                         {0, 0, 0.06, 0.06}});
  m.polylines.push_back(
      {peritwin_msgs::mesh_polyline_t::KIND_NOTCH, 0, false, {0, 0.03}, {0.03, 0.03}});
  return m;
}

/// The FIELD of state `seq` in chunks of at most `per` nodes.
std::vector<peritwin_msgs::damage_field_t> field_chunks(std::int64_t seq, const std::string& hash,
                                                        const std::vector<float>& damage, int per) {
  std::vector<peritwin_msgs::damage_field_t> out;
  const int total = static_cast<int>(damage.size());
  const int chunks = (total + per - 1) / per;
  for (int c = 0; c < chunks; ++c) {
    peritwin_msgs::damage_field_t f{};
    f.detail_id = "b1-ct";
    f.state_seq = seq;
    f.mesh_hash = hash;
    f.chunk_index = c;
    f.num_chunks = chunks;
    f.total_nodes = total;
    f.first_node = c * per;
    f.num_nodes = std::min(per, total - f.first_node);
    f.damage.assign(damage.begin() + f.first_node, damage.begin() + f.first_node + f.num_nodes);
    out.push_back(f);
  }
  return out;
}

TEST(DashboardStore, MeshAndFieldAreReassembledServedAndRequestedWhenMissing) {
  dashboard::Store store;
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(state(1, 1000, 0.002)));
  EXPECT_EQ(store.mesh_json("b1-ct"), std::string());  // known, no mesh yet
  EXPECT_FALSE(store.mesh_json("nope"));
  // Without a mesh: asked for once, again only after kMeshRequestPeriodS.
  EXPECT_EQ(store.take_mesh_requests(kT0), std::vector<std::string>{"b1-ct"});
  EXPECT_TRUE(store.take_mesh_requests(kT0 + std::chrono::seconds(1)).empty());
  EXPECT_EQ(store.take_mesh_requests(kT0 + std::chrono::seconds(6)),
            std::vector<std::string>{"b1-ct"});

  const auto mesh = grid_mesh();
  const auto hash = messages::mesh_hash(mesh);
  const auto chunks = messages::mesh_messages(mesh, 7);
  ASSERT_EQ(chunks.size(), 2u);
  // A malformed chunk is counted and its reason kept; the mesh still completes after it.
  auto bad = chunks[1];
  bad.chunk_index = 5;
  feed(store, messages::channel("b1-ct", messages::Kind::kMesh), encode(bad));
  for (const auto& c : chunks)
    feed(store, messages::channel("b1-ct", messages::Kind::kMesh), encode(c));
  auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["mesh_hash"], hash);
  EXPECT_EQ(j["mesh_nodes"], 6000);
  EXPECT_TRUE(j["mesh_error"].is_null());
  EXPECT_EQ(j["undecodable"], 1);
  EXPECT_TRUE(store.take_mesh_requests(kT0 + std::chrono::seconds(60)).empty());

  const auto m = json::parse(*store.mesh_json("b1-ct"));
  EXPECT_EQ(m["mesh_hash"], hash);
  EXPECT_EQ(m["x"].get<std::vector<double>>(), mesh.x);
  EXPECT_EQ(m["y"].get<std::vector<double>>(), mesh.y);
  EXPECT_EQ(m["dx"], 1e-3);
  EXPECT_EQ(m["box"], json({0.0, 0.0, 0.1, 0.06}));
  ASSERT_EQ(m["polylines"].size(), 2u);
  EXPECT_EQ(m["polylines"][1]["kind"], "notch");
  EXPECT_EQ(m["polylines"][1]["closed"], false);

  // A field in three chunks; a chunk of an older state in between is dropped with its set.
  std::vector<float> damage(6000);
  for (std::size_t i = 0; i < damage.size(); ++i) damage[i] = static_cast<float>(i % 97) / 96.0F;
  EXPECT_EQ(store.field_json("b1-ct"), std::string());
  const auto parts = field_chunks(3, hash, damage, 2500);
  feed(store, messages::channel("b1-ct", messages::Kind::kField), encode(parts[0]));
  feed(store, messages::channel("b1-ct", messages::Kind::kField), encode(parts[2]));
  feed(store, messages::channel("b1-ct", messages::Kind::kField), encode(parts[1]));
  const auto f = json::parse(*store.field_json("b1-ct"));
  EXPECT_EQ(f["state_seq"], 3);
  EXPECT_EQ(f["mesh_hash"], hash);
  EXPECT_EQ(f["damage"].get<std::vector<float>>(), damage);
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["field_seq"], 3);
  EXPECT_EQ(j["cracks"].size(), 1u);

  // A field of another mesh (the daemon restarted on a new grid): the mesh is asked for again.
  for (const auto& p : field_chunks(4, "00000000000000aa", damage, 6000)) {
    feed(store, messages::channel("b1-ct", messages::Kind::kField), encode(p));
  }
  EXPECT_EQ(store.take_mesh_requests(kT0 + std::chrono::seconds(120)),
            std::vector<std::string>{"b1-ct"});
}

TEST(DashboardStore, BackfillFromAResultsFileGivesTheSameHistoryAsTheStates) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("peritwin_dashboard_backfill_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "b1-ct");
  {
    outputs::ResultsWriter writer(dir / "b1-ct" / "b1-ct.h5", {"b1-ct"});
    const std::vector<double> x{0.0, 1.0}, y{0.0, 0.0};
    writer.write_mesh(x, y);
    for (int seq = 0; seq <= 6; ++seq) {
      const auto s = state(seq, 1000 * seq, 0.001 * seq);
      outputs::TimeSeriesRow row;
      row.state_seq = s.state_seq;
      row.total_cycles = s.total_cycles;
      row.crack_length_m = s.crack_length_m;
      row.remaining_cycles = s.remaining_cycles;
      row.remaining_low = s.remaining_cycles_low;
      row.remaining_high = s.remaining_cycles_high;
      writer.append(row);
    }
  }
  std::ofstream(dir / "not-a-detail.txt") << "x";
  const auto files = dashboard::find_results_files(dir);
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].detail_id, "b1-ct");
  const auto points = dashboard::read_history_points(files[0].path);
  ASSERT_EQ(points.size(), 7u);

  // Live from the start: every state.
  dashboard::Store live;
  for (int seq = 0; seq <= 8; ++seq) {
    feed(live, messages::channel("b1-ct", messages::Kind::kState),
         encode(state(seq, 1000 * seq, 0.001 * seq)));
  }
  // Started late (states 5.. live): the file fills in 0..4; started later still (nothing live
  // yet): the whole file, then the live states after it (6 again is no new point).
  dashboard::Store late;
  for (int seq = 5; seq <= 8; ++seq) {
    feed(late, messages::channel("b1-ct", messages::Kind::kState),
         encode(state(seq, 1000 * seq, 0.001 * seq)));
  }
  EXPECT_EQ(late.backfill("b1-ct", points, kT0), 5u);
  dashboard::Store later;
  EXPECT_EQ(later.backfill("b1-ct", points, kT0), 7u);
  for (int seq = 6; seq <= 8; ++seq) {
    feed(later, messages::channel("b1-ct", messages::Kind::kState),
         encode(state(seq, 1000 * seq, 0.001 * seq)));
  }
  auto strip = [](std::string text) {
    auto j = json::parse(text);
    j.erase("pushed");
    j.erase("backfilled");
    return j;
  };
  const auto expected = strip(*live.history_json("b1-ct"));
  EXPECT_EQ(expected["state_seq"], json({0, 1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(strip(*late.history_json("b1-ct")), expected);
  EXPECT_EQ(strip(*later.history_json("b1-ct")), expected);
  EXPECT_EQ(json::parse(*later.history_json("b1-ct"))["backfilled"], 7);
  std::filesystem::remove_all(dir);
}

/// A STATE of `source`'s batch `seq` (state `state_seq`, `cycles` in all) carrying the estimate
/// (`central`, band ±20 %) made on the state of (`life_source`, `life_seq`); utime 1 s per state.
peritwin_msgs::damage_state_t life_state(std::int64_t state_seq, const std::string& source,
                                         std::int64_t seq, std::int64_t cycles, double central,
                                         const std::string& life_source, std::int64_t life_seq) {
  auto s = state(state_seq, cycles, 0.001);
  s.utime = 1'000'000 * (state_seq + 1);
  s.source_ids = {source};
  s.applied_seq = {seq};
  s.remaining_cycles = central;
  s.remaining_cycles_low = central * 0.8;
  s.remaining_cycles_high = central * 1.2;
  s.remaining_life_source = life_source;
  s.remaining_life_seq = life_seq;
  return s;
}

// Issue 30 item 1: between two estimates the remaining life falls by exactly the cycles applied.
// The estimate made on batch 3's state (9,000 cycles) arrives with state 5 (the life worker
// lags); from then on remaining = 9,000 + 38,373 − cycles, and the history plots that line.
TEST(DashboardStore, RemainingLifeCountsDownBetweenEstimates) {
  dashboard::Store store;
  const auto ch = messages::channel("b1-ct", messages::Kind::kState);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Cycles after each batch: 0, 3000, 6000, 9000, 10000, 12500, 17500, 18000.
  const std::vector<std::int64_t> cycles{0, 3000, 6000, 9000, 10000, 12500, 17500, 18000};
  // State 0 carries the estimate made on the initial state; 1..4 still that one; 5.. batch 3's.
  feed(store, ch, encode(life_state(0, "replay", 0, 0, 38373.0, "", -1)));
  auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "countdown");
  EXPECT_EQ(j["life"]["estimate_cycle"], 0);
  EXPECT_EQ(j["life"]["remaining"], 38373.0);
  for (std::int64_t k = 1; k <= 4; ++k) {
    feed(store, ch, encode(life_state(k, "replay", k, cycles[k], 38373.0, "", -1)));
  }
  j = json::parse(*store.detail_json("b1-ct", kT0));
  // The old card said 38,373 at 10,000 cycles; it counts down now.
  EXPECT_EQ(j["life"]["remaining"], 38373.0 - 10000.0);
  EXPECT_EQ(j["life"]["end_cycle"], 38373);
  EXPECT_EQ(j["life"]["age_cycles"], 10000);
  EXPECT_EQ(j["life"]["age_s"], 4.0);         // utime of state 4 − state 0's
  EXPECT_EQ(j["remaining_cycles"], 38373.0);  // the message's own field, as published

  std::vector<double> remaining;
  for (std::int64_t k = 5; k <= 7; ++k) {
    feed(store, ch, encode(life_state(k, "replay", k, cycles[k], 30000.0, "replay", 3)));
    j = json::parse(*store.detail_json("b1-ct", kT0));
    EXPECT_EQ(j["life"]["state"], "countdown") << k;
    EXPECT_EQ(j["life"]["estimate_cycle"], 9000) << k;
    EXPECT_EQ(j["life"]["estimate_source"], "replay");
    EXPECT_EQ(j["life"]["estimate_seq"], 3);
    EXPECT_EQ(j["life"]["end_cycle"], 39000) << k;
    EXPECT_EQ(j["life"]["age_cycles"], cycles[k] - 9000) << k;
    EXPECT_EQ(j["life"]["age_s"], static_cast<double>(k - 3)) << k;
    EXPECT_EQ(j["life"]["low"], 24000.0 - static_cast<double>(cycles[k] - 9000)) << k;
    EXPECT_EQ(j["life"]["high"], 36000.0 - static_cast<double>(cycles[k] - 9000)) << k;
    remaining.push_back(j["life"]["remaining"].get<double>());
  }
  // Successive states between estimates: the difference is exactly the cycles applied.
  EXPECT_EQ(remaining[0] - remaining[1], static_cast<double>(cycles[6] - cycles[5]));
  EXPECT_EQ(remaining[1] - remaining[2], static_cast<double>(cycles[7] - cycles[6]));
  EXPECT_EQ(remaining[2], 39000.0 - 18000.0);

  // The chart's series: a falling line, not a staircase (state 0 .. 7).
  const auto h = json::parse(*store.history_json("b1-ct"));
  const std::vector<double> expected{38373, 35373, 32373, 29373, 28373, 26500, 21500, 21000};
  EXPECT_EQ(h["remaining"].get<std::vector<double>>(), expected);
  EXPECT_EQ(h["low"][7], 24000.0 - 9000.0);

  // Past the predicted end without failing: 0, not below.
  feed(store, ch, encode(life_state(8, "replay", 8, 50000, 30000.0, "replay", 3)));
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "countdown");
  EXPECT_EQ(j["life"]["remaining"], 0.0);
  EXPECT_EQ(j["life"]["low"], 0.0);
  // Failed: END OF LIFE (not the health word "failed"), at the cycle it failed.
  auto failed = life_state(9, "replay", 9, 50100, 0.0, "replay", 9);
  failed.failure = peritwin_msgs::damage_state_t::FAILURE_END_CRITERION;
  failed.end_of_life_cycle = 50050;
  feed(store, ch, encode(failed));
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "end_of_life");
  EXPECT_EQ(j["life"]["remaining"], 0.0);
  EXPECT_EQ(j["life"]["end_cycle"], 50050);
  EXPECT_EQ(j["health"], "waiting");  // the daemon's health is another thing

  // No estimate: nulls.
  feed(store, ch, encode(life_state(10, "replay", 10, 50100, nan, "", -1)));
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "none");
  EXPECT_TRUE(j["life"]["remaining"].is_null());
  EXPECT_TRUE(j["life"]["end_cycle"].is_null());
}

// Two producers interleaved: the state an estimate was made on is the one the named batch
// produced, found by which source's applied seq moved; a dashboard that did not receive that
// state (started later) shows the estimate as published ("unanchored"), not a wrong countdown.
TEST(DashboardStore, EstimateStateIsFoundAmongInterleavedSourcesOrLeftUnanchored) {
  dashboard::Store store;
  const auto ch = messages::channel("b1-ct", messages::Kind::kState);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // state k: source a, b, a, b...; applied_seq of both listed.
  auto two = [&](std::int64_t k, std::int64_t a, std::int64_t b, std::int64_t cycles, double life,
                 const std::string& src, std::int64_t seq) {
    auto s = life_state(k, "a", a, cycles, life, src, seq);
    s.num_sources = 2;
    s.source_ids = {"a", "b"};
    s.applied_seq = {a, b};
    s.checkpointed_seq = {0, 0};
    s.history = {0, 0};
    s.history_start = {0, 0};
    return s;
  };
  feed(store, ch, encode(two(0, 0, 0, 0, nan, "", -1)));
  feed(store, ch, encode(two(1, 1, 0, 100, nan, "", -1)));    // a 1
  feed(store, ch, encode(two(2, 1, 1, 700, nan, "", -1)));    // b 1
  feed(store, ch, encode(two(3, 2, 1, 800, nan, "", -1)));    // a 2
  feed(store, ch, encode(two(4, 2, 2, 1500, 5000, "b", 1)));  // b 2; estimate on b 1's state
  auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["estimate_cycle"], 700);
  EXPECT_EQ(j["life"]["remaining"], 5000.0 - 800.0);

  dashboard::Store late;  // first state received: 4
  feed(late, ch, encode(two(4, 2, 2, 1500, 5000, "b", 1)));
  j = json::parse(*late.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "unanchored");
  EXPECT_EQ(j["life"]["remaining"], 5000.0);
  EXPECT_TRUE(j["life"]["estimate_cycle"].is_null());
  EXPECT_TRUE(j["life"]["end_cycle"].is_null());
  EXPECT_TRUE(j["life"]["age_cycles"].is_null());
}

// The batches kept to date estimates are bounded (kBatchMemory): an estimate made on a state
// further back than that is shown as published, one within it is counted down.
TEST(DashboardStore, EstimatesBeyondTheBatchMemoryAreUnanchored) {
  dashboard::Store store;
  const auto ch = messages::channel("b1-ct", messages::Kind::kState);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto n = static_cast<std::int64_t>(kBatchMemory) + 10;
  for (std::int64_t k = 0; k <= n; ++k) {
    feed(store, ch, encode(life_state(k, "replay", k, 10 * k, nan, "", -1)));
  }
  feed(store, ch, encode(life_state(n + 1, "replay", n + 1, 10 * (n + 1), 500.0, "replay", 5)));
  EXPECT_EQ(json::parse(*store.detail_json("b1-ct", kT0))["life"]["state"], "unanchored");
  feed(store, ch, encode(life_state(n + 2, "replay", n + 2, 10 * (n + 2), 500.0, "replay", n)));
  const auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "countdown");
  EXPECT_EQ(j["life"]["estimate_cycle"], 10 * n);
  EXPECT_EQ(j["life"]["remaining"], 480.0);
}

// Cycle counts off the bus are not trusted: a hostile pair saturates the estimate's age instead
// of overflowing, and the countdown stays at 0.
TEST(DashboardStore, HostileCyclesSaturateTheCountdown) {
  dashboard::Store store;
  const auto ch = messages::channel("b1-ct", messages::Kind::kState);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::int64_t max = std::numeric_limits<std::int64_t>::max();
  feed(store, ch, encode(life_state(0, "replay", 0, 0, nan, "", -1)));
  feed(store, ch, encode(life_state(1, "replay", 1, -5, nan, "", -1)));
  feed(store, ch, encode(life_state(2, "replay", 2, max, 100.0, "replay", 1)));
  const auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["life"]["state"], "countdown");
  EXPECT_EQ(j["life"]["estimate_cycle"], -5);
  EXPECT_EQ(j["life"]["age_cycles"], "9223372036854775807");
  EXPECT_EQ(j["life"]["remaining"], 0.0);
  EXPECT_EQ(j["life"]["end_cycle"], 95);
  EXPECT_EQ(j["cycles"], "9223372036854775807");
}

/// The JSON text's value of `key` inside `text` as written (digits or a quoted string).
std::string raw_value(const std::string& text, const std::string& key) {
  const auto at = text.find("\"" + key + "\":");
  if (at == std::string::npos) return "";
  const auto from = at + key.size() + 3;
  return text.substr(from, text.find_first_of(",}", from) - from);
}

// Issue 30 item 2: the card's reject count and last reason are refusals only; a producer's probe,
// a resend answered as DUPLICATE and a GAP asking for a resend are counted apart. A seq past 2^53
// (the probe's 2^63 − 1) goes as a string, so the page shows it exactly.
TEST(DashboardStore, RefusalsAndProtocolEventsAreCountedApart) {
  dashboard::Store store;
  const auto ch = messages::channel("b1-ct", messages::Kind::kReject);
  const std::int64_t probe = std::numeric_limits<std::int64_t>::max();
  auto reject = [&](std::int64_t seq, messages::Verdict v, const std::string& why) {
    feed(store, ch, encode(messages::reject_message("b1-ct", "replay", seq, {v, "seq", why}, 1)));
  };
  reject(probe, messages::Verdict::gap, "probe");
  reject(3, messages::Verdict::duplicate, "seq 3 is already applied");
  reject(3, messages::Verdict::duplicate, "seq 3 is already applied");
  reject(9, messages::Verdict::gap, "resend from 5");
  auto j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["rejects"], 0);
  EXPECT_TRUE(j["last_reject"].is_null());
  EXPECT_EQ(j["protocol"]["probes"], 1);
  EXPECT_EQ(j["protocol"]["duplicates"], 2);
  EXPECT_EQ(j["protocol"]["gaps"], 1);
  EXPECT_EQ(j["protocol"]["last"]["why"], "resend from 5");

  reject(4, messages::Verdict::invalid, "r = 1.2 must be < 1");
  reject(5, messages::Verdict::auth, "unknown source");
  reject(6, messages::Verdict::limit, "max_sources 4");
  reject(probe - 1, messages::Verdict::failed, "the detail has failed");
  reject(probe, messages::Verdict::gap, "probe");
  const auto text = *store.detail_json("b1-ct", kT0);
  j = json::parse(text);
  EXPECT_EQ(j["rejects"], 4);
  EXPECT_EQ(j["last_reject"]["code"], peritwin_msgs::reject_t::CODE_FAILED);
  EXPECT_EQ(j["last_reject"]["why"], "the detail has failed");
  EXPECT_EQ(j["last_reject"]["seq"], "9223372036854775806");
  EXPECT_EQ(j["protocol"]["probes"], 2);
  EXPECT_EQ(j["protocol"]["last"]["seq"], "9223372036854775807");
  EXPECT_EQ(j["protocol"]["last"]["code"], peritwin_msgs::reject_t::CODE_GAP);
  // As written: a string, not a number a browser would round to 9223372036854775808.
  const auto last = text.substr(text.find("\"protocol\":"));
  EXPECT_EQ(raw_value(last, "seq"), "\"9223372036854775807\"");
  // Small integers stay numbers.
  EXPECT_EQ(raw_value(text.substr(text.find("\"last_reject\":")), "code"), "6");
  // The events carry the same summary.
  const auto events = store.events_after(0, std::chrono::milliseconds(0));
  ASSERT_EQ(events.size(), 9u);
  EXPECT_NE(events.back().data.find("\"9223372036854775807\""), std::string::npos);

  // A STATE with integers past 2^53 (a hostile cycle count): strings too, the rest unchanged.
  auto s = state(2, (std::int64_t{1} << 53) + 1, 0.001);
  s.end_of_life_cycle = probe;
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(s));
  const auto st = *store.detail_json("b1-ct", kT0);
  j = json::parse(st);
  EXPECT_EQ(j["cycles"], "9007199254740993");
  EXPECT_EQ(j["end_of_life_cycle"], "9223372036854775807");
  EXPECT_EQ(j["state_seq"], 2);
  EXPECT_EQ(j["rejects"], 4);
  EXPECT_EQ(top_level_keys(st).size(), j.size());
  const auto h = json::parse(*store.history_json("b1-ct"));
  EXPECT_TRUE(h["cycles"][0].is_string());
}

// Issue 30 item 3: a dashboard started late with --results shows, before the detail publishes
// again, the card of the file's last row (remaining life counted down from the row of its
// estimate's state) and the damage map of the file's newest snapshot on the bus's mesh.
TEST(DashboardStore, LateDashboardShowsTheResultsFilesLastStateAndField) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("peritwin_dashboard_late_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto path = dir / "b1-ct.h5";
  const auto mesh = grid_mesh();
  std::vector<float> damage(mesh.x.size());
  for (std::size_t i = 0; i < damage.size(); ++i) damage[i] = static_cast<float>(i % 11) / 20.0F;
  std::vector<outputs::TimeSeriesRow> rows;
  {
    outputs::ResultsWriter writer(path, {"b1-ct"});
    writer.write_mesh(mesh.x, mesh.y);
    for (int seq = 0; seq <= 6; ++seq) {
      outputs::TimeSeriesRow row;
      row.state_seq = seq;
      row.total_cycles = 2000 * seq + (seq == 6 ? 123 : 0);
      row.broken_bonds = 11 * seq;
      row.crack_count = seq > 2 ? 1 : 0;
      row.crack_length_m = 0.0005 * seq;
      row.tip_x = 0.03 + 0.0005 * seq;
      row.tip_y = 0.03;
      row.k_i = 1e6 * seq;
      row.k_ii = 1e5 * seq;
      if (seq >= 2) {  // estimates made on state 2 (4,000 cycles), published from state 4 on
        row.remaining_cycles = seq >= 4 ? 20000.0 : std::numeric_limits<double>::quiet_NaN();
        row.remaining_low = row.remaining_cycles * 0.5;
        row.remaining_high = row.remaining_cycles * 2.0;
        row.remaining_state_seq = seq >= 4 ? 2 : -1;
      }
      writer.append(row);
      rows.push_back(row);
      if (seq == 3) writer.write_snapshot(3, row.total_cycles, std::vector<float>(damage.size()));
    }
    writer.write_snapshot(6, rows.back().total_cycles, damage);
  }
  const auto content = dashboard::read_results(path);
  ASSERT_TRUE(content.last);
  ASSERT_TRUE(content.snapshot);
  EXPECT_EQ(content.snapshot->state_seq, 6);
  EXPECT_EQ(content.last->estimate_cycles, 4000);
  // The history counts down from the estimate's state too.
  ASSERT_EQ(content.points.size(), 7u);
  EXPECT_EQ(content.points[4].remaining, 20000.0 - 4000.0);
  EXPECT_EQ(content.points[6].remaining, 20000.0 - 8123.0);
  EXPECT_EQ(content.points[6].low, 10000.0 - 8123.0);

  dashboard::Store store;
  store.backfill("b1-ct", content.points, kT0);
  store.backfill_latest("b1-ct", *content.last, content.snapshot, kT0);
  auto j = json::parse(*store.detail_json("b1-ct", kT0));
  const auto& last = rows.back();
  EXPECT_EQ(j["from_results"], true);
  EXPECT_EQ(j["state_seq"], last.state_seq);
  EXPECT_EQ(j["cycles"], last.total_cycles);
  EXPECT_EQ(j["broken_bonds"], last.broken_bonds);
  EXPECT_EQ(j["crack_count"], last.crack_count);
  EXPECT_EQ(j["crack_length_m"], last.crack_length_m);
  EXPECT_EQ(j["k_i"], last.k_i);
  EXPECT_EQ(j["k_ii"], last.k_ii);
  EXPECT_EQ(j["tip"]["x"], last.tip_x);
  EXPECT_EQ(j["tip"]["k_i"], last.k_i);
  EXPECT_EQ(j["remaining_cycles"], last.remaining_cycles);
  EXPECT_EQ(j["max_damage"], 0.5);  // the snapshot of the last row's state: max (10 % 11) / 20
  EXPECT_EQ(j["life"]["state"], "countdown");
  EXPECT_EQ(j["life"]["estimate_cycle"], 4000);
  EXPECT_EQ(j["life"]["remaining"], 20000.0 - 8123.0);
  EXPECT_EQ(j["life"]["end_cycle"], 24000);
  EXPECT_EQ(j["field_seq"], 6);
  EXPECT_EQ(j["field_from_results"], true);
  EXPECT_TRUE(j["mesh_hash"].is_null());

  // The bus's mesh of the same grid: the file's field is drawn on it (its mesh_hash).
  const auto hash = messages::mesh_hash(mesh);
  for (const auto& c : messages::mesh_messages(mesh, 7)) {
    feed(store, messages::channel("b1-ct", messages::Kind::kMesh), encode(c));
  }
  auto f = json::parse(*store.field_json("b1-ct"));
  EXPECT_EQ(f["mesh_hash"], hash);
  EXPECT_EQ(f["state_seq"], 6);
  EXPECT_EQ(f["damage"].get<std::vector<float>>(), damage);
  EXPECT_TRUE(store.take_mesh_requests(kT0 + std::chrono::seconds(60)).empty());
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["field_mesh_hash"], hash);

  // A mesh of another grid: the file's field is not drawn on it.
  dashboard::Store other;
  other.backfill_latest("b1-ct", *content.last, content.snapshot, kT0);
  auto moved = mesh;
  moved.x[0] += 1e-4;
  for (const auto& c : messages::mesh_messages(moved, 7)) {
    feed(other, messages::channel("b1-ct", messages::Kind::kMesh), encode(c));
  }
  EXPECT_EQ(other.field_json("b1-ct"), std::string());

  // The next live STATE: the card is the bus's again; the file's estimate is the same one
  // (same numbers), so its countdown goes on from the file's state.
  auto s = life_state(7, "replay", 7, 9000, 20000.0, "replay", 2);
  s.remaining_cycles_low = 10000.0;
  s.remaining_cycles_high = 40000.0;
  feed(store, messages::channel("b1-ct", messages::Kind::kState), encode(s));
  j = json::parse(*store.detail_json("b1-ct", kT0));
  EXPECT_EQ(j["from_results"], false);
  EXPECT_EQ(j["cycles"], 9000);
  EXPECT_EQ(j["life"]["estimate_cycle"], 4000);
  EXPECT_EQ(j["life"]["estimate_seq"], 2);
  EXPECT_EQ(j["life"]["remaining"], 20000.0 - 5000.0);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace peritwin::dashboard
