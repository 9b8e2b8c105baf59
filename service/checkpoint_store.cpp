#include "service/checkpoint_store.h"

#include <spdlog/spdlog.h>

#include <utility>
#include <vector>

#include "core/blas_kernel.h"
#include "outputs/checkpoint_io.h"

namespace peritwin::service {

namespace {

using Clock = std::chrono::steady_clock;

constexpr std::string_view kCheckpointPrefix = "checkpoint";
constexpr std::size_t kCheckpointsKept = 3;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// Every observation taken in moves its source's seq by one (gauge observations of a detail that
/// does not learn too).
std::int64_t observations_taken_in(const twin::Twin& twin) {
  std::int64_t n = 0;
  for (const auto& [source, seq] : twin.observed()) n += seq;
  return n;
}

}  // namespace

CheckpointStore::CheckpointStore(std::string id, std::filesystem::path dir, bool enabled)
    : id_(std::move(id)), dir_(std::move(dir)), enabled_(enabled), last_(Clock::now()) {}

core::Status CheckpointStore::resume(twin::Twin& twin, bool fresh_start) {
  const auto files = outputs::list_checkpoints(dir_, kCheckpointPrefix);
  if (files.empty()) {
    spdlog::info("[{}] no checkpoint in {}: starting from the virgin state", id_, dir_.string());
    return {};
  }
  std::vector<std::string> refused;
  for (const auto& file : files) {
    twin::CheckpointData data;
    try {
      data = outputs::read_checkpoint(file.path);
    } catch (const outputs::CheckpointError& e) {
      refused.emplace_back(e.what());
      continue;
    }
    if (const core::Status matches =
            twin.check_checkpoint(data, static_cast<std::int64_t>(file.seq));
        !matches) {
      refused.push_back(file.path.string() + ": " + matches.error().message());
      continue;
    }
    for (const auto& r : refused) spdlog::warn("[{}] skipping checkpoint {}", id_, r);
    if (const core::Status restored = twin.restore(data); !restored) {
      return core::failure(file.path.string() + ": " + restored.error().message());
    }
    seq_ = twin.state_seq();
    observations_ = observations_taken_in(twin);
    checkpointed_ = twin.applied();
    spdlog::info("[{}] resumed from {}: state_seq {}, {} cycles, state_hash {}", id_,
                 file.path.string(), twin.state_seq(), twin.engine().total_cycles(),
                 twin.state_hash_hex());
    const auto written = data.strings.find("blas_kernel");
    if (written != data.strings.end() && written->second != core::blas_kernel_name()) {
      spdlog::warn(
          "[{}] the checkpoint was written on BLAS kernel {}, this process runs {}: the run "
          "goes on correctly, but its states now agree with an uninterrupted run only to "
          "rounding, not bit for bit (set OPENBLAS_CORETYPE={} to match)",
          id_, written->second, core::blas_kernel_name(), written->second);
    }
    return {};
  }
  std::string why = "[" + id_ + "] none of the " + std::to_string(files.size()) +
                    " checkpoint(s) in " + dir_.string() + " is valid:";
  for (const auto& r : refused) why += "\n  " + r;
  if (fresh_start) {
    spdlog::warn("{}", why);
    spdlog::warn("[{}] --fresh-start: starting from the virgin state", id_);
    return {};
  }
  return core::failure(
      why +
      "\nStarting from the virgin state would silently forget every applied cycle: "
      "repair or move the files away, or start with --fresh-start");
}

core::Status CheckpointStore::check_writable() const {
  try {
    std::filesystem::create_directories(dir_);
    const auto probe = dir_ / ".writable";
    outputs::write_file_atomically(probe, "peritwin", true);
    std::filesystem::remove(probe);
  } catch (const std::exception& e) {
    return core::failure("[" + id_ + "] the state dir " + dir_.string() +
                         " is not writable, so no checkpoint could be kept: " + e.what());
  }
  return {};
}

core::Expected<bool> CheckpointStore::write(const twin::Twin& twin, const char* why) {
  last_ = Clock::now();
  // An observation changes the state without a batch: the same state_seq, written again (the file
  // of that state_seq replaced atomically) when the count of observations taken in differs.
  const std::int64_t observations = observations_taken_in(twin);
  if (!enabled_ || (seq_ == twin.state_seq() && observations_ == observations)) return false;
  const auto path = outputs::checkpoint_path(dir_, kCheckpointPrefix,
                                             static_cast<std::uint64_t>(twin.state_seq()));
  try {
    const auto t0 = Clock::now();
    std::filesystem::create_directories(dir_);
    outputs::write_checkpoint(path, twin.to_checkpoint());
    outputs::prune_checkpoints(dir_, kCheckpointPrefix, kCheckpointsKept);
    seq_ = twin.state_seq();
    observations_ = observations;
    checkpointed_ = twin.applied();
    spdlog::info("[{}] checkpoint ({}): {} in {:.3f} s", id_, why, path.string(),
                 seconds(Clock::now() - t0));
  } catch (const std::exception& e) {
    return core::failure("[" + id_ + "] cannot write checkpoint " + path.string() + ": " +
                         e.what());
  }
  return true;
}

bool CheckpointStore::due(double every_seconds, Clock::time_point now) const {
  return every_seconds > 0 && seconds(now - last_) >= every_seconds;
}

}  // namespace peritwin::service
