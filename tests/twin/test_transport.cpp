// The tools when the tcpq hub is not there (issue 14, finding 5), across processes with LCM's Java
// hub on a loopback port: the replay tool exits 3 naming the URL (it used to abort in FD_SET with
// exit 134); the daemon started without a hub waits for it, then serves a replay to the in-process
// final state; a hub killed mid-replay ends the replay with exit 3, and the daemon reconnects to
// the restarted hub with its model and serves the rest of the history. Skipped (GTEST_SKIP) only
// when java or lcm.jar is missing (the first test needs neither).
//
// Timing: as in test_cross_process.cpp, every wait has a deadline of minutes and nothing asserts
// a duration: exit statuses, log lines (waited for) and state hashes.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tests/support/lcm_hub.h"
#include "tests/support/twin_fixtures.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
using namespace peritwin::testing;

constexpr double kWaitS = 900.0;
constexpr const char* kWaitArg = "900";

class Transport : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("peritwin_transport_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    port_ = core::free_loopback_port();  // nothing listens here until a test starts a hub
    url_ = "tcpq://127.0.0.1:" + std::to_string(port_);
    // B1, 3 mm life criterion, 24 batches (testing::write_cross_process_inputs).
    config_ = (dir_ / "b1.toml").string();
    history_ = (dir_ / "history.csv").string();
    testing::write_cross_process_inputs(config_, history_);
  }
  void TearDown() override {
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }

  /// Java and lcm.jar, or the test is skipped.
  bool have_hub() {
    java_ = find_java();
    return !java_.empty() && fs::exists(kLcmJar);
  }
  /// A hub of this test on port_ (again after a kill: the port is the daemon's).
  void start_hub() {
    hub_ = start_lcm_hub(java_, port_, dir_ / "hub.log", kWaitS);
    ASSERT_TRUE(hub_) << "no LCM hub of this test listening on " << url_ << " (see "
                      << (dir_ / "hub.log") << ")";
  }
  void kill_hub() {
    hub_->signal(SIGKILL);
    ASSERT_TRUE(hub_->wait_for(kWaitS).has_value());
    hub_.reset();
  }
  std::unique_ptr<Process> daemon() {
    return std::make_unique<Process>(
        std::vector<std::string>{std::string(PERITWIN_BIN_DIR) + "/peritwin", "--config", config_,
                                 "--lcm-url", url_, "--state-dir", (dir_ / "state").string(),
                                 "--deterministic", "--no-results"},
        (dir_ / "daemon.log").string());
  }
  std::unique_ptr<Process> replay(bool in_process, const std::string& log = "replay.log",
                                  bool resume = false) {
    std::vector<std::string> argv{std::string(PERITWIN_BIN_DIR) + "/peritwin-replay",
                                  "--config",
                                  config_,
                                  "--history",
                                  history_,
                                  "--json"};
    if (in_process) {
      argv.push_back("--in-process");
    } else {
      for (const auto* a : {"--lcm-url", url_.c_str(), "--lockstep", "--give-up-after", kWaitArg}) {
        argv.emplace_back(a);
      }
      if (resume) argv.emplace_back("--resume");
    }
    return std::make_unique<Process>(argv, (dir_ / log).string());
  }
  static std::vector<std::string> lines_to_end(Process& p) {
    std::vector<std::string> lines;
    while (auto line = p.read_line(kWaitS)) lines.push_back(*line);
    return lines;
  }
  /// The in-process run's summary line (the reference of every LCM run).
  std::string reference_summary() {
    auto run = replay(true, "reference.log");
    const auto lines = lines_to_end(*run);
    EXPECT_FALSE(lines.empty());
    return lines.empty() ? std::string() : lines.back();
  }
  /// A lockstep replay over the hub to its end: exit 0 and the in-process summary. `resume`: the
  /// same history again after an interrupted run (--resume).
  void expect_replay_reaches(const std::string& summary, bool resume = false) {
    auto r = replay(false, "replay.log", resume);
    const auto lines = lines_to_end(*r);
    const auto status = r->wait_for(kWaitS);
    ASSERT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
        << "replay: " << (status ? *status : -1) << "\n"
        << read_file(dir_ / "replay.log");
    ASSERT_FALSE(lines.empty());
    EXPECT_EQ(lines.back(), summary);
  }
  /// SIGTERM stops the daemon with exit 0 after its checkpoint; its last line has `hash`.
  void expect_clean_stop(Process& d, const std::string& hash) {
    d.signal(SIGTERM);
    const auto status = d.wait_for(kWaitS);
    ASSERT_TRUE(status.has_value()) << "no exit after SIGTERM";
    EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << *status;
    const std::string log = read_file(dir_ / "daemon.log");
    EXPECT_NE(log.find("state_hash " + hash), std::string::npos) << log;
    EXPECT_EQ(log.find("FD_SETSIZE"), std::string::npos) << log;
  }

  std::string java_, url_, config_, history_;
  int port_ = 0;
  fs::path dir_;
  std::unique_ptr<Process> hub_;
};

TEST_F(Transport, ReplayWithoutHubExitsThreeNamingTheUrl) {
  auto r = replay(false);
  const auto lines = lines_to_end(*r);
  const auto status = r->wait_for(kWaitS);
  ASSERT_TRUE(status.has_value());
  ASSERT_TRUE(WIFEXITED(*status)) << "killed by signal " << WTERMSIG(*status);
  EXPECT_EQ(WEXITSTATUS(*status), 3);
  EXPECT_TRUE(lines.empty());  // no state, no summary
  const std::string log = read_file(dir_ / "replay.log");
  EXPECT_NE(log.find("peritwin-replay: LCM hub " + url_ + " unreachable: Connection refused\n"),
            std::string::npos)
      << log;
}

TEST_F(Transport, DaemonStoppedWhileWaitingForTheHubExitsZero) {
  auto d = daemon();
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", "waiting for it", kWaitS))
      << read_file(dir_ / "daemon.log");
  d->signal(SIGTERM);
  const auto status = d->wait_for(kWaitS);
  ASSERT_TRUE(status.has_value());
  EXPECT_TRUE(WIFEXITED(*status) && WEXITSTATUS(*status) == 0) << *status;
  const std::string log = read_file(dir_ / "daemon.log");
  EXPECT_NE(log.find("LCM hub " + url_ + " unreachable (Connection refused): waiting for it"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("while waiting for the LCM hub: stopping"), std::string::npos) << log;
  EXPECT_EQ(log.find(" ready\n"), std::string::npos) << log;  // nothing was started
}

TEST_F(Transport, DaemonStartedWithoutHubWaitsThenServesAReplay) {
  if (!have_hub()) GTEST_SKIP() << "java or " << kLcmJar << " missing";
  const std::string summary = reference_summary();
  ASSERT_FALSE(state_hash_of(summary).empty()) << summary;

  auto d = daemon();
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", "waiting for it", kWaitS))
      << read_file(dir_ / "daemon.log");
  ASSERT_TRUE(d->running());
  ASSERT_NO_FATAL_FAILURE(start_hub());
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", " ready\n", kWaitS))
      << read_file(dir_ / "daemon.log");
  const std::string log = read_file(dir_ / "daemon.log");
  EXPECT_NE(log.find("LCM hub " + url_ + " reachable after"), std::string::npos) << log;
  // One line while waiting, whatever the number of probes.
  EXPECT_EQ(log.find("waiting for it"), log.rfind("waiting for it")) << log;
  ASSERT_NO_FATAL_FAILURE(expect_replay_reaches(summary));
  ASSERT_NO_FATAL_FAILURE(expect_clean_stop(*d, state_hash_of(summary)));
}

TEST_F(Transport, HubKilledMidReplayDaemonReconnectsAndFinishes) {
  if (!have_hub()) GTEST_SKIP() << "java or " << kLcmJar << " missing";
  const std::string summary = reference_summary();
  ASSERT_FALSE(state_hash_of(summary).empty()) << summary;
  ASSERT_NO_FATAL_FAILURE(start_hub());
  auto d = daemon();
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", " ready\n", kWaitS))
      << read_file(dir_ / "daemon.log");

  // The replay reads state 5, then the hub dies under it: exit 3 naming the hub.
  auto r = replay(false);
  std::int64_t seen = -1;
  while (seen < 5) {
    const auto line = r->read_line(kWaitS);
    ASSERT_TRUE(line.has_value()) << "the replay stopped before state 5\n"
                                  << read_file(dir_ / "replay.log");
    seen = std::max(seen, state_seq_of(*line));
  }
  ASSERT_NO_FATAL_FAILURE(kill_hub());
  lines_to_end(*r);
  const auto status = r->wait_for(kWaitS);
  ASSERT_TRUE(status.has_value());
  ASSERT_TRUE(WIFEXITED(*status)) << "killed by signal " << WTERMSIG(*status);
  // It may, on a loaded machine, have seen the whole history applied before the kill (exit 0).
  if (WEXITSTATUS(*status) != 0) {
    EXPECT_EQ(WEXITSTATUS(*status), 3);
    const std::string log = read_file(dir_ / "replay.log");
    EXPECT_NE(log.find("peritwin-replay: LCM hub " + url_ + ": connection lost"), std::string::npos)
        << log;
  }

  // The daemon says so once, keeps running, and is back once the hub is.
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", "connection lost; the models are kept", kWaitS))
      << read_file(dir_ / "daemon.log");
  ASSERT_TRUE(d->running()) << read_file(dir_ / "daemon.log");
  ASSERT_NO_FATAL_FAILURE(start_hub());
  ASSERT_TRUE(wait_for_text(dir_ / "daemon.log", "reconnected after", kWaitS))
      << read_file(dir_ / "daemon.log");
  const std::string log = read_file(dir_ / "daemon.log");
  EXPECT_EQ(log.find("connection lost"), log.rfind("connection lost")) << log;
  EXPECT_EQ(log.find("resumed from"), std::string::npos) << log;  // the same process, no restart

  // The whole history again (--resume): what the daemon holds comes back as duplicates, the rest
  // is applied.
  ASSERT_NO_FATAL_FAILURE(expect_replay_reaches(summary, true));
  ASSERT_NO_FATAL_FAILURE(expect_clean_stop(*d, state_hash_of(summary)));
}

}  // namespace
}  // namespace peritwin::twin
