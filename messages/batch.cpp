#include "messages/batch.h"

namespace peritwin::messages {

namespace {

Outcome invalid(std::string what, std::string why) {
  return {Verdict::invalid, std::move(what), std::move(why)};
}

bool printable_ascii(std::string_view s) {
  for (const char c : s) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return true;
}

}  // namespace

bool is_valid_source_id(std::string_view id) {
  return !id.empty() && id.size() <= kMaxSourceIdLength && printable_ascii(id);
}

Outcome check_batch(const Batch& batch, std::string_view detail_id) {
  if (batch.detail_id != detail_id) {
    return {Verdict::wrong_detail, "detail_id",
            "detail_id \"" + batch.detail_id + "\" does not match the channel's detail \"" +
                std::string(detail_id) + "\""};
  }
  if (!is_valid_source_id(batch.source_id)) {
    return invalid("source_id", "source_id must be 1 to " + std::to_string(kMaxSourceIdLength) +
                                    " printable ASCII characters without blanks");
  }
  if (batch.seq < 1) return invalid("seq", "seq = " + std::to_string(batch.seq) + " must be >= 1");
  if (batch.history == 0 ? batch.history_start != 0
                         : batch.history_start < 1 || batch.history_start > batch.seq) {
    return invalid("history_start",
                   "history_start = " + std::to_string(batch.history_start) +
                       (batch.history == 0 ? " must be 0 without a history"
                                           : " must be 1 to seq = " + std::to_string(batch.seq)));
  }
  if (batch.blocks.empty()) return invalid("num_blocks", "num_blocks = 0 must be >= 1");
  if (batch.blocks.size() > kMaxBlocksPerBatch) {
    return invalid("num_blocks", "num_blocks = " + std::to_string(batch.blocks.size()) +
                                     " must be <= " + std::to_string(kMaxBlocksPerBatch));
  }
  // The one rule for load blocks and their cycle total (core/load_block.h).
  if (const core::Status valid = core::check_load_blocks(batch.blocks); !valid) {
    return invalid(valid.error().field, valid.error().reason);
  }
  return {};
}

}  // namespace peritwin::messages
