// scripts/spy.sh, lcm-spy as shipped (issue 17): its options and errors, and the real lcm-spy it
// starts, under Xvfb on a tcpq:// hub, decoding every peritwin type and opening its viewer and a
// plot (the check itself runs inside Spy: spy/lcm/spy/PeritwinSpyCheck.java, a Spy plugin; the
// messages come from another JVM, spy/PeritwinSpyPublish.java).
//
// The types expected are those of messages/*.lcm, read at test time: a new .lcm file is checked
// without a change here (and fails if peritwin_msgs.jar lacks it).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tests/support/lcm_hub.h"

namespace fs = std::filesystem;
using namespace peritwin::testing;
using peritwin::core::free_loopback_port;

namespace {

const fs::path kSpy = fs::path(PERITWIN_SOURCE_DIR) / "scripts" / "spy.sh";
const fs::path kBuildDir = PERITWIN_BUILD_DIR;
const fs::path kSpyTestJar = PERITWIN_SPY_TEST_JAR;
constexpr double kWaitS = 300;  // only catches a hang; a loaded machine may be slow

/// Every `struct` of messages/*.lcm (package peritwin_msgs), sorted.
std::vector<std::string> message_types() {
  std::set<std::string> types;
  const std::regex package_re(R"(^\s*package\s+(\w+)\s*;)");
  const std::regex struct_re(R"(^\s*struct\s+(\w+))");
  for (const auto& entry : fs::directory_iterator(fs::path(PERITWIN_SOURCE_DIR) / "messages")) {
    if (entry.path().extension() != ".lcm") continue;
    std::ifstream in(entry.path());
    std::string line;
    std::smatch m;
    while (std::getline(in, line)) {
      if (std::regex_search(line, m, package_re)) {
        EXPECT_EQ(m[1], "peritwin_msgs") << entry.path();
      }
      if (std::regex_search(line, m, struct_re)) types.insert(m[1]);
    }
  }
  return {types.begin(), types.end()};
}

/// `name` on $PATH, or "".
std::string find_program(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && access((fs::path(dir) / name).c_str(), X_OK) == 0) {
      return (fs::path(dir) / name).string();
    }
  }
  return {};
}

struct Outcome {
  int exit_code = -1;  // -1: killed or still running after kWaitS
  std::string out;     // stdout
  std::string err;     // stderr
};

/// Runs argv to its end: all of its stdout, its stderr (via `dir`/name.err) and exit code.
Outcome run(const std::vector<std::string>& argv, const fs::path& dir, const std::string& name) {
  const fs::path err = dir / (name + ".err");
  fs::remove(err);
  Process p(argv, err.string());
  Outcome r;
  if (!p.started()) return r;
  while (const auto line = p.read_line(kWaitS)) r.out += *line + "\n";
  const auto status = p.wait_for(kWaitS);
  if (status && WIFEXITED(*status)) r.exit_code = WEXITSTATUS(*status);
  r.err = read_file(err);
  return r;
}

class LcmSpy : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(PERITWIN_TEST_OUT_DIR) /
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  // Environment changes of one test, undone after it.
  void set_env(const char* name, const std::string& value) {
    saved_.emplace_back(
        name, std::getenv(name) ? std::optional<std::string>(std::getenv(name)) : std::nullopt);
    setenv(name, value.c_str(), 1);
  }
  void unset_env(const char* name) {
    saved_.emplace_back(
        name, std::getenv(name) ? std::optional<std::string>(std::getenv(name)) : std::nullopt);
    unsetenv(name);
  }
  void TearDown() override {
    for (auto it = saved_.rbegin(); it != saved_.rend(); ++it) {
      if (it->second) {
        setenv(it->first.c_str(), it->second->c_str(), 1);
      } else {
        unsetenv(it->first.c_str());
      }
    }
  }

  fs::path dir_;
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

TEST_F(LcmSpy, HelpAndClassPath) {
  const Outcome help = run({kSpy.string(), "--help"}, dir_, "help");
  EXPECT_EQ(help.exit_code, 0) << help.err;
  EXPECT_NE(help.out.find("usage: scripts/spy.sh"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("libjchart2d-java"), std::string::npos) << help.out;

  unset_env("CLASSPATH");
  const Outcome cp =
      run({kSpy.string(), "--build-dir", kBuildDir.string(), "--classpath"}, dir_, "cp");
  ASSERT_EQ(cp.exit_code, 0) << cp.err;
  std::vector<std::string> entries;
  std::stringstream in(cp.out.substr(0, cp.out.find('\n')));
  for (std::string e; std::getline(in, e, ':');) entries.push_back(e);
  ASSERT_EQ(entries.size(), 3u) << cp.out;
  EXPECT_EQ(fs::path(entries[0]).filename(), "lcm.jar");
  EXPECT_EQ(fs::path(entries[1]), kBuildDir / "peritwin_msgs.jar");
  EXPECT_EQ(fs::path(entries[2]).filename(), "jchart2d.jar");
  for (const auto& e : entries) EXPECT_TRUE(fs::is_regular_file(e)) << e;

  // $CLASSPATH is appended (other type jars, Spy plugins).
  set_env("CLASSPATH", "/x/extra.jar");
  const Outcome extra =
      run({kSpy.string(), "--build-dir", kBuildDir.string(), "--classpath"}, dir_, "extra");
  EXPECT_EQ(extra.out, cp.out.substr(0, cp.out.find('\n')) + ":/x/extra.jar\n");

  const Outcome bad = run({kSpy.string(), "--no-such-option"}, dir_, "bad");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("unknown option --no-such-option"), std::string::npos) << bad.err;
}

TEST_F(LcmSpy, MissingJarNamesThePackage) {
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  set_env("PERITWIN_JAVA_DIR", empty.string());
  const Outcome r = run({kSpy.string(), "--build-dir", empty.string(), "memq://"}, dir_, "missing");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find((empty / "lcm.jar").string() + ": install the Debian package liblcm-java"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find((empty / "jchart2d.jar").string() +
                       ": install the Debian package libjchart2d-java"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find((empty / "peritwin_msgs.jar").string() + ": build it with"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.out, "");
}

TEST_F(LcmSpy, WithoutDisplaySaysHow) {
  unset_env("DISPLAY");
  unset_env("WAYLAND_DISPLAY");
  const Outcome r =
      run({kSpy.string(), "--build-dir", kBuildDir.string(), "memq://"}, dir_, "nodisp");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("xvfb-run -a scripts/spy.sh"), std::string::npos) << r.err;
}

// The real thing: scripts/spy.sh under Xvfb on a tcpq:// hub, another JVM publishing one message of
// every type; the check inside Spy reads its channel table, double-clicks every channel and opens a
// plot of one number of each.
TEST_F(LcmSpy, DecodesEveryTypeAndOpensViewerAndPlot) {
  const std::string java = find_java();
  const std::string xvfb_run = find_program("xvfb-run");
  ASSERT_FALSE(java.empty()) << "java not found";
  ASSERT_FALSE(xvfb_run.empty()) << "xvfb-run not found: install the Debian packages xvfb and "
                                    "xauth (scripts/install-deps.sh)";
  const auto types = message_types();
  ASSERT_GE(types.size(), 1u);
  std::string type_list;
  for (const auto& t : types) type_list += (type_list.empty() ? "" : ",") + t;
  const std::string prefix = "PERITWIN_SPY_TEST_";

  std::unique_ptr<Process> hub;
  int port = 0;
  for (int attempt = 0; attempt < 5 && !hub; ++attempt) {
    port = peritwin::core::free_loopback_port();
    hub = start_lcm_hub(java, port, dir_ / "hub.log", 60);
  }
  ASSERT_TRUE(hub) << read_file(dir_ / "hub.log");
  const std::string url = "tcpq://127.0.0.1:" + std::to_string(port);

  std::vector<std::string> publish = {java,
                                      "-cp",
                                      std::string(kLcmJar) + ":" +
                                          (kBuildDir / "peritwin_msgs.jar").string() + ":" +
                                          kSpyTestJar.string(),
                                      "PeritwinSpyPublish",
                                      url,
                                      prefix,
                                      "400"};
  publish.insert(publish.end(), types.begin(), types.end());
  Process publisher(publish, (dir_ / "publisher.err").string());
  ASSERT_TRUE(publisher.started());
  const auto published = publisher.read_line(120);
  ASSERT_TRUE(published) << read_file(dir_ / "publisher.err");
  EXPECT_EQ(*published, "published " + std::to_string(types.size()) + " types");

  set_env("CLASSPATH", kSpyTestJar.string());
  set_env("PERITWIN_SPY_CHECK_TYPES", type_list);
  set_env("PERITWIN_SPY_CHECK_PREFIX", prefix);
  set_env("PERITWIN_SPY_CHECK_SECONDS", "240");
  // timeout signals its whole process group: Xvfb and Spy too, should Spy hang without the check.
  const std::string timeout = find_program("timeout");
  ASSERT_FALSE(timeout.empty());
  const Outcome spy = run({timeout, "-k", "10", "270", xvfb_run, "-a", kSpy.string(), "--build-dir",
                           kBuildDir.string(), "--lcm-url", url},
                          dir_, "spy");
  EXPECT_EQ(spy.exit_code, 0) << spy.out << spy.err;
  EXPECT_NE(spy.out.find("spy-check: OK\n"), std::string::npos) << spy.out << spy.err;
  EXPECT_EQ(spy.out.find("spy-check: FAIL"), std::string::npos) << spy.out;
  for (const auto& t : types) {
    SCOPED_TRACE(t);
    EXPECT_NE(spy.out.find("spy-check: discovered " + t + " fingerprint "), std::string::npos);
    EXPECT_NE(spy.out.find("spy-check: " + prefix + t + " listed as " + t + ", "),
              std::string::npos);
    EXPECT_NE(spy.out.find("spy-check: " + prefix + t + ": viewer open, plot of "),
              std::string::npos);
  }
  EXPECT_TRUE(publisher.running())
      << "the publisher ended before the check: " << read_file(dir_ / "publisher.err");
}

}  // namespace
