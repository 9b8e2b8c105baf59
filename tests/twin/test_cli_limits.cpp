// The binaries and the config's resource bounds (issue 14, item 6): peritwin --max-memory, and
// configs that used to exhaust memory (dx = 1 µm: std::bad_alloc, exit 3, no key named;
// horizon_ratio = 1000: 3.4 GB inside config checking) refused with exit 2 and the key path by the
// daemon and by peritwin-replay --in-process. Every refusal happens before LCM is opened, so no
// hub is needed. The waits are deadlines against a hang, not timing assertions.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/process.h"

namespace peritwin::twin {
namespace {

namespace fs = std::filesystem;
using peritwin::testing::Process;

constexpr double kWaitS = 300.0;

std::string read_file(const fs::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class CliLimits : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("peritwin_cli_limits_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// The B1 example with its line starting `prefix` replaced by `line`, written to the test dir.
  [[nodiscard]] std::string b1_with(const std::string& prefix, const std::string& line) const {
    std::ifstream in(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
    const fs::path out_file = dir_ / "detail.toml";
    std::ofstream out(out_file);
    std::string l;
    bool replaced = false;
    while (std::getline(in, l)) {
      if (!replaced && l.starts_with(prefix)) {
        l = line;
        replaced = true;
      }
      out << l << "\n";
    }
    EXPECT_TRUE(replaced) << prefix;
    return out_file.string();
  }

  /// Runs a binary of the build to its exit; its exit code (-1: did not exit normally) and stderr.
  std::pair<int, std::string> run(const std::string& binary, std::vector<std::string> args) {
    args.insert(args.begin(), std::string(PERITWIN_BIN_DIR) + "/" + binary);
    const fs::path log = dir_ / (binary + ".log");
    fs::remove(log);
    Process p(args, log.string(), dir_.string());
    EXPECT_TRUE(p.started());
    const auto status = p.wait_for(kWaitS);
    EXPECT_TRUE(status.has_value()) << binary << " did not exit";
    const int code = status && WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
    return {code, read_file(log)};
  }

  fs::path dir_;
};

TEST_F(CliLimits, DaemonRefusesTheB1ExampleUnder64MiB) {
  // The B1 example is estimated at 542 MiB (docs/limits.md).
  const auto [code, err] = run("peritwin", {"--config", b1_with("dx = ", "dx = 0.001"),
                                            "--max-memory", "64M", "--state-dir", "state"});
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("detail[0].grid.dx: the detail would need an estimated"), std::string::npos)
      << err;
  EXPECT_NE(err.find("more than the memory limit 64 MiB (--max-memory)"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir_ / "state")) << "nothing may be started";
}

TEST_F(CliLimits, DaemonRejectsAMaxMemoryThatIsNoByteSize) {
  for (const char* bad : {"8X", "0", "-1G", "1.5G"}) {
    SCOPED_TRACE(bad);
    const auto [code, err] =
        run("peritwin", {"--config", b1_with("dx = ", "dx = 0.001"), "--max-memory", bad});
    EXPECT_EQ(code, 2) << err;
    EXPECT_NE(err.find("--max-memory"), std::string::npos) << err;
  }
}

TEST_F(CliLimits, MicrometreGridRefusedByTheDaemonAndTheInProcessReplay) {
  // 3.75e9 nodes, 5.25e10 bonds: an estimated 1.6 PiB, whatever the machine's memory.
  const std::string config = b1_with("dx = ", "dx = 1e-6");
  const auto [code, err] = run("peritwin", {"--config", config, "--state-dir", "state"});
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("detail[0].grid.dx: the detail would need an estimated 1.6 PiB"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("bad_alloc"), std::string::npos) << err;

  const auto [replay_code, replay_err] = run(
      "peritwin-replay", {"--config", config, "--history",
                          std::string(PERITWIN_EXAMPLES_DIR) + "/b1-cycles.csv", "--in-process"});
  EXPECT_EQ(replay_code, 2) << replay_err;
  EXPECT_NE(replay_err.find("detail[0].grid.dx"), std::string::npos) << replay_err;
}

TEST_F(CliLimits, HorizonRatioOf1000RefusedWithItsKeyPath) {
  const auto [code, err] =
      run("peritwin",
          {"--config", b1_with("horizon_ratio", "horizon_ratio = 1000"), "--state-dir", "s"});
  EXPECT_EQ(code, 2) << err;
  EXPECT_NE(err.find("detail[0].grid.horizon_ratio: must be <= 10"), std::string::npos) << err;
}

}  // namespace
}  // namespace peritwin::twin
