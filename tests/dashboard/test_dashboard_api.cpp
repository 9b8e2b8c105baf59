// The dashboard binary next to the daemon binary over tcpq:// with LCM's Java hub, while the
// replay binary applies a short history in lockstep (B1 example, no remaining-life estimates,
// 6 batches): the HTTP API reports the last STATE (cycles, crack length, state_hash), 404 for an
// unknown detail, one history point per state; then headless chromium loads the page and its DOM
// shows the same numbers and one crack-length chart point per state (screenshot in the build
// directory). Skipped (GTEST_SKIP) only without java/lcm.jar, or, for the browser part, chromium.
//
// Every wait has a deadline of minutes (shared, loaded machines); nothing asserts on wall time.
#include <gtest/gtest.h>
#include <httplib.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <thread>

#include "tests/support/lcm_hub.h"
#include "tests/support/process.h"

namespace peritwin::dashboard {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::Process;
using testing::read_file;
using testing::wait_for_text;

constexpr double kWaitS = 900.0;
constexpr int kBatches = 6;
constexpr const char* kChromium = "/usr/bin/chromium";

class DashboardApi : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("peritwin_dashboard_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    hub_ = std::make_unique<testing::LcmHub>(dir_ / "hub.log", kWaitS);
    if (!hub_->missing().empty()) GTEST_SKIP() << hub_->missing();
    ASSERT_TRUE(hub_->up()) << read_file(dir_ / "hub.log");
    // The B1 example without remaining-life estimates, and a short history.
    std::string text = read_file(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
    const std::string anchor = "\nevery_batches = 10\n";
    ASSERT_NE(text.find(anchor), std::string::npos);
    text.replace(text.find(anchor), anchor.size(), "\nevery_batches = 0\n");
    config_ = (dir_ / "b1.toml").string();
    std::ofstream(config_) << text;
    history_ = (dir_ / "history.csv").string();
    std::ofstream h(history_);
    h << "p_max_N,r,angle_rad,count\n";
    for (int i = 0; i < kBatches; ++i) h << "4000,0.1,0,2000\n";
  }
  void TearDown() override {
    if (dashboard_) {
      dashboard_->signal(SIGTERM);
      const auto status = dashboard_->wait_for(kWaitS);
      EXPECT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
          << read_file(dir_ / "dashboard.log");
    }
    if (daemon_) {
      daemon_->signal(SIGTERM);
      daemon_->wait_for(kWaitS);
    }
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }

  /// Starts the dashboard (any free port) and waits for its URL and its subscriptions.
  void start_dashboard() {
    dashboard_ = std::make_unique<Process>(
        std::vector<std::string>{std::string(PERITWIN_BIN_DIR) + "/peritwin-dashboard", "--lcm-url",
                                 hub_->url(), "--listen", "127.0.0.1:0"},
        (dir_ / "dashboard.log").string());
    const auto line = dashboard_->read_line(kWaitS);
    ASSERT_TRUE(line) << read_file(dir_ / "dashboard.log");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(*line, m, std::regex("http://127\\.0\\.0\\.1:([0-9]+)/")))
        << *line;
    port_ = std::stoi(m[1]);
    ASSERT_TRUE(wait_for_text(dir_ / "dashboard.log", "subscribed to", kWaitS))
        << read_file(dir_ / "dashboard.log");
  }

  /// Daemon up, the history replayed in lockstep; returns the replay's last STATE line.
  json run_history() {
    daemon_ = std::make_unique<Process>(
        std::vector<std::string>{std::string(PERITWIN_BIN_DIR) + "/peritwin", "--config", config_,
                                 "--lcm-url", hub_->url(), "--state-dir", (dir_ / "state").string(),
                                 "--deterministic", "--no-results"},
        (dir_ / "daemon.log").string());
    Process replay(
        {std::string(PERITWIN_BIN_DIR) + "/peritwin-replay", "--config", config_, "--history",
         history_, "--json", "--lcm-url", hub_->url(), "--lockstep", "--give-up-after", "900"},
        (dir_ / "replay.log").string());
    json last;
    while (const auto line = replay.read_line(kWaitS)) {
      const auto j = json::parse(*line, nullptr, false);
      if (j.is_object() && j.contains("state_seq")) last = j;
    }
    const auto status = replay.wait_for(kWaitS);
    EXPECT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
        << read_file(dir_ / "replay.log");
    return last;
  }

  /// GET path: {status, body}; status -1 when the request failed.
  std::pair<int, std::string> get(const std::string& path) {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(60, 0);
    const auto res = client.Get(path.c_str());
    if (!res) return {-1, ""};
    return {res->status, res->body};
  }

  /// Waits until /api/details/b1-ct reports `seq`; its JSON (null after the deadline).
  json wait_for_seq(std::int64_t seq) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
    while (std::chrono::steady_clock::now() < deadline) {
      const auto [status, body] = get("/api/details/b1-ct");
      if (status == 200) {
        const auto j = json::parse(body);
        if (j["state_seq"] == seq) return j;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return nullptr;
  }

  fs::path dir_;
  std::string config_, history_;
  int port_ = 0;
  std::unique_ptr<testing::LcmHub> hub_;
  std::unique_ptr<Process> dashboard_, daemon_;
};

TEST_F(DashboardApi, ReportsTheLastStateAndItsHistoryAndThePageShowsThem) {
  ASSERT_NO_FATAL_FAILURE(start_dashboard());
  EXPECT_EQ(get("/api/details/b1-ct").first, 404);  // nothing on the bus yet
  const json last = run_history();
  ASSERT_EQ(last["state_seq"], kBatches) << last.dump();

  const json detail = wait_for_seq(kBatches);
  ASSERT_FALSE(detail.is_null()) << read_file(dir_ / "dashboard.log");
  EXPECT_EQ(detail["cycles"], last["cycles"]);
  EXPECT_EQ(detail["crack_length_m"], last["crack_length_m"]);
  EXPECT_EQ(detail["state_hash"], last["state_hash"]);
  EXPECT_EQ(detail["engine_hash"], last["engine_hash"]);
  EXPECT_EQ(detail["detail"], "b1-ct");
  EXPECT_EQ(detail["undecodable"], 0);

  const auto [missing, error] = get("/api/details/nope");
  EXPECT_EQ(missing, 404);
  EXPECT_TRUE(json::parse(error).contains("error")) << error;
  EXPECT_EQ(get("/api/details/nope/history").first, 404);

  // One point per state: 0 (published at the daemon's start) .. kBatches.
  const auto [hs, hbody] = get("/api/details/b1-ct/history");
  ASSERT_EQ(hs, 200);
  const auto history = json::parse(hbody);
  json seqs = json::array();
  for (int s = 0; s <= kBatches; ++s) seqs.push_back(s);
  EXPECT_EQ(history["state_seq"], seqs);
  EXPECT_EQ(history["cycles"].back(), last["cycles"]);
  EXPECT_EQ(history["crack_length_m"].size(), std::size_t(kBatches + 1));

  const auto list = json::parse(get("/api/details").second);
  ASSERT_EQ(list["details"].size(), 1u);
  EXPECT_EQ(list["details"][0]["cycles"], last["cycles"]);
  EXPECT_EQ(get("/").first, 200);
  EXPECT_EQ(get("/chart.js").first, 200);

  // The page in a real browser. ?events=off: headless chromium's virtual time does not run out
  // while an event stream is open; the page loads /api/details and the history either way.
  if (!fs::exists(kChromium))
    GTEST_SKIP() << kChromium << " not installed (scripts/install-deps.sh)";
  const std::string url = "http://127.0.0.1:" + std::to_string(port_) + "/?events=off";
  const std::vector<std::string> common{kChromium,
                                        "--headless",
                                        "--no-sandbox",
                                        "--disable-gpu",
                                        "--window-size=1300,900",
                                        "--virtual-time-budget=10000"};
  auto dom_args = common;
  dom_args.insert(dom_args.end(), {"--dump-dom", url});
  Process dom(dom_args, (dir_ / "chromium.log").string());
  std::string html;
  while (const auto line = dom.read_line(kWaitS)) html += *line + "\n";
  const auto status = dom.wait_for(kWaitS);
  ASSERT_TRUE(status && WIFEXITED(*status) && WEXITSTATUS(*status) == 0)
      << read_file(dir_ / "chromium.log");
  std::smatch m;
  // The card (the <template> holds another copy without data-detail).
  const auto card_at = html.find("data-detail=\"b1-ct\"");
  ASSERT_NE(card_at, std::string::npos) << html;
  const std::string card = html.substr(card_at);
  ASSERT_TRUE(std::regex_search(card, m, std::regex("class=\"cycles\" data-value=\"([0-9]+)\"")))
      << card;
  EXPECT_EQ(std::stoll(m[1]), last["cycles"].get<std::int64_t>());
  ASSERT_TRUE(std::regex_search(
      card, m, std::regex("class=\"crack-length\" data-value=\"([^\"]*)\">([^<]*)<")))
      << card;
  EXPECT_DOUBLE_EQ(std::stod(m[1]), last["crack_length_m"].get<double>());
  char mm[32];
  std::snprintf(mm, sizeof mm, "%.3f", last["crack_length_m"].get<double>() * 1e3);
  EXPECT_EQ(m[2], mm);
  ASSERT_TRUE(
      std::regex_search(card, m, std::regex("class=\"chart-crack\" data-points=\"([0-9]+)\"")))
      << card;
  EXPECT_EQ(std::stoi(m[1]), kBatches + 1);

  const fs::path shot = fs::path(PERITWIN_TEST_OUT_DIR) / "dashboard-test.png";
  fs::remove(shot);
  auto shot_args = common;
  shot_args.insert(shot_args.end(), {"--screenshot=" + shot.string(), url});
  Process screenshot(shot_args, (dir_ / "chromium.log").string());
  const auto shot_status = screenshot.wait_for(kWaitS);
  EXPECT_TRUE(shot_status && WIFEXITED(*shot_status) && WEXITSTATUS(*shot_status) == 0)
      << read_file(dir_ / "chromium.log");
  EXPECT_TRUE(fs::exists(shot) && fs::file_size(shot) > 0) << shot;
}

}  // namespace
}  // namespace peritwin::dashboard
