// The replay tool's library: batching, block checks, history formats (LCM log included); its
// authentication against a fake daemon, in-process over memq:// (the library) and across
// processes over tcpq:// with LCM's Java hub (the binary and its exit codes; skipped without java
// or lcm.jar). The fake daemon checks every batch's tag on the bytes, as the daemon does, and
// answers with STATE or REJECT signed, unsigned or signed with another key.
//
// Timing: waits on other processes have minute-scale deadlines (kWaitS) and nothing asserts a
// duration; on a loaded machine a run may resend batches, which the fake answers again.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "messages/auth.h"
#include "messages/channels.h"
#include "replay/replay_tool.h"
#include "tests/support/lcm_hub.h"
#include "tests/support/process.h"

namespace peritwin::replay {
namespace {

namespace fs = std::filesystem;

// Issue 30: a history's fingerprint is that of its batches (blocks and where the batches are
// cut), whatever they are numbered from and whoever sends them; every batch carries it with the
// history's first seq, within the rule check_batch applies.
TEST(ReplayBatches, TheHistoryFingerprintIsTheBatchesNotTheirIdsOrSeqs) {
  std::vector<core::LoadBlock> blocks;
  for (int i = 0; i < 10; ++i) blocks.push_back({4000.0 + 10.0 * i, 0.1, 0.0, 600});
  auto batches = loads::make_twin_batches(blocks, "b1-ct", "replay", {16, 1000});
  ASSERT_EQ(batches.size(), 5u);
  loads::mark_history(batches);
  const std::uint64_t fingerprint = batches.front().history;
  EXPECT_NE(fingerprint, 0u);
  EXPECT_EQ(fingerprint, loads::history_fingerprint(batches));
  for (const auto& b : batches) {
    EXPECT_EQ(b.history, fingerprint);
    EXPECT_EQ(b.history_start, 1);
    EXPECT_TRUE(messages::check_batch(b, "b1-ct").applied());
  }
  // Appended at seq 6 by another source: the same history.
  auto appended = loads::make_twin_batches(blocks, "b1-ct", "gauge", {16, 1000}, 6);
  loads::mark_history(appended);
  EXPECT_EQ(appended.back().history, fingerprint);
  EXPECT_EQ(appended.back().history_start, 6);
  EXPECT_TRUE(messages::check_batch(appended.back(), "b1-ct").applied());
  // Cut otherwise, or one load otherwise: another history.
  EXPECT_NE(
      loads::history_fingerprint(loads::make_twin_batches(blocks, "b1-ct", "replay", {16, 2000})),
      fingerprint);
  blocks[7].p_max += 1e-9;
  EXPECT_NE(
      loads::history_fingerprint(loads::make_twin_batches(blocks, "b1-ct", "replay", {16, 1000})),
      fingerprint);
  // history_start: 1..seq with a history, 0 without.
  messages::Batch b = batches[2];  // seq 3
  for (const std::int64_t start : {std::int64_t{0}, std::int64_t{4}, std::int64_t{-1}}) {
    b.history_start = start;
    const auto o = messages::check_batch(b, "b1-ct");
    EXPECT_EQ(o.verdict, messages::Verdict::invalid) << start;
    EXPECT_EQ(o.what, "history_start");
    EXPECT_EQ(o.why, "history_start = " + std::to_string(start) + " must be 1 to seq = 3");
  }
  b.history = 0;
  b.history_start = 1;
  EXPECT_EQ(messages::check_batch(b, "b1-ct").why, "history_start = 1 must be 0 without a history");
  b.history_start = 0;
  EXPECT_TRUE(messages::check_batch(b, "b1-ct").applied());
}

TEST(ReplayBatches, ByBlocksAndCyclesWithSequentialSeq) {
  std::vector<peritwin::core::LoadBlock> blocks;
  for (int i = 0; i < 40; ++i) blocks.push_back({4000, 0.1, 0, 1});
  blocks.push_back({4000, 0.1, 0, 5000});
  blocks.push_back({4000, 0.1, 0, 1});
  const auto batches = loads::make_twin_batches(blocks, "b1-ct", "src", {16, 1000});
  ASSERT_EQ(batches.size(), 4u);  // 16 + 16 + (8 + the 5000-cycle block) + 1
  EXPECT_EQ(batches[0].blocks.size(), 16u);
  EXPECT_EQ(batches[2].blocks.size(), 9u);
  EXPECT_EQ(batches[3].blocks.size(), 1u);
  for (std::size_t i = 0; i < batches.size(); ++i) {
    EXPECT_EQ(batches[i].seq, static_cast<std::int64_t>(i) + 1);
    EXPECT_EQ(batches[i].detail_id, "b1-ct");
    EXPECT_EQ(batches[i].source_id, "src");
  }
  EXPECT_TRUE(loads::make_twin_batches({}, "b1-ct", "src", {}).empty());
}

TEST(ReplayBatches, ContinueNumbersFromTheGivenSeq) {
  const std::vector<core::LoadBlock> blocks(3, {4000, 0.1, 0, 1000});
  const auto batches = loads::make_twin_batches(blocks, "b1-ct", "src", {1024, 1000}, 6);
  ASSERT_EQ(batches.size(), 3u);
  EXPECT_EQ(batches[0].seq, 6);
  EXPECT_EQ(batches[2].seq, 8);
}

TEST(ReplayBatches, StreamBatcherClosesBySampleTime) {
  // 2 s of sample time per batch; blocks arrive between ticks.
  loads::Batcher batcher("b1-ct", "s", 1, {1024, 1000, 2.0});
  std::vector<messages::Batch> out;
  batcher.tick(10.0, out);  // opens at t = 10
  batcher.add({4000, 0.1, 0, 1}, out);
  batcher.tick(11.5, out);
  EXPECT_TRUE(out.empty());
  batcher.add({4000, 0.1, 0, 1}, out);
  batcher.tick(12.0, out);  // 2 s: closed with both blocks, the next one opens at 12
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].blocks.size(), 2u);
  EXPECT_EQ(out[0].seq, 1);
  batcher.tick(14.0, out);  // nothing in it: no empty batch
  EXPECT_EQ(out.size(), 1u);
  batcher.add({4000, 0.1, 0, 999}, out);
  batcher.add({4000, 0.1, 0, 1}, out);  // the cycle rule still closes it
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].seq, 2);
  batcher.add({4000, 0.1, 0, 1}, out);
  batcher.flush(out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(batcher.next_seq(), 4);
}

TEST(ReplayBatches, StreamBatcherMergesIdenticalConsecutiveBlocks) {
  loads::BatchingOptions options{1024, 5, 0.0, true};
  loads::Batcher batcher("b1-ct", "s", 1, options);
  std::vector<messages::Batch> out;
  for (int i = 0; i < 3; ++i) batcher.add({4000, 0.1, 0, 1}, out);
  batcher.add({3000, 0.1, 0, 1}, out);
  batcher.add({3000, 0.1, 0, 1}, out);  // 5 cycles: closed
  ASSERT_EQ(out.size(), 1u);
  ASSERT_EQ(out[0].blocks.size(), 2u);
  EXPECT_EQ(out[0].blocks[0].count, 3);
  EXPECT_EQ(out[0].blocks[1].count, 2);
}

TEST(ReplayBatches, CheckBlocksNamesTheFirstBadOne) {
  const std::vector<core::LoadBlock> good{{4000, 0.1, 0, 1}};
  EXPECT_TRUE(replay::check_blocks(good).ok());
  const std::vector<core::LoadBlock> blocks{{4000, 0.1, 0, 1}, {4000, 1.0, 0, 1}};
  const core::Status bad = replay::check_blocks(blocks);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().field, "blocks[1].r") << bad.error().message();
  // A history may exceed one batch's cap but not what the engine's int64 cycle count holds:
  // 2^13 blocks of 2^50 cycles sum to 2^63, one more than int64's maximum, at the last block.
  const std::vector<core::LoadBlock> beyond_batch(2, {4000, 0.1, 0, core::kMaxBatchCycles});
  EXPECT_TRUE(replay::check_blocks(beyond_batch).ok());
  const std::vector<core::LoadBlock> beyond_int64(8192, {4000, 0.1, 0, core::kMaxBatchCycles});
  const core::Status overflow = replay::check_blocks(beyond_int64);
  ASSERT_FALSE(overflow.ok());
  EXPECT_EQ(overflow.error().field, "blocks[8191].count") << overflow.error().message();
}

TEST(ReplayHistory, ExampleFilesInEveryFormat) {
  const fs::path examples = PERITWIN_EXAMPLES_DIR;
  const auto cycles_read =
      replay::read_history(examples / "b1-cycles.csv", replay::InputFormat::cycles, "b1-ct");
  ASSERT_TRUE(cycles_read.ok()) << cycles_read.error().message();
  const replay::HistoryBlocks& cycles = *cycles_read;
  EXPECT_EQ(cycles.blocks.size(), 64u);
  const auto spectrum_read =
      replay::read_history(examples / "b1-spectrum.csv", replay::InputFormat::spectrum, "b1-ct");
  ASSERT_TRUE(spectrum_read.ok()) << spectrum_read.error().message();
  const replay::HistoryBlocks& spectrum = *spectrum_read;
  std::int64_t total = 0;
  for (const auto& b : spectrum.blocks) total += b.count;
  EXPECT_EQ(total, 60000);
  const auto series_read =
      replay::read_history(examples / "b1-series.csv", replay::InputFormat::series, "b1-ct");
  ASSERT_TRUE(series_read.ok()) << series_read.error().message();
  const replay::HistoryBlocks& series = *series_read;
  EXPECT_GT(series.blocks.size(), 10u);
  EXPECT_NE(series.note.find("rainflow"), std::string::npos);
  for (const auto* h : {&cycles, &spectrum, &series})
    EXPECT_TRUE(replay::check_blocks(h->blocks).ok());
  const auto missing =
      replay::read_history(examples / "none.csv", replay::InputFormat::cycles, "b1-ct");
  EXPECT_FALSE(missing.ok());
}

// A series whose only cycle has R = -11 (the issue's "100, -1100", refused before as
// blocks[0].r = -11 < -10) with two dropouts: applied as the same range at R = -10
// (loads/cycle_blocks.h), the counts reach HistoryBlocks, the stderr line and the summary.
TEST(ReplayHistory, SeriesRulesReachTheBlocksTheCountsAndTheSummary) {
  const fs::path path =
      fs::temp_directory_path() / ("peritwin_replay_series_" + std::to_string(::getpid()) + ".csv");
  std::ofstream(path) << "time_s,load_N\n0,100\n1,nan\n2,-1100\n3,inf\n";
  const auto half = replay::read_history(path, replay::InputFormat::series, "b1-ct");
  ASSERT_TRUE(half.ok()) << half.error().message();
  EXPECT_EQ(half->blocks, (std::vector<core::LoadBlock>{{1200.0 / 11.0, -10.0, 0.0, 1}}));
  EXPECT_TRUE(replay::check_blocks(half->blocks).ok());
  ASSERT_TRUE(half->conversion.has_value());
  EXPECT_EQ(half->conversion->skipped.remapped_below_floor, 0.5);
  EXPECT_EQ(half->conversion->nonfinite_samples, 2u);
  EXPECT_EQ(replay::describe_skipped(*half->conversion),
            "skipped cycles: compressive 0, mirrored_compressive 0, remapped_below_floor 0.5, "
            "degenerate 0, nonfinite_samples 2");
  peritwin_msgs::damage_state_t state{};
  state.detail_id = "b1-ct";
  const std::string summary = messages::summary_json(
      state, {{"skipped_cycles", replay::skipped_cycles(*half->conversion)}});
  const std::string tail = R"(,"skipped_cycles":{"compressive":0,"mirrored_compressive":0,)"
                           R"("remapped_below_floor":0.5,"degenerate":0,"nonfinite_samples":2}})";
  ASSERT_GE(summary.size(), tail.size());
  EXPECT_EQ(summary.substr(summary.size() - tail.size()), tail) << summary;
  EXPECT_EQ(messages::summary_json(state).find("skipped_cycles"), std::string::npos);
  // keep: the only range is the open residue, nothing is applied; whole: one whole cycle.
  loads::SeriesRules keep;
  keep.residue = loads::ResidueRule::keep;
  const auto kept = replay::read_history(path, replay::InputFormat::series, "b1-ct", keep);
  ASSERT_TRUE(kept.ok());
  EXPECT_TRUE(kept->blocks.empty());
  loads::SeriesRules whole;
  whole.residue = loads::ResidueRule::whole;
  const auto whole_read = replay::read_history(path, replay::InputFormat::series, "b1-ct", whole);
  ASSERT_TRUE(whole_read.ok());
  EXPECT_EQ(whole_read->blocks, half->blocks);
  EXPECT_EQ(whole_read->conversion->full_cycles, 1u);
  EXPECT_EQ(whole_read->conversion->rounded_up_half_cycles, 0u);
  // Other formats carry no conversion counts.
  EXPECT_FALSE(replay::read_history(fs::path(PERITWIN_EXAMPLES_DIR) / "b1-cycles.csv",
                                    replay::InputFormat::cycles, "b1-ct")
                   ->conversion.has_value());
  fs::remove(path);
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
      const auto m = messages::batch_message({detail, "gauge", seq, {{p, 0.1, 0, 10}}}, 0);
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
  const auto read = replay::read_history(path, replay::InputFormat::lcm_log, "b1-ct");
  ASSERT_TRUE(read.ok()) << read.error().message();
  const replay::HistoryBlocks& h = *read;
  ASSERT_EQ(h.blocks.size(), 3u);
  EXPECT_EQ(h.blocks[0].p_max, 1000);
  EXPECT_EQ(h.blocks[1].p_max, 2000);
  EXPECT_EQ(h.blocks[2].p_max, 3000);
  EXPECT_NE(h.note.find("2 skipped"), std::string::npos) << h.note;
  EXPECT_FALSE(replay::read_history(path, replay::InputFormat::lcm_log, "b2-cts")->blocks.empty());
  fs::remove(path);
}

// One LCM log event as lcm-logger writes it (big-endian header; loads/lcm_log.h), with the
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
  const auto m = messages::batch_message({"b1-ct", "gauge", seq, {{p_max, 0.1, 0, 10}}}, 0);
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
    const auto read = replay::read_lcm_log(in, "log", "b1-ct");
    ASSERT_FALSE(read.ok());
    EXPECT_EQ(read.error().message(), cases[i].second);
  }
  // An event too large to be a batch is skipped unread and counted; the log goes on.
  std::istringstream in(good + log_event(load, std::string(messages::kMaxBatchPayload + 1, '\0')) +
                        log_event("OTHER", std::string(100'000, 'x')) +
                        log_event(load, encoded_batch(2, 2000)));
  const auto read = replay::read_lcm_log(in, "log", "b1-ct");
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

TEST(ReplayDescribe, TheRemainingLifeCountsDownBetweenEstimates) {
  // B1 in the demo: estimate at the initial state 38,373 cycles [30,000, 48,000]; after batches
  // of 1000 cycles the text line counts down by exactly the cycles applied; a new estimate made
  // after batch 10 (10,000 cycles) counts down from there.
  replay::LifeCountdown countdown;
  auto state = [](std::int64_t seq, double remaining, std::int64_t life_seq) {
    peritwin_msgs::damage_state_t s{};
    s.state_seq = seq;
    s.total_cycles = 1000 * seq;
    if (seq > 0) {
      s.num_sources = 1;
      s.source_ids = {"replay"};
      s.applied_seq = {seq};
    }
    s.remaining_cycles = remaining;
    s.remaining_cycles_low = remaining - 8373;
    s.remaining_cycles_high = remaining + 9627;
    s.remaining_life_seq = life_seq;
    s.remaining_life_source = life_seq < 0 ? "" : "replay";
    s.failure = 0;
    return s;
  };
  for (std::int64_t seq = 0; seq <= 9; ++seq) {
    const auto s = state(seq, 38373, -1);
    const auto at = countdown.observe(s);
    ASSERT_EQ(at, 0) << seq;
    EXPECT_EQ(describe(s, at),
              "state " + std::to_string(seq) + ": " + std::to_string(1000 * seq) +
                  " cycles, 0 broken bonds, crack 0.00 mm, remaining " +
                  std::to_string(38373 - 1000 * seq) + " cycles [" +
                  std::to_string(30000 - 1000 * seq) + ", " + std::to_string(48000 - 1000 * seq) +
                  "] (estimated at cycle 0, " + std::to_string(1000 * seq) + " cycles ago)");
  }
  // The estimate of state 10 arrives with state 11 (the life worker lags by one).
  ASSERT_EQ(countdown.observe(state(10, 38373, -1)), 0);
  const auto s11 = state(11, 28000, 10);
  const auto at = countdown.observe(s11);
  ASSERT_EQ(at, 10000);
  EXPECT_NE(describe(s11, at).find("remaining 27000 cycles [18627, 36627] (estimated at cycle "
                                   "10000, 1000 cycles ago)"),
            std::string::npos)
      << describe(s11, at);
  // An estimate of a batch never seen (before this printer started) is shown as published.
  const auto unseen = state(12, 5000, 3);
  replay::LifeCountdown late;
  EXPECT_FALSE(late.observe(unseen).has_value());
  // After a missed state the next one's batch is not dated (a source that moved in the missed
  // state would be dated too late): state 14 after 12 leaves batch 14 unknown, 15 after 14 not.
  EXPECT_FALSE(late.observe(state(14, 5000, 14)).has_value());
  EXPECT_EQ(late.observe(state(15, 5000, 15)), 15000);
  EXPECT_NE(describe(unseen, std::nullopt)
                .find("remaining 5000 cycles [-3373, 14627] (estimated "
                      "at seq 3)"),
            std::string::npos);
}

// --- authentication against a fake daemon ------------------------------------------------

/// Deadline of every wait on another process or on a replay run.
constexpr double kWaitS = 600.0;

/// How the fake daemon answers a batch.
enum class Answer {
  signed_states,     ///< STATE signed with the daemon key (only for a batch that verifies)
  unsigned_states,   ///< STATE without a tag
  wrong_key_states,  ///< STATE signed with a key that is not the daemon's
  unsigned_reject,   ///< REJECT (GAP) without a tag
  auth_reject,       ///< REJECT CODE_AUTH, signed, as a daemon with another key for the source
  invalid_reject,    ///< REJECT CODE_INVALID (p_max above max_p) for every batch, signed
  failed_reject,     ///< REJECT CODE_FAILED for every batch: a detail that had ended before
  end_of_life,       ///< seq 1 applied and the end of life reached, CODE_FAILED for the others
  /// signed_states, each after a genuine signed STATE of an earlier run (source "replay" at seq
  /// 3, hash "old-3", echoing that run's nonce) and its CODE_FAILED reject of the batch's seq,
  /// published again (issue 30: a tag proves who made a message, not when)
  old_answers_first,
};

/// The nonce of the earlier run whose answers Answer::old_answers_first publishes again.
constexpr std::uint64_t kEarlierRunNonce = 0x0123456789abcdefULL;

/// Answers every batch on b1-ct's LOAD channel of `lcm` like a daemon would, after checking its
/// tag on the received bytes with tag_matches(source key, bytes, signed_size, auth_tag) — the
/// daemon's check.
class FakeDaemon {
 public:
  FakeDaemon(lcm::LCM& lcm, Answer answer, messages::AuthKey daemon_key,
             messages::AuthKey source_key)
      : lcm_(lcm), answer_(answer), daemon_key_(daemon_key), source_key_(source_key) {
    sub_ = lcm_.subscribe(messages::channel("b1-ct", messages::Kind::kLoad), &FakeDaemon::on_load,
                          this);
  }
  ~FakeDaemon() { lcm_.unsubscribe(sub_); }
  FakeDaemon(const FakeDaemon&) = delete;
  FakeDaemon& operator=(const FakeDaemon&) = delete;

  [[nodiscard]] int batches() const { return batches_.load(); }
  [[nodiscard]] int verified() const { return verified_.load(); }

 private:
  void on_load(const lcm::ReceiveBuffer* rb, const std::string&) {
    ++batches_;
    const auto* bytes = static_cast<const std::uint8_t*>(rb->data);
    const messages::Decoded d = messages::decode_batch(bytes, rb->data_size);
    if (!d.batch) return;
    const bool ok = messages::tag_matches(source_key_, bytes, d.signed_size, d.auth_tag);
    if (ok) ++verified_;
    const std::string& source = d.batch->source_id;
    const std::uint64_t nonce = d.batch->nonce;  // echoed in every answer, as the daemon does
    if (answer_ == Answer::old_answers_first) publish_old_answers(d.batch->seq);
    if (answer_ == Answer::auth_reject || answer_ == Answer::unsigned_reject) {
      auto r = messages::reject_message(
          "b1-ct", source, d.batch->seq,
          answer_ == Answer::auth_reject
              ? messages::Outcome{messages::Verdict::auth, "auth_tag",
                                  "wrong tag for source \"" + source + "\""}
              : messages::Outcome{messages::Verdict::gap, "seq", "forged gap"},
          messages::now_utime(), nonce);
      if (answer_ == Answer::auth_reject) messages::sign(r, daemon_key_);
      lcm_.publish(messages::channel("b1-ct", messages::Kind::kReject), &r);
      return;
    }
    const bool failed =
        answer_ == Answer::failed_reject || (answer_ == Answer::end_of_life && d.batch->seq > 1);
    if (answer_ == Answer::invalid_reject || failed) {
      auto r = messages::reject_message(
          "b1-ct", source, d.batch->seq,
          failed ? messages::Outcome{messages::Verdict::failed, "message",
                                     "the detail reached its end-of-life criterion at cycle 700; "
                                     "it applies no more cycles"}
                 : messages::Outcome{messages::Verdict::invalid, "blocks[0].p_max",
                                     "p_max = 4e+06 N is above the detail's bound max_p = 40000 N"},
          messages::now_utime(), nonce);
      messages::sign(r, daemon_key_);
      lcm_.publish(messages::channel("b1-ct", messages::Kind::kReject), &r);
      return;
    }
    const bool signs = answer_ == Answer::signed_states || answer_ == Answer::end_of_life ||
                       answer_ == Answer::old_answers_first;
    if (!ok && signs) return;  // a daemon with [auth] rejects it
    if (d.batch->seq == applied_ + 1) ++applied_;
    auto s = state(source, applied_, "fake-" + std::to_string(applied_), nonce);
    if (answer_ == Answer::end_of_life) s.failure = 1;
    if (signs) messages::sign(s, daemon_key_);
    if (answer_ == Answer::wrong_key_states) {
      messages::AuthKey other = daemon_key_;
      other.bytes[0] ^= 1;
      messages::sign(s, other);
    }
    lcm_.publish(messages::channel("b1-ct", messages::Kind::kState), &s);
  }

  static peritwin_msgs::damage_state_t state(const std::string& source, std::int64_t applied,
                                             const std::string& hash, std::uint64_t nonce) {
    peritwin_msgs::damage_state_t s{};
    s.utime = messages::now_utime();
    s.detail_id = "b1-ct";
    s.state_seq = applied;
    s.source_ids = {source};
    s.applied_seq = {applied};
    s.checkpointed_seq = {0};
    s.history = {0};
    s.history_start = {0};
    s.num_sources = 1;
    s.total_cycles = 1000 * applied;
    s.k_i = s.k_ii = std::numeric_limits<double>::quiet_NaN();
    s.remaining_cycles = s.remaining_cycles_low = s.remaining_cycles_high = s.k_i;
    s.remaining_life_seq = -1;
    s.state_hash = hash;
    s.echo_source = source;
    s.echo_nonce = static_cast<std::int64_t>(nonce);
    return s;
  }

  /// What the daemon signed for an earlier run of source "replay": its final STATE (seq 3
  /// applied) and a CODE_FAILED reject of batch `seq`.
  void publish_old_answers(std::int64_t seq) {
    auto s = state("replay", 3, "old-3", kEarlierRunNonce);
    messages::sign(s, daemon_key_);
    lcm_.publish(messages::channel("b1-ct", messages::Kind::kState), &s);
    auto r = messages::reject_message(
        "b1-ct", "replay", seq,
        {messages::Verdict::failed, "message", "an earlier run's detail had ended"},
        messages::now_utime(), kEarlierRunNonce);
    messages::sign(r, daemon_key_);
    lcm_.publish(messages::channel("b1-ct", messages::Kind::kReject), &r);
  }

  lcm::LCM& lcm_;
  Answer answer_;
  messages::AuthKey daemon_key_, source_key_;
  lcm::Subscription* sub_ = nullptr;
  std::atomic<int> batches_{0}, verified_{0};
  std::int64_t applied_ = 0;
};

messages::AuthKey test_key(std::uint8_t seed) {
  messages::AuthKey k;
  for (std::size_t i = 0; i < k.bytes.size(); ++i)
    k.bytes[i] = static_cast<std::uint8_t>(seed * 31 + i);
  return k;
}

std::vector<messages::Batch> three_batches() {
  const std::vector<core::LoadBlock> blocks(3, {4000, 0.1, 0, 1000});
  return loads::make_twin_batches(blocks, "b1-ct", "replay", {1024, 1000});
}

/// The library on memq://: the replayer and the fake share one LCM.
struct MemqRun {
  replay::ReplayResult result;
  int batches = 0, verified = 0;
  std::vector<std::string> hashes;  ///< of the states the run accepted
};
MemqRun run_memq(Answer answer, loads::ReplayAuth auth) {
  lcm::LCM lcm("memq://");
  EXPECT_TRUE(lcm.good());
  const messages::AuthKey daemon = test_key(1), source = test_key(2);
  FakeDaemon fake(lcm, answer, daemon, source);
  MemqRun run;
  replay::LcmReplayer replayer(lcm, three_batches(), {true, 1, 3.0, kWaitS}, std::move(auth));
  run.result = replayer.run([&](const auto& s) { run.hashes.push_back(s.state_hash); });
  run.batches = fake.batches();
  run.verified = fake.verified();
  return run;
}

loads::ReplayAuth both_keys() { return {test_key(2), test_key(1), "peritwin"}; }

TEST(ReplayAuthMemq, SignedBatchesAndVerifiedStates) {
  const auto run = run_memq(Answer::signed_states, both_keys());
  ASSERT_TRUE(run.result.ok) << run.result.error;
  ASSERT_TRUE(run.result.final_state);
  EXPECT_EQ(run.result.final_state->state_hash, "fake-3");
  EXPECT_EQ(run.hashes, (std::vector<std::string>{"fake-1", "fake-2", "fake-3"}));
  EXPECT_GE(run.batches, 3);
  EXPECT_EQ(run.verified, run.batches);  // every batch carried the source's tag
}

TEST(ReplayAuthMemq, UnsignedOrForeignStateEndsTheRun) {
  for (const auto& [answer, why] : {std::pair{Answer::unsigned_states, "unsigned"},
                                    std::pair{Answer::wrong_key_states, "wrong tag"}}) {
    const auto run = run_memq(answer, both_keys());
    EXPECT_FALSE(run.result.ok);
    EXPECT_EQ(run.result.error,
              std::string("PERITWIN_B1_CT_STATE: state_seq 1 of detail \"b1-ct\": ") + why +
                  " (not from the holder of daemon key \"peritwin\")");
    EXPECT_TRUE(run.hashes.empty());  // nothing unverified reached on_state
    EXPECT_FALSE(run.result.final_state);
  }
}

TEST(ReplayAuthMemq, UnsignedRejectAndAuthRejectEndTheRun) {
  const auto forged = run_memq(Answer::unsigned_reject, both_keys());
  EXPECT_FALSE(forged.result.ok);
  EXPECT_EQ(forged.result.error,
            "PERITWIN_B1_CT_REJECT: reject of source \"replay\" seq 1: unsigned (not from the "
            "holder of daemon key \"peritwin\")");
  const auto refused = run_memq(Answer::auth_reject, both_keys());
  EXPECT_FALSE(refused.result.ok);
  EXPECT_EQ(refused.result.error,
            "the daemon refused batch 1 of source \"replay\" (CODE_AUTH): auth_tag: wrong tag for "
            "source \"replay\"");
  // Unsigned batches to a daemon that wants them signed: the same, with a hint.
  const auto unsigned_run = run_memq(Answer::auth_reject, {});
  EXPECT_FALSE(unsigned_run.result.ok);
  EXPECT_NE(unsigned_run.result.error.find("give it --key-file"), std::string::npos)
      << unsigned_run.result.error;
  EXPECT_EQ(unsigned_run.verified, 0);
}

// Issue 30: the answers the daemon signed for an earlier run, published again during this one,
// are not this run's: its states (echoing its nonce) are taken, the old STATE (seq 3 applied,
// which would have ended this three-batch run at once) and the old FAILED rejects are not.
TEST(ReplayAuthMemq, AnEarlierRunsSignedAnswersPublishedAgainAreNotThisRunsProgress) {
  const auto run = run_memq(Answer::old_answers_first, both_keys());
  ASSERT_TRUE(run.result.ok) << run.result.error;
  EXPECT_TRUE(run.result.end_of_life.empty()) << run.result.end_of_life;
  ASSERT_TRUE(run.result.final_state);
  EXPECT_EQ(run.result.final_state->state_hash, "fake-3");
  // Each state of this run (one may come twice: the old STATE disagrees with the run, which then
  // probes, and the probe's answer is the current state again), never the old one.
  std::vector<std::string> hashes = run.hashes;
  hashes.erase(std::unique(hashes.begin(), hashes.end()), hashes.end());
  EXPECT_EQ(hashes, (std::vector<std::string>{"fake-1", "fake-2", "fake-3"}));
  EXPECT_GE(run.result.stale_states, 3);  // one before the answer to each batch
  EXPECT_EQ(run.verified, run.batches);
}

TEST(ReplayAuthMemq, WithoutKeysAForgedStateIsBelieved) {
  // The documented limit of a run without --key-file: unsigned states are taken as they come
  // (they echo the run's nonce, which anyone on the bus can read off its batches).
  const auto run = run_memq(Answer::unsigned_states, {});
  ASSERT_TRUE(run.result.ok) << run.result.error;
  EXPECT_EQ(run.result.final_state->state_hash, "fake-3");
  EXPECT_EQ(run.verified, 0);
}

// A reject no resend can cure ends the run at once with the daemon's reason: INVALID (and
// AUTH, LIMIT) fail it after the one batch, not after give_up_after_s of resends (kWaitS here).
TEST(ReplayRejectMemq, InvalidRejectEndsTheRunAtOnceWithTheReason) {
  const auto run = run_memq(Answer::invalid_reject, both_keys());
  EXPECT_FALSE(run.result.ok);
  EXPECT_EQ(run.result.error,
            "the daemon refused batch 1 of source \"replay\" (CODE_INVALID): blocks[0].p_max: "
            "p_max = 4e+06 N is above the detail's bound max_p = 40000 N (not sent again: no "
            "resend can change that)");
  EXPECT_EQ(run.batches, 1);  // lockstep: batch 1, never resent
}

// FAILED: done when a batch of the run was applied before it (the run reached the end of life,
// the rest is not applied, and the reason is kept), failed when none was (the detail had ended).
TEST(ReplayRejectMemq, FailedIsTheEndOfLifeOnlyAfterABatchOfTheRun) {
  const auto reached = run_memq(Answer::end_of_life, both_keys());
  ASSERT_TRUE(reached.result.ok) << reached.result.error;
  EXPECT_EQ(reached.result.end_of_life,
            "the daemon refused batch 2 of source \"replay\" (CODE_FAILED): message: the detail "
            "reached its end-of-life criterion at cycle 700; it applies no more cycles");
  EXPECT_EQ(reached.batches, 2);
  const auto ended = run_memq(Answer::failed_reject, both_keys());
  EXPECT_FALSE(ended.result.ok);
  EXPECT_NE(ended.result.error.find("(CODE_FAILED): message: the detail reached its end-of-life "
                                    "criterion at cycle 700; it applies no more cycles; none of "
                                    "this run's batches was applied"),
            std::string::npos)
      << ended.result.error;
}

// [detail.limits] max_p set in the config: a history above it is named before anything is sent.
TEST(ReplayPeak, AHistoryAboveTheConfiguredMaxPIsNamed) {
  config::LimitsConfig limits;
  const std::vector<core::LoadBlock> blocks{{4000, 0.1, 0, 10}, {4e6, 0.1, 0, 10}, {5e6, 0, 0, 1}};
  EXPECT_TRUE(check_peak(blocks, limits));  // max_p derived from the model: not known here
  limits.max_p = 5000.0;
  const core::Status peak = check_peak(blocks, limits);
  ASSERT_FALSE(peak);
  EXPECT_EQ(peak.error().field, "blocks[1].p_max");
  EXPECT_EQ(peak.error().reason,
            "p_max = 4e+06 N is above the detail's [detail.limits] max_p = 5000 N (the history's "
            "peak is 5e+06 N, 1e+03 x max_p: a load in the wrong unit?)");
  EXPECT_TRUE(check_peak(std::vector<core::LoadBlock>{{5000, 0.1, 0, 1}}, limits));
}

TEST(ReplayPeak, TheBinaryExitsTwoBeforeSendingAnything) {
  const fs::path dir =
      fs::temp_directory_path() / ("peritwin_replay_peak_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ifstream in(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
  std::string config((std::istreambuf_iterator<char>(in)), {});
  const std::string commented = "# max_p = 40000.0";
  ASSERT_NE(config.find(commented), std::string::npos);
  config.replace(config.find(commented), commented.size(), "max_p = 5000.0");
  std::ofstream(dir / "b1.toml") << config;
  std::ofstream(dir / "kn-as-n.csv") << "p_max_N,r,angle_rad,count\n4000,0.1,0,1000\n"
                                        "4000000,0.1,0,1000\n";
  // An LCM URL nobody listens on: a run that got as far as sending would exit 3.
  peritwin::testing::Process r(
      {std::string(PERITWIN_BIN_DIR) + "/peritwin-replay", "--config", (dir / "b1.toml").string(),
       "--history", (dir / "kn-as-n.csv").string(), "--lcm-url", "tcpq://127.0.0.1:1"},
      (dir / "replay.log").string());
  const auto status = r.wait_for(kWaitS);
  ASSERT_TRUE(status && WIFEXITED(*status));
  EXPECT_EQ(WEXITSTATUS(*status), 2);
  std::ifstream log_in(dir / "replay.log");
  const std::string log((std::istreambuf_iterator<char>(log_in)), {});
  EXPECT_NE(log.find("kn-as-n.csv: blocks[1].p_max: p_max = 4e+06 N is above the detail's "
                     "[detail.limits] max_p = 5000 N"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("nothing sent"), std::string::npos) << log;
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

/// The binary over tcpq:// with LCM's Java hub (one per suite) and the fake daemon on a thread.
class ReplayAuthBinary : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    hub_log_ = fs::temp_directory_path() /
               ("peritwin_replay_auth_hub_" + std::to_string(::getpid()) + ".log");
    hub_ = new peritwin::testing::LcmHub(hub_log_, kWaitS);
  }
  static void TearDownTestSuite() {
    delete hub_;
    hub_ = nullptr;
    fs::remove(hub_log_);
  }
  void SetUp() override {
    if (!hub_->missing().empty()) GTEST_SKIP() << hub_->missing();
    ASSERT_TRUE(hub_->up()) << "no LCM hub of this test (see " << hub_log_ << ")";
    dir_ = fs::temp_directory_path() /
           ("peritwin_replay_auth_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    history_ = dir_ / "history.csv";
    std::ofstream(history_) << "p_max_N,r,angle_rad,count\n4000,0.1,0,1000\n4000,0.1,0,1000\n"
                               "4000,0.1,0,1000\n";
    keys_ = dir_ / "keys.toml";
    const auto generated = exit_code(run_replay({"--generate-key-file", keys_.string()}));
    ASSERT_EQ(generated, 0) << log();
    const auto ring = messages::KeyRing::load(keys_);
    ASSERT_TRUE(ring.ok()) << ring.error().message();
    ASSERT_EQ(ring->ids(), (std::vector<std::string>{"peritwin", "replay"}));
    replay_key_ = *ring->find("replay");
    daemon_key_ = *ring->find("peritwin");
  }
  void TearDown() override {
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }

  std::unique_ptr<peritwin::testing::Process> run_replay(const std::vector<std::string>& args) {
    std::vector<std::string> argv{std::string(PERITWIN_BIN_DIR) + "/peritwin-replay"};
    argv.insert(argv.end(), args.begin(), args.end());
    return std::make_unique<peritwin::testing::Process>(argv, (dir_ / "replay.log").string());
  }
  /// A lockstep replay of the three-batch history with `args` added.
  std::unique_ptr<peritwin::testing::Process> replay_over_hub(std::vector<std::string> args) {
    std::vector<std::string> argv{
        "--config",        std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml",
        "--history",       history_.string(),
        "--json",          "--lcm-url",
        hub_->url(),       "--lockstep",
        "--give-up-after", "600"};
    argv.insert(argv.end(), args.begin(), args.end());
    return run_replay(argv);
  }
  /// Exit code, or -1 when it did not exit normally within kWaitS.
  static int exit_code(const std::unique_ptr<peritwin::testing::Process>& p) {
    const auto status = p->wait_for(kWaitS);
    return status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
  }
  static std::vector<std::string> lines_to_end(peritwin::testing::Process& p) {
    std::vector<std::string> lines;
    while (auto line = p.read_line(kWaitS)) lines.push_back(*line);
    return lines;
  }
  std::string log() const {
    std::ifstream in(dir_ / "replay.log");
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  /// Runs the fake daemon on its own LCM connection to the hub while `body` runs.
  struct FakeOnHub {
    FakeOnHub(const std::string& url, Answer answer, messages::AuthKey daemon,
              messages::AuthKey source)
        : lcm(url), fake(lcm, answer, daemon, source), thread([this] {
            while (!stop.load()) lcm.handleTimeout(50);
          }) {}
    ~FakeOnHub() {
      stop.store(true);
      thread.join();
    }
    lcm::LCM lcm;
    FakeDaemon fake;
    std::atomic<bool> stop{false};
    std::thread thread;
  };

  static inline peritwin::testing::LcmHub* hub_ = nullptr;
  static inline fs::path hub_log_;
  fs::path dir_, history_, keys_;
  messages::AuthKey replay_key_, daemon_key_;
};

TEST_F(ReplayAuthBinary, SignedStatesExitZero) {
  FakeOnHub daemon(hub_->url(), Answer::signed_states, daemon_key_, replay_key_);
  ASSERT_TRUE(daemon.lcm.good());
  auto r = replay_over_hub({"--key-file", keys_.string()});
  const auto lines = lines_to_end(*r);
  ASSERT_EQ(exit_code(r), 0) << log();
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("\"state_hash\":\"fake-3\""), std::string::npos) << lines.back();
  EXPECT_GE(daemon.fake.batches(), 3);
  EXPECT_EQ(daemon.fake.verified(), daemon.fake.batches());
}

TEST_F(ReplayAuthBinary, UnsignedOrWronglySignedStateExitsThree) {
  for (const auto& [answer, why] : {std::pair{Answer::unsigned_states, "unsigned"},
                                    std::pair{Answer::wrong_key_states, "wrong tag"}}) {
    fs::remove(dir_ / "replay.log");
    FakeOnHub daemon(hub_->url(), answer, daemon_key_, replay_key_);
    auto r = replay_over_hub({"--key-file", keys_.string()});
    const auto lines = lines_to_end(*r);
    EXPECT_EQ(exit_code(r), 3) << log();
    for (const auto& line : lines) EXPECT_EQ(line.find("fake-"), std::string::npos) << line;
    const std::string expected = std::string(
                                     "peritwin-replay: PERITWIN_B1_CT_STATE: state_seq 0 of "
                                     "detail \"b1-ct\": ") +
                                 why + " (not from the holder of daemon key \"peritwin\")\n";
    EXPECT_NE(log().find(expected), std::string::npos) << log();
  }
}

TEST_F(ReplayAuthBinary, AuthRejectExitsThreeWithTheDaemonsReason) {
  FakeOnHub daemon(hub_->url(), Answer::auth_reject, daemon_key_, replay_key_);
  auto r = replay_over_hub({"--key-file", keys_.string()});
  lines_to_end(*r);
  EXPECT_EQ(exit_code(r), 3) << log();
  // The first batch it sends is the probe of what the daemon holds (BatchSender::probe_applied).
  EXPECT_NE(log().find("peritwin-replay: the daemon refused the probe batch of source \"replay\" "
                       "(CODE_AUTH): auth_tag: wrong tag for source \"replay\"\n"),
            std::string::npos)
      << log();
}

TEST_F(ReplayAuthBinary, MissingKeyExitsTwoBeforePublishingAndSignOnlyNeedsNoDaemonKey) {
  FakeOnHub daemon(hub_->url(), Answer::signed_states, daemon_key_, replay_key_);
  auto r = replay_over_hub({"--key-file", keys_.string(), "--source", "gauge-3"});
  lines_to_end(*r);
  EXPECT_EQ(exit_code(r), 2) << log();
  EXPECT_NE(log().find("no key \"gauge-3\" (--source)"), std::string::npos) << log();
  auto d = replay_over_hub({"--key-file", keys_.string(), "--daemon-key", "twin-7"});
  lines_to_end(*d);
  EXPECT_EQ(exit_code(d), 2) << log();
  EXPECT_NE(log().find("no key \"twin-7\" (--daemon-key)"), std::string::npos) << log();
  ::chmod(keys_.c_str(), 0644);
  auto open = replay_over_hub({"--key-file", keys_.string()});
  lines_to_end(*open);
  EXPECT_EQ(exit_code(open), 2) << log();
  EXPECT_NE(log().find("mode 0644"), std::string::npos) << log();
  EXPECT_EQ(daemon.fake.batches(), 0);
  // --sign-only needs no daemon key (and checks nothing).
  const auto own_key = dir_ / "own-key.toml";
  std::ofstream(own_key) << "[keys]\nreplay = \"" << [&] {
    std::string hex;
    for (const auto b : replay_key_.bytes)
      hex += "0123456789abcdef"[b >> 4], hex += "0123456789abcdef"[b & 15];
    return hex;
  }() << "\"\n";
  ::chmod(own_key.c_str(), 0600);
  auto sign_only = replay_over_hub({"--key-file", own_key.string(), "--sign-only"});
  const auto lines = lines_to_end(*sign_only);
  EXPECT_EQ(exit_code(sign_only), 0) << log();
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines.back().find("\"state_hash\":\"fake-3\""), std::string::npos) << lines.back();
  EXPECT_GE(daemon.fake.verified(), 3);
  EXPECT_EQ(daemon.fake.verified(), daemon.fake.batches());
  // The key file is never overwritten.
  const auto again = run_replay({"--generate-key-file", keys_.string()});
  EXPECT_EQ(exit_code(again), 2) << log();
  EXPECT_EQ(messages::KeyRing::parse(
                [&] {
                  std::ifstream in(keys_);
                  return std::string(std::istreambuf_iterator<char>(in), {});
                }(),
                keys_.string())
                ->find("replay")
                ->bytes,
            replay_key_.bytes);
}

}  // namespace
}  // namespace peritwin::replay
