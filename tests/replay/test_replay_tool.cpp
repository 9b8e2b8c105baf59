// The replay tool's library: batching, block checks, history formats (LCM log included).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "messages/channels.h"
#include "replay/replay_tool.h"

namespace peritwin::replay {
namespace {

namespace fs = std::filesystem;

TEST(ReplayBatches, ByBlocksAndCyclesWithSequentialSeq) {
  std::vector<peritwin::LoadBlock> blocks;
  for (int i = 0; i < 40; ++i) blocks.push_back({4000, 0.1, 0, 1});
  blocks.push_back({4000, 0.1, 0, 5000});
  blocks.push_back({4000, 0.1, 0, 1});
  const auto batches = make_twin_batches(blocks, "b1-ct", "src", {16, 1000});
  ASSERT_EQ(batches.size(), 4u);  // 16 + 16 + (8 + the 5000-cycle block) + 1
  EXPECT_EQ(batches[0].blocks.size(), 16u);
  EXPECT_EQ(batches[2].blocks.size(), 9u);
  EXPECT_EQ(batches[3].blocks.size(), 1u);
  for (std::size_t i = 0; i < batches.size(); ++i) {
    EXPECT_EQ(batches[i].seq, static_cast<std::int64_t>(i) + 1);
    EXPECT_EQ(batches[i].detail_id, "b1-ct");
    EXPECT_EQ(batches[i].source_id, "src");
  }
  EXPECT_TRUE(make_twin_batches({}, "b1-ct", "src", {}).empty());
}

TEST(ReplayBatches, CheckBlocksNamesTheFirstBadOne) {
  const std::vector<LoadBlock> good{{4000, 0.1, 0, 1}};
  EXPECT_TRUE(check_blocks(good).ok());
  const std::vector<LoadBlock> blocks{{4000, 0.1, 0, 1}, {4000, 1.0, 0, 1}};
  const Status bad = check_blocks(blocks);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().field, "blocks[1].r") << bad.error().message();
  // A history may exceed one batch's cap but not what the engine's int64 cycle count holds:
  // 2^13 blocks of 2^50 cycles sum to 2^63, one more than int64's maximum, at the last block.
  const std::vector<LoadBlock> beyond_batch(2, {4000, 0.1, 0, kMaxBatchCycles});
  EXPECT_TRUE(check_blocks(beyond_batch).ok());
  const std::vector<LoadBlock> beyond_int64(8192, {4000, 0.1, 0, kMaxBatchCycles});
  const Status overflow = check_blocks(beyond_int64);
  ASSERT_FALSE(overflow.ok());
  EXPECT_EQ(overflow.error().field, "blocks[8191].count") << overflow.error().message();
}

TEST(ReplayHistory, ExampleFilesInEveryFormat) {
  const fs::path examples = PERITWIN_EXAMPLES_DIR;
  const auto cycles_read = read_history(examples / "b1-cycles.csv", InputFormat::cycles, "b1-ct");
  ASSERT_TRUE(cycles_read.ok()) << cycles_read.error().message();
  const HistoryBlocks& cycles = *cycles_read;
  EXPECT_EQ(cycles.blocks.size(), 64u);
  const auto spectrum_read =
      read_history(examples / "b1-spectrum.csv", InputFormat::spectrum, "b1-ct");
  ASSERT_TRUE(spectrum_read.ok()) << spectrum_read.error().message();
  const HistoryBlocks& spectrum = *spectrum_read;
  std::int64_t total = 0;
  for (const auto& b : spectrum.blocks) total += b.count;
  EXPECT_EQ(total, 60000);
  const auto series_read = read_history(examples / "b1-series.csv", InputFormat::series, "b1-ct");
  ASSERT_TRUE(series_read.ok()) << series_read.error().message();
  const HistoryBlocks& series = *series_read;
  EXPECT_GT(series.blocks.size(), 10u);
  EXPECT_NE(series.note.find("rainflow"), std::string::npos);
  for (const auto* h : {&cycles, &spectrum, &series}) EXPECT_TRUE(check_blocks(h->blocks).ok());
  const auto missing = read_history(examples / "none.csv", InputFormat::cycles, "b1-ct");
  EXPECT_FALSE(missing.ok());
}

TEST(ReplayHistory, LcmLogKeepsEachBatchOnceInLogOrder) {
  const auto path = fs::temp_directory_path() /
                    ("peritwin_replay_test_" + std::to_string(::getpid()) + ".lcmlog");
  fs::remove(path);
  {
    lcm::LogFile log(path.string(), "w");
    ASSERT_TRUE(log.good());
    auto write = [&](const std::string& channel, const std::vector<std::uint8_t>& bytes) {
      lcm::LogEvent e{};
      e.timestamp = 0;
      e.channel = channel;
      e.datalen = static_cast<std::int32_t>(bytes.size());
      e.data = const_cast<std::uint8_t*>(bytes.data());
      ASSERT_EQ(log.writeEvent(&e), 0);
    };
    auto batch = [](const std::string& detail, std::int64_t seq, double p) {
      const auto m = twin::batch_message({detail, "gauge", seq, {{p, 0.1, 0, 10}}}, 0);
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
      m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
      return bytes;
    };
    const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
    write(load, batch("b1-ct", 1, 1000));
    write(load, batch("b1-ct", 2, 2000));
    write(load, batch("b1-ct", 2, 2000));  // duplicate
    write(load, {1, 2, 3});                // undecodable
    write(messages::channel("b2-cts", messages::Kind::kLoad), batch("b2-cts", 3, 9000));
    write("OTHER", batch("b1-ct", 9, 9000));  // another channel
    write(load, batch("b1-ct", 3, 3000));
  }
  const auto read = read_history(path, InputFormat::lcm_log, "b1-ct");
  ASSERT_TRUE(read.ok()) << read.error().message();
  const HistoryBlocks& h = *read;
  ASSERT_EQ(h.blocks.size(), 3u);
  EXPECT_EQ(h.blocks[0].p_max, 1000);
  EXPECT_EQ(h.blocks[1].p_max, 2000);
  EXPECT_EQ(h.blocks[2].p_max, 3000);
  EXPECT_NE(h.note.find("2 skipped"), std::string::npos) << h.note;
  EXPECT_FALSE(read_history(path, InputFormat::lcm_log, "b2-cts")->blocks.empty());
  fs::remove(path);
}

// One LCM log event as lcm-logger writes it (big-endian header; replay/lcm_log.h), with the
// lengths given explicitly so that they can lie.
std::string log_event(const std::string& channel, const std::string& data,
                      std::int32_t channel_length, std::int32_t data_length) {
  std::string out;
  auto be = [&out](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  be(0xEDA1DA01, 4);
  be(7, 8);              // eventnum
  be(1'700'000'000, 8);  // timestamp
  be(static_cast<std::uint32_t>(channel_length), 4);
  be(static_cast<std::uint32_t>(data_length), 4);
  return out + channel + data;
}

std::string log_event(const std::string& channel, const std::string& data) {
  return log_event(channel, data, static_cast<std::int32_t>(channel.size()),
                   static_cast<std::int32_t>(data.size()));
}

std::string encoded_batch(std::int64_t seq, double p_max) {
  const auto m = twin::batch_message({"b1-ct", "gauge", seq, {{p_max, 0.1, 0, 10}}}, 0);
  std::string bytes(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Found by fuzz_lcm_log: LCM 1.3.1's reader callocs whatever data length an event header claims
// (1.36 GB from a 40-byte file) and ends the log silently at a malformed event. The bounded reader
// refuses each malformed log naming the event and its byte offset, and never stores more than
// kMaxBatchPayload bytes of an event.
TEST(ReplayHistory, MalformedLcmLogsAreRefusedWithTheEventAndItsOffset) {
  const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
  const std::string good = log_event(load, encoded_batch(1, 1000));
  const std::string at = "log: event 2 at byte " + std::to_string(good.size()) + ": ";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {log_event(load, "", 19, 1'358'954'650),
       "log: event 1 at byte 0: the file ends inside the event's 1358954650 data bytes"},
      {good + "garbage", at + "no LCM log sync word (not an LCM log, or corrupt)"},
      {good + log_event(load, "x", 0, 1), at + "channel length 0 is not in 1..999"},
      {good + log_event(std::string(1000, 'C'), "x"), at + "channel length 1000 is not in 1..999"},
      {good + log_event(load, "", 19, -5), at + "negative data length -5"},
      {good + log_event(load, "").substr(0, 10), at + "the file ends inside the event header"},
      {good + log_event(load, "", 19, 0).substr(0, 30),
       at + "the file ends inside the channel name"},
  };
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE(i);
    std::istringstream in(cases[i].first);
    const auto read = read_lcm_log(in, "log", "b1-ct");
    ASSERT_FALSE(read.ok());
    EXPECT_EQ(read.error().message(), cases[i].second);
  }
  // An event too large to be a batch is skipped unread and counted; the log goes on.
  std::istringstream in(good + log_event(load, std::string(messages::kMaxBatchPayload + 1, '\0')) +
                        log_event("OTHER", std::string(100'000, 'x')) +
                        log_event(load, encoded_batch(2, 2000)));
  const auto read = read_lcm_log(in, "log", "b1-ct");
  ASSERT_TRUE(read.ok()) << read.error().message();
  ASSERT_EQ(read.value().blocks.size(), 2u);
  EXPECT_EQ(read.value().blocks[1].p_max, 2000);
  EXPECT_EQ(read.value().note, "LCM log: 3 events on " + load +
                                   ", 1 skipped (undecodable, other detail or duplicate)");
}

TEST(ReplayDescribe, OneLinePerState) {
  peritwin_msgs::damage_state_t s{};
  s.state_seq = 3;
  s.total_cycles = 3000;
  s.broken_bonds = 7;
  s.remaining_cycles = 1000;
  s.remaining_cycles_low = 900;
  s.remaining_cycles_high = 1100;
  s.remaining_life_seq = 2;
  s.failure = 0;
  EXPECT_EQ(describe(s),
            "state 3: 3000 cycles, 7 broken bonds, crack 0.00 mm, remaining 1000 cycles [900, "
            "1100] (estimated at seq 2)");
  s.failure = peritwin_msgs::damage_state_t::FAILURE_END_CRITERION;
  EXPECT_NE(describe(s).find("END OF LIFE"), std::string::npos);
}

}  // namespace
}  // namespace peritwin::replay
