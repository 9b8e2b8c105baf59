// The daemon service and the replay client on one in-process LCM (memq://): every state through
// LCM equals the in-process run, rejects are published with their reasons, a stopped daemon
// resumes from its checkpoint and a full replay then gives the same final state.
//
// Timing: these run on shared, loaded machines (2 cores, load 4-18). Every wait has a deadline of
// minutes (kGiveUpS), and nothing asserts what only timing decides: the replayer resends after
// 3 s without progress, so on a slow run the daemon may see (and drop) extra duplicates.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <thread>

#include "messages/channels.h"
#include "replay/replay_tool.h"
#include "tests/support/twin_fixtures.h"
#include "twin/service/daemon.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
using testing::b1_text;

/// No progress for this long fails a replay or a wait; generous for a loaded 2-core machine.
constexpr double kGiveUpS = 600.0;

TwinConfig config_of(const std::string& text) {
  auto r = parse_config(text, "b1-memq.toml");
  EXPECT_TRUE(r.ok()) << r.error_text();
  return *r.config;
}

std::vector<Batch> history(int n, std::int64_t cycles = 1500) {
  std::vector<LoadBlock> blocks;
  for (int i = 0; i < n; ++i) blocks.push_back({4000.0 + 25.0 * (i % 3), 0.1, 0.0, cycles});
  return replay::make_twin_batches(blocks, "b1-ct", "replay", {4, 1000});
}

class MemqTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("peritwin_memq_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(::getpid()));  // per process: other checkouts run this suite too
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    options_.state_dir = dir_ / "state";
    options_.deterministic = true;
    options_.results = false;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  DaemonOptions options_;
};

std::map<std::int64_t, std::string> in_process_hashes(const TwinConfig& config,
                                                      const std::vector<Batch>& batches) {
  std::map<std::int64_t, std::string> hashes;
  const auto r = replay::run_in_process(config.details[0], batches,
                                        [&](const auto& s) { hashes[s.state_seq] = s.state_hash; });
  EXPECT_TRUE(r.error.empty()) << r.error;
  return hashes;
}

TEST_F(MemqTest, EveryStateThroughLcmEqualsTheInProcessRun) {
  const TwinConfig config = config_of(b1_text());
  const auto batches = history(12);  // 12 x 1500 cycles in batches of 4 blocks / 1000 cycles
  ASSERT_EQ(batches.size(), 12u);
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Daemon daemon(lcm, config, options_);
  const Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  std::map<std::int64_t, std::string> seen;
  replay::LcmReplayer replayer(lcm, batches, {false, 5, 3.0, kGiveUpS});
  const auto result = replayer.run([&](const auto& s) { seen[s.state_seq] = s.state_hash; },
                                   [&] {
                                     daemon.tick();
                                     return true;
                                   });
  ASSERT_TRUE(result.ok) << result.error;
  ASSERT_TRUE(result.final_state);
  EXPECT_EQ(result.final_state->state_seq, 12);
  // Each batch at least once; a slow daemon (no STATE within 3 s) gets some resent, which it
  // drops as duplicates, and no gap ever.
  EXPECT_GE(result.published, 12);
  EXPECT_EQ(daemon.twin(0).counters().gaps, 0);
  const auto expected = in_process_hashes(config, batches);
  for (std::int64_t s = 1; s <= 12; ++s) {
    ASSERT_TRUE(seen.count(s)) << s;
    EXPECT_EQ(seen[s], expected.at(s)) << s;
  }
  EXPECT_GT(daemon.twin(0).broken_bonds(), 0);
  daemon.stop();
  EXPECT_EQ(daemon.checkpoints_written(), 1);  // at stop
}

TEST_F(MemqTest, RejectsArePublishedWithTheirReasons) {
  const TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  Daemon daemon(lcm, config, options_);
  const Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  std::vector<peritwin_msgs::reject_t> rejects;
  std::vector<peritwin_msgs::damage_state_t> states;
  struct Sink {
    std::vector<peritwin_msgs::reject_t>* rejects;
    std::vector<peritwin_msgs::damage_state_t>* states;
    void reject(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::reject_t* m) {
      rejects->push_back(*m);
    }
    void state(const lcm::ReceiveBuffer*, const std::string&,
               const peritwin_msgs::damage_state_t* m) {
      states->push_back(*m);
    }
  } sink{&rejects, &states};
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kReject), &Sink::reject, &sink);
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kState), &Sink::state, &sink);
  const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
  auto send = [&](const Batch& b) {
    const auto m = batch_message(b, 0);
    lcm.publish(load, &m);
  };
  const LoadBlock ok{4000, 0.1, 0, 100};
  const std::uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  lcm.publish(load, garbage, sizeof garbage);        // decode
  send({"b1-ct", "p", 1, {ok, {4000, 2.0, 0, 1}}});  // invalid
  send({"b2-cts", "p", 1, {ok}});                    // wrong detail
  send({"b1-ct", "p", 1, {ok}});                     // applied
  send({"b1-ct", "p", 1, {ok}});                     // duplicate
  send({"b1-ct", "p", 5, {ok}});                     // gap
  for (int i = 0; i < 50 && (rejects.size() < 5 || states.size() < 3); ++i) daemon.poll(20);
  ASSERT_EQ(rejects.size(), 5u);
  using R = peritwin_msgs::reject_t;
  EXPECT_EQ(rejects[0].code, R::CODE_DECODE);
  EXPECT_EQ(rejects[0].seq, -1);
  EXPECT_EQ(rejects[0].source_id, "");
  EXPECT_EQ(rejects[1].code, R::CODE_INVALID);
  EXPECT_EQ(rejects[1].what, "blocks[1].r");
  EXPECT_EQ(rejects[2].code, R::CODE_WRONG_DETAIL);
  EXPECT_EQ(rejects[3].code, R::CODE_DUPLICATE);
  EXPECT_EQ(rejects[4].code, R::CODE_GAP);
  EXPECT_EQ(rejects[4].seq, 5);
  for (const auto& r : rejects) {
    EXPECT_EQ(r.detail_id, "b1-ct");
    EXPECT_FALSE(r.why.empty());
  }
  // After the applied batch, and republished after the duplicate and the gap (the initial state
  // went out before this test subscribed).
  ASSERT_EQ(states.size(), 3u);
  EXPECT_EQ(states.back().state_seq, 1);
  EXPECT_EQ(applied_seq(states.back(), "p"), 1);
  EXPECT_EQ(daemon.twin(0).state_seq(), 1);
  daemon.stop();
}

TEST_F(MemqTest, StopCheckpointsAndARestartResumesBitIdentically) {
  const TwinConfig config = config_of(b1_text());
  const auto batches = history(16);
  const auto expected = in_process_hashes(config, batches);
  lcm::LCM lcm("memq://");
  {
    Daemon first(lcm, config, options_);
    const Status started = first.start();
    ASSERT_TRUE(started.ok()) << message_of(started);
    const std::vector<Batch> half(batches.begin(), batches.begin() + 7);
    replay::LcmReplayer replayer(lcm, half, {true, 1, 3.0, kGiveUpS});
    ASSERT_TRUE(replayer
                    .run({},
                         [&] {
                           first.tick();  // the replayer drives LCM: the daemon applies here
                           return true;
                         })
                    .ok);
    first.stop();
    EXPECT_EQ(first.twin(0).state_hash_hex(), expected.at(7));
  }
  Daemon second(lcm, config, options_);
  const Status started = second.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  EXPECT_EQ(second.twin(0).state_seq(), 7);
  EXPECT_EQ(second.twin(0).state_hash_hex(), expected.at(7));
  // The whole history again: 1..7 are duplicates, 8..16 are applied.
  replay::LcmReplayer replayer(lcm, batches, {false, 16, 3.0, kGiveUpS});
  const auto result = replayer.run({}, [&] {
    second.tick();
    return true;
  });
  ASSERT_TRUE(result.ok) << result.error;
  EXPECT_EQ(result.final_state->state_seq, 16);
  EXPECT_EQ(result.final_state->state_hash, expected.at(16));
  EXPECT_EQ(second.twin(0).state_hash_hex(), expected.at(16));
  // 1..7 at least once each; more when a slow apply made the replayer resend.
  EXPECT_GE(second.twin(0).counters().duplicates, 7);
  EXPECT_EQ(second.twin(0).counters().gaps, 0);
  second.stop();
}

TEST_F(MemqTest, OneTwinPerDetailEachOnItsOwnChannels) {
  // B1 and B2 (examples) in one config: batches go to the twin of their channel only.
  const std::string b2 =
      testing::read_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b2-cts-al6061.toml");
  const TwinConfig config = config_of(b1_text() + "\n" + b2);
  ASSERT_EQ(config.details.size(), 2u);
  lcm::LCM lcm("memq://");
  Daemon daemon(lcm, config, options_);
  const Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  ASSERT_EQ(daemon.num_details(), 2u);
  auto send = [&](const Batch& b) {
    const auto m = batch_message(b, 0);
    lcm.publish(messages::channel(b.detail_id, messages::Kind::kLoad), &m);
  };
  send({"b1-ct", "a", 1, {{4000, 0.1, 0, 1000}}});
  send({"b2-cts", "a", 1, {{6000, 0.1, 0.3, 500}}});
  send({"b1-ct", "a", 2, {{4000, 0.1, 0, 1000}}});
  for (int i = 0; i < 20; ++i) daemon.poll(10);
  EXPECT_EQ(daemon.twin(0).detail_id(), "b1-ct");
  EXPECT_EQ(daemon.twin(0).state_seq(), 2);
  EXPECT_EQ(daemon.twin(0).engine().total_cycles(), 2000);
  EXPECT_EQ(daemon.twin(1).detail_id(), "b2-cts");
  EXPECT_EQ(daemon.twin(1).state_seq(), 1);
  EXPECT_EQ(daemon.twin(1).engine().total_cycles(), 500);
  // B2 estimates under the empirical spectrum: none at state 0 (nothing received yet).
  EXPECT_TRUE(std::isnan(daemon.twin(1).life().central));
  daemon.stop();
  EXPECT_TRUE(fs::exists(options_.state_dir / "b2-cts"));
}

TEST_F(MemqTest, AsynchronousLifeEstimatesArriveLabelledWithTheirState) {
  // Not deterministic: a worker thread estimates; ingest goes on meanwhile. Every estimate is a
  // pure function of the state it names, so it equals the synchronous one for that state.
  const TwinConfig config = config_of(b1_text(
      "every_batches = 10", {{"critical_crack_length = 0.008", "critical_crack_length = 0.003"},
                             {"band = \"a2_scatter\"", "band = \"none\""},
                             {"a2_relative_scatter = 0.2", ""}}));
  options_.deterministic = false;
  const auto batches = history(6);
  lcm::LCM lcm("memq://");
  Daemon daemon(lcm, config, options_);
  const Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  std::vector<peritwin_msgs::damage_state_t> states;
  replay::LcmReplayer replayer(lcm, batches, {false, 6, 3.0, kGiveUpS});
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(replayer
                  .run([&](const auto& s) { states.push_back(s); },
                       [&] {
                         daemon.tick();
                         return true;
                       })
                  .ok);
  const double ingest_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // Keep polling until the estimate of the final state arrives (the worker restarts on the
  // newest state whenever it finishes).
  struct Sink {
    std::vector<peritwin_msgs::damage_state_t>* states;
    void on(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::damage_state_t* m) {
      states->push_back(*m);
    }
  } sink{&states};
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kState), &Sink::on, &sink);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
  while ((states.empty() || states.back().remaining_life_seq != 6) &&
         std::chrono::steady_clock::now() < deadline) {
    daemon.poll(50);
  }
  ASSERT_FALSE(states.empty());
  ASSERT_EQ(states.back().remaining_life_seq, 6)
      << "no estimate of state 6 in " << kGiveUpS << " s";
  EXPECT_EQ(states.back().remaining_life_source, "replay");
  EXPECT_EQ(states.back().state_seq, 6);
  // Estimates lag: the first states went out before any estimate.
  EXPECT_TRUE(std::isnan(states.front().remaining_cycles) || states.front().remaining_life_seq < 6);
  auto twin = testing::make_twin(testing::b1_model(config.details[0]));
  ASSERT_NE(twin, nullptr);
  for (const auto& b : batches) ASSERT_TRUE(twin->apply(b).applied());
  twin->estimate_life_now();
  EXPECT_EQ(states.back().remaining_cycles, twin->life().central);
  EXPECT_EQ(states.back().state_hash, twin->state_hash_hex());
  RecordProperty("ingest_s", std::to_string(ingest_s));
  daemon.stop();
}

TEST_F(MemqTest, StatusCountsTheBatchesWaitingAndTheAgeOfTheOldest) {
  const TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  options_.status_period_s = 0.0;  // a STATUS after every applied batch
  Daemon daemon(lcm, config, options_);
  const Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << message_of(started);
  std::vector<peritwin_msgs::status_t> statuses;
  struct Sink {
    std::vector<peritwin_msgs::status_t>* statuses;
    void status(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::status_t* m) {
      statuses->push_back(*m);
    }
  } sink{&statuses};
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kStatus), &Sink::status, &sink);
  const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
  for (std::int64_t seq = 1; seq <= 3; ++seq) {
    const auto m = batch_message({"b1-ct", "p", seq, {{4000, 0.1, 0, 10}}}, 0);
    lcm.publish(load, &m);
  }
  while (lcm.handleTimeout(0) > 0) {  // received into the inbox, not yet applied
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  daemon.tick();  // applies the three, a STATUS after each
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_GE(statuses.size(), 3u);
  // After batch k of 3: 3 − k still wait, the oldest of them received >= 30 ms ago.
  for (int k = 1; k <= 3; ++k) {
    const auto& s = statuses[static_cast<std::size_t>(k - 1)];
    EXPECT_EQ(s.last_seq, k);
    EXPECT_EQ(s.pending, 3 - k);
    if (k < 3) {
      EXPECT_GE(s.lag_s, 0.030);
      EXPECT_LT(s.lag_s, kGiveUpS);  // a sanity bound, not a timing one
    } else {
      EXPECT_EQ(s.lag_s, 0.0);
    }
    EXPECT_EQ(s.health, "ok");
  }
  daemon.stop();
}

}  // namespace
}  // namespace peritwin::twin
