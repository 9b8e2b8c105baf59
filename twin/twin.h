// The live twin of one detail: the fatigue engine on the detail's model, exactly-once
// bookkeeping per load source, crack metrics, end-of-life state, the rolling spectrum, the latest
// remaining-life estimate, and checkpoint export/import. No LCM, no threads, no wall clock: the
// state after a batch sequence is a pure function of (config, sequence).
//
// Exactly-once (docs/design.md): every batch carries (source_id, seq). Per source the twin applies
// seq = last + 1 only: seq <= last is a DUPLICATE (ignored, counted), seq > last + 1 is a GAP
// (rejected, counted; the producer resends from applied_seq + 1, which every state publishes).
// A batch is applied as a unit, its blocks in order. A batch that is rejected for any reason
// leaves the model untouched. After final failure (end criterion met or singular stiffness)
// every new batch is rejected with FAILED.
//
// Remaining life (LifeMode):
//  * synchronous (deterministic mode: replay in-process, the daemon with --deterministic): an
//    estimate is computed inside apply() whenever state_seq is a multiple of
//    life.every_batches (catch_up_life() does it for the state the twin starts from);
//  * external (the daemon's worker thread): the owner takes life_job() snapshots, runs
//    estimate_life() elsewhere and hands the result back with set_life().
// The estimate is not part of state_hash(); it is published with the state it was computed on.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "solver/fatigue_engine.h"
#include "twin/checkpoint_io.h"
#include "twin/detail_model.h"
#include "twin/life.h"

namespace peritwin::twin {

/// One load batch (the fields of peritwin_msgs::load_batch_t the model uses).
struct Batch {
  std::string detail_id;
  std::string source_id;
  std::int64_t seq = 0;
  std::vector<LoadBlock> blocks;
};

/// What became of a batch; the values of the rejections are reject_t's CODE_* constants.
enum class Verdict : std::int8_t {
  applied = 0,
  decode = 1,
  invalid = 2,
  wrong_detail = 3,
  duplicate = 4,
  gap = 5,
  failed = 6,
  internal = 7,
};

struct Outcome {
  Verdict verdict = Verdict::applied;
  std::string what;  ///< offending field path ("blocks[3].r", "seq", "message"); empty if applied
  std::string why;   ///< for humans
  [[nodiscard]] bool applied() const { return verdict == Verdict::applied; }
};

// Accepted domain of a batch (reject_t INVALID outside it).
inline constexpr std::size_t kMaxBlocksPerBatch = 100'000;
inline constexpr std::size_t kMaxSourceIdLength = 64;
inline constexpr double kMinLoadRatio = -10.0;                          ///< R >= -10 (and R < 1)
inline constexpr std::int64_t kMaxBatchCycles = std::int64_t{1} << 50;  ///< Σ count per batch

/// Checks one block; `what` is prefixed with "blocks[<index>].".
Outcome check_block(const LoadBlock& block, std::size_t index);
/// Everything about a batch that needs no bookkeeping: WRONG_DETAIL or INVALID, else applied.
Outcome check_batch(const Batch& batch, std::string_view detail_id);

enum class LifeMode { synchronous, external };

/// Counters since this Twin object was created (not part of the state, not checkpointed).
struct TwinCounters {
  std::int64_t applied = 0;
  std::int64_t duplicates = 0;
  std::int64_t gaps = 0;
  std::int64_t rejected = 0;  ///< everything not applied except duplicates
};

/// A snapshot for a remaining-life estimate off the ingest path.
struct LifeJob {
  std::shared_ptr<const DetailModel> model;
  EngineState state;
  std::vector<LoadBlock> spectrum;
  std::int64_t state_seq = 0;
  std::int64_t seq = -1;
  std::string source;
};

class Twin {
 public:
  struct Options {
    LifeMode life = LifeMode::synchronous;
    bool parallel_band = true;  ///< the three band simulations on three threads
  };

  /// Builds the engine on `model` and solves the virgin state. nullptr with `error` on failure.
  static std::unique_ptr<Twin> create(std::shared_ptr<const DetailModel> model, Options options,
                                      std::string* error);

  Outcome apply(const Batch& batch);

  [[nodiscard]] const DetailModel& model() const { return *model_; }
  [[nodiscard]] const std::shared_ptr<const DetailModel>& model_ptr() const { return model_; }
  [[nodiscard]] const std::string& detail_id() const { return model_->config().id; }
  [[nodiscard]] const Options& options() const { return options_; }
  /// Batches applied since the virgin state, all sources together (0 = virgin).
  [[nodiscard]] std::int64_t state_seq() const { return state_seq_; }
  /// Last applied seq per source (sorted by source id).
  [[nodiscard]] const std::map<std::string, std::int64_t>& applied() const { return applied_; }
  [[nodiscard]] std::int64_t applied_seq(const std::string& source) const;
  /// (source, seq) of the batch that produced the current state ("" / -1 for the virgin state).
  [[nodiscard]] const std::string& last_source() const { return last_source_; }
  [[nodiscard]] std::int64_t last_seq() const { return last_seq_; }
  [[nodiscard]] const FatigueEngine& engine() const { return *engine_; }
  [[nodiscard]] const CrackReport& cracks() const { return report_; }
  [[nodiscard]] Failure failure() const { return failure_; }
  [[nodiscard]] const LifeEstimate& life() const { return life_; }
  [[nodiscard]] const RollingSpectrum& spectrum() const { return spectrum_; }
  [[nodiscard]] const std::optional<LoadBlock>& last_block() const { return last_block_; }
  [[nodiscard]] const TwinCounters& counters() const { return counters_; }
  /// Broken bonds since the virgin state (notch-cut bonds not counted).
  [[nodiscard]] std::int64_t broken_bonds() const;
  /// FNV-1a 64 over 64-bit words of every bond's remaining life, intact flag and phase, the
  /// cycle count, state_seq, the applied seq per source, the failure code, the last block and
  /// the rolling spectrum (twin.cpp). Not over the life estimate.
  [[nodiscard]] std::uint64_t state_hash() const;
  [[nodiscard]] std::string state_hash_hex() const;

  /// Remaining life ----------------------------------------------------------------------------
  [[nodiscard]] LifeJob life_job() const;
  /// Installs an estimate unless it belongs to an older state than the current estimate.
  void set_life(const LifeEstimate& estimate);
  /// True when a synchronous estimate is due for the current state and not computed yet.
  [[nodiscard]] bool life_due() const;
  /// Computes the estimate for the current state now (on this thread).
  void estimate_life_now();
  /// Synchronous mode: estimate_life_now() if life_due().
  void catch_up_life();

  /// Checkpoints -------------------------------------------------------------------------------
  static constexpr std::int64_t kCheckpointFormat = 2;  ///< 2: bilinear law state
  [[nodiscard]] CheckpointData to_checkpoint() const;
  /// Restores a checkpoint of the same model (signature checked). On failure (`error` set) the
  /// twin must be discarded.
  bool restore(const CheckpointData& data, std::string* error);

 private:
  Twin(std::shared_ptr<const DetailModel> model, Options options);
  void refresh();  ///< crack report and failure from the engine

  std::shared_ptr<const DetailModel> model_;
  Options options_;
  std::unique_ptr<FatigueEngine> engine_;
  std::int64_t state_seq_ = 0;
  std::map<std::string, std::int64_t> applied_;
  std::string last_source_;
  std::int64_t last_seq_ = -1;
  std::optional<LoadBlock> last_block_;
  CrackReport report_;
  Failure failure_ = Failure::none;
  LifeEstimate life_;
  RollingSpectrum spectrum_;
  TwinCounters counters_;
};

/// 16 lower-case hex digits.
std::string hex64(std::uint64_t value);

}  // namespace peritwin::twin
