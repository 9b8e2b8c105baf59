// A detail's checkpoints: <state_dir>/<id>/checkpoint-<state_seq>.h5, written atomically, the
// three newest kept (rotation). At start the newest valid one whose content matches its name
// (detail, model, state_seq) is restored; when checkpoints exist and none is valid, the start is
// refused unless fresh_start. Also what the daemon's STATE reports as durable: the state_seq and
// the applied seq per source of the newest checkpoint on disk.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <string>

#include "core/expected.h"
#include "twin/messages_io.h"
#include "twin/twin.h"

namespace peritwin::service {

class CheckpointStore {
 public:
  /// Checkpoints of detail `id` in `dir`; none are read or written unless `enabled`.
  CheckpointStore(std::string id, std::filesystem::path dir, bool enabled);

  /// Restores `twin` from the newest valid checkpoint, or leaves it virgin when there is none
  /// (or none is valid and `fresh_start`); or why not.
  core::Status resume(twin::Twin& twin, bool fresh_start);
  /// The state dir can be written to (a probe file, written atomically and removed).
  [[nodiscard]] core::Status check_writable() const;
  /// Writes the twin's state unless it is the newest checkpoint already (or checkpoints are off),
  /// prunes the old ones; starts the every_seconds period again either way. Whether it wrote, or
  /// why it could not.
  core::Expected<bool> write(const twin::Twin& twin, const char* why);
  /// Starts the every_seconds period again (at start, once the detail is ready).
  void restart_period(std::chrono::steady_clock::time_point now) { last_ = now; }
  /// every_seconds > 0 have passed since the last write() (or restart_period()).
  [[nodiscard]] bool due(double every_seconds, std::chrono::steady_clock::time_point now) const;

  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }
  /// state_seq of the newest checkpoint on disk, −1 for none.
  [[nodiscard]] std::int64_t seq() const { return seq_; }
  /// The applied seq per source of that checkpoint (STATE's checkpointed_seq).
  [[nodiscard]] const twin::SeqBySource& checkpointed() const { return checkpointed_; }

 private:
  std::string id_;
  std::filesystem::path dir_;
  bool enabled_;
  std::int64_t seq_ = -1;
  std::int64_t observations_ = 0;  ///< observations taken in at that checkpoint
  twin::SeqBySource checkpointed_;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace peritwin::service
