// What a checkpoint holds: named 1-D arrays and scalars and the caller's format version. The twin
// fills and reads it (twin/twin_checkpoint.cpp); HDF5 files hold it
// (outputs/checkpoint_io.h).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace peritwin::twin {

struct CheckpointData {
  /// The caller's format version (what the arrays mean); stored and returned as is.
  std::int64_t format_version = 1;
  std::map<std::string, std::vector<double>> f64_arrays;
  std::map<std::string, std::vector<std::int64_t>> i64_arrays;
  std::map<std::string, std::vector<std::uint8_t>> u8_arrays;
  std::map<std::string, std::int64_t> i64_scalars;
  std::map<std::string, double> f64_scalars;
  std::map<std::string, std::string> strings;
};

}  // namespace peritwin::twin
