// LCM's Java TCP hub (lcm.jar's lcm.lcm.TCPService) as a child process on a loopback port, for the
// cross-process tests, and what those tests read back: files (logs) and the final state hash.
#pragma once

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>

#include "tests/support/process.h"

namespace peritwin::testing {

inline constexpr const char* kLcmJar = "/usr/share/java/lcm.jar";

/// java on $PATH, or "" (then the tests skip).
inline std::string find_java() {
  const char* path = std::getenv("PATH");
  const std::string dirs = path != nullptr ? path : "/usr/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const auto end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path candidate =
        std::filesystem::path(dirs.substr(start, end - start)) / "java";
    if (!candidate.parent_path().empty() && std::filesystem::exists(candidate)) {
      return candidate.string();
    }
    start = end + 1;
  }
  return {};
}

/// A hub started on `port`, once it is the process listening there; nullptr if it exited or
/// something else holds the port after timeout_s. Its output goes to `log` (appended).
inline std::unique_ptr<Process> start_lcm_hub(const std::string& java, int port,
                                              const std::filesystem::path& log, double timeout_s) {
  auto hub = std::make_unique<Process>(
      std::vector<std::string>{java, "-cp", kLcmJar, "lcm.lcm.TCPService", std::to_string(port)},
      log.string());
  if (!hub->started()) return nullptr;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!listens_on(hub->pid(), port)) {
    if (hub->wait_for(0).has_value() || std::chrono::steady_clock::now() > deadline) {
      return nullptr;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return core::wait_for_loopback_port(port, timeout_s) ? std::move(hub) : nullptr;
}

inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Waits until `file` contains `text` (a process's log line); false after timeout_s.
inline bool wait_for_text(const std::filesystem::path& file, const std::string& text,
                          double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (read_file(file).find(text) == std::string::npos) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return true;
}

/// The "state_hash" of a JSON state or summary line, or "".
inline std::string state_hash_of(const std::string& json) {
  const std::string key = "\"state_hash\":\"";
  const auto p = json.find(key);
  if (p == std::string::npos) return {};
  const auto start = p + key.size();
  return json.substr(start, json.find('"', start) - start);
}

/// The "state_seq" of a JSON state line, or -1.
inline std::int64_t state_seq_of(const std::string& json) {
  const auto p = json.find("\"state_seq\":");
  return p == std::string::npos ? -1 : std::atoll(json.c_str() + p + 12);
}

/// A hub of one test on a port that was free a moment ago, checked to be this hub's (another
/// process may take the port between the check and the JVM's bind: then it retries on another
/// port). For tests that run the binaries over tcpq://127.0.0.1:PORT; without java or lcm.jar
/// such tests skip.
class LcmHub {
 public:
  /// Starts the hub, its output to `log`; waits up to timeout_s for it to listen.
  LcmHub(const std::filesystem::path& log, double timeout_s) {
    const std::string java = find_java();
    if (java.empty() || !std::filesystem::exists(kLcmJar)) {
      missing_ = std::string("java or ") + kLcmJar + " missing";
      return;
    }
    for (int attempt = 0; attempt < 5 && !hub_; ++attempt) {
      port_ = core::free_loopback_port();
      hub_ = std::make_unique<Process>(
          std::vector<std::string>{java, "-cp", kLcmJar, "lcm.lcm.TCPService",
                                   std::to_string(port_)},
          log.string());
      if (!hub_->started()) {
        hub_.reset();
        break;
      }
      const auto deadline =
          std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
      bool ours = false;
      while (!(ours = listens_on(hub_->pid(), port_)) && !hub_->wait_for(0).has_value() &&
             std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
      if (!ours) hub_.reset();
    }
    if (hub_ && !core::wait_for_loopback_port(port_, timeout_s)) hub_.reset();
  }

  /// Why there is no hub to test with (java or lcm.jar missing: skip), or "".
  [[nodiscard]] const std::string& missing() const { return missing_; }
  /// True when the hub is up; url() is then tcpq://127.0.0.1:PORT.
  [[nodiscard]] bool up() const { return hub_ != nullptr; }
  [[nodiscard]] std::string url() const { return "tcpq://127.0.0.1:" + std::to_string(port_); }

 private:
  std::string missing_;
  int port_ = 0;
  std::unique_ptr<Process> hub_;
};

}  // namespace peritwin::testing
