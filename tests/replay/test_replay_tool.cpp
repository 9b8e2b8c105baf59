// The replay tool's library: batching, block checks, history formats (LCM log included).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

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
