// A Chrome DevTools Protocol client over --remote-debugging-pipe, for the browser tests: chromium
// reads commands on its fd 3 and writes responses and events on its fd 4, each message one JSON
// text ended by a NUL byte (no WebSocket, no port). One browser process per object, started
// headless with its own profile directory; every read has a deadline; the destructor closes the
// browser (Browser.close, then SIGKILL if it does not exit).
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace peritwin::testing {

class CdpPipe {
 public:
  /// Starts `argv` (chromium and its flags; --remote-debugging-pipe is added) with stdout and
  /// stderr appended to `log_file`.
  CdpPipe(std::vector<std::string> argv, const std::string& log_file) {
    int to_browser[2], from_browser[2];
    if (pipe2(to_browser, O_CLOEXEC) != 0) return;
    if (pipe2(from_browser, O_CLOEXEC) != 0) {
      close(to_browser[0]);
      close(to_browser[1]);
      return;
    }
    // The child's ends away from 3 and 4 first: dup2 onto the same fd would keep O_CLOEXEC.
    const int child_in = fcntl(to_browser[0], F_DUPFD_CLOEXEC, 10);
    const int child_out = fcntl(from_browser[1], F_DUPFD_CLOEXEC, 10);
    close(to_browser[0]);
    close(from_browser[1]);
    write_fd_ = to_browser[1];
    read_fd_ = from_browser[0];
    argv.push_back("--remote-debugging-pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_file.c_str(), O_WRONLY | O_CREAT | O_APPEND,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_adddup2(&actions, child_in, 3);
    posix_spawn_file_actions_adddup2(&actions, child_out, 4);
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    if (posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    close(child_in);
    close(child_out);
  }
  ~CdpPipe() {
    if (pid_ > 0 && !exited_) {
      call("Browser.close", nlohmann::json::object(), "", 30.0);
      if (!wait_for_exit(60.0)) {
        kill(pid_, SIGKILL);
        wait_for_exit(30.0);
      }
    }
    if (write_fd_ >= 0) close(write_fd_);
    if (read_fd_ >= 0) close(read_fd_);
  }
  CdpPipe(const CdpPipe&) = delete;
  CdpPipe& operator=(const CdpPipe&) = delete;

  [[nodiscard]] bool started() const { return pid_ > 0; }

  /// Sends a command (to the browser, or to an attached target's `session`) and waits up to
  /// `timeout_s` for its answer: the whole response ({"id", "result"} or {"id", "error"}), or
  /// nullopt when the browser went away or did not answer in time. Events read meanwhile are
  /// dropped.
  std::optional<nlohmann::json> call(const std::string& method, const nlohmann::json& params,
                                     const std::string& session, double timeout_s) {
    const std::int64_t id = next_id_++;
    nlohmann::json message{{"id", id}, {"method", method}, {"params", params}};
    if (!session.empty()) message["sessionId"] = session;
    std::string text = message.dump();
    text.push_back('\0');
    for (std::size_t sent = 0; sent < text.size();) {
      const ssize_t n = write(write_fd_, text.data() + sent, text.size() - sent);
      if (n <= 0) return std::nullopt;
      sent += static_cast<std::size_t>(n);
    }
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      if (const auto nul = buffer_.find('\0'); nul != std::string::npos) {
        auto reply = nlohmann::json::parse(buffer_.substr(0, nul), nullptr, false);
        buffer_.erase(0, nul + 1);
        if (reply.is_object() && reply.contains("id") && reply["id"] == id) return reply;
        continue;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) return std::nullopt;
      pollfd p{read_fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      char chunk[65536];
      const ssize_t n = read(read_fd_, chunk, sizeof chunk);
      if (n <= 0) return std::nullopt;  // the browser closed its end
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  /// Runtime.evaluate of `expression` in the page of `session` (promises awaited), its value
  /// (returnByValue); nullopt on an exception, a protocol error or no answer in `timeout_s`.
  std::optional<nlohmann::json> evaluate(const std::string& session, const std::string& expression,
                                         double timeout_s) {
    const auto reply =
        call("Runtime.evaluate",
             {{"expression", expression}, {"returnByValue", true}, {"awaitPromise", true}}, session,
             timeout_s);
    if (!reply || !reply->contains("result") || (*reply)["result"].contains("exceptionDetails")) {
      return std::nullopt;
    }
    const auto& result = (*reply)["result"]["result"];
    return result.contains("value") ? result["value"] : nlohmann::json();
  }

  bool wait_for_exit(double timeout_s) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!exited_) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        break;
      }
      if (std::chrono::steady_clock::now() > deadline) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return true;
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int write_fd_ = -1;
  int read_fd_ = -1;
  std::int64_t next_id_ = 1;
  std::string buffer_;
};

/// Standard base64 (RFC 4648, with padding) to bytes; nullopt on a character outside the alphabet.
inline std::optional<std::string> base64_decode(const std::string& text) {
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char ch : text) {
    int v;
    if (ch >= 'A' && ch <= 'Z') {
      v = ch - 'A';
    } else if (ch >= 'a' && ch <= 'z') {
      v = ch - 'a' + 26;
    } else if (ch >= '0' && ch <= '9') {
      v = ch - '0' + 52;
    } else if (ch == '+') {
      v = 62;
    } else if (ch == '/') {
      v = 63;
    } else if (ch == '=') {
      break;
    } else {
      return std::nullopt;
    }
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<char>((bits >> count) & 0xFF));
    }
  }
  return out;
}

}  // namespace peritwin::testing
