// Child processes of the benchmarks that run the deployed binaries (peritwin-bench-soak,
// peritwin-bench-stream): spawn with redirected output, stop with SIGTERM and a deadline.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace peritwin::bench {

using Clock = std::chrono::steady_clock;

inline double since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

/// Starts argv (PATH searched) with stdout and stderr appended to `out` and `err`, and stdin from
/// `stdin_fd` when >= 0 (closed in the child after the dup); -1 when it cannot start.
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& out,
                   const std::string& err, int stdin_fd = -1) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdin_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdin_fd, 0);
    posix_spawn_file_actions_addclose(&actions, stdin_fd);
  }
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

/// Waits up to timeout_s for the child to exit; its exit status (128 + signal), or -1 on timeout.
inline int wait_child(pid_t pid, double timeout_s) {
  if (pid <= 0) return -1;
  const auto t0 = Clock::now();
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) != pid) {
    if (since(t0) > timeout_s) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// SIGTERM, then the exit status (-1 if it had to be killed after timeout_s).
inline int stop_child(pid_t pid, double timeout_s) {
  if (pid <= 0) return -1;
  kill(pid, SIGTERM);
  const int status = wait_child(pid, timeout_s);
  if (status == -1) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  return status;
}

}  // namespace peritwin::bench
