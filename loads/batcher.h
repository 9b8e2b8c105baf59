// Packing load blocks into the twin's batches, one rule for the replay and the stream.
//
// Blocks are packed in order into batches of at most `max_blocks` blocks, and a batch is closed
// as soon as it holds `max_cycles` cycles or more (make_twin_batches' rule). A live stream also
// closes the open batch once `max_seconds` of sample time have passed since it was opened (the
// time of the first sample after the previous close): tick(t) with every sample's time. Seq
// numbers are consecutive from the first one given.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/load_block.h"
#include "messages/batch.h"

namespace peritwin::loads {

struct BatchingOptions {
  // 1024 blocks = 32 KB of payload: below LCM 1.3.1's 64 KB UDP fragmentation limit, and large
  // enough that a rainflow-counted history of 1-cycle blocks is not limited by round trips.
  std::size_t max_blocks = 1024;
  std::int64_t max_cycles = 1000;
  double max_seconds = 0.0;  ///< of sample time per batch; 0: no time rule
  /// A block identical (p_max, r, alpha) to the open batch's last one adds its count to it (the
  /// stream: rainflow gives 1-cycle blocks; the engine's state does not depend on the cutting).
  bool merge_identical = false;
};

class Batcher {
 public:
  Batcher(std::string detail_id, std::string source_id, std::int64_t first_seq,
          BatchingOptions options);

  /// Adds a block; a batch it completes goes to `out`.
  void add(const core::LoadBlock& block, std::vector<messages::Batch>& out);
  /// The sample time `t` [s] has been reached: closes the open batch into `out` when max_seconds
  /// of sample time have passed since it was opened (no-op without the time rule).
  void tick(double t, std::vector<messages::Batch>& out);
  /// Closes the open batch (if it holds any block) into `out`.
  void flush(std::vector<messages::Batch>& out);

  [[nodiscard]] std::int64_t next_seq() const { return next_seq_; }
  /// The open batch's blocks (not in any batch yet).
  [[nodiscard]] const std::vector<core::LoadBlock>& open_blocks() const { return current_; }
  /// The sample time at which the open batch was opened (time rule), if any.
  [[nodiscard]] std::optional<double> opened_at() const { return opened_at_; }
  /// Restores the open batch and the sequence (the stream's state file).
  void restore(std::int64_t next_seq, std::vector<core::LoadBlock> open_blocks,
               std::optional<double> opened_at);

 private:
  void close(std::vector<messages::Batch>& out);
  std::string detail_id_, source_id_;
  std::int64_t next_seq_;
  BatchingOptions options_;
  std::vector<core::LoadBlock> current_;
  std::int64_t cycles_ = 0;
  std::optional<double> opened_at_;
};

/// Every block of a history in batches numbered first_seq, first_seq + 1, ... (no time rule).
std::vector<messages::Batch> make_twin_batches(const std::vector<core::LoadBlock>& blocks,
                                               const std::string& detail_id,
                                               const std::string& source_id,
                                               const BatchingOptions& options,
                                               std::int64_t first_seq = 1);

/// The fingerprint of a recorded history as the batches it was cut into (load_batch_t.history):
/// word-wise FNV-1a 64 (core/fnv1a.h) over the number of batches and, per batch, its number of
/// blocks and each block's p_max, r and alpha (bits) and count; not the ids, not the seqs. So the
/// same file read and batched the same way has the same fingerprint wherever it is numbered
/// from, and another file, conversion (series rules) or batching another. Never 0 (0 = none).
std::uint64_t history_fingerprint(std::span<const messages::Batch> batches);
/// Puts history_fingerprint(batches) and the first batch's seq (history_start) into every batch.
void mark_history(std::vector<messages::Batch>& batches);

}  // namespace peritwin::loads
