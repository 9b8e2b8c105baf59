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
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/mesh.h"
#include "outputs/checkpoint_io.h"
#include "replay/learning.h"
#include "replay/observation_sender.h"
#include "replay/replay_tool.h"
#include "service/daemon.h"
#include "tests/support/twin_fixtures.h"
#include "twin/messages_io.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
using testing::b1_text;

/// No progress for this long fails a replay or a wait; generous for a loaded 2-core machine.
constexpr double kGiveUpS = 600.0;

config::TwinConfig config_of(const std::string& text) {
  auto r = config::parse_config(text, "b1-memq.toml");
  EXPECT_TRUE(r.ok()) << r.error_text();
  return *r.config;
}

std::vector<messages::Batch> history(int n, std::int64_t cycles = 1500) {
  std::vector<core::LoadBlock> blocks;
  for (int i = 0; i < n; ++i) blocks.push_back({4000.0 + 25.0 * (i % 3), 0.1, 0.0, cycles});
  return loads::make_twin_batches(blocks, "b1-ct", "replay", {4, 1000});
}

/// Collects a detail's REJECTs and STATEs from the bus.
struct BusSink {
  std::vector<peritwin_msgs::reject_t>* rejects;
  std::vector<peritwin_msgs::damage_state_t>* states;
  void reject(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::reject_t* m) {
    rejects->push_back(*m);
  }
  void state(const lcm::ReceiveBuffer*, const std::string&,
             const peritwin_msgs::damage_state_t* m) {
    states->push_back(*m);
  }
  void subscribe(lcm::LCM& lcm, const std::string& detail) {
    lcm.subscribe(messages::channel(detail, messages::Kind::kReject), &BusSink::reject, this);
    lcm.subscribe(messages::channel(detail, messages::Kind::kState), &BusSink::state, this);
  }
};

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
  service::DaemonOptions options_;
};

std::map<std::int64_t, std::string> in_process_hashes(const config::TwinConfig& config,
                                                      const std::vector<messages::Batch>& batches) {
  std::map<std::int64_t, std::string> hashes;
  const auto r = twin::run_in_process(config.details[0], batches,
                                      [&](const auto& s) { hashes[s.state_seq] = s.state_hash; });
  EXPECT_TRUE(r.error.empty()) << r.error;
  return hashes;
}

TEST_F(MemqTest, EveryStateThroughLcmEqualsTheInProcessRun) {
  const config::TwinConfig config = config_of(b1_text());
  const auto batches = history(12);  // 12 x 1500 cycles in batches of 4 blocks / 1000 cycles
  ASSERT_EQ(batches.size(), 12u);
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
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
  const config::TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  std::vector<peritwin_msgs::reject_t> rejects;
  std::vector<peritwin_msgs::damage_state_t> states;
  BusSink sink{&rejects, &states};
  sink.subscribe(lcm, "b1-ct");
  const std::string load = messages::channel("b1-ct", messages::Kind::kLoad);
  auto send = [&](const messages::Batch& b) {
    const auto m = messages::batch_message(b, 0);
    lcm.publish(load, &m);
  };
  const core::LoadBlock ok{4000, 0.1, 0, 100};
  const std::uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8, 9};
  lcm.publish(load, garbage, sizeof garbage);        // decode
  send({"b1-ct", "p", 1, {ok, {4000, 2.0, 0, 1}}});  // invalid
  send({"b2-cts", "p", 1, {ok}});                    // wrong detail
  send({"b1-ct", "p", 1, {ok}});                     // applied
  send({"b1-ct", "p", 1, {ok}});                     // duplicate
  send({"b1-ct", "p", 5, {ok}});                     // gap
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
  while ((rejects.size() < 5 || states.size() < 3) && std::chrono::steady_clock::now() < deadline) {
    daemon.poll(20);
  }
  daemon.tick();
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
  EXPECT_EQ(messages::applied_seq(states.back(), "p"), 1);
  EXPECT_EQ(daemon.twin(0).state_seq(), 1);
  daemon.stop();
}

// Issue 32: observations on the bus. The daemon takes an observation_t in from the detail's
// OBSERVATION channel in arrival order with the batches, refuses a bad one with a REJECT whose
// `what` names the observation's field, lists what it took in in STATE, checkpoints it at once,
// and a restarted daemon resumes the learning twin with the same bits (equal to the in-process
// twin fed the same batches and observations).
TEST_F(MemqTest, ObservationsOnTheBusAreTakenInOnceRefusedWithReasonsAndSurviveARestart) {
  std::string text = b1_text("every_batches = 0", {{"dx = 0.001 ", "dx = 0.002 "}});
  text +=
      "\n[detail.uncertainty]\nparticles = 4\nseed = 2\na2 = { median = 1301.0, cov = 0.3 "
      "}\n";
  const config::TwinConfig config = config_of(text);
  const auto batches = history(12, 2000);  // 24,000 cycles
  messages::Observation seen;
  seen.detail_id = "b1-ct";
  seen.source_id = "ndt";
  seen.seq = 1;
  seen.cycle = 20000;
  seen.length_m = 0.0015;
  seen.sigma_m = 0.0003;
  // The in-process twin fed the same: the bits the daemon must reach.
  auto model = testing::b1_model(config.details[0]);
  auto expected = testing::make_twin(model);
  for (const auto& b : batches) ASSERT_TRUE(expected->apply(b).applied());
  ASSERT_TRUE(expected->observe(seen).applied());

  lcm::LCM lcm("memq://");
  std::vector<peritwin_msgs::reject_t> rejects;
  std::vector<peritwin_msgs::damage_state_t> states;
  BusSink sink{&rejects, &states};
  sink.subscribe(lcm, "b1-ct");
  const std::string channel = messages::channel("b1-ct", messages::Kind::kObservation);
  auto send = [&](const messages::Observation& o) {
    const auto m = messages::observation_message(o, 0);
    lcm.publish(channel, &m);
  };
  const auto wait_for = [&](service::Daemon& d, std::size_t n_rejects, std::size_t n_states) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
    while ((rejects.size() < n_rejects || states.size() < n_states) &&
           std::chrono::steady_clock::now() < deadline) {
      d.poll(20);
    }
    d.tick();
  };
  {
    service::Daemon first(lcm, config, options_);
    const core::Status started = first.start();
    ASSERT_TRUE(started.ok()) << core::message_of(started);
    replay::LcmReplayer replayer(lcm, batches, {true, 1, 3.0, kGiveUpS});
    ASSERT_TRUE(replayer
                    .run({},
                         [&] {
                           first.tick();
                           return true;
                         })
                    .ok);
    states.clear();
    messages::Observation future = seen;
    future.cycle = 30000;
    messages::Observation unknown = seen;
    unknown.origin = "hole 0";
    const std::uint8_t garbage[] = {9, 8, 7};
    send(future);                                   // in the twin's future
    send(unknown);                                  // no hole on B1
    lcm.publish(channel, garbage, sizeof garbage);  // does not decode
    send(seen);                                     // taken in
    send(seen);                                     // a duplicate
    wait_for(first, 4, 2);
    ASSERT_EQ(rejects.size(), 4u);
    using R = peritwin_msgs::reject_t;
    EXPECT_EQ(rejects[0].code, R::CODE_INVALID);
    EXPECT_EQ(rejects[0].what, "observation.cycle");
    EXPECT_EQ(rejects[1].what, "observation.origin");
    EXPECT_EQ(rejects[2].code, R::CODE_DECODE);
    EXPECT_EQ(rejects[2].what, "observation");
    EXPECT_EQ(rejects[3].code, R::CODE_DUPLICATE);
    EXPECT_EQ(rejects[3].what, "observation.seq");
    for (const auto& r : rejects) EXPECT_FALSE(r.why.empty());
    ASSERT_GE(states.size(), 1u);
    const auto& taken = states.front();
    EXPECT_EQ(taken.observation_count, 1);
    ASSERT_EQ(taken.num_observation_sources, 1);
    EXPECT_EQ(taken.observation_source_ids[0], "ndt");
    EXPECT_EQ(taken.observation_applied_seq[0], 1);
    EXPECT_EQ(taken.ensemble_estimate_cycle, 24000);
    EXPECT_EQ(taken.state_hash, expected->state_hash_hex());
    EXPECT_EQ(first.twin(0).state_hash_hex(), expected->state_hash_hex());
    first.stop();
  }
  // Taken in means durable: the restart resumes with the observation and the same bits.
  service::Daemon second(lcm, config, options_);
  const core::Status started = second.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  EXPECT_EQ(second.twin(0).state_hash_hex(), expected->state_hash_hex());
  EXPECT_EQ(second.twin(0).observed().at("ndt"), 1);
  second.stop();
}

// peritwin-replay --observations over the bus (replay::replay_with_observations): the batches
// split at the observations' cycles, each observation sent once the batches up to its cycle are
// applied; the daemon's learning twin ends with the bits of the in-process learning run.
TEST_F(MemqTest, ObservationsReplayedOverTheBusGiveTheInProcessLearningRun) {
  std::string text = b1_text("every_batches = 0", {{"dx = 0.001 ", "dx = 0.002 "}});
  text +=
      "\n[detail.uncertainty]\nparticles = 4\nseed = 3\na2 = { median = 1301.0, cov = 0.3 "
      "}\n";
  const config::TwinConfig config = config_of(text);
  std::vector<messages::Observation> observations(2);
  for (std::size_t i = 0; i < 2; ++i) {
    messages::Observation& o = observations[i];
    o.detail_id = "b1-ct";
    o.source_id = "replay";
    o.seq = static_cast<std::int64_t>(i) + 1;
    o.cycle = i == 0 ? 9000 : 23000;  // inside batches: they are split there
    o.length_m = i == 0 ? 0.0 : 0.001;
    o.sigma_m = 0.0003;
  }
  const auto batches =
      replay::split_batches_at(history(12, 2000), {observations[0].cycle, observations[1].cycle});
  const auto expected =
      replay::run_learning_in_process(config.details[0], batches, observations, true, {}, {});
  ASSERT_TRUE(expected.error.empty()) << expected.error;

  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  const auto r = replay::replay_with_observations(lcm, batches, observations,
                                                  {true, 1, 3.0, kGiveUpS}, {}, {}, [&] {
                                                    daemon.tick();
                                                    return true;
                                                  });
  ASSERT_TRUE(r.ok) << r.error;
  daemon.tick();
  EXPECT_EQ(daemon.twin(0).observed().at("replay"), 2);
  EXPECT_EQ(daemon.twin(0).state_hash_hex(), expected.final_state->state_hash);
  // The same again (a resumed run): the batches are duplicates, the observations too, and
  // nothing changes.
  const auto again = replay::replay_with_observations(lcm, batches, observations,
                                                      {true, 1, 3.0, kGiveUpS}, {}, {}, [&] {
                                                        daemon.tick();
                                                        return true;
                                                      });
  ASSERT_TRUE(again.ok) << again.error;
  daemon.tick();
  EXPECT_EQ(daemon.twin(0).state_hash_hex(), expected.final_state->state_hash);
  // An observation the daemon refuses: the sender says why.
  messages::Observation bad = observations[1];
  bad.origin = "hole 2";
  bad.source_id = "other";
  bad.seq = 1;
  const auto refused = replay::send_observation(lcm, bad, {true, 1, 3.0, kGiveUpS}, {}, {}, [&] {
    daemon.tick();
    return true;
  });
  ASSERT_FALSE(refused.ok());
  const std::string why = refused.error().message();
  EXPECT_NE(why.find("observation.origin"), std::string::npos) << why;
  daemon.stop();
}

TEST_F(MemqTest, StopCheckpointsAndARestartResumesBitIdentically) {
  const config::TwinConfig config = config_of(b1_text());
  const auto batches = history(16);
  const auto expected = in_process_hashes(config, batches);
  lcm::LCM lcm("memq://");
  {
    service::Daemon first(lcm, config, options_);
    const core::Status started = first.start();
    ASSERT_TRUE(started.ok()) << core::message_of(started);
    const std::vector<messages::Batch> half(batches.begin(), batches.begin() + 7);
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
  service::Daemon second(lcm, config, options_);
  const core::Status started = second.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
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
      twin::testing::read_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b2-cts-al6061.toml");
  const config::TwinConfig config = config_of(b1_text() + "\n" + b2);
  ASSERT_EQ(config.details.size(), 2u);
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  ASSERT_EQ(daemon.num_details(), 2u);
  auto send = [&](const messages::Batch& b) {
    const auto m = messages::batch_message(b, 0);
    lcm.publish(messages::channel(b.detail_id, messages::Kind::kLoad), &m);
  };
  send({"b1-ct", "a", 1, {{4000, 0.1, 0, 1000}}});
  send({"b2-cts", "a", 1, {{6000, 0.1, 0.3, 500}}});
  send({"b1-ct", "a", 2, {{4000, 0.1, 0, 1000}}});
  for (int i = 0; i < 20; ++i) daemon.poll(10);
  daemon.tick();  // the workers apply off the LCM thread: wait for them
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

TEST_F(MemqTest, AnyNumberOfWorkerThreadsGivesEachDetailItsSingleDetailRun) {
  // Three copies of B1, one loud (4 kN: breaks bonds batch after batch) and two quiet, their
  // batches interleaved on the bus. Whatever the pool's size (one thread: every detail waits
  // for the loud one's re-solves; two; more than details: capped), each detail's final state is
  // bit for bit its own single-detail run: the pool changes when a batch is applied, never what.
  const std::vector<std::pair<std::string, double>> details = {
      {"loud", 4000.0}, {"quiet-a", 1500.0}, {"quiet-b", 2000.0}};
  std::string text;
  for (const auto& [id, load] : details) {
    text += b1_text("every_batches = 0", {{"id = \"b1-ct\"", "id = \"" + id + "\""},
                                          {"\"results/b1-ct\"", "\"results/" + id + "\""}}) +
            "\n";
  }
  const config::TwinConfig config = config_of(text);
  ASSERT_EQ(config.details.size(), details.size());
  std::vector<std::vector<messages::Batch>> batches;
  std::vector<std::string> expected_hash;
  for (std::size_t i = 0; i < details.size(); ++i) {
    std::vector<core::LoadBlock> blocks;
    for (int k = 0; k < 8; ++k) blocks.push_back({details[i].second, 0.1, 0.0, 1500});
    batches.push_back(loads::make_twin_batches(blocks, details[i].first, "replay", {4, 1000}));
    std::string last;
    const auto r = twin::run_in_process(config.details[i], batches.back(),
                                        [&](const auto& s) { last = s.state_hash; });
    ASSERT_TRUE(r.error.empty()) << r.error;
    expected_hash.push_back(last);
  }
  for (const int threads : {1, 2, 5}) {
    SCOPED_TRACE("worker_threads " + std::to_string(threads));
    fs::remove_all(options_.state_dir);
    options_.worker_threads = threads;
    lcm::LCM lcm("memq://");
    service::Daemon daemon(lcm, config, options_);
    const core::Status started = daemon.start();
    ASSERT_TRUE(started.ok()) << core::message_of(started);
    for (std::size_t k = 0; k < batches[0].size(); ++k) {
      for (const auto& detail_batches : batches) {
        const auto m = messages::batch_message(detail_batches[k], 0);
        lcm.publish(messages::channel(detail_batches[k].detail_id, messages::Kind::kLoad), &m);
      }
    }
    for (int i = 0; i < 20; ++i) daemon.poll(10);
    daemon.tick();
    for (std::size_t i = 0; i < details.size(); ++i) {
      EXPECT_EQ(daemon.twin(i).state_seq(), static_cast<std::int64_t>(batches[i].size()));
      EXPECT_EQ(daemon.twin(i).state_hash_hex(), expected_hash[i]) << details[i].first;
    }
    EXPECT_GT(daemon.twin(0).broken_bonds(), 0);  // the loud one did break bonds
    daemon.stop();
  }
}

TEST_F(MemqTest, AsynchronousLifeEstimatesArriveLabelledWithTheirState) {
  // Not deterministic: a worker thread estimates; ingest goes on meanwhile. Every estimate is a
  // pure function of the state it names, so it equals the synchronous one for that state.
  const config::TwinConfig config = config_of(b1_text(
      "every_batches = 10", {{"critical_crack_length = 0.008", "critical_crack_length = 0.003"},
                             {"band = \"a2_scatter\"", "band = \"none\""},
                             {"a2_relative_scatter = 0.2", ""}}));
  options_.deterministic = false;
  const auto batches = history(6);
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
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

TEST_F(MemqTest, OneSharedLifeThreadEstimatesEveryDetailsFinalState) {
  // Three copies of B1 with asynchronous estimates on one shared life thread (life_threads 1):
  // the details take turns on it, and each one's STATE ends with the estimate of its final state,
  // equal to the synchronous estimate of that state.
  const std::vector<std::string> ids = {"a", "b", "c"};
  std::string text;
  for (const auto& id : ids) {
    text += b1_text("every_batches = 10",
                    {{"critical_crack_length = 0.008", "critical_crack_length = 0.003"},
                     {"band = \"a2_scatter\"", "band = \"none\""},
                     {"a2_relative_scatter = 0.2", ""},
                     {"id = \"b1-ct\"", "id = \"" + id + "\""},
                     {"\"results/b1-ct\"", "\"results/" + id + "\""}}) +
            "\n";
  }
  const config::TwinConfig config = config_of(text);
  ASSERT_EQ(config.details.size(), ids.size());
  options_.deterministic = false;
  options_.life_threads = 1;
  const auto batches = history(4);
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  struct Sink {
    std::map<std::string, peritwin_msgs::damage_state_t> last;
    void on(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::damage_state_t* m) {
      last[m->detail_id] = *m;
    }
  } sink;
  lcm.subscribe("PERITWIN_.*_STATE", &Sink::on, &sink);
  for (const messages::Batch& b : batches) {
    for (const auto& id : ids) {
      messages::Batch copy = b;
      copy.detail_id = id;
      const auto m = messages::batch_message(copy, 0);
      lcm.publish(messages::channel(id, messages::Kind::kLoad), &m);
    }
  }
  const auto all_estimated = [&] {
    return std::all_of(ids.begin(), ids.end(), [&](const std::string& id) {
      const auto it = sink.last.find(id);
      return it != sink.last.end() && it->second.remaining_life_seq == 4;
    });
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
  while (!all_estimated() && std::chrono::steady_clock::now() < deadline) daemon.poll(50);
  ASSERT_TRUE(all_estimated()) << "not every detail has the estimate of state 4 in " << kGiveUpS
                               << " s";
  auto twin = testing::make_twin(testing::b1_model(config.details[0]));
  ASSERT_NE(twin, nullptr);
  for (const auto& b : batches) {
    messages::Batch copy = b;
    copy.detail_id = ids[0];
    ASSERT_TRUE(twin->apply(copy).applied());
  }
  twin->estimate_life_now();
  ASSERT_TRUE(std::isfinite(twin->life().central));
  for (const auto& id : ids) {
    EXPECT_EQ(sink.last[id].state_seq, 4) << id;
    EXPECT_EQ(sink.last[id].remaining_cycles, twin->life().central) << id;
  }
  daemon.stop();
}

TEST_F(MemqTest, ALongBatchOnOneDetailStallsNeitherTheOtherDetailNorAnyHeartbeat) {
  // Two details on one daemon. Detail b1-ct's worker is held inside its first batch (the test
  // hook stands in for a batch that takes minutes); meanwhile b2-cts applies its batches and
  // publishes its states, and STATUS keeps coming for both: b1-ct's says how long it has been
  // busy and how many batches wait behind it.
  const std::string b2 =
      twin::testing::read_text(std::string(PERITWIN_EXAMPLES_DIR) + "/b2-cts-al6061.toml");
  // b1-ct turns "degraded" once its batch has run for 0.2 s ([detail.limits] max_batch_seconds).
  const config::TwinConfig config = config_of(
      b1_text("every_batches = 0", {{"max_batch_seconds = 60.0", "max_batch_seconds = 0.2"}}) +
      "\n" + b2);
  std::mutex hold_mutex;
  std::condition_variable hold_cv;
  bool held = false, release = false;
  options_.status_period_s = 0.05;
  options_.before_apply = [&](const std::string& detail) {
    if (detail != "b1-ct") return;
    std::unique_lock lock(hold_mutex);
    held = true;
    hold_cv.notify_all();
    hold_cv.wait(lock, [&] { return release; });
  };
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  struct Sink {
    std::map<std::string, std::vector<peritwin_msgs::status_t>> statuses;
    std::map<std::string, std::vector<peritwin_msgs::damage_state_t>> states;
    void status(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::status_t* m) {
      statuses[m->detail_id].push_back(*m);
    }
    void state(const lcm::ReceiveBuffer*, const std::string&,
               const peritwin_msgs::damage_state_t* m) {
      states[m->detail_id].push_back(*m);
    }
  } sink;
  lcm.subscribe(messages::channel_regex(messages::Kind::kStatus), &Sink::status, &sink);
  lcm.subscribe(messages::channel_regex(messages::Kind::kState), &Sink::state, &sink);
  auto send = [&](const messages::Batch& b) {
    const auto m = messages::batch_message(b, 0);
    lcm.publish(messages::channel(b.detail_id, messages::Kind::kLoad), &m);
  };
  for (std::int64_t seq = 1; seq <= 3; ++seq) send({"b1-ct", "p", seq, {{4000, 0.1, 0, 10}}});
  for (std::int64_t seq = 1; seq <= 3; ++seq) send({"b2-cts", "p", seq, {{6000, 0.1, 0.3, 10}}});

  // Wait (deadline of minutes, no timing assertion) until b2-cts has published state 3 and
  // b1-ct's STATUS has reported a busy batch with the two others waiting, twice.
  auto b1_busy_reports = [&] {
    int n = 0;
    for (const auto& s : sink.statuses["b1-ct"]) n += s.busy_s > 0.2 && s.pending == 2 ? 1 : 0;
    return n;
  };
  auto b2_done = [&] {
    const auto& v = sink.states["b2-cts"];
    return !v.empty() && v.back().state_seq == 3;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
  while ((!b2_done() || b1_busy_reports() < 2) && std::chrono::steady_clock::now() < deadline) {
    daemon.poll(20);
  }
  {
    std::lock_guard lock(hold_mutex);
    ASSERT_TRUE(held);
  }
  EXPECT_TRUE(b2_done());
  ASSERT_GE(b1_busy_reports(), 2);
  // b1-ct has published nothing but its initial state... (subscribed after start: none at all)
  for (const auto& s : sink.states["b1-ct"]) EXPECT_EQ(s.state_seq, 0);
  // ...and its busy time grows from one heartbeat to the next while b2-cts stays idle.
  std::vector<double> busy;
  for (const auto& s : sink.statuses["b1-ct"]) {
    if (s.pending == 2) busy.push_back(s.busy_s);
  }
  EXPECT_GT(busy.back(), busy.front());
  EXPECT_EQ(sink.statuses["b2-cts"].back().busy_s, 0.0);
  EXPECT_EQ(sink.statuses["b2-cts"].back().last_seq, 3);
  EXPECT_EQ(sink.statuses["b2-cts"].back().health, "ok");
  const auto& waiting = sink.statuses["b1-ct"].back();
  EXPECT_EQ(waiting.health, "degraded");  // busy_s > max_batch_seconds
  EXPECT_EQ(waiting.last_seq, 0);
  EXPECT_GT(waiting.lag_s, 0.0);  // the oldest waiting batch has waited since it was received
  EXPECT_LT(waiting.lag_s, kGiveUpS);
  {
    std::lock_guard lock(hold_mutex);
    release = true;
  }
  hold_cv.notify_all();
  daemon.tick();  // b1-ct applies its three
  EXPECT_EQ(daemon.twin(0).state_seq(), 3);
  EXPECT_EQ(daemon.twin(1).state_seq(), 3);
  daemon.stop();
}

/// What a hostile producer and the real one see on the REJECT and STATE channels.
struct Observer {
  std::vector<peritwin_msgs::reject_t> rejects;
  std::vector<peritwin_msgs::damage_state_t> states;
  std::vector<peritwin_msgs::status_t> statuses;
  void reject(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::reject_t* m) {
    rejects.push_back(*m);
  }
  void state(const lcm::ReceiveBuffer*, const std::string&,
             const peritwin_msgs::damage_state_t* m) {
    states.push_back(*m);
  }
  void status(const lcm::ReceiveBuffer*, const std::string&, const peritwin_msgs::status_t* m) {
    statuses.push_back(*m);
  }
  void subscribe(lcm::LCM& lcm) {
    lcm.subscribe(messages::channel("b1-ct", messages::Kind::kReject), &Observer::reject, this);
    lcm.subscribe(messages::channel("b1-ct", messages::Kind::kState), &Observer::state, this);
    lcm.subscribe(messages::channel("b1-ct", messages::Kind::kStatus), &Observer::status, this);
  }
};

/// Publishes, lets the daemon apply everything, and delivers what it published.
void exchange(lcm::LCM& lcm, service::Daemon& daemon,
              const std::vector<peritwin_msgs::load_batch_t>& sent) {
  for (const auto& m : sent) lcm.publish(messages::channel("b1-ct", messages::Kind::kLoad), &m);
  while (lcm.handleTimeout(0) > 0) {
  }
  daemon.tick();
  while (lcm.handleTimeout(0) > 0) {
  }
}

/// Runs a daemon over `batches` (in-process LCM) and stops it: one checkpoint, at stop.
void run_and_stop(const config::TwinConfig& config, const service::DaemonOptions& options,
                  const std::vector<messages::Batch>& batches) {
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  for (const auto& b : batches) {
    const auto m = messages::batch_message(b, 0);
    lcm.publish(messages::channel(b.detail_id, messages::Kind::kLoad), &m);
  }
  while (lcm.handleTimeout(0) > 0) {
  }
  daemon.tick();
  daemon.stop();
  ASSERT_EQ(daemon.twin(0).state_seq(), static_cast<std::int64_t>(batches.size()));
}

fs::path checkpoint_file(const fs::path& state_dir, std::uint64_t seq) {
  return outputs::checkpoint_path(state_dir / "b1-ct", "checkpoint", seq);
}

TEST_F(MemqTest, CheckpointsThatAllFailRefuseTheStartUnlessFreshStart) {
  const config::TwinConfig config = config_of(b1_text());
  run_and_stop(config, options_, history(3));
  const fs::path good = checkpoint_file(options_.state_dir, 3);
  ASSERT_TRUE(fs::exists(good));
  // Corrupt the one checkpoint (a byte in its middle) and add two that are not HDF5 at all.
  {
    std::fstream f(good, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(fs::file_size(good) / 2));
    f.put('\x5a');
  }
  for (const std::uint64_t seq : {4u, 5u}) {
    std::ofstream(checkpoint_file(options_.state_dir, seq), std::ios::binary) << "not a checkpoint";
  }
  lcm::LCM lcm("memq://");
  {
    service::Daemon daemon(lcm, config, options_);
    const core::Status started = daemon.start();
    ASSERT_FALSE(started.ok());
    const std::string why = started.error().message();
    EXPECT_NE(why.find("none of the 3 checkpoint(s)"), std::string::npos) << why;
    for (const std::uint64_t seq : {3u, 4u, 5u}) {
      EXPECT_NE(why.find(checkpoint_file(options_.state_dir, seq).string()), std::string::npos)
          << why;
    }
    EXPECT_NE(why.find("--fresh-start"), std::string::npos) << why;
  }
  options_.fresh_start = true;
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  EXPECT_EQ(daemon.twin(0).state_seq(), 0);
  daemon.stop();
}

TEST_F(MemqTest, ACheckpointWhoseContentDisagreesWithItsNameIsNotResumed) {
  // A valid checkpoint of another history (2 batches) renamed to a newer seq (9): skipped, the
  // daemon resumes from the newest one whose name and content agree; alone, it stops the start.
  const config::TwinConfig config = config_of(b1_text());
  const auto batches = history(4);
  run_and_stop(config, options_, {batches.begin(), batches.begin() + 2});
  const fs::path other = dir_ / "other-history.h5";
  fs::copy_file(checkpoint_file(options_.state_dir, 2), other);
  fs::remove_all(options_.state_dir);
  run_and_stop(config, options_, {batches.begin(), batches.begin() + 3});
  fs::copy_file(other, checkpoint_file(options_.state_dir, 9));
  lcm::LCM lcm("memq://");
  {
    service::Daemon daemon(lcm, config, options_);
    const core::Status started = daemon.start();
    ASSERT_TRUE(started.ok()) << core::message_of(started);
    EXPECT_EQ(daemon.twin(0).state_seq(), 3);
    daemon.stop();
  }
  fs::remove(checkpoint_file(options_.state_dir, 3));
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.error().message().find("holds state_seq 2 but its file name says 9"),
            std::string::npos)
      << started.error().message();
}

TEST_F(MemqTest, AStateDirThatCannotBeWrittenStopsTheStartBeforeAnyState) {
  // Root may write to a mode-0555 directory, so the state dir of the detail is made a regular
  // file: nothing can be created in it, for root or anyone.
  const config::TwinConfig config = config_of(b1_text());
  fs::create_directories(options_.state_dir);
  std::ofstream(options_.state_dir / "b1-ct") << "in the way";
  lcm::LCM lcm("memq://");
  int states = 0;
  struct Sink {
    int* states;
    void on(const lcm::ReceiveBuffer*, const std::string&) { ++*states; }
  } sink{&states};
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kState), &Sink::on, &sink);
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_FALSE(started.ok());
  EXPECT_NE(started.error().message().find("is not writable"), std::string::npos)
      << started.error().message();
  while (lcm.handleTimeout(0) > 0) {
  }
  EXPECT_EQ(states, 0);
}

TEST_F(MemqTest, StatesSayWhichSeqIsDurable) {
  // checkpointed_seq follows the checkpoints: 0 before the first, then the seq of the newest.
  const config::TwinConfig config =
      config_of(b1_text("every_batches = 0", {{"every_batches = 100", "every_batches = 2"}}));
  ASSERT_EQ(config.details[0].checkpoint.every_batches, 2);
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  Observer seen;
  seen.subscribe(lcm);
  std::vector<peritwin_msgs::load_batch_t> sent;
  for (const auto& b : history(3)) sent.push_back(messages::batch_message(b, 0));
  exchange(lcm, daemon, sent);
  const auto& states = seen.states;
  ASSERT_EQ(states.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    ASSERT_EQ(states[k].num_sources, 1);
    ASSERT_EQ(states[k].checkpointed_seq.size(), 1u);
    EXPECT_EQ(states[k].applied_seq[0], static_cast<std::int64_t>(k + 1));
  }
  EXPECT_EQ(states[0].checkpointed_seq[0], 0);
  EXPECT_EQ(states[1].checkpointed_seq[0], 2);  // checkpoint written before this STATE
  EXPECT_EQ(states[2].checkpointed_seq[0], 2);
  daemon.stop();  // checkpoint 3, and a STATE saying so
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(states.size(), 4u);
  EXPECT_EQ(states.back().checkpointed_seq[0], 3);
}

TEST_F(MemqTest, WithAuthAHijackerIsRefusedAndTheRealProducerGoesOn) {
  // The hostile producer of issue 14 publishes source "replay", seq 1 before the real replay.
  // With [auth] its batch is refused (unsigned, wrongly signed, unknown source), the model is
  // untouched, and the real seq 1 is applied; STATE and REJECT carry the daemon's tag.
  const fs::path key_file = dir_ / "keys.toml";
  const std::vector<std::string> ids = {"replay", "peritwin"};
  ASSERT_TRUE(messages::write_key_file(key_file, ids).ok());
  const config::TwinConfig config =
      config_of(b1_text() + "\n[auth]\nkey_file = \"" + key_file.string() + "\"\n");
  ASSERT_TRUE(config.auth.has_value());
  const auto keys = messages::KeyRing::load(key_file);
  ASSERT_TRUE(keys.ok());
  const messages::AuthKey& replay_key = *keys->find("replay");
  const messages::AuthKey& daemon_key = *keys->find("peritwin");
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  Observer seen;
  seen.subscribe(lcm);
  const messages::Batch real = history(1).front();
  auto unsigned_hijack = messages::batch_message(real, 0);
  unsigned_hijack.blocks[0].p_max *= 1.5;  // a different load under the real (source, seq)
  unsigned_hijack.nonce = 101;
  auto forged = unsigned_hijack;
  forged.nonce = 102;
  messages::AuthKey wrong;
  wrong.bytes.fill(0x42);
  messages::sign(forged, wrong);
  auto intruder = messages::batch_message({"b1-ct", "intruder", 1, real.blocks}, 0);
  intruder.nonce = 103;
  messages::sign(intruder, replay_key);  // a stolen key does not make another source
  exchange(lcm, daemon, {unsigned_hijack, forged, intruder});
  ASSERT_EQ(seen.rejects.size(), 3u);
  const std::vector<std::string> what = {"auth_tag", "auth_tag", "source_id"};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(seen.rejects[k].code, peritwin_msgs::reject_t::CODE_AUTH) << k;
    EXPECT_EQ(seen.rejects[k].what, what[k]) << seen.rejects[k].why;
    EXPECT_TRUE(messages::verify(seen.rejects[k], daemon_key).ok()) << k;
    EXPECT_EQ(seen.rejects[k].nonce, static_cast<std::int64_t>(101 + k));  // the batch's, echoed
  }
  EXPECT_NE(seen.rejects[0].why.find("unsigned"), std::string::npos);
  EXPECT_NE(seen.rejects[1].why.find("wrong tag"), std::string::npos);
  EXPECT_EQ(daemon.twin(0).state_seq(), 0);
  EXPECT_EQ(daemon.twin(0).applied_seq("replay"), 0);

  auto genuine = messages::batch_message(real, 0);
  genuine.nonce = 104;
  messages::sign(genuine, replay_key);
  exchange(lcm, daemon, {genuine});
  ASSERT_FALSE(seen.states.empty());
  const auto& state = seen.states.back();
  EXPECT_EQ(state.state_seq, 1);
  // A refused batch is not answered by STATE, nor is its nonce echoed in a later one.
  EXPECT_EQ(state.echo_source, "replay");
  EXPECT_EQ(state.echo_nonce, 104);
  EXPECT_EQ(messages::applied_seq(state, "replay"), 1);
  EXPECT_TRUE(messages::verify(state, daemon_key).ok());
  EXPECT_EQ(state.state_hash, in_process_hashes(config, {real}).at(1));
  for (int i = 0; i < 200 && (seen.statuses.empty() || seen.statuses.back().auth_rejects < 3);
       ++i) {
    daemon.poll(10);
    while (lcm.handleTimeout(0) > 0) {
    }
  }
  ASSERT_FALSE(seen.statuses.empty());
  EXPECT_EQ(seen.statuses.back().auth_rejects, 3);
  EXPECT_EQ(seen.statuses.back().errors, 3);
  daemon.stop();
}

// Issue 30: every STATE echoes the source and nonce of the last batch the daemon took (the one
// that produced it, or a duplicate or gap it answers: a producer's probe), every REJECT the
// rejected batch's nonce; the start-up STATE echoes none. STATE also names each source's history
// (the fingerprint and first seq of its last applied batch).
TEST_F(MemqTest, StatesAndRejectsEchoTheNonceOfTheBatchTheyAnswer) {
  const config::TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  Observer seen;
  seen.subscribe(lcm);
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  exchange(lcm, daemon, {});
  ASSERT_EQ(seen.states.size(), 1u);  // the start-up STATE
  EXPECT_EQ(seen.states[0].echo_source, "");
  EXPECT_EQ(seen.states[0].echo_nonce, 0);
  auto batches = history(2);
  ASSERT_EQ(batches.size(), 2u);
  loads::mark_history(batches);
  const auto sent = [](messages::Batch b, std::uint64_t nonce) {
    b.nonce = nonce;
    return messages::batch_message(b, 0);
  };
  messages::Batch gap = batches[1];
  gap.seq = 5;
  messages::Batch invalid = batches[1];
  invalid.history_start = 7;                      // after its seq 2
  exchange(lcm, daemon, {sent(batches[0], 11)});  // applied
  exchange(lcm, daemon, {sent(batches[0], 22)});  // duplicate
  exchange(lcm, daemon, {sent(gap, 33)});         // gap
  exchange(lcm, daemon, {sent(invalid, 44)});     // invalid: no STATE
  ASSERT_EQ(seen.states.size(), 4u);
  for (std::size_t k = 1; k < 4; ++k) {
    EXPECT_EQ(seen.states[k].state_seq, 1) << k;
    EXPECT_EQ(seen.states[k].echo_source, "replay") << k;
    EXPECT_EQ(messages::source_history(seen.states[k], "replay"),
              (messages::SourceHistory{batches[0].history, 1}))
        << k;
  }
  EXPECT_EQ(seen.states[1].echo_nonce, 11);
  EXPECT_EQ(seen.states[2].echo_nonce, 22);
  EXPECT_EQ(seen.states[3].echo_nonce, 33);
  ASSERT_EQ(seen.rejects.size(), 3u);
  EXPECT_EQ(seen.rejects[0].code, peritwin_msgs::reject_t::CODE_DUPLICATE);
  EXPECT_EQ(seen.rejects[0].nonce, 22);
  EXPECT_EQ(seen.rejects[1].code, peritwin_msgs::reject_t::CODE_GAP);
  EXPECT_EQ(seen.rejects[1].nonce, 33);
  EXPECT_EQ(seen.rejects[2].code, peritwin_msgs::reject_t::CODE_INVALID);
  EXPECT_EQ(seen.rejects[2].what, "history_start");
  EXPECT_EQ(seen.rejects[2].nonce, 44);
  daemon.stop();
}

TEST_F(MemqTest, WithoutAuthTheFirstToPublishASeqOwnsIt) {
  // The documented behaviour without [auth] (messages/README.md, Authentication): exactly-once
  // trusts (source, seq), so a hijacker's seq 1 is applied and the real seq 1 is then a
  // duplicate. Unsigned STATE.
  const config::TwinConfig config = config_of(b1_text());
  ASSERT_FALSE(config.auth.has_value());
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  Observer seen;
  seen.subscribe(lcm);
  const messages::Batch real = history(1).front();
  auto hijack = messages::batch_message(real, 0);
  hijack.blocks[0].p_max *= 1.5;
  exchange(lcm, daemon, {hijack, messages::batch_message(real, 0)});
  ASSERT_EQ(seen.rejects.size(), 1u);
  EXPECT_EQ(seen.rejects[0].code, peritwin_msgs::reject_t::CODE_DUPLICATE);
  EXPECT_EQ(daemon.twin(0).state_seq(), 1);
  EXPECT_NE(daemon.twin(0).state_hash_hex(), in_process_hashes(config, {real}).at(1));
  EXPECT_EQ(seen.states.back().tag_length, 0);
  daemon.stop();
}

TEST_F(MemqTest, OverflowingCountsAndAbsurdLoadsAreInvalidOverLcm) {
  // Issue 14's hostile cases over the bus: count INT64_MAX (wrapped total_cycles), 2^50 + 1
  // (final failure in one batch) and p_max = 1e308 (210 s in one batch): INVALID with the field,
  // nothing applied.
  const config::TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  Observer seen;
  seen.subscribe(lcm);
  const auto hash = daemon.twin(0).state_hash_hex();
  exchange(
      lcm, daemon,
      {messages::batch_message(
           {"b1-ct", "p", 1, {{4000, 0.1, 0, std::numeric_limits<std::int64_t>::max()}}}, 0),
       messages::batch_message({"b1-ct", "p", 1, {{4000, 0.1, 0, core::kMaxBatchCycles + 1}}}, 0),
       messages::batch_message({"b1-ct", "p", 1, {{1e308, 0.1, 0, 1}}}, 0)});
  ASSERT_EQ(seen.rejects.size(), 3u);
  const std::vector<std::string> what = {"blocks[0].count", "blocks[0].count", "blocks[0].p_max"};
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(seen.rejects[k].code, peritwin_msgs::reject_t::CODE_INVALID) << k;
    EXPECT_EQ(seen.rejects[k].what, what[k]) << seen.rejects[k].why;
  }
  EXPECT_EQ(daemon.twin(0).state_seq(), 0);
  EXPECT_EQ(daemon.twin(0).engine().total_cycles(), 0);
  EXPECT_EQ(daemon.twin(0).state_hash_hex(), hash);
  daemon.stop();
}

TEST_F(MemqTest, AFloodOfRejectsTurnsHealthDegradedAndIsCountedNotLoggedPerBatch) {
  // 40 invalid batches at once against max_rejects_per_second = 1 (over 10 s): STATUS counts
  // them all, reports the rate and says "degraded"; the model is untouched.
  const config::TwinConfig config = config_of(b1_text(
      "every_batches = 0", {{"max_rejects_per_second = 10.0", "max_rejects_per_second = 1.0"}}));
  options_.status_period_s = 0.0;
  lcm::LCM lcm("memq://");
  service::Daemon daemon(lcm, config, options_);
  ASSERT_TRUE(daemon.start().ok());
  Observer seen;
  seen.subscribe(lcm);
  std::vector<peritwin_msgs::load_batch_t> flood;
  for (int k = 0; k < 40; ++k)
    flood.push_back(messages::batch_message({"b1-ct", "p", 1, {{4000, 2.0, 0, 1}}}, 0));
  exchange(lcm, daemon, flood);
  daemon.poll(0);  // a heartbeat after the flood
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(seen.rejects.size(), 40u);
  ASSERT_FALSE(seen.statuses.empty());
  const auto& s = seen.statuses.back();
  EXPECT_EQ(s.errors, 40);
  // 40 in the 10-s window (fewer only if this machine stalled for seconds in between).
  EXPECT_LE(s.reject_rate, 4.0);
  EXPECT_GT(s.reject_rate, 1.0);
  EXPECT_EQ(s.health, "degraded");
  EXPECT_EQ(daemon.twin(0).state_seq(), 0);
  daemon.stop();
}

// The last state a dashboard's damage map should show is the end of life: its FIELD goes out
// even when the state is not on the field_every_batches period.
TEST_F(MemqTest, TheEndOfLifeStatePublishesItsField) {
  const config::TwinConfig config = config_of(
      b1_text("every_batches = 0", {{"field_every_batches = 10", "field_every_batches = 1000"}}));
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  struct Sink {
    std::set<std::int64_t> field_states;
    void field(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      const auto f = messages::decode_field(rbuf->data, rbuf->data_size);
      if (f) field_states.insert(f->state_seq);
    }
  } sink;
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kField), &Sink::field, &sink);
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  // Seq 1: 1000 cycles, no end of life; seq 2: enough cycles at 4 kN to reach the 8 mm criterion.
  for (const messages::Batch& b : {messages::Batch{"b1-ct", "p", 1, {{4000, 0.1, 0, 1000}}},
                                   messages::Batch{"b1-ct", "p", 2, {{4000, 0.1, 0, 1'000'000}}}}) {
    const auto m = messages::batch_message(b, 0);
    lcm.publish(messages::channel("b1-ct", messages::Kind::kLoad), &m);
  }
  for (int i = 0; i < 20; ++i) daemon.poll(10);
  daemon.tick();
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(daemon.twin(0).state_seq(), 2);
  ASSERT_NE(daemon.twin(0).failure(), twin::Failure::none);
  EXPECT_EQ(sink.field_states, (std::set<std::int64_t>{0, 2}));  // start and end of life only
  daemon.stop();
}

// The mesh (message set version 6): every chunk on PERITWIN_<DETAIL>_MESH at start, the FIELD at
// start names its hash, and a mesh_request_t has the mesh published again; a request that does not
// decode or names another detail is ignored.
TEST_F(MemqTest, TheMeshIsPublishedAtStartAndOnRequest) {
  const config::TwinConfig config = config_of(b1_text());
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  struct Sink {
    messages::MeshAssembler assembler;
    std::vector<messages::Mesh> meshes;
    std::vector<std::string> errors;
    std::vector<std::string> field_hashes;
    std::size_t chunks = 0;
    void mesh(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      ++chunks;
      auto decoded = messages::decode_mesh_chunk(rbuf->data, rbuf->data_size);
      if (!decoded.chunk) return errors.push_back(decoded.error);
      EXPECT_LE(rbuf->data_size, messages::kMaxMeshChunkBytes);
      auto r = assembler.add(std::move(*decoded.chunk));
      if (!r.error.empty()) errors.push_back(r.error);
      if (r.mesh) meshes.push_back(std::move(*r.mesh));
    }
    void field(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      const auto f = messages::decode_field(rbuf->data, rbuf->data_size);
      if (f) field_hashes.push_back(f->mesh_hash);
    }
  } sink;
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kMesh), &Sink::mesh, &sink);
  lcm.subscribe(messages::channel("b1-ct", messages::Kind::kField), &Sink::field, &sink);
  service::Daemon daemon(lcm, config, options_);
  const core::Status started = daemon.start();
  ASSERT_TRUE(started.ok()) << core::message_of(started);
  while (lcm.handleTimeout(0) > 0) {
  }
  ASSERT_EQ(sink.meshes.size(), 1u);
  EXPECT_TRUE(sink.errors.empty()) << sink.errors.front();
  const messages::Mesh expected = twin::detail_mesh(daemon.twin(0).model());
  EXPECT_EQ(sink.meshes[0], expected);
  EXPECT_EQ(sink.meshes[0].x.size(),
            static_cast<std::size_t>(daemon.twin(0).model().disc().num_nodes()));
  // The B1 outline and its notch are drawn.
  std::map<int, int> kinds;
  for (const auto& line : sink.meshes[0].polylines) ++kinds[line.kind];
  EXPECT_GE(kinds[peritwin_msgs::mesh_polyline_t::KIND_OUTLINE], 1);
  EXPECT_EQ(kinds[peritwin_msgs::mesh_polyline_t::KIND_NOTCH], 1);
  ASSERT_FALSE(sink.field_hashes.empty());
  EXPECT_EQ(sink.field_hashes.front(), messages::mesh_hash(expected));
  const std::size_t chunks_at_start = sink.chunks;

  // Ignored: bytes that are no request, a request for another detail on this channel.
  const std::string requests = messages::channel("b1-ct", messages::Kind::kMeshRequest);
  const std::uint8_t junk[5] = {1, 2, 3, 4, 5};
  lcm.publish(requests, junk, sizeof junk);
  const auto other = messages::mesh_request_message("B1_CT", "test", messages::now_utime());
  lcm.publish(requests, &other);
  // Answered: a request (after the 1 s republish interval, whatever the clock says).
  const auto request = messages::mesh_request_message("b1-ct", "test", messages::now_utime());
  lcm.publish(requests, &request);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kGiveUpS);
  while (sink.meshes.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    lcm.handleTimeout(50);
    daemon.tick();
  }
  ASSERT_EQ(sink.meshes.size(), 2u);
  EXPECT_EQ(sink.meshes[1], expected);
  EXPECT_EQ(sink.chunks, 2 * chunks_at_start);  // one publication for three requests
  daemon.stop();
}

}  // namespace
}  // namespace peritwin::twin
