// The files the benchmarks read: a whole text file (a config, a log, /proc/<pid>/stat) and a
// process's memory as the kernel reports it in /proc/<pid>/status (VmRSS, VmHWM).
#pragma once

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace peritwin::bench {

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

}  // namespace peritwin::bench
