// peritwin-stream end to end (the binaries): the same series through the stream (a FIFO written
// in random pieces, a TCP connection, load_samples_t messages over LCM's hub) and through
// peritwin-replay --format series reaches the same engine_hash and total cycles; over a hub and a
// daemon the stream killed with SIGKILL at random points and restarted on its state file and the
// same FILE ends at the replay's engine_hash (no cycle lost or doubled); a corrupt state file is
// refused (exit 2 naming it); samples of a stdin stream killed between batches are reported as
// lost_samples. Every wait on another process has a deadline of minutes; no timing is asserted.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "core/loopback_port.h"
#include "messages/auth.h"
#include "messages/channels.h"
#include "messages/codec.h"
#include "tests/support/lcm_hub.h"
#include "tests/support/process.h"
#include "twin/detail_model.h"
#include "twin/gauges.h"

namespace peritwin::stream {
namespace {

namespace fs = std::filesystem;
using peritwin::testing::Process;

constexpr double kWaitS = 600.0;
const std::string kBin = PERITWIN_BIN_DIR;
const std::string kConfig = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml";
const std::string kSeries = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-series.csv";

std::string read_file(const fs::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string field(const std::string& json, const std::string& key) {
  const std::string k = "\"" + key + "\":";
  const auto p = json.find(k);
  if (p == std::string::npos) return {};
  auto start = p + k.size();
  if (json[start] == '"') ++start;
  const auto end = json.find_first_of(",}\"", start);
  return json.substr(start, end - start);
}

/// A TCP connection to 127.0.0.1:`port` (the stream's tcp:// input); -1 when it fails.
int connect_loopback(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

std::vector<std::string> lines_to_end(Process& p) {
  std::vector<std::string> lines;
  while (auto line = p.read_line(kWaitS)) lines.push_back(*line);
  return lines;
}

int exit_code(Process& p) {
  const auto status = p.wait_for(kWaitS);
  return status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
}

class Stream : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           (std::string("peritwin_stream_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  /// The replay's summary of `series` in-process (the reference).
  std::string replay_summary(const std::string& series) {
    Process r({kBin + "/peritwin-replay", "--config", kConfig, "--history", series, "--format",
               "series", "--in-process", "--json"},
              (dir_ / "replay.log").string());
    const auto lines = lines_to_end(r);
    EXPECT_EQ(exit_code(r), 0) << read_file(dir_ / "replay.log");
    return lines.empty() ? std::string() : lines.back();
  }
  std::unique_ptr<Process> stream(std::vector<std::string> args, const std::string& log,
                                  const std::string& config = kConfig) {
    std::vector<std::string> argv{kBin + "/peritwin-stream", "--config", config, "--json"};
    argv.insert(argv.end(), args.begin(), args.end());
    return std::make_unique<Process>(argv, (dir_ / log).string());
  }
  static void expect_same_load(const std::string& reference, const std::string& summary) {
    ASSERT_FALSE(field(reference, "engine_hash").empty()) << reference;
    EXPECT_EQ(field(summary, "engine_hash"), field(reference, "engine_hash")) << summary;
    EXPECT_EQ(field(summary, "cycles"), field(reference, "cycles")) << summary;
  }
  fs::path dir_;
};

TEST_F(Stream, FifoInRandomPiecesEqualsTheReplay) {
  const std::string reference = replay_summary(kSeries);
  const fs::path fifo = dir_ / "in.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto s = stream({"--input", fifo.string(), "--in-process", "--batch-cycles", "7"}, "stream.log");
  const std::string text = read_file(kSeries);
  {
    std::ofstream out(fifo, std::ios::binary);  // blocks until the stream opens it
    std::mt19937 rng(20261203);
    std::size_t at = 0;
    while (at < text.size()) {
      const std::size_t n = std::uniform_int_distribution<std::size_t>(1, 900)(rng);
      out.write(text.data() + at, static_cast<std::streamsize>(std::min(n, text.size() - at)));
      out.flush();
      at += n;
      if (rng() % 8 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  const auto lines = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  expect_same_load(reference, lines.back());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  EXPECT_EQ(field(lines.back(), "lost_samples"), "0") << lines.back();
  // Several batches: states arrived as the data came, not only at the end.
  EXPECT_GT(lines.size(), 5u);
}

TEST_F(Stream, TcpConnectionEqualsTheReplayAfterSigterm) {
  const std::string reference = replay_summary(kSeries);
  const int port = peritwin::core::free_loopback_port();
  auto s =
      stream({"--input", "tcp://127.0.0.1:" + std::to_string(port), "--in-process"}, "stream.log");
  ASSERT_TRUE(peritwin::core::wait_for_loopback_port(port, kWaitS))
      << read_file(dir_ / "stream.log");
  const std::string text = read_file(kSeries);
  const std::size_t half = text.find('\n', text.size() / 2) + 1;
  for (const auto& piece : {text.substr(0, half), text.substr(half)}) {  // two connections
    const int fd = connect_loopback(port);
    ASSERT_GE(fd, 0) << "connect to 127.0.0.1:" << port;
    ASSERT_EQ(::write(fd, piece.data(), piece.size()), static_cast<ssize_t>(piece.size()));
    ::close(fd);
  }
  // SIGTERM once every sample is in (the stream says nothing per sample: wait for its states).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(600);
  std::vector<std::string> lines;
  while (std::chrono::steady_clock::now() < deadline) {
    auto line = s->read_line(1.0);
    if (line) lines.push_back(*line);
    if (!line) break;  // quiet for a second
  }
  std::this_thread::sleep_for(std::chrono::seconds(2));
  s->signal(SIGTERM);
  for (auto& l : lines_to_end(*s)) lines.push_back(l);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  expect_same_load(reference, lines.back());
}

TEST_F(Stream, CorruptStateFileExitsTwoNamingIt) {
  const fs::path state = dir_ / "stream.state";
  std::ofstream(state) << "peritwin-stream-state 1\ncounts 1 2 3\nchecksum 0000000000000000\n";
  auto s = stream(
      {"--input", kSeries, "--state-file", state.string(), "--lcm-url", "tcpq://127.0.0.1:1"},
      "stream.log");
  lines_to_end(*s);
  EXPECT_EQ(exit_code(*s), 2);
  const std::string log = read_file(dir_ / "stream.log");
  EXPECT_NE(log.find("corrupt state file " + state.string() + ": checksum mismatch"),
            std::string::npos)
      << log;
}

/// The data rows of the example series ("t,P"), without its comments and header.
std::vector<std::string> series_rows() {
  std::vector<std::string> rows;
  std::ifstream in(kSeries);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#' && line[0] != 't') rows.push_back(line);
  }
  return rows;
}

void write_rows(const fs::path& file, const std::vector<std::string>& rows) {
  std::ofstream out(file);
  out << "time_s,load_N\n";
  for (const auto& r : rows) out << r << "\n";
}

/// Writes `bytes` to the loopback TCP port without a newline; errors (the stream closing the
/// connection) end it quietly.
void send_without_newline(int port, std::size_t bytes) {
  const int fd = connect_loopback(port);
  ASSERT_GE(fd, 0) << "connect to 127.0.0.1:" << port;
  const std::string chunk(65536, '7');
  for (std::size_t sent = 0; sent < bytes;) {
    const ssize_t n = ::send(fd, chunk.data(), std::min(chunk.size(), bytes - sent), MSG_NOSIGNAL);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
  ::close(fd);
}

// stdin that never ends its line (an endless pipe): the stream stops reading at 4 KiB, says so
// and exits 2, instead of growing its memory for ever.
TEST_F(Stream, AnEndlessLineOnStdinEndsTheStreamWithExitTwo) {
  Process s({"/bin/sh", "-c",
             "yes 1234567890 | tr -d '\\n' | '" + kBin + "/peritwin-stream' --config '" + kConfig +
                 "' --json --in-process --input -"},
            (dir_ / "stream.log").string());
  lines_to_end(s);
  EXPECT_EQ(exit_code(s), 2) << read_file(dir_ / "stream.log");
  EXPECT_NE(read_file(dir_ / "stream.log")
                .find("peritwin-stream: stdin: line 1 is longer than 4096 bytes without an end of "
                      "line: no sample stream; input ended there"),
            std::string::npos)
      << read_file(dir_ / "stream.log");
}

// The same over TCP, after half the series: those samples are taken (the summary says so), the
// 1 MB line ends the stream with exit 2.
TEST_F(Stream, AnEndlessLineOnTcpEndsTheStreamWithExitTwo) {
  const int port = peritwin::core::free_loopback_port();
  auto s =
      stream({"--input", "tcp://127.0.0.1:" + std::to_string(port), "--in-process"}, "stream.log");
  ASSERT_TRUE(peritwin::core::wait_for_loopback_port(port, kWaitS))
      << read_file(dir_ / "stream.log");
  const auto rows = series_rows();
  {
    std::string text;
    for (std::size_t i = 0; i < 600; ++i) text += rows[i] + "\n";
    const int fd = connect_loopback(port);
    ASSERT_GE(fd, 0) << "connect to 127.0.0.1:" << port;
    ASSERT_EQ(::write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
    ::close(fd);
  }
  ASSERT_NO_FATAL_FAILURE(send_without_newline(port, 1u << 20));
  const auto lines = lines_to_end(*s);
  EXPECT_EQ(exit_code(*s), 2) << read_file(dir_ / "stream.log");
  const std::string log = read_file(dir_ / "stream.log");
  EXPECT_NE(log.find("tcp://127.0.0.1:" + std::to_string(port) +
                     ": line 601 is longer than 4096 bytes without an end of line"),
            std::string::npos)
      << log;
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "600") << lines.back();
}

// One bad time skips its line and is counted, and no later sample is lost: 1e308 s (beyond the
// clock), inf, and a time going backwards. The load is the replay's of the clean series.
TEST_F(Stream, ABadTimestampSkipsItsLineOnly) {
  const std::string reference = replay_summary(kSeries);
  auto rows = series_rows();
  rows.insert(rows.begin() + 500, "1.0,2500");  // backwards (the row before is at 24.95 s)
  rows.insert(rows.begin() + 300, "inf,2500");
  rows.insert(rows.begin() + 100, "1e308,5");
  write_rows(dir_ / "bad-times.csv", rows);
  auto s = stream({"--input", (dir_ / "bad-times.csv").string(), "--in-process"}, "stream.log");
  const auto lines = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  EXPECT_EQ(field(lines.back(), "bad_lines"), "3") << lines.back();
  expect_same_load(reference, lines.back());  // every later sample taken: the same cycles
  EXPECT_NE(read_file(dir_ / "stream.log").find("more than a day after the clock"),
            std::string::npos)
      << read_file(dir_ / "stream.log");
}

// A time glitch ahead that is no nonsense by itself (30000 s in a 60 s record): the samples after
// it are refused as going backwards, five in a row, then the stream takes that time as the
// outlier and goes on; the rest of the record is taken.
TEST_F(Stream, ATimeGlitchAheadIsOvercome) {
  auto rows = series_rows();
  rows.insert(rows.begin() + 100, "30000,2500");
  write_rows(dir_ / "glitch.csv", rows);
  auto s = stream({"--input", (dir_ / "glitch.csv").string(), "--in-process"}, "stream.log");
  const auto lines = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "bad_lines"), "5") << lines.back();
  EXPECT_EQ(field(lines.back(), "samples"), "1196") << lines.back();  // 1201 - 5
  EXPECT_GT(std::stoll(field(lines.back(), "cycles")), 50) << lines.back();
  EXPECT_NE(read_file(dir_ / "stream.log").find("that time was out of line"), std::string::npos)
      << read_file(dir_ / "stream.log");
}

// One absurd load (1e308 N), and in-process one above the twin's max_p (derived from the model),
// is skipped and counted, a NaN one is a dropout (nonfinite_samples):
// the batch they fall in is applied, the load is the clean series' (the in-process twin refuses an
// invalid batch, which would end the stream with exit 3).
TEST_F(Stream, AnAbsurdSampleIsSkippedAndItsBatchApplied) {
  const std::string reference = replay_summary(kSeries);
  auto rows = series_rows();
  ASSERT_EQ(rows[600].substr(0, 6), "30.00,");
  rows.insert(rows.begin() + 601, "30.025,500000");  // above B1's derived max_p (~177 kN)
  ASSERT_EQ(rows[400].substr(0, 6), "20.00,");
  rows.insert(rows.begin() + 401, "20.025,nan");
  ASSERT_EQ(rows[200].substr(0, 6), "10.00,");
  rows.insert(rows.begin() + 201, "10.025,1e308");
  write_rows(dir_ / "absurd.csv", rows);
  auto s = stream({"--input", (dir_ / "absurd.csv").string(), "--in-process"}, "stream.log");
  const auto lines = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "bad_lines"), "2") << lines.back();
  EXPECT_EQ(field(lines.back(), "nonfinite_samples"), "1") << lines.back();
  EXPECT_EQ(field(lines.back(), "samples"), "1201") << lines.back();
  expect_same_load(reference, lines.back());
  EXPECT_NE(read_file(dir_ / "stream.log").find("load P = 1e+308 N is outside"), std::string::npos)
      << read_file(dir_ / "stream.log");
}

// A semicolon, decimal-comma CSV: every line is bad, no sample; exit 2 naming the first line.
TEST_F(Stream, NoUsableLineExitsTwoNamingTheFirst) {
  {
    std::ofstream out(dir_ / "excel.csv");
    out << "time_s;load_N\n";
    for (const auto& row : series_rows()) {
      std::string r = row;
      for (char& c : r) c = c == ',' ? ';' : c == '.' ? ',' : c;
      out << r << "\n";
    }
  }
  auto s = stream({"--input", (dir_ / "excel.csv").string(), "--in-process"}, "stream.log");
  lines_to_end(*s);
  EXPECT_EQ(exit_code(*s), 2) << read_file(dir_ / "stream.log");
  const std::string log = read_file(dir_ / "stream.log");
  EXPECT_NE(log.find("excel.csv: no usable sample in 1201 skipped lines or samples; the first: "
                     "line 1 \"time_s;load_N\": expected t,P or t,P,alpha (1 fields)"),
            std::string::npos)
      << log;
}

/// Issue 33: the B1 example's gauges read the loads of examples/b1-series.csv through the virgin
/// model's coefficients (no noise): --identify-only gives the loads back, and the stream applies
/// the same cycles as the series' replay; a header naming no gauge of the detail exits 2.
/// The B1 example without its learning ensemble ([detail.uncertainty]: 64 particles, a
/// calibration run at start-up and an estimate at each observation), written to `file`: the
/// gauge tests are about the loads and the residuals.
std::string write_config_without_ensemble(const fs::path& file) {
  std::string text = read_file(kConfig);
  const auto u = text.find("\n[detail.uncertainty]");
  if (u != std::string::npos) text.erase(u + 1, text.find("\n[", u + 1) - u);
  std::ofstream(file) << text;
  return file.string();
}

/// The strains the B1 example's gauges read under examples/b1-series.csv through the virgin
/// model's coefficients (no noise), written to `file` (columns in another order than the
/// config's); the series' (time, load) rows.
std::vector<std::pair<std::string, double>> write_gauge_strains(const fs::path& file) {
  auto parsed = peritwin::config::load_config(kConfig);
  EXPECT_TRUE(parsed.ok()) << parsed.error_text();
  const auto model = peritwin::twin::DetailModel::build(parsed.config->details.at(0));
  EXPECT_TRUE(model.ok());
  auto engine = (*model)->make_engine();
  EXPECT_TRUE(engine->initialize());
  const auto c = peritwin::twin::gauge_influences((*model)->gauges(), engine->solver());
  EXPECT_EQ(c.size(), 3u);
  std::vector<std::pair<std::string, double>> truth;
  std::ofstream out(file);
  out << "# strains of examples/b1-series.csv\ntime_s,back,tip,arm\n";  // any column order
  out.precision(17);
  for (const auto& row : series_rows()) {
    const auto comma = row.find(',');
    const double p = std::stod(row.substr(comma + 1));
    truth.emplace_back(row.substr(0, comma), p);
    out << row.substr(0, comma) << "," << p * c[2][0] << "," << p * c[0][0] << "," << p * c[1][0]
        << "\n";
  }
  return truth;
}

TEST_F(Stream, GaugeStrainsIdentifyTheLoads) {
  const auto truth = write_gauge_strains(dir_ / "strains.csv");
  const std::string config = write_config_without_ensemble(dir_ / "b1.toml");
  ASSERT_EQ(truth.size(), series_rows().size());
  auto id = stream({"--input", (dir_ / "strains.csv").string(), "--in-process", "--format",
                    "gauges", "--identify-only"},
                   "identify.log", config);
  const auto lines = lines_to_end(*id);
  ASSERT_EQ(exit_code(*id), 0) << read_file(dir_ / "identify.log");
  std::vector<std::string> rows;
  for (const auto& l : lines) {
    if (!l.empty() && l[0] != '{' && l[0] != 't') rows.push_back(l);
  }
  ASSERT_EQ(rows.size(), truth.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const auto first = rows[k].find(',');
    const double p = std::stod(rows[k].substr(first + 1));
    EXPECT_NEAR(p, truth[k].second, 1e-6 * std::abs(truth[k].second) + 1e-9) << rows[k];
  }
  // Streamed: the cycles of the series' replay.
  auto s =
      stream({"--input", (dir_ / "strains.csv").string(), "--in-process", "--format", "gauges"},
             "stream.log", config);
  const auto summary = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(summary.empty());
  EXPECT_EQ(field(summary.back(), "cycles"), field(replay_summary(kSeries), "cycles"));
  // A column that is no gauge of the detail: exit 2 with the reason.
  {
    std::ofstream out(dir_ / "wrong.csv");
    out << "time_s,tip,elsewhere\n0,1e-4,2e-4\n";
  }
  auto w = stream({"--input", (dir_ / "wrong.csv").string(), "--in-process", "--format", "gauges"},
                  "wrong.log", config);
  lines_to_end(*w);
  EXPECT_EQ(exit_code(*w), 2);
  EXPECT_NE(read_file(dir_ / "wrong.log").find("elsewhere"), std::string::npos)
      << read_file(dir_ / "wrong.log");
}

/// Over LCM's TCP hub (skipped without java / lcm.jar).
class StreamOverHub : public Stream {
 protected:
  void SetUp() override {
    Stream::SetUp();
    hub_ = std::make_unique<peritwin::testing::LcmHub>(dir_ / "hub.log", kWaitS);
    if (!hub_->missing().empty()) GTEST_SKIP() << hub_->missing();
    ASSERT_TRUE(hub_->up()) << read_file(dir_ / "hub.log");
  }
  std::unique_ptr<Process> daemon(const std::string& log, const std::string& config = kConfig) {
    return std::make_unique<Process>(
        std::vector<std::string>{kBin + "/peritwin", "--config", config, "--lcm-url", hub_->url(),
                                 "--state-dir", (dir_ / "state").string(), "--deterministic",
                                 "--no-results"},
        (dir_ / log).string());
  }
  std::unique_ptr<peritwin::testing::LcmHub> hub_;
};

TEST_F(StreamOverHub, SigkillAtRandomPointsThenRestartOnTheStateFile) {
  const std::string reference = replay_summary(kSeries);
  auto d = daemon("daemon.log");
  const fs::path state = dir_ / "stream.state";
  std::mt19937 rng(4242);
  std::string last;
  int kills = 0;
  for (int run = 0; run < 40; ++run) {
    auto s = stream({"--input", kSeries, "--state-file", state.string(), "--lcm-url", hub_->url(),
                     "--batch-cycles", "3", "--lockstep", "--give-up-after", "600"},
                    "stream.log");
    if (kills < 6) {
      // Kill after 1 to 3 states of this run.
      const int states = std::uniform_int_distribution<int>(1, 3)(rng);
      int seen = 0;
      while (seen < states) {
        const auto line = s->read_line(kWaitS);
        if (!line) break;
        if (line->find("\"state_seq\"") != std::string::npos) ++seen;
        last = *line;
      }
      if (seen == states) {
        s->signal(SIGKILL);
        s->wait_for(kWaitS);
        ++kills;
        continue;
      }
    }
    const auto lines = lines_to_end(*s);
    ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
    ASSERT_FALSE(lines.empty());
    last = lines.back();
    break;
  }
  EXPECT_GE(kills, 5);
  ASSERT_NE(last.find("\"engine_hash\""), std::string::npos) << last;
  expect_same_load(reference, last);
  EXPECT_EQ(field(last, "lost_samples"), "0") << last;  // a FILE is read again
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

TEST_F(StreamOverHub, SamplesOfAKilledPipeStreamAreReportedLost) {
  auto d = daemon("daemon.log");
  const fs::path state = dir_ / "stream.state", fifo = dir_ / "in.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::vector<std::string> args{
      "--input",        fifo.string(), "--state-file",    state.string(), "--lcm-url", hub_->url(),
      "--batch-cycles", "3",           "--give-up-after", "600"};
  std::vector<std::string> rows;
  {
    std::ifstream in(kSeries);
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line[0] != '#' && line[0] != 't') rows.push_back(line);
    }
  }
  auto s = stream(args, "stream1.log");
  std::ofstream out(fifo);
  const std::size_t written = 500;
  for (std::size_t i = 0; i < written; ++i) out << rows[i] << "\n";
  out.flush();
  // Every sample read (the .received count), then SIGKILL: whatever is not in the state file is
  // lost to a pipe.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(600);
  std::string received;
  while (std::chrono::steady_clock::now() < deadline) {
    received = read_file(state.string() + ".received");
    if (!received.empty() && std::stoull(received) == written) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_EQ(std::stoull(received), written) << read_file(dir_ / "stream1.log");
  s->signal(SIGKILL);
  s->wait_for(kWaitS);
  out.close();
  const std::string saved = read_file(state);
  const auto counts = saved.find("\ncounts ");
  ASSERT_NE(counts, std::string::npos) << saved;
  std::istringstream fields(saved.substr(counts + 8));
  std::uint64_t lines = 0, persisted = 0;
  fields >> lines >> persisted;
  const std::uint64_t lost = written - persisted;

  // The rest of the data to a restarted stream on the same state file.
  auto again = stream(args, "stream2.log");
  {
    std::ofstream rest(fifo);
    for (std::size_t i = written; i < rows.size(); ++i) rest << rows[i] << "\n";
  }
  const auto output = lines_to_end(*again);
  ASSERT_EQ(exit_code(*again), 0) << read_file(dir_ / "stream2.log");
  ASSERT_FALSE(output.empty());
  EXPECT_EQ(field(output.back(), "lost_samples"), std::to_string(lost)) << output.back();
  EXPECT_EQ(field(output.back(), "samples"), std::to_string(rows.size() - lost)) << output.back();
  EXPECT_NE(read_file(dir_ / "stream2.log").find("lost_samples " + std::to_string(lost)),
            std::string::npos)
      << read_file(dir_ / "stream2.log");
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

/// The series as load_samples_t of 100 samples with their times (seq 1 to 12), source `source`,
/// each signed with `key` when given; seq 3 is published twice (a duplicate the stream drops).
/// Only the messages with seq <= last_seq.
void publish_series_as_samples(lcm::LCM& lcm, const std::string& source,
                               const messages::AuthKey* key, std::size_t last_seq = 12) {
  std::vector<double> t, p;
  std::ifstream in(kSeries);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 't') continue;
    const auto comma = line.find(',');
    t.push_back(std::stod(line.substr(0, comma)));
    p.push_back(std::stod(line.substr(comma + 1)));
  }
  ASSERT_EQ(p.size(), 1200u);
  for (std::size_t i = 0, seq = 1; i < p.size() && seq <= last_seq; i += 100, ++seq) {
    messages::Samples m{"b1-ct", source, static_cast<std::int64_t>(seq), 0.0, 0.0, {}, {}, {}};
    m.p.assign(p.begin() + static_cast<std::ptrdiff_t>(i),
               p.begin() + static_cast<std::ptrdiff_t>(i + 100));
    m.t.assign(t.begin() + static_cast<std::ptrdiff_t>(i),
               t.begin() + static_cast<std::ptrdiff_t>(i + 100));
    auto msg = messages::samples_message(m, messages::now_utime());
    if (key != nullptr) messages::sign(msg, *key);
    lcm.publish(messages::channel("b1-ct", messages::Kind::kSamples), &msg);
    if (seq == 3) lcm.publish(messages::channel("b1-ct", messages::Kind::kSamples), &msg);  // dup
  }
}

/// The stream's output once the samples stopped: 10 s of quiet on stdout after the last state
/// (its stderr says nothing per message), then SIGTERM; its lines to the end. For an in-process
/// stream, which has no state file; with one, stop_when_received is exact.
std::vector<std::string> stop_when_quiet(Process& s) {
  while (s.read_line(10.0)) {
  }
  s.signal(SIGTERM);
  return lines_to_end(s);
}

/// SIGTERM once the stream has taken `samples` samples (its "<state file>.received", at most
/// kWaitS), then its lines to the end: a loaded machine cannot stop it early.
std::vector<std::string> stop_when_received(Process& s, const fs::path& state_file,
                                            std::uint64_t samples) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(600);
  std::string received;
  while (std::chrono::steady_clock::now() < deadline) {
    received = read_file(state_file.string() + ".received");
    if (!received.empty() && std::stoull(received) >= samples) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_EQ(received.empty() ? 0 : std::stoull(received), samples);
  s.signal(SIGTERM);
  return lines_to_end(s);
}

TEST_F(StreamOverHub, LcmSamplesEqualTheReplay) {
  const std::string reference = replay_summary(kSeries);
  auto s = stream({"--input", "lcm", "--lcm-url", hub_->url(), "--in-process"}, "stream.log");
  // The stream is subscribed once it prints its initial state.
  ASSERT_TRUE(s->read_line(kWaitS).has_value()) << read_file(dir_ / "stream.log");
  lcm::LCM lcm(hub_->url());
  ASSERT_TRUE(lcm.good());
  ASSERT_NO_FATAL_FAILURE(publish_series_as_samples(lcm, "gauge", nullptr));
  const auto lines = stop_when_quiet(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  expect_same_load(reference, lines.back());
}

// --input lcm with a state file: the last seq taken per source survives a restart, so a gateway
// that sends everything again after the restart has its old messages dropped as duplicates and
// its next one is no gap; the load equals the replay of the whole series. (The first run ends
// with --residue keep: its open reversals go on in the second.)
TEST_F(StreamOverHub, LcmSamplesTakenOnceAcrossARestart) {
  const std::string reference = replay_summary(kSeries);
  auto d = daemon("daemon.log");
  const fs::path state = dir_ / "stream.state";
  const std::vector<std::string> args{"--input",         "lcm",          "--lcm-url",
                                      hub_->url(),       "--state-file", state.string(),
                                      "--give-up-after", "600"};
  lcm::LCM lcm(hub_->url());
  ASSERT_TRUE(lcm.good());
  {
    auto first_args = args;
    first_args.insert(first_args.end(), {"--residue", "keep"});
    auto s = stream(first_args, "stream1.log");
    ASSERT_TRUE(s->read_line(kWaitS).has_value()) << read_file(dir_ / "stream1.log");
    ASSERT_NO_FATAL_FAILURE(publish_series_as_samples(lcm, "gauge", nullptr, 6));
    stop_when_received(*s, state, 600);
    ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream1.log");
  }
  ASSERT_NE(read_file(state).find("samples_taken 1 6761756765 6"), std::string::npos)
      << read_file(state);  // "gauge" in hex, seq 6
  auto s = stream(args, "stream2.log");
  ASSERT_TRUE(s->read_line(kWaitS).has_value()) << read_file(dir_ / "stream2.log");
  ASSERT_NO_FATAL_FAILURE(publish_series_as_samples(lcm, "gauge", nullptr));  // 1..12 again
  const auto lines = stop_when_received(*s, state, 1200);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream2.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  expect_same_load(reference, lines.back());
  EXPECT_EQ(read_file(dir_ / "stream2.log").find("gap"), std::string::npos)
      << read_file(dir_ / "stream2.log");
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

// Loads in the wrong unit (x1000, above the detail's max_p, which the daemon derives from the
// model): the daemon refuses the first batch INVALID, and both producers say why and exit 3 at
// once instead of resending until --give-up-after (600 s here).
TEST_F(StreamOverHub, ProducersExitThreeOnAnInvalidBatchWithTheDaemonsReason) {
  auto d = daemon("daemon.log");
  std::ofstream(dir_ / "cycles-x1000.csv") << "p_max_N,r,angle_rad,count\n4000000,0.1,0,1000\n"
                                              "4000000,0.1,0,1000\n";
  Process r(
      {kBin + "/peritwin-replay", "--config", kConfig, "--history",
       (dir_ / "cycles-x1000.csv").string(), "--lcm-url", hub_->url(), "--give-up-after", "600"},
      (dir_ / "replay.log").string());
  lines_to_end(r);
  EXPECT_EQ(exit_code(r), 3) << read_file(dir_ / "replay.log");
  EXPECT_NE(read_file(dir_ / "replay.log")
                .find("peritwin-replay: the daemon refused batch 1 of source \"replay\" "
                      "(CODE_INVALID): blocks[0].p_max: p_max = 4e+06 N is above the detail's "
                      "bound max_p"),
            std::string::npos)
      << read_file(dir_ / "replay.log");

  auto rows = series_rows();
  for (auto& row : rows) {
    const auto comma = row.find(',');
    row = row.substr(0, comma) + "," + std::to_string(1000 * std::stod(row.substr(comma + 1)));
  }
  write_rows(dir_ / "series-x1000.csv", rows);
  auto s = stream({"--input", (dir_ / "series-x1000.csv").string(), "--lcm-url", hub_->url(),
                   "--give-up-after", "600"},
                  "stream.log");
  lines_to_end(*s);
  EXPECT_EQ(exit_code(*s), 3) << read_file(dir_ / "stream.log");
  const std::string log = read_file(dir_ / "stream.log");
  EXPECT_NE(log.find("peritwin-stream: the daemon refused batch 1 of source \"stream\" "
                     "(CODE_INVALID): blocks["),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("is above the detail's bound max_p"), std::string::npos) << log;
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

// The gauge record takes the demo detail to its end of life (state 40, cycle 39 639): the batches
// after it are refused FAILED, which for the stream that applied the batches before is the end,
// not an error: the daemon's reason on stderr, exit 0.
TEST_F(StreamOverHub, TheEndOfLifeReachedByTheStreamExitsZeroWithTheReason) {
  auto d = daemon("daemon.log");
  auto s = stream({"--input", std::string(PERITWIN_EXAMPLES_DIR) + "/b1-gauge.csv", "--lcm-url",
                   hub_->url(), "--give-up-after", "600"},
                  "stream.log");
  const auto lines = lines_to_end(*s);
  EXPECT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(field(lines.back(), "end_of_life_cycle"), "-1") << lines.back();
  EXPECT_NE(read_file(dir_ / "stream.log")
                .find("peritwin-stream: end of life reached, the rest of the input is not applied: "
                      "the daemon refused batch "),
            std::string::npos)
      << read_file(dir_ / "stream.log");
  EXPECT_NE(read_file(dir_ / "stream.log")
                .find("(CODE_FAILED): message: the detail reached its end-of-life criterion"),
            std::string::npos)
      << read_file(dir_ / "stream.log");
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

// Issue 33 over the bus: the daemon's STATE gives the coefficients, the stream identifies the
// loads (the series' cycles applied) and sends the gauges' compliance every 50 cycles and at the
// end, which the daemon takes in: residuals of 0 (to round-off: the record is the daemon's own
// virgin model).
TEST_F(StreamOverHub, GaugeStrainsOverTheBus) {
  write_gauge_strains(dir_ / "strains.csv");
  const std::string config = write_config_without_ensemble(dir_ / "b1.toml");
  const std::string reference = replay_summary(kSeries);
  auto d = daemon("daemon.log", config);
  auto s = stream({"--input", (dir_ / "strains.csv").string(), "--lcm-url", hub_->url(), "--format",
                   "gauges", "--gauge-observe-cycles", "200", "--give-up-after", "600"},
                  "stream.log", config);
  const auto lines = lines_to_end(*s);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  const std::string& summary = lines.back();
  EXPECT_EQ(field(summary, "cycles"), field(reference, "cycles")) << summary;
  const auto json = nlohmann::json::parse(summary);
  ASSERT_TRUE(json.contains("gauges")) << summary;
  for (const char* id : {"tip", "arm", "back"}) {
    ASSERT_TRUE(json["gauges"][id]["residual"].is_number()) << summary;
    EXPECT_NEAR(json["gauges"][id]["residual"].get<double>(), 0.0, 1e-6) << id;
    EXPECT_EQ(json["gauges"][id]["in_a_row"].get<int>(), 0) << id;
  }
  EXPECT_NE(read_file(dir_ / "daemon.log").find("observation stream#"), std::string::npos)
      << read_file(dir_ / "daemon.log");
  d->signal(SIGTERM);
  d->wait_for(kWaitS);
}

// --key-file: a daemon with [auth] takes the stream's signed batches, the stream verifies every
// STATE, and of the samples on the bus only those signed with their source's key are taken
// (an unsigned copy of the whole series from another source is refused). The same load as the
// in-process replay. A stream without the key is refused by the daemon (CODE_AUTH, exit 3).
TEST_F(StreamOverHub, SignedStreamFeedsAnAuthenticatedDaemon) {
  const std::string reference = replay_summary(kSeries);
  const std::string keys = (dir_ / "keys.toml").string();
  Process keygen({kBin + "/peritwin-replay", "--generate-key-file", keys, "--key-ids",
                  "stream,peritwin,gauge,rogue"},
                 (dir_ / "keygen.log").string());
  ASSERT_EQ(exit_code(keygen), 0) << read_file(dir_ / "keygen.log");
  const fs::path config = dir_ / "b1-auth.toml";
  std::ofstream(config) << read_file(kConfig) << "\n[auth]\nkey_file = \"keys.toml\"\n";
  Process d({kBin + "/peritwin", "--config", config.string(), "--lcm-url", hub_->url(),
             "--state-dir", (dir_ / "state").string(), "--deterministic", "--no-results"},
            (dir_ / "daemon.log").string());

  // Without the key: the daemon refuses the stream's first batch.
  auto unsigned_stream = std::make_unique<Process>(
      std::vector<std::string>{kBin + "/peritwin-stream", "--config", config.string(), "--input",
                               kSeries, "--lcm-url", hub_->url(), "--give-up-after", "600"},
      (dir_ / "unsigned.log").string());
  EXPECT_EQ(exit_code(*unsigned_stream), 3) << read_file(dir_ / "unsigned.log");
  EXPECT_NE(read_file(dir_ / "unsigned.log").find("auth"), std::string::npos)
      << read_file(dir_ / "unsigned.log");

  auto s = std::make_unique<Process>(
      std::vector<std::string>{kBin + "/peritwin-stream", "--config", config.string(), "--input",
                               "lcm", "--lcm-url", hub_->url(), "--key-file", keys, "--json",
                               "--give-up-after", "600", "--state-file",
                               (dir_ / "stream.state").string()},
      (dir_ / "stream.log").string());
  ASSERT_TRUE(s->read_line(kWaitS).has_value()) << read_file(dir_ / "stream.log");
  const auto ring = messages::KeyRing::load(keys);
  ASSERT_TRUE(ring) << ring.error().message();
  lcm::LCM lcm(hub_->url());
  ASSERT_TRUE(lcm.good());
  ASSERT_NO_FATAL_FAILURE(publish_series_as_samples(lcm, "rogue", nullptr));  // unsigned
  ASSERT_NO_FATAL_FAILURE(publish_series_as_samples(lcm, "gauge", ring->find("gauge")));
  const auto lines = stop_when_received(*s, dir_ / "stream.state", 1200);
  ASSERT_EQ(exit_code(*s), 0) << read_file(dir_ / "stream.log");
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(field(lines.back(), "samples"), "1200") << lines.back();
  expect_same_load(reference, lines.back());
  EXPECT_NE(read_file(dir_ / "stream.log").find("refused: auth: auth_tag: unsigned"),
            std::string::npos)
      << read_file(dir_ / "stream.log");
  d.signal(SIGTERM);
  d.wait_for(kWaitS);
}

}  // namespace
}  // namespace peritwin::stream
