#include "core/load_block.h"

#include <charconv>
#include <cmath>
#include <string>

namespace peritwin::core {

namespace {

std::string number(double v) {
  char buf[64];
  const auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return ec == std::errc{} ? std::string(buf, end) : std::string("?");
}

Error broken(const char* field, std::string reason) { return {field, std::move(reason)}; }

}  // namespace

Status check_load_block(const LoadBlock& b) {
  if (!std::isfinite(b.p_max))
    return broken("p_max", "p_max = " + number(b.p_max) + " is not finite");
  if (!(b.p_max > 0)) {
    return broken("p_max",
                  "p_max = " + number(b.p_max) + " must be > 0 (the peak load of a tensile cycle)");
  }
  if (!std::isfinite(b.r)) return broken("r", "r = " + number(b.r) + " is not finite");
  if (!(b.r < 1.0)) return broken("r", "r = " + number(b.r) + " must be < 1 (R = P_min/P_max)");
  if (!(b.r >= kMinLoadRatio)) {
    return broken("r", "r = " + number(b.r) + " must be >= " + number(kMinLoadRatio));
  }
  if (!std::isfinite(b.alpha))
    return broken("alpha", "alpha = " + number(b.alpha) + " is not finite");
  if (b.count < 1) return broken("count", "count = " + std::to_string(b.count) + " must be >= 1");
  if (b.count > kMaxBatchCycles) {
    return broken("count", "count = " + std::to_string(b.count) +
                               " must be <= " + std::to_string(kMaxBatchCycles));
  }
  return {};
}

Status check_load_blocks(std::span<const LoadBlock> blocks, std::int64_t max_cycles) {
  std::int64_t cycles = 0;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const std::string at = "blocks[" + std::to_string(i) + "].";
    if (Status s = check_load_block(blocks[i]); !s) return s.error().within(at);
    // cycles <= max_cycles and count >= 1: the comparison cannot overflow, and neither can the sum.
    if (blocks[i].count > max_cycles - cycles) {
      return Error{at + "count", "the blocks' cycle count exceeds " + std::to_string(max_cycles)};
    }
    cycles += blocks[i].count;
  }
  return {};
}

}  // namespace peritwin::core
