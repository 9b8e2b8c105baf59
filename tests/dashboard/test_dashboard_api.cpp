// The dashboard binary next to the daemon binary over tcpq:// with LCM's Java hub, while the
// replay binary applies a short history in lockstep (B1 example, no remaining-life estimates,
// 6 batches): the HTTP API reports the last STATE (cycles, crack length, state_hash), 404 for an
// unknown detail, one history point per state; then headless chromium loads the page and its DOM
// shows the same numbers and one crack-length chart point per state (screenshot in the build
// directory). A second test opens the page first, events on, and reads its live DOM through the
// DevTools protocol while the daemon applies the history (tests/dashboard/cdp_pipe.h). The mesh
// and the newest field the API serves equal what the daemon published (the
// test subscribes too), and the page draws the damage map (its canvas says how many nodes, which
// field and how many crack paths) with its legend. A second dashboard started after the run gets
// the mesh by asking the daemon (mesh_request_t) and the whole history from the daemon's results
// file (--results). Skipped (GTEST_SKIP) only without java/lcm.jar, or, for the browser part,
// chromium.
//
// Every wait has a deadline of minutes (shared, loaded machines); nothing asserts on wall time.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <thread>

#include "core/proc_files.h"
#include "dashboard/server.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "messages/mesh.h"
#include "outputs/results_writer.h"
#include "tests/dashboard/cdp_pipe.h"
#include "tests/support/http_chunks.h"
#include "tests/support/lcm_hub.h"
#include "tests/support/process.h"
#include "tests/support/state_messages.h"

namespace peritwin::dashboard {
namespace {

using testing::dechunk;

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
    // Results under the test's directory, a FIELD after every batch.
    const std::string output = "directory = \"results/b1-ct\"\nfield_every_batches = 10\n";
    ASSERT_NE(text.find(output), std::string::npos);
    text.replace(
        text.find(output), output.size(),
        "directory = \"" + (dir_ / "results" / "b1-ct").string() + "\"\nfield_every_batches = 1\n");
    config_ = (dir_ / "b1.toml").string();
    std::ofstream(config_) << text;
    history_ = (dir_ / "history.csv").string();
    std::ofstream h(history_);
    h << "p_max_N,r,angle_rad,count\n";
    for (int i = 0; i < kBatches; ++i) h << "4000,0.1,0,2000\n";
  }
  void TearDown() override {
    stop_listening();
    if (late_) {
      late_->signal(SIGTERM);
      late_->wait_for(kWaitS);
    }
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

  /// Starts a dashboard (any free port) and waits for its URL and its subscriptions.
  void start_dashboard(std::unique_ptr<Process>& process, int& port, const std::string& log,
                       std::vector<std::string> extra = {}) {
    std::vector<std::string> args{std::string(PERITWIN_BIN_DIR) + "/peritwin-dashboard",
                                  "--lcm-url", hub_->url(), "--listen", "127.0.0.1:0"};
    args.insert(args.end(), extra.begin(), extra.end());
    process = std::make_unique<Process>(args, (dir_ / log).string());
    const auto line = process->read_line(kWaitS);
    ASSERT_TRUE(line) << read_file(dir_ / log);
    std::smatch m;
    ASSERT_TRUE(std::regex_search(*line, m, std::regex("http://127\\.0\\.0\\.1:([0-9]+)/")))
        << *line;
    port = std::stoi(m[1]);
    ASSERT_TRUE(wait_for_text(dir_ / log, "subscribed to", kWaitS)) << read_file(dir_ / log);
  }
  void start_dashboard() { start_dashboard(dashboard_, port_, "dashboard.log"); }

  /// Subscribes this process to the detail's MESH and FIELD channels (a thread handles LCM): what
  /// the daemon published, to compare the API with.
  void listen_to_bus() {
    bus_ = std::make_unique<lcm::LCM>(hub_->url());
    ASSERT_TRUE(bus_->good());
    bus_->subscribe(messages::channel("b1-ct", messages::Kind::kMesh), &DashboardApi::on_mesh,
                    this);
    bus_->subscribe(messages::channel("b1-ct", messages::Kind::kField), &DashboardApi::on_field,
                    this);
    listening_ = true;
    listener_ = std::thread([this] {
      while (listening_) messages::handle_lcm(*bus_, 100);
    });
  }
  void stop_listening() {
    listening_ = false;
    if (listener_.joinable()) listener_.join();
  }
  void on_mesh(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    auto decoded = messages::decode_mesh_chunk(rbuf->data, rbuf->data_size);
    const std::lock_guard lock(bus_mutex_);
    ++mesh_chunks_;
    if (!decoded.chunk) return;
    if (auto r = assembler_.add(std::move(*decoded.chunk)); r.mesh) mesh_ = std::move(r.mesh);
  }
  void on_field(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    auto f = messages::decode_field(rbuf->data, rbuf->data_size);
    if (!f) return;
    const std::lock_guard lock(bus_mutex_);
    auto& damage = fields_[f->state_seq];
    damage.resize(static_cast<std::size_t>(f->total_nodes));
    std::copy(f->damage.begin(), f->damage.end(),
              damage.begin() + static_cast<std::ptrdiff_t>(f->first_node));
    field_hash_ = f->mesh_hash;
  }

  /// Daemon up, the history replayed in lockstep; returns the replay's last STATE line.
  json run_history() {
    daemon_ = std::make_unique<Process>(
        std::vector<std::string>{std::string(PERITWIN_BIN_DIR) + "/peritwin", "--config", config_,
                                 "--lcm-url", hub_->url(), "--state-dir", (dir_ / "state").string(),
                                 "--deterministic"},
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
  std::pair<int, std::string> get(const std::string& path, int port = 0) {
    httplib::Client client("127.0.0.1", port == 0 ? port_ : port);
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

  /// Waits until GET `path` on `port` answers 200; its JSON (null after the deadline).
  json wait_for_ok(const std::string& path, int port) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
    while (std::chrono::steady_clock::now() < deadline) {
      const auto [status, body] = get(path, port);
      if (status == 200) return json::parse(body);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return nullptr;
  }

  fs::path dir_;
  std::string config_, history_;
  int port_ = 0, late_port_ = 0;
  std::unique_ptr<testing::LcmHub> hub_;
  std::unique_ptr<Process> dashboard_, daemon_, late_;
  std::unique_ptr<lcm::LCM> bus_;
  std::thread listener_;
  std::atomic<bool> listening_{false};
  std::mutex bus_mutex_;
  messages::MeshAssembler assembler_;
  std::optional<messages::Mesh> mesh_;
  std::size_t mesh_chunks_ = 0;
  std::map<std::int64_t, std::vector<float>> fields_;
  std::string field_hash_;
};

/// The API's mesh equals `mesh`.
void expect_mesh(const json& api, const messages::Mesh& mesh) {
  EXPECT_EQ(api["mesh_hash"], messages::mesh_hash(mesh));
  EXPECT_EQ(api["total_nodes"], mesh.x.size());
  EXPECT_EQ(api["x"].get<std::vector<double>>(), mesh.x);
  EXPECT_EQ(api["y"].get<std::vector<double>>(), mesh.y);
  EXPECT_EQ(api["dx"], mesh.dx);
  EXPECT_EQ(api["polylines"].size(), mesh.polylines.size());
}

TEST_F(DashboardApi, ReportsTheLastStateAndItsHistoryAndThePageShowsThem) {
  ASSERT_NO_FATAL_FAILURE(listen_to_bus());
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

  // The event stream from the start (?after=0): every STATE's event, in order, with its cycles.
  // A STATE published again (the daemon answers the replay's probe with the current state, state
  // 0 here) is an event too: consecutive events of one state count once.
  {
    httplib::Client client("127.0.0.1", port_);
    client.set_read_timeout(60, 0);
    std::string stream;
    std::vector<json> states;
    client.Get("/api/events?after=0", [&](const char* data, std::size_t size) {
      stream.append(data, size);
      for (std::size_t end; (end = stream.find("\n\n")) != std::string::npos;
           stream.erase(0, end + 2)) {
        const std::string event = stream.substr(0, end);
        const auto at = event.find("\ndata: ");
        if (event.find("event: state\n") == std::string::npos || at == std::string::npos) continue;
        json summary = json::parse(event.substr(at + 7))["summary"];
        if (states.empty() || states.back()["state_seq"] != summary["state_seq"]) {
          states.push_back(std::move(summary));
        }
      }
      return states.empty() || states.back()["state_seq"] != kBatches;
    });
    ASSERT_EQ(states.size(), std::size_t(kBatches + 1));
    for (int s = 0; s <= kBatches; ++s) {
      EXPECT_EQ(states[std::size_t(s)]["state_seq"], s);
      EXPECT_EQ(states[std::size_t(s)]["cycles"], history["cycles"][std::size_t(s)]);
    }
  }

  const auto list = json::parse(get("/api/details").second);
  ASSERT_EQ(list["details"].size(), 1u);
  EXPECT_EQ(list["details"][0]["cycles"], last["cycles"]);
  {  // The snapshot names the newest event it includes (at least the states').
    httplib::Client client("127.0.0.1", port_);
    const auto res = client.Get("/api/details");
    ASSERT_TRUE(res && res->has_header("X-Last-Event-Id"));
    EXPECT_GE(std::stoull(res->get_header_value("X-Last-Event-Id")), std::uint64_t(kBatches + 1));
  }
  EXPECT_EQ(get("/").first, 200);
  EXPECT_EQ(get("/chart.js").first, 200);

  // The mesh and the last field, as the daemon published them (FIELD after every batch).
  const json api_field = [&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
    while (std::chrono::steady_clock::now() < deadline) {
      const auto [status, body] = get("/api/details/b1-ct/field");
      if (status == 200 && json::parse(body)["state_seq"] == kBatches) return json::parse(body);
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return json();
  }();
  ASSERT_FALSE(api_field.is_null()) << read_file(dir_ / "dashboard.log");
  const json api_mesh = wait_for_ok("/api/details/b1-ct/mesh", port_);
  ASSERT_FALSE(api_mesh.is_null());
  EXPECT_EQ(get("/api/details/nope/mesh").first, 404);
  EXPECT_EQ(get("/api/details/nope/field").first, 404);
  {
    const std::lock_guard lock(bus_mutex_);
    ASSERT_TRUE(mesh_) << "the daemon published no complete mesh";
    expect_mesh(api_mesh, *mesh_);
    EXPECT_EQ(api_field["mesh_hash"], messages::mesh_hash(*mesh_));
    EXPECT_EQ(field_hash_, messages::mesh_hash(*mesh_));
    ASSERT_TRUE(fields_.count(kBatches));
    EXPECT_EQ(api_field["damage"].get<std::vector<float>>(), fields_.at(kBatches));
  }
  const json with_mesh = json::parse(get("/api/details/b1-ct").second);
  EXPECT_EQ(with_mesh["mesh_hash"], api_mesh["mesh_hash"]);
  EXPECT_EQ(with_mesh["field_seq"], kBatches);

  // A dashboard started now has missed the daemon's start: it asks for the mesh, and reads the
  // history from the results file.
  ASSERT_NO_FATAL_FAILURE(
      start_dashboard(late_, late_port_, "late.log", {"--results", (dir_ / "results").string()}));
  const json late_mesh = wait_for_ok("/api/details/b1-ct/mesh", late_port_);
  ASSERT_FALSE(late_mesh.is_null())
      << read_file(dir_ / "late.log") << read_file(dir_ / "daemon.log");
  EXPECT_EQ(late_mesh, api_mesh);
  EXPECT_TRUE(wait_for_text(dir_ / "daemon.log", "mesh requested by peritwin-dashboard", kWaitS));
  const auto late_history = json::parse(get("/api/details/b1-ct/history", late_port_).second);
  EXPECT_EQ(late_history["backfilled"], kBatches + 1) << read_file(dir_ / "late.log");
  for (const char* column : {"state_seq", "cycles", "crack_length_m", "remaining"}) {
    EXPECT_EQ(late_history[column], history[column]) << column;
  }
  // Issue 30 item 3: no STATE since it started, yet its card is the results file's last row and
  // its map the file's newest snapshot (drawn on the mesh it asked for), not "–" and a blank map.
  {
    const auto rows = outputs::read_time_series(dir_ / "results" / "b1-ct" / "b1-ct.h5");
    ASSERT_FALSE(rows.empty());
    const auto& row = rows.back();
    const json card = json::parse(get("/api/details/b1-ct", late_port_).second);
    EXPECT_EQ(card["from_results"], true) << card.dump();
    EXPECT_EQ(card["state_seq"], row.state_seq);
    EXPECT_EQ(card["state_seq"], kBatches);
    EXPECT_EQ(card["cycles"], row.total_cycles);
    EXPECT_EQ(card["cycles"], last["cycles"]);
    EXPECT_EQ(card["broken_bonds"], row.broken_bonds);
    EXPECT_EQ(card["crack_length_m"], row.crack_length_m);
    EXPECT_EQ(card["crack_length_m"], last["crack_length_m"]);
    EXPECT_EQ(card["crack_count"], row.crack_count);
    const auto snapshots = outputs::read_snapshot_list(dir_ / "results" / "b1-ct" / "b1-ct.h5");
    ASSERT_FALSE(snapshots.empty());
    const auto& newest = snapshots.back();
    const json late_field = [&] {
      const auto deadline =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
      while (std::chrono::steady_clock::now() < deadline) {
        const auto [status, body] = get("/api/details/b1-ct/field", late_port_);
        if (status == 200 && json::parse(body)["mesh_hash"] == api_mesh["mesh_hash"]) {
          return json::parse(body);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      return json();
    }();
    ASSERT_FALSE(late_field.is_null()) << read_file(dir_ / "late.log");
    EXPECT_EQ(late_field["state_seq"], newest.state_seq);
    EXPECT_EQ(late_field["from_results"], true);
    EXPECT_EQ(late_field["damage"].get<std::vector<float>>(),
              outputs::read_snapshot_damage(dir_ / "results" / "b1-ct" / "b1-ct.h5", newest));
  }

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
  // The damage map: every node of the mesh, the last field, the legend drawn.
  ASSERT_TRUE(std::regex_search(card, m, std::regex("class=\"damage-map\"[^>]*>"))) << card;
  const std::string map_tag = m[0];
  ASSERT_TRUE(std::regex_search(map_tag, m, std::regex("data-nodes=\"([0-9]+)\""))) << map_tag;
  EXPECT_EQ(std::stoul(m[1]), api_mesh["total_nodes"].get<std::size_t>());
  ASSERT_TRUE(std::regex_search(map_tag, m, std::regex("data-field-seq=\"([0-9]+)\""))) << map_tag;
  EXPECT_EQ(std::stoi(m[1]), kBatches);
  ASSERT_TRUE(std::regex_search(map_tag, m, std::regex("data-mesh-hash=\"([0-9a-f]+)\"")))
      << map_tag;
  EXPECT_EQ(m[1], api_mesh["mesh_hash"].get<std::string>());
  EXPECT_NE(card.find("class=\"damage-legend\" width=\"64\" height=\"320\" data-drawn=\"true\""),
            std::string::npos)
      << card;

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

// The page opened first, before any detail is on the bus and with its event stream on; then the
// daemon applies the history. Read from the live DOM through the DevTools protocol (chromium
// --remote-debugging-pipe): the card shows the last STATE's cycles and crack length, the
// crack-length chart holds one point per state at the API history's cycles and lengths, and the
// damage map shows the last field — in the same document (a mark set before the run is still
// there: no reload), updated by the state events it counted. Screenshot in the build directory.
TEST_F(DashboardApi, ThePageOpenedFirstUpdatesLiveAsTheDaemonAppliesTheHistory) {
  if (!fs::exists(kChromium))
    GTEST_SKIP() << kChromium << " not installed (scripts/install-deps.sh)";
  ASSERT_NO_FATAL_FAILURE(start_dashboard());
  testing::CdpPipe browser(
      {kChromium, "--headless", "--no-sandbox", "--disable-gpu", "--window-size=1300,1000",
       "--no-first-run", "--user-data-dir=" + (dir_ / "chromium-profile").string(), "about:blank"},
      (dir_ / "chromium.log").string());
  ASSERT_TRUE(browser.started());
  const auto targets = browser.call("Target.getTargets", json::object(), "", kWaitS);
  ASSERT_TRUE(targets) << read_file(dir_ / "chromium.log");
  std::string target;
  for (const auto& t : (*targets)["result"]["targetInfos"]) {
    if (t["type"] == "page") target = t["targetId"];
  }
  ASSERT_FALSE(target.empty()) << targets->dump();
  const auto attached =
      browser.call("Target.attachToTarget", {{"targetId", target}, {"flatten", true}}, "", kWaitS);
  ASSERT_TRUE(attached && (*attached)["result"].contains("sessionId"))
      << attached.value_or(json()).dump();
  const std::string page = (*attached)["result"]["sessionId"];
  const std::string url = "http://127.0.0.1:" + std::to_string(port_) + "/";
  const auto navigated = browser.call("Page.navigate", {{"url", url}}, page, kWaitS);
  ASSERT_TRUE(navigated && !(*navigated)["result"].contains("errorText"))
      << navigated.value_or(json()).dump();

  // Polls `expression` until it is true (the deadline is kWaitS).
  const auto wait_until = [&](const std::string& expression) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
    while (std::chrono::steady_clock::now() < deadline) {
      if (const auto v = browser.evaluate(page, expression, 60.0); v && *v == true) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  };
  // The event stream is open, no detail yet; the mark tells this document from a reloaded one.
  ASSERT_TRUE(wait_until("document.getElementById('connection').textContent === 'live'"))
      << read_file(dir_ / "chromium.log");
  EXPECT_EQ(browser.evaluate(page, "document.querySelectorAll('.card[data-detail]').length", 60)
                .value_or(json()),
            json(0));
  ASSERT_TRUE(
      browser.evaluate(page, "window.peritwinMark = 'before the run'; true", 60).has_value());

  const json last = run_history();
  ASSERT_EQ(last["state_seq"], kBatches) << last.dump();
  const auto [hs, hbody] = get("/api/details/b1-ct/history");
  ASSERT_EQ(hs, 200);
  const auto history = json::parse(hbody);

  // What the page shows once its card has the last state and the last field drawn.
  const std::string card = "document.querySelector('.card[data-detail=\"b1-ct\"]')";
  ASSERT_TRUE(wait_until(
      "(() => { const c = " + card +
      "; return c !== null && c.querySelector('.state-seq').dataset.value === '" +
      std::to_string(kBatches) + "' && c.querySelector('.damage-map').dataset.fieldSeq === '" +
      std::to_string(kBatches) + "'; })()"))
      << browser.evaluate(page, "document.body.outerHTML", 60).value_or(json()).dump();
  const auto shown = browser.evaluate(page, "(() => { const c = " + card + R"(;
      const chart = Chart.getChart(c.querySelector('.chart-crack'));
      const points = chart.data.datasets[0].data;
      return {mark: window.peritwinMark ?? null,
              stateEvents: Number(document.body.dataset.stateEvents ?? 0),
              cycles: c.querySelector('.cycles').dataset.value,
              cyclesText: c.querySelector('.cycles').textContent,
              crack: c.querySelector('.crack-length').dataset.value,
              crackText: c.querySelector('.crack-length').textContent,
              dataPoints: Number(c.querySelector('.chart-crack').dataset.points),
              x: points.map(p => p.x), y: points.map(p => p.y),
              mapNodes: Number(c.querySelector('.damage-map').dataset.nodes)}; })())",
                                      60);
  ASSERT_TRUE(shown && shown->is_object()) << read_file(dir_ / "chromium.log");
  const json& s = *shown;
  EXPECT_EQ(s["mark"], "before the run") << "the page was reloaded";
  // Every state arrived as an event (the card was created by the first one).
  EXPECT_GE(s["stateEvents"].get<int>(), kBatches + 1);
  EXPECT_EQ(std::stoll(s["cycles"].get<std::string>()), last["cycles"].get<std::int64_t>());
  EXPECT_DOUBLE_EQ(std::stod(s["crack"].get<std::string>()), last["crack_length_m"].get<double>());
  char mm[32];
  std::snprintf(mm, sizeof mm, "%.3f", last["crack_length_m"].get<double>() * 1e3);
  EXPECT_EQ(s["crackText"], mm);
  // One chart point per state, at the history's cycles and crack lengths (mm; the page's
  // product by 1e3 in double, so within an ulp or two of ours).
  EXPECT_EQ(s["dataPoints"], kBatches + 1);
  ASSERT_EQ(s["x"].size(), history["cycles"].size());
  ASSERT_EQ(s["y"].size(), history["crack_length_m"].size());
  for (std::size_t i = 0; i < s["x"].size(); ++i) {
    EXPECT_EQ(s["x"][i].get<double>(), history["cycles"][i].get<double>()) << i;
    EXPECT_NEAR(s["y"][i].get<double>(), history["crack_length_m"][i].get<double>() * 1e3,
                1e-12 * (1.0 + std::abs(s["y"][i].get<double>())))
        << i;
  }
  EXPECT_GT(s["mapNodes"].get<int>(), 0);

  // Issue 30 item 2: whatever the replay's probe (seq 2^63 − 1, answered with GAP when the daemon
  // was up to hear it) did, the card counts refusals only: none here.
  const auto rejects = browser.evaluate(page, "(() => { const c = " + card + R"(;
      return {rejects: c.querySelector('.rejects').dataset.value,
              lastRejectHidden: c.querySelector('.last-reject').hidden}; })())",
                                        60);
  ASSERT_TRUE(rejects && rejects->is_object());
  EXPECT_EQ((*rejects)["rejects"], "0");
  EXPECT_EQ((*rejects)["lastRejectHidden"], true);

  // Issue 30 item 1, in the page: a detail whose STATEs (published here) carry the estimate made
  // on the initial state, 38,373 cycles, then 3,000 and 9,000 cycles applied: the card counts
  // down to 29,373 and the chart falls by the cycles applied; a refusal is counted; then the
  // detail fails: END OF LIFE.
  lcm::LCM bus(hub_->url());
  ASSERT_TRUE(bus.good());
  const std::string demo = "life-demo";
  const auto demo_state = [&](std::int64_t seq, std::int64_t cycles) {
    auto m = testing::minimal_state(demo, seq, cycles);
    m.remaining_cycles = 38373.0;
    m.remaining_cycles_low = 30000.0;
    m.remaining_cycles_high = 50000.0;
    return m;
  };
  const std::vector<std::int64_t> demo_cycles{0, 3000, 9000};
  for (std::size_t k = 0; k < demo_cycles.size(); ++k) {
    const auto m = demo_state(static_cast<std::int64_t>(k), demo_cycles[k]);
    bus.publish(messages::channel(demo, messages::Kind::kState), &m);
  }
  const auto refusal = messages::reject_message(
      demo, "gauge", 7, {messages::Verdict::invalid, "blocks[0].r", "r = 1.2 must be < 1"}, 1);
  bus.publish(messages::channel(demo, messages::Kind::kReject), &refusal);
  // A producer's probe and a resend: protocol events, shown apart, the probe's seq exactly.
  const auto duplicate = messages::reject_message(
      demo, "gauge", 2, {messages::Verdict::duplicate, "seq", "seq 2 is already applied"}, 1);
  bus.publish(messages::channel(demo, messages::Kind::kReject), &duplicate);
  const auto probe =
      messages::reject_message(demo, "gauge", std::numeric_limits<std::int64_t>::max(),
                               {messages::Verdict::gap, "seq", "probe"}, 1);
  bus.publish(messages::channel(demo, messages::Kind::kReject), &probe);
  const std::string demo_card = "document.querySelector('.card[data-detail=\"life-demo\"]')";
  ASSERT_TRUE(wait_until("(() => { const c = " + demo_card +
                         "; return c !== null && c.querySelector('.state-seq').dataset.value === "
                         "'2' && c.querySelector('.probes').dataset.value === '1'; })()"))
      << browser.evaluate(page, "document.body.outerHTML", 60).value_or(json()).dump();
  const auto life = browser.evaluate(page, "(() => { const c = " + demo_card + R"(;
      const chart = Chart.getChart(c.querySelector('.chart-life'));
      return {remaining: c.querySelector('.remaining').dataset.value,
              remainingText: c.querySelector('.remaining').textContent,
              end: c.querySelector('.end-of-life').dataset.value,
              x: chart.data.datasets[2].data.map(p => p.x),
              y: chart.data.datasets[2].data.map(p => p.y),
              eolHidden: c.querySelector('.eol').hidden,
              rejects: c.querySelector('.rejects').dataset.value,
              lastReject: c.querySelector('.last-reject').textContent,
              duplicates: c.querySelector('.duplicates').dataset.value,
              lastProtocol: c.querySelector('.last-protocol').dataset.value,
              lastProtocolText: c.querySelector('.last-protocol').textContent}; })())",
                                     60);
  ASSERT_TRUE(life && life->is_object()) << read_file(dir_ / "chromium.log");
  EXPECT_EQ((*life)["rejects"], "1");
  EXPECT_NE((*life)["lastReject"].get<std::string>().find("r = 1.2 must be < 1"),
            std::string::npos);
  EXPECT_EQ((*life)["duplicates"], "1");
  EXPECT_EQ((*life)["lastProtocol"], "9223372036854775807");
  EXPECT_NE((*life)["lastProtocolText"].get<std::string>().find("seq 9223372036854775807"),
            std::string::npos)
      << life->dump();
  EXPECT_EQ((*life)["remaining"], "29373");
  EXPECT_EQ((*life)["remainingText"], "29,373");
  EXPECT_EQ((*life)["end"], "38373");
  EXPECT_EQ((*life)["eolHidden"], true);
  ASSERT_EQ((*life)["y"].size(), demo_cycles.size()) << life->dump();
  for (std::size_t k = 0; k < demo_cycles.size(); ++k) {
    EXPECT_EQ((*life)["x"][k].get<double>(), static_cast<double>(demo_cycles[k]));
    EXPECT_EQ((*life)["y"][k].get<double>(), 38373.0 - static_cast<double>(demo_cycles[k]));
  }
  auto failed = demo_state(3, 9500);
  failed.failure = peritwin_msgs::damage_state_t::FAILURE_END_CRITERION;
  failed.end_of_life_cycle = 9400;
  failed.remaining_cycles = failed.remaining_cycles_low = failed.remaining_cycles_high = 0.0;
  bus.publish(messages::channel(demo, messages::Kind::kState), &failed);
  ASSERT_TRUE(wait_until("(() => { const c = " + demo_card +
                         "; return c.querySelector('.state-seq').dataset.value === '3'; })()"));
  const auto eol = browser.evaluate(page, "(() => { const c = " + demo_card + R"(;
      return {eolHidden: c.querySelector('.eol').hidden,
              eolText: c.querySelector('.eol').textContent,
              health: c.querySelector('.health').textContent,
              remaining: c.querySelector('.remaining').dataset.value,
              end: c.querySelector('.end-of-life').dataset.value}; })())",
                                    60);
  ASSERT_TRUE(eol && eol->is_object());
  EXPECT_EQ((*eol)["eolHidden"], false);
  EXPECT_EQ((*eol)["eolText"], "end of life");  // shown upper case by CSS
  EXPECT_NE((*eol)["health"], "failed");
  EXPECT_EQ((*eol)["remaining"], "0");
  EXPECT_EQ((*eol)["end"], "9400");

  // Issue 32 item 6, in the page: a learning detail (STATEs with its ensemble, published here)
  // at 0, 20,000 and 40,000 cycles; the end of life predicted at the 5/50/95th percentiles moves
  // and narrows; two observations (a crack of 2.1 ± 0.3 mm at 35,000 cycles, no crack found at
  // 15,000 with a50 0.8 mm). The fan chart holds one point per state at the history's numbers, the
  // crack-length chart the two markers with their bars, the card the posterior and P(horizon).
  const std::string learn = "learn-demo";
  const std::vector<std::int64_t> learn_cycles{0, 20000, 40000};
  const std::vector<std::vector<double>> learn_eol{
      {60000.0, 90000.0, 150000.0}, {65000.0, 85000.0, 120000.0}, {70000.0, 82000.0, 95000.0}};
  const std::vector<testing::StateObservation> observed{
      {.cycle = 15000, .no_crack = true, .pod_a50_m = 0.8e-3, .predicted_m = 0.0},
      {.cycle = 35000, .length_m = 2.1e-3, .sigma_m = 0.3e-3, .predicted_m = 1.7e-3}};
  for (std::size_t k = 0; k < learn_cycles.size(); ++k) {
    auto m = testing::minimal_state(learn, static_cast<std::int64_t>(k), learn_cycles[k]);
    // The observations as taken in by the ensemble: none, the first, both.
    const double kd = static_cast<double>(k);
    testing::set_ensemble(m, 64, learn_cycles[k], learn_eol[k], 50000.0, 0.05 * (kd + 1),
                          60.0 - 10.0 * kd,
                          {{1.2e-9 * (1 + 0.1 * kd), 0.3 / (kd + 1)}, {1.0, 0.05}},
                          std::vector<testing::StateObservation>(
                              observed.begin(), observed.begin() + static_cast<std::ptrdiff_t>(k)));
    bus.publish(messages::channel(learn, messages::Kind::kState), &m);
  }
  const std::string learn_card = "document.querySelector('.card[data-detail=\"learn-demo\"]')";
  ASSERT_TRUE(wait_until("(() => { const c = " + learn_card +
                         "; return c !== null && c.querySelector('.state-seq').dataset.value === "
                         "'2' && c.querySelector('.chart-crack').dataset.observations === '2' && "
                         "c.querySelector('.chart-eol').dataset.points === '3'; })()"))
      << browser.evaluate(page, "document.body.outerHTML", 60).value_or(json()).dump();
  const auto [ls, lbody] = get("/api/details/learn-demo/history");
  ASSERT_EQ(ls, 200);
  const auto learn_history = json::parse(lbody);
  EXPECT_EQ(learn_history["eol_median"], json({90000, 85000, 82000})) << lbody;
  EXPECT_EQ(learn_history["eol_percentiles"], json({5.0, 50.0, 95.0})) << lbody;
  ASSERT_EQ(learn_history["observations"].size(), 2u) << lbody;
  const auto fan = browser.evaluate(page,
                                    "(() => { const c = " + learn_card + R"(;
      const eol = Chart.getChart(c.querySelector('.chart-eol'));
      const crack = Chart.getChart(c.querySelector('.chart-crack'));
      const xy = d => d.data.map(p => [p.x, p.y]);
      const bar = d => d.data.map(p => [p.x, p.y, p.lo, p.hi]);
      return {fanHidden: c.querySelector('.fan').hidden,
              low: xy(eol.data.datasets[0]), high: xy(eol.data.datasets[1]),
              median: xy(eol.data.datasets[2]),
              bandFill: eol.data.datasets[1].fill,
              observed: bar(crack.data.datasets[1]), noCrack: bar(crack.data.datasets[2]),
              predicted: xy(crack.data.datasets[3]),
              observedStyle: crack.data.datasets[1].pointStyle,
              noCrackStyle: crack.data.datasets[2].pointStyle,
              markers: crack.getDatasetMeta(1).data.length + crack.getDatasetMeta(2).data.length,
              ensembleHidden: c.querySelector('.ensemble').hidden,
              eolMedian: c.querySelector('.eol-median').dataset.value,
              eolLow: c.querySelector('.eol-band').dataset.low,
              eolHigh: c.querySelector('.eol-band').dataset.high,
              pHorizon: c.querySelector('.p-horizon').dataset.value,
              pHorizonTitle: c.querySelector('.p-horizon-title').textContent,
              ess: c.querySelector('.ess').dataset.value,
              parameters: [...c.querySelectorAll('.posterior .parameter')].map(
                  p => [p.dataset.name, Number(p.dataset.median), Number(p.dataset.cov)]),
              // The life-demo detail has no ensemble: no fan chart, no posterior.
              otherFanHidden: )" + demo_card +
                                        R"(.querySelector('.fan').hidden,
              otherEnsembleHidden: )" + demo_card +
                                        R"(.querySelector('.ensemble').hidden}; })())",
                                    60);
  ASSERT_TRUE(fan && fan->is_object()) << read_file(dir_ / "chromium.log");
  const json& f = *fan;
  EXPECT_EQ(f["fanHidden"], false);
  EXPECT_EQ(f["bandFill"], "-1");  // the 5–95 % band shaded down to the 5 % line
  for (std::size_t k = 0; k < learn_cycles.size(); ++k) {
    const double x = static_cast<double>(learn_cycles[k]);
    EXPECT_EQ(f["low"][k], json({x, learn_eol[k][0]})) << f.dump();
    EXPECT_EQ(f["median"][k], json({x, learn_eol[k][1]})) << f.dump();
    EXPECT_EQ(f["high"][k], json({x, learn_eol[k][2]})) << f.dump();
  }
  // Observations in mm: 2.1 ± 0.3 at 35,000; no crack at 15,000 (a bar to a50 = 0.8).
  ASSERT_EQ(f["observed"].size(), 1u) << f.dump();
  EXPECT_EQ(f["observed"][0][0], 35000);
  EXPECT_NEAR(f["observed"][0][1].get<double>(), 2.1, 1e-12);
  EXPECT_NEAR(f["observed"][0][2].get<double>(), 1.8, 1e-12);
  EXPECT_NEAR(f["observed"][0][3].get<double>(), 2.4, 1e-12);
  ASSERT_EQ(f["noCrack"].size(), 1u) << f.dump();
  EXPECT_EQ(f["noCrack"][0][0], 15000);
  EXPECT_EQ(f["noCrack"][0][1], 0);
  EXPECT_NEAR(f["noCrack"][0][3].get<double>(), 0.8, 1e-12);
  EXPECT_NE(f["observedStyle"], f["noCrackStyle"]);
  EXPECT_EQ(f["markers"], 2);
  ASSERT_EQ(f["predicted"].size(), 2u) << f.dump();
  EXPECT_NEAR(f["predicted"][1][1].get<double>(), 1.7, 1e-12);
  // The card: the last STATE's percentiles, P(end within 50,000 cycles), ESS, the posterior.
  EXPECT_EQ(f["ensembleHidden"], false);
  EXPECT_EQ(f["eolMedian"], "82000");
  EXPECT_EQ(f["eolLow"], "70000");
  EXPECT_EQ(f["eolHigh"], "95000");
  EXPECT_EQ(std::stod(f["pHorizon"].get<std::string>()), 0.05 * 3);
  EXPECT_NE(f["pHorizonTitle"].get<std::string>().find("50,000"), std::string::npos);
  EXPECT_EQ(std::stod(f["ess"].get<std::string>()), 40.0);
  ASSERT_EQ(f["parameters"].size(), 2u) << f.dump();
  EXPECT_EQ(f["parameters"][0][0], "a2");
  EXPECT_DOUBLE_EQ(f["parameters"][0][1].get<double>(), 1.2e-9 * 1.2);
  EXPECT_DOUBLE_EQ(f["parameters"][0][2].get<double>(), 0.1);
  EXPECT_EQ(f["parameters"][1][0], "load_scale");
  EXPECT_EQ(f["otherFanHidden"], true);
  EXPECT_EQ(f["otherEnsembleHidden"], true);
  // The learning card, for a person to look at.
  ASSERT_TRUE(browser.evaluate(page, learn_card + ".scrollIntoView(); true", 60).value_or(json()) ==
              true);
  const auto learn_captured =
      browser.call("Page.captureScreenshot", {{"format", "png"}}, page, kWaitS);
  ASSERT_TRUE(learn_captured && (*learn_captured)["result"].contains("data"));
  const auto learn_png =
      testing::base64_decode((*learn_captured)["result"]["data"].get<std::string>());
  ASSERT_TRUE(learn_png && learn_png->size() > 8);
  std::ofstream(fs::path(PERITWIN_TEST_OUT_DIR) / "dashboard-learn-test.png", std::ios::binary)
      << *learn_png;
  ASSERT_TRUE(browser.evaluate(page, "window.scrollTo(0, 0); true", 60).value_or(json()) == true);

  const fs::path shot = fs::path(PERITWIN_TEST_OUT_DIR) / "dashboard-live-test.png";
  fs::remove(shot);
  const auto captured = browser.call("Page.captureScreenshot", {{"format", "png"}}, page, kWaitS);
  ASSERT_TRUE(captured && (*captured)["result"].contains("data"))
      << captured.value_or(json()).dump();
  const auto png = testing::base64_decode((*captured)["result"]["data"].get<std::string>());
  ASSERT_TRUE(png && png->size() > 8);
  EXPECT_EQ(png->substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  std::ofstream(shot, std::ios::binary) << *png;
  EXPECT_TRUE(fs::exists(shot) && fs::file_size(shot) == png->size()) << shot;

  // The demo detail's card (END OF LIFE, the countdown chart), for a person to look at.
  ASSERT_TRUE(browser.evaluate(page, demo_card + ".scrollIntoView(); true", 60).value_or(json()) ==
              true);
  const fs::path life_shot = fs::path(PERITWIN_TEST_OUT_DIR) / "dashboard-life-test.png";
  const auto life_captured =
      browser.call("Page.captureScreenshot", {{"format", "png"}}, page, kWaitS);
  ASSERT_TRUE(life_captured && (*life_captured)["result"].contains("data"));
  const auto life_png =
      testing::base64_decode((*life_captured)["result"]["data"].get<std::string>());
  ASSERT_TRUE(life_png && life_png->size() > 8);
  std::ofstream(life_shot, std::ios::binary) << *life_png;
}

// A raw connection to the dashboard (no thread per connection in the test): what the lockout
// tests hold open by the hundred.
class RawConnection {
 public:
  explicit RawConnection(int port) : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = fd_ >= 0 && ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawConnection() {
    if (fd_ >= 0) ::close(fd_);
  }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;
  bool connected() const { return connected_; }
  int fd() const { return fd_; }
  bool send(const std::string& text) {
    return ::send(fd_, text.data(), text.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(text.size());
  }
  /// What arrives until the response headers are complete; shorter if the connection closes or
  /// nothing comes for `timeout_s`.
  std::string read_headers(double timeout_s) {
    std::string got;
    while (got.find("\r\n\r\n") == std::string::npos) {
      if (!wait_readable(timeout_s)) break;
      char buffer[4096];
      const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      got.append(buffer, static_cast<std::size_t>(n));
    }
    return got;
  }
  /// True when the server closed the connection (EOF or reset) within `timeout_s`.
  bool closed_by_server(double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < deadline) {
      if (!wait_readable(1.0)) continue;
      char buffer[4096];
      if (::recv(fd_, buffer, sizeof buffer, 0) <= 0) return true;
    }
    return false;
  }

 private:
  bool wait_readable(double timeout_s) {
    pollfd p{fd_, POLLIN, 0};
    return ::poll(&p, 1, static_cast<int>(timeout_s * 1000)) > 0;
  }
  int fd_;
  bool connected_ = false;
};

constexpr const char* kEventsRequest = "GET /api/events HTTP/1.1\r\nHost: test\r\n\r\n";
/// The cap of event streams the lockout tests start the dashboard with (the default, 4096, is
/// more connections than a test should open).
constexpr std::size_t kTestStreamCap = 64;
/// The lockout tests' "still served": an answer within this (generous; not a speed assertion).
constexpr int kServedWithinS = 10;

/// `count` event streams, each answered 200 (its headers read); what came after the headers in
/// `bodies` when given.
std::vector<std::unique_ptr<RawConnection>> open_event_streams(
    int port, std::size_t count, std::vector<std::string>* bodies = nullptr) {
  std::vector<std::unique_ptr<RawConnection>> streams;
  for (std::size_t i = 0; i < count; ++i) {
    auto c = std::make_unique<RawConnection>(port);
    EXPECT_TRUE(c->connected() && c->send(kEventsRequest)) << i;
    const std::string headers = c->read_headers(kWaitS);
    EXPECT_EQ(headers.rfind("HTTP/1.1 200", 0), 0u) << "stream " << i << ": " << headers;
    if (bodies != nullptr) {
      const auto end = headers.find("\r\n\r\n");
      bodies->push_back(end == std::string::npos ? std::string() : headers.substr(end + 4));
    }
    streams.push_back(std::move(c));
  }
  return streams;
}

/// GET path with a client of `timeout_s` (connect and read): {status, seconds taken}.
std::pair<int, double> timed_get(int port, const std::string& path, int timeout_s) {
  httplib::Client client("127.0.0.1", port);
  client.set_connection_timeout(timeout_s, 0);
  client.set_read_timeout(timeout_s, 0);
  const auto start = std::chrono::steady_clock::now();
  const auto res = client.Get(path.c_str());
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  return {res ? res->status : -1, took.count()};
}

// Issue 30 item 4: eight open event streams used to lock the page out (httplib's 8 workers, one
// per stream). With the cap of streams open (64 here), the page and the API are still served, one
// stream more gets 503 with its reason and Retry-After, and once the streams close (the clients
// gone, noticed by the dashboard) a new stream is accepted again.
TEST_F(DashboardApi, EventStreamsBeyondTheCapGet503AndThePageIsStillServed) {
  ASSERT_NO_FATAL_FAILURE(start_dashboard(dashboard_, port_, "dashboard.log",
                                          {"--max-event-streams", std::to_string(kTestStreamCap)}));
  auto streams = open_event_streams(port_, kTestStreamCap);
  ASSERT_FALSE(::testing::Test::HasFailure()) << read_file(dir_ / "dashboard.log");

  EXPECT_EQ(timed_get(port_, "/", kServedWithinS).first, 200);
  EXPECT_EQ(timed_get(port_, "/api/details", kServedWithinS).first, 200);

  httplib::Client client("127.0.0.1", port_);
  client.set_read_timeout(kServedWithinS, 0);
  const auto refused = client.Get("/api/events");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503);
  EXPECT_NE(refused->body.find("too many open event streams"), std::string::npos) << refused->body;
  EXPECT_EQ(refused->get_header_value("Content-Type"), "text/plain; charset=utf-8");
  EXPECT_EQ(refused->get_header_value("Retry-After"), "10");

  streams.clear();  // the clients go away: their streams end and give their slots back
  bool accepted = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  while (!accepted && std::chrono::steady_clock::now() < deadline) {
    RawConnection again(port_);
    ASSERT_TRUE(again.connected() && again.send(kEventsRequest));
    const std::string headers = again.read_headers(kWaitS);
    accepted = headers.rfind("HTTP/1.1 200", 0) == 0;
    if (!accepted) std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  EXPECT_TRUE(accepted) << read_file(dir_ / "dashboard.log");
  EXPECT_EQ(timed_get(port_, "/", kServedWithinS).first, 200);
}

// 200 connections that send nothing or half a request line (slowloris) hold no worker: with them
// and the cap of event streams open the page is served, and after they close it still is. A
// connection that never completes its request is closed by the dashboard (header timeout). The
// times of GET / are printed, not asserted.
TEST_F(DashboardApi, IdleAndHalfRequestConnectionsDoNotLockThePageOut) {
  ASSERT_NO_FATAL_FAILURE(start_dashboard(dashboard_, port_, "dashboard.log",
                                          {"--max-event-streams", std::to_string(kTestStreamCap)}));
  auto streams = open_event_streams(port_, kTestStreamCap);
  ASSERT_FALSE(::testing::Test::HasFailure()) << read_file(dir_ / "dashboard.log");
  std::vector<std::unique_ptr<RawConnection>> idle;
  for (int i = 0; i < 200; ++i) {
    idle.push_back(std::make_unique<RawConnection>(port_));
    ASSERT_TRUE(idle.back()->connected()) << i;
    if (i % 2 == 1) {
      ASSERT_TRUE(idle.back()->send("GET / HT"));  // half a request line
    }
  }
  for (int run = 0; run < 5; ++run) {
    const auto [status, took] = timed_get(port_, "/", kServedWithinS);
    EXPECT_EQ(status, 200) << "run " << run;
    std::printf("GET / with %zu event streams and 200 idle connections open: %.1f ms\n",
                kTestStreamCap, took * 1e3);
  }
  EXPECT_EQ(timed_get(port_, "/api/details", kServedWithinS).first, 200);

  // Closed by the dashboard, not by the client: idle for longer than the header timeout.
  EXPECT_TRUE(idle.front()->closed_by_server(kWaitS));
  EXPECT_TRUE(idle.back()->closed_by_server(kWaitS));
  idle.clear();
  streams.clear();
  for (int run = 0; run < 3; ++run) {
    const auto [status, took] = timed_get(port_, "/", kServedWithinS);
    EXPECT_EQ(status, 200) << "run " << run;
    std::printf("GET / after they closed: %.1f ms\n", took * 1e3);
  }
}

/// The state_seqs of the "state" events of `detail` in an event stream's body, in order.
std::vector<std::int64_t> state_seqs(const std::string& body, const std::string& detail) {
  std::vector<std::int64_t> seqs;
  std::size_t start = 0;
  for (auto end = body.find("\n\n"); end != std::string::npos; end = body.find("\n\n", start)) {
    const std::string event = body.substr(start, end - start);
    start = end + 2;
    const auto data = event.find("\ndata: ");
    if (event.find("\nevent: state\n") == std::string::npos || data == std::string::npos) continue;
    const auto j = json::parse(event.substr(data + 7), nullptr, false);
    if (j.is_object() && j["detail"] == detail) seqs.push_back(j["summary"]["state_seq"]);
  }
  return seqs;
}

// Issue 30 item 4: event streams hold no thread each. With more streams open than the server
// has threads of any kind (300, where 64 used to be the cap, one worker each) and 100 idle or
// half-request connections, the page and the API are answered, every stream receives the STATEs
// published then, all of them in order, and the dashboard's thread count is what it was before
// the streams opened (counted, not timed).
TEST_F(DashboardApi, ManyEventStreamsShareOneThreadAndEachGetsEveryEvent) {
  constexpr std::size_t kStreams = 300;
  constexpr int kIdle = 100;
  ASSERT_NO_FATAL_FAILURE(start_dashboard());
  const auto pid = std::to_string(dashboard_->pid());
  const std::int64_t threads_before = core::proc_status_kb("Threads", pid);
  ASSERT_GT(threads_before, 0);

  std::vector<std::string> raw;  // each stream's bytes after its headers
  auto streams = open_event_streams(port_, kStreams, &raw);
  ASSERT_FALSE(::testing::Test::HasFailure()) << read_file(dir_ / "dashboard.log");
  ASSERT_EQ(raw.size(), kStreams);
  std::vector<std::unique_ptr<RawConnection>> idle;
  for (int i = 0; i < kIdle; ++i) {
    idle.push_back(std::make_unique<RawConnection>(port_));
    ASSERT_TRUE(idle.back()->connected()) << i;
    if (i % 2 == 1) {
      ASSERT_TRUE(idle.back()->send("GET / HT"));  // half a request line
    }
  }
  EXPECT_EQ(timed_get(port_, "/", kServedWithinS).first, 200);
  EXPECT_EQ(timed_get(port_, "/api/details", kServedWithinS).first, 200);
  const std::int64_t threads_with_streams = core::proc_status_kb("Threads", pid);
  std::printf("dashboard threads: %lld before, %lld with %zu event streams and %d idle open\n",
              static_cast<long long>(threads_before), static_cast<long long>(threads_with_streams),
              kStreams, kIdle);
  EXPECT_LE(threads_with_streams, threads_before + 1);
  EXPECT_LT(static_cast<std::size_t>(threads_with_streams), kStreams / 10);

  // Three STATEs of one detail: every stream gets all three, in order.
  lcm::LCM bus(hub_->url());
  ASSERT_TRUE(bus.good());
  const std::string detail = "fanout-demo";
  constexpr int kStates = 3;
  for (int seq = 0; seq < kStates; ++seq) {
    const auto m = testing::minimal_state(detail, seq, 1000 * seq);
    bus.publish(messages::channel(detail, messages::Kind::kState), &m);
  }
  const std::vector<std::int64_t> expected{0, 1, 2};
  std::vector<bool> done(kStreams, false);
  std::size_t complete = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(kWaitS);
  while (complete < kStreams && std::chrono::steady_clock::now() < deadline) {
    std::vector<pollfd> fds;
    for (const auto& c : streams) fds.push_back(pollfd{c->fd(), POLLIN, 0});
    if (::poll(fds.data(), fds.size(), 1000) <= 0) continue;
    for (std::size_t i = 0; i < kStreams; ++i) {
      if (done[i] || (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      char buffer[65536];
      const ssize_t n = ::recv(fds[i].fd, buffer, sizeof buffer, MSG_DONTWAIT);
      if (n <= 0) {
        done[i] = true;  // closed: counted as incomplete below
        continue;
      }
      raw[i].append(buffer, static_cast<std::size_t>(n));
      if (state_seqs(dechunk(raw[i]), detail).size() >= expected.size()) {
        done[i] = true;
        ++complete;
      }
    }
  }
  std::size_t in_order = 0;
  bool reported = false;  // the first stream that did not get them, shown
  for (std::size_t i = 0; i < kStreams; ++i) {
    if (state_seqs(dechunk(raw[i]), detail) == expected) {
      ++in_order;
    } else if (!reported) {
      reported = true;
      ADD_FAILURE() << "stream " << i << " did not get states 0, 1, 2 in order: " << raw[i];
    }
  }
  EXPECT_EQ(in_order, kStreams) << read_file(dir_ / "dashboard.log");
  EXPECT_EQ(timed_get(port_, "/", kServedWithinS).first, 200);
  EXPECT_LE(core::proc_status_kb("Threads", pid), threads_before + 1);
}

}  // namespace
}  // namespace peritwin::dashboard
