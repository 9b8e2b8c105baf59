// A process's memory as the kernel reports it (/proc/<pid>/status): the benchmarks' RSS (VmRSS)
// and peak RSS (VmHWM) in MB.
#pragma once

#include <cstdlib>
#include <fstream>
#include <string>

namespace peritwin::bench {

/// The line "Key:   123 kB" of /proc/<pid>/status in MB (pid "self": this process); `missing`
/// when the file or the line is not there.
inline double proc_status_mb(const std::string& key, const std::string& pid = "self",
                             double missing = 0.0) {
  std::ifstream status("/proc/" + pid + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(key + ":", 0) == 0)
      return std::strtod(line.c_str() + key.size() + 1, nullptr) / 1024.0;
  }
  return missing;
}

}  // namespace peritwin::bench
