// What the programs read of the kernel's files: a whole text file (a config, a log,
// /proc/loadavg), a process's memory as /proc/<pid>/status reports it (VmRSS, VmHWM) and its CPU
// time from /proc/<pid>/stat.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace peritwin::core {

/// The whole file ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// The line "Key:   123 kB" of /proc/<pid>/status in kB (pid "self": this process); -1 when the
/// file or the line is not there.
inline std::int64_t proc_status_kb(const std::string& key, const std::string& pid = "self") {
  std::ifstream status("/proc/" + pid + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(key + ":", 0) == 0) return std::atoll(line.c_str() + key.size() + 1);
  }
  return -1;
}

/// The same in MB (kB / 1024); `missing` when the file or the line is not there.
inline double proc_status_mb(const std::string& key, const std::string& pid = "self",
                             double missing = 0.0) {
  const std::int64_t kb = proc_status_kb(key, pid);
  return kb < 0 ? missing : static_cast<double>(kb) / 1024.0;
}

/// utime + stime of a process (all its threads) in seconds from /proc/<pid>/stat, or -1.
inline double proc_cpu_s(pid_t pid) {
  const std::string text = read_text("/proc/" + std::to_string(pid) + "/stat");
  const auto paren = text.rfind(')');  // the command name may hold spaces
  if (paren == std::string::npos) return -1.0;
  std::istringstream in(text.substr(paren + 2));
  std::string field;
  // After ") ": state (3), ppid, pgrp, session, tty_nr, tpgid, flags, minflt, cminflt, majflt,
  // cmajflt, utime (14), stime (15).
  std::vector<std::string> fields;
  while (fields.size() < 13 && in >> field) fields.push_back(field);
  if (fields.size() < 13) return -1.0;
  const double ticks =
      static_cast<double>(std::atoll(fields[11].c_str()) + std::atoll(fields[12].c_str()));
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

}  // namespace peritwin::core
