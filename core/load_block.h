// The load block: `count` identical load cycles between P_min = R·P_max and P_max at load angle α.
// One type for the whole product: the engine applies it, the twin receives it in batches, the
// replay tool reads it from histories, the config lists it as a reference spectrum; only the LCM
// message (messages/load_block_t.lcm) and the history files have their own shape, converted at
// those edges.
//
// Validity (check_load_block, check_load_blocks): the one rule every path calls — the daemon's
// ingest, the replay tool's readers and in-process runs, the config's reference spectrum.
// messages/README.md and load_block_t.lcm document it:
//   p_max  finite and > 0 (N): the peak load of a tensile cycle;
//   r      finite, kMinLoadRatio (−10) <= R < 1: R = P_min/P_max. R >= 1 is no cycle; R < −10
//          means a cycle almost wholly in compression (|P_min| > 10·P_max), which the tensile
//          fatigue laws (000 Eq. 15, 002 Eq. 12) were never calibrated for. The floor is a rule
//          for blocks, not for histories: the replay's rainflow conversion applies a counted
//          cycle below it as the same range ΔP = P_max − P_min at R = −10 (p_max = ΔP/11, the
//          range being what drives 000 Eq. 15) and a fully compressive cycle as its tensile
//          mirror (loads/cycle_blocks.h);
//   alpha  finite (rad);
//   count  1 <= count <= kMaxBatchCycles;
// and a sequence of blocks applied as one unit (a batch) holds at most kMaxBatchCycles cycles in
// all, summed without overflow, so the engine's int64 cycle count cannot wrap.
#pragma once

#include <cstdint>
#include <span>

#include "core/expected.h"

namespace peritwin::core {

struct LoadBlock {
  double p_max = 0.0;      ///< N
  double r = 0.0;          ///< P_min / P_max
  double alpha = 0.0;      ///< load angle, rad
  std::int64_t count = 0;  ///< cycles
  friend bool operator==(const LoadBlock&, const LoadBlock&) = default;
};

/// Lowest accepted load ratio R (see the file comment).
inline constexpr double kMinLoadRatio = -10.0;
/// Most cycles in one block and in one batch (Σ count): 2^50 ≈ 1.1e15, far beyond any structure's
/// life, and 2^13 batches of it still fit in int64.
inline constexpr std::int64_t kMaxBatchCycles = std::int64_t{1} << 50;
/// Most cycles a detail's life may total (its running count): 2^53 ≈ 9.0e15, so that every count
/// is exact as a double (the life arithmetic, JSON numbers on the dashboard) and the running total
/// plus one batch (<= 2^50) cannot wrap int64. A batch that would take the total past it is
/// INVALID (twin::Twin::check_limits), naming the cap.
inline constexpr std::int64_t kMaxTotalCycles = std::int64_t{1} << 53;

/// OK, or the first rule the block breaks: field "p_max", "r", "alpha" or "count" and the reason.
Status check_load_block(const LoadBlock& block);

/// Every block (fields "blocks[i].<field>") and the total count (field "blocks[i].count" of the
/// block that takes the sum past `max_cycles`, >= 0): kMaxBatchCycles for a batch; a whole
/// history (the replay tool) passes the int64 maximum, the most the engine's cycle count holds.
Status check_load_blocks(std::span<const LoadBlock> blocks,
                         std::int64_t max_cycles = kMaxBatchCycles);

}  // namespace peritwin::core
