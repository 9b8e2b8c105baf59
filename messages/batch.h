// A load batch as the twin receives it (the fields of peritwin_msgs::load_batch_t the model uses),
// what became of it (reject_t's codes), and the checks that need no bookkeeping. The exactly-once
// rules per (source, seq) are the twin's (twin/twin.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/load_block.h"

namespace peritwin::messages {

/// One load batch: the fields of peritwin_msgs::load_batch_t but utime and the tag. The model
/// uses detail_id, source_id, seq and blocks; the twin keeps history and history_start per
/// source (bookkeeping for a resumed replay, no hash covers them); nonce is the producer run's,
/// echoed in the daemon's answers (load_batch_t.lcm).
struct Batch {
  std::string detail_id;
  std::string source_id;
  std::int64_t seq = 0;
  std::vector<core::LoadBlock> blocks;
  std::uint64_t nonce = 0;         ///< the producer run's nonce; 0 = none
  std::uint64_t history = 0;       ///< fingerprint of the history it belongs to; 0 = none
  std::int64_t history_start = 0;  ///< seq of that history's first batch; 0 without a history
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
  auth = 8,
  limit = 9,
};

struct Outcome {
  Verdict verdict = Verdict::applied;
  std::string what;  ///< offending field path ("blocks[3].r", "seq", "message"); empty if applied
  std::string why;   ///< for humans
  [[nodiscard]] bool applied() const { return verdict == Verdict::applied; }
};

// Accepted domain of a batch (reject_t INVALID outside it); each block and the batch's cycle total
// by check_load_blocks (core/load_block.h: kMinLoadRatio, kMaxBatchCycles).
inline constexpr std::size_t kMaxBlocksPerBatch = 100'000;
inline constexpr std::size_t kMaxSourceIdLength = 64;
/// Length of an HMAC-SHA256 tag (load_batch_t.auth_tag and the daemon's messages).
inline constexpr std::size_t kAuthTagBytes = 32;

/// 1 to kMaxSourceIdLength printable ASCII characters without blanks.
bool is_valid_source_id(std::string_view id);

/// Everything about a batch that needs no bookkeeping: WRONG_DETAIL or INVALID, else applied.
Outcome check_batch(const Batch& batch, std::string_view detail_id);

}  // namespace peritwin::messages
