// Atomic, self-verifying checkpoint files (HDF5) and the durable-file helpers they rest on.
//
// A checkpoint is generic: named 1-D arrays (float64, int64, uint8), named scalars (int64,
// float64, string) and the caller's format version. write_checkpoint() never leaves a partial
// file under the final name: it writes <path>.tmp, flushes and closes it, fsyncs it, renames it
// over <path> and fsyncs the directory. An FNV-1a 64 checksum over the whole content is stored
// with it, so read_checkpoint() rejects a truncated or corrupted file with a clear message, and
// newest_valid_checkpoint() falls back to the newest file that verifies.
//
// File layout (layout_version 1):
//   /                attributes: format = "peritwin-checkpoint", layout_version = 1 (int64),
//                    format_version (int64, the caller's), checksum_fnv1a64 (16 hex digits)
//   /arrays/f64/<name>   float64[n]
//   /arrays/i64/<name>   int64[n]
//   /arrays/u8/<name>    uint8[n]
//   /scalars/i64         one int64 attribute per scalar
//   /scalars/f64         one float64 attribute per scalar
//   /strings/<name>      scalar UTF-8 string dataset (no size limit)
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "twin/checkpoint_data.h"

namespace peritwin::outputs {

/// A checkpoint that cannot be written, or read back and verified.
class CheckpointError : public std::runtime_error {
 public:
  CheckpointError(const std::filesystem::path& path, const std::string& reason);
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
};

/// FNV-1a 64 over a canonical little-endian serialization of everything in `data`: the format
/// version, then per section (f64, i64, u8 arrays; i64, f64 scalars; strings) each entry in name
/// order as name, NUL, element count (8 bytes), element bytes.
std::uint64_t checkpoint_checksum(const twin::CheckpointData& data);

/// Writes atomically (see the top of this file). Names must be non-empty, without '/', not "."
/// or ".."; violations throw std::invalid_argument, I/O failures CheckpointError.
void write_checkpoint(const std::filesystem::path& path, const twin::CheckpointData& data);

/// Reads and verifies (format, layout version, element types, checksum). Throws CheckpointError
/// naming the file and what is wrong with it.
twin::CheckpointData read_checkpoint(const std::filesystem::path& path);

/// <dir>/<prefix>-<seq>.h5, seq zero-padded to 12 digits (so `ls` sorts them).
std::filesystem::path checkpoint_path(const std::filesystem::path& dir, std::string_view prefix,
                                      std::uint64_t seq);

struct CheckpointFile {
  std::filesystem::path path;
  std::uint64_t seq = 0;
};

/// Every <prefix>-<digits>.h5 in `dir`, newest (highest seq) first; empty if dir does not exist.
std::vector<CheckpointFile> list_checkpoints(const std::filesystem::path& dir,
                                             std::string_view prefix);

struct FoundCheckpoint {
  CheckpointFile file;
  twin::CheckpointData data;
};

/// The newest checkpoint that reads and verifies, or nullopt. Every file skipped on the way is
/// reported in `skipped` (when given) as "<path>: <reason>".
std::optional<FoundCheckpoint> newest_valid_checkpoint(const std::filesystem::path& dir,
                                                       std::string_view prefix,
                                                       std::vector<std::string>* skipped = nullptr);

/// Keeps the `keep` (>= 1) newest checkpoints by seq and deletes the older ones, and stale
/// <prefix>-<seq>.h5.tmp files older than the newest kept one. Returns the deleted paths.
/// Assumes one writer per prefix.
std::vector<std::filesystem::path> prune_checkpoints(const std::filesystem::path& dir,
                                                     std::string_view prefix, std::size_t keep);

// --- durable file helpers (POSIX) --------------------------------------------------------------

/// fsync(2) of a regular file; throws std::system_error naming the path.
void fsync_file(const std::filesystem::path& path);
/// fsync(2) of a directory, making renames and unlinks in it durable.
void fsync_directory(const std::filesystem::path& dir);
/// Writes `bytes` to <path>.tmp, fsyncs it (when durable), renames it over `path` and fsyncs the
/// directory (when durable): readers see either the old or the new content, never a mix.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes,
                           bool durable = true);

}  // namespace peritwin::outputs
