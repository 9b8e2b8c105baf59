#include "loads/batcher.h"

#include <algorithm>
#include <utility>

#include "core/fnv1a.h"

namespace peritwin::loads {

Batcher::Batcher(std::string detail_id, std::string source_id, std::int64_t first_seq,
                 BatchingOptions options)
    : detail_id_(std::move(detail_id)),
      source_id_(std::move(source_id)),
      next_seq_(first_seq),
      options_(options) {}

void Batcher::add(const core::LoadBlock& block, std::vector<messages::Batch>& out) {
  if (options_.merge_identical && !current_.empty() && current_.back().p_max == block.p_max &&
      current_.back().r == block.r && current_.back().alpha == block.alpha) {
    current_.back().count += block.count;
  } else {
    current_.push_back(block);
  }
  cycles_ += block.count;
  if (current_.size() >= std::max<std::size_t>(1, options_.max_blocks) ||
      cycles_ >= options_.max_cycles) {
    close(out);
  }
}

void Batcher::tick(double t, std::vector<messages::Batch>& out) {
  if (!(options_.max_seconds > 0.0)) return;
  if (!opened_at_) {
    opened_at_ = t;
    return;
  }
  if (t - *opened_at_ >= options_.max_seconds) {
    if (!current_.empty()) close(out);
    opened_at_ = t;
  }
}

void Batcher::flush(std::vector<messages::Batch>& out) {
  if (!current_.empty()) close(out);
}

void Batcher::restore(std::int64_t next_seq, std::vector<core::LoadBlock> open_blocks,
                      std::optional<double> opened_at) {
  next_seq_ = next_seq;
  current_ = std::move(open_blocks);
  cycles_ = 0;
  for (const auto& b : current_) cycles_ += b.count;
  opened_at_ = opened_at;
}

void Batcher::close(std::vector<messages::Batch>& out) {
  out.push_back({detail_id_, source_id_, next_seq_++, std::move(current_)});
  current_.clear();
  cycles_ = 0;
}

std::vector<messages::Batch> make_twin_batches(const std::vector<core::LoadBlock>& blocks,
                                               const std::string& detail_id,
                                               const std::string& source_id,
                                               const BatchingOptions& options,
                                               std::int64_t first_seq) {
  BatchingOptions no_time = options;
  no_time.max_seconds = 0.0;
  Batcher batcher(detail_id, source_id, first_seq, no_time);
  std::vector<messages::Batch> out;
  for (const auto& b : blocks) batcher.add(b, out);
  batcher.flush(out);
  return out;
}

std::uint64_t history_fingerprint(std::span<const messages::Batch> batches) {
  core::Fnv1a64 h;
  h.integer(static_cast<std::int64_t>(batches.size()));
  for (const messages::Batch& batch : batches) {
    h.integer(static_cast<std::int64_t>(batch.blocks.size()));
    for (const core::LoadBlock& b : batch.blocks) {
      h.real(b.p_max);
      h.real(b.r);
      h.real(b.alpha);
      h.integer(b.count);
    }
  }
  return h.get() == 0 ? 1 : h.get();
}

void mark_history(std::vector<messages::Batch>& batches) {
  if (batches.empty()) return;
  const std::uint64_t fingerprint = history_fingerprint(batches);
  const std::int64_t start = batches.front().seq;
  for (messages::Batch& b : batches) {
    b.history = fingerprint;
    b.history_start = start;
  }
}

}  // namespace peritwin::loads
