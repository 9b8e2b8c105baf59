// Rainflow cycles -> load blocks, incrementally (one cycle at a time, the pending half cycles kept
// in the state), used by the series reader (loads/load_history.h) and by a stream alike. SI
// units: loads in N, angles in rad.
//
// Rules, for a cycle between the reversal values `from` and `to` (loads/rainflow.h):
//  * P_max = the larger reversal value, P_min = the smaller, R = P_min / P_max, all bit-exact
//    from the reversal values, so cycles between the same two load levels get identical keys.
//  * ALPHA: the cycle's alpha (the angle at its peak) rounded to the nearest multiple of
//    BlockRules::alpha_bin (0 = kept as it is).
//  * DEGENERATE: P_max == P_min is no cycle: skipped, counted in skipped.degenerate.
//  * R FLOOR: the daemon accepts kMinLoadRatio (-10) <= R (core/load_block.h). A cycle with
//    P_max > 0 and R < -10 is applied with the same load RANGE dP = P_max - P_min, which is what
//    drives the fatigue laws (000 Eq. (15): the bond stretch range |s(1 - R)| is proportional to
//    P_max(1 - R) = dP in the linear model): p_max = dP / 11, r = -10. Counted in
//    skipped.remapped_below_floor. Its limit: the static (overload) check at p_max sees dP / 11
//    instead of the true P_max, and the compressive part is applied as tensile; for R < -10 the
//    cycle is nearly all compression, where both matter little for a tensile crack.
//  * FULLY COMPRESSIVE (P_max <= 0): with BlockRules::compressed_bonds_fatigue (true, the fatigue
//    law's default: bonds fatigue on |stretch range| whatever its sign, 000 Eq. (15)) the linear
//    model's response to the cycle is the mirror of the tensile cycle between -P_max and -P_min,
//    and every bond sees the same |range|: the cycle is applied as that mirror, p_max = -P_min,
//    r = P_max / P_min (0 <= r < 1), counted in skipped.mirrored_compressive. Its limit: the
//    static (overload) check at p_max and the sign of each bond's stretch (which bonds are "in
//    tension") are those of the mirror, not of the compressive load. With false (only bonds in
//    tension at P_max fatigue) a fully compressive cycle drives no fatigue: skipped, counted in
//    skipped.compressive.
//  * HALF CYCLES (the engine takes integer counts): half cycles are paired per identical key
//    (p_max, r, alpha) of the block they become, compared exactly (==). A half cycle whose key has
//    no pending half emits a whole cycle at its position in the sequence and leaves a pending
//    half; the next half cycle of the same key consumes that pending half and emits nothing. So
//    2k halves of a key give k cycles and 2k+1 give k+1: no damage is lost, the surplus is at most
//    half a cycle per pending key, and damage is applied no later than in the history
//    (conservative for sequence effects). At most kMaxPendingHalves keys are pending; one more
//    drops the oldest pending key (its whole cycle was already emitted: nothing is lost, that half
//    simply can no longer be paired).
//  * Every block has count 1, in the order the cycles come; merging is the caller's business
//    (merge_consecutive in loads/load_history.h).
// Skipped amounts count cycles as counted by the rainflow (a half cycle adds 0.5).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "core/expected.h"
#include "core/load_block.h"
#include "loads/rainflow.h"

namespace peritwin::loads {

using peritwin::core::LoadBlock;

/// Most keys with a pending half cycle (see the header comment).
inline constexpr std::size_t kMaxPendingHalves = 4096;

struct ConversionStats {
  /// Cycles that became no block, or another block than their own (see the header comment).
  struct SkippedCycles {
    double compressive = 0.0;           ///< P_max <= 0, compressed bonds do not fatigue: skipped
    double mirrored_compressive = 0.0;  ///< P_max <= 0, applied as the tensile mirror
    double remapped_below_floor = 0.0;  ///< R < -10: applied as the same range at R = -10
    double degenerate = 0.0;            ///< P_max == P_min: skipped
    friend bool operator==(const SkippedCycles&, const SkippedCycles&) = default;
  };
  std::size_t reversals = 0;          ///< rainflow reversals (series; 0 from CycleBlocks alone)
  std::size_t nonfinite_samples = 0;  ///< NaN/inf samples skipped (series; 0 from CycleBlocks)
  std::size_t full_cycles = 0;        ///< rainflow full cycles converted (incl. skipped ones)
  std::size_t half_cycles = 0;        ///< rainflow half cycles converted (incl. skipped ones)
  /// Half cycles emitted as whole cycles whose pairing half has not come (yet).
  std::size_t rounded_up_half_cycles = 0;
  SkippedCycles skipped;
  friend bool operator==(const ConversionStats&, const ConversionStats&) = default;
};

struct BlockRules {
  double alpha_bin = 0.0;                ///< rad, finite, >= 0; 0 = no binning
  bool compressed_bonds_fatigue = true;  ///< the detail's FatigueSettings::compressed_bonds_fatigue
  friend bool operator==(const BlockRules&, const BlockRules&) = default;
};

/// The incremental converter (see the header comment).
class CycleBlocks {
 public:
  /// Throws std::invalid_argument when alpha_bin is not finite or < 0.
  explicit CycleBlocks(BlockRules rules);

  /// Converts one cycle, appending 0 or 1 block (count 1) to `out`. Throws std::invalid_argument
  /// for a non-finite from/to/alpha or a count other than 1 or 0.5.
  void add(const CountedCycle& cycle, std::vector<core::LoadBlock>& out);

  [[nodiscard]] const ConversionStats& stats() const { return stats_; }
  [[nodiscard]] const BlockRules& rules() const { return rules_; }
  /// Keys (p_max, r, alpha) with a pending half cycle, oldest first.
  [[nodiscard]] std::vector<core::LoadBlock> pending_halves() const;

  /// The whole state (rules, stats, pending halves in age order) as text, doubles as %a.
  [[nodiscard]] std::string save() const;
  /// The converter save() wrote, or the reason the text is not one.
  static core::Expected<CycleBlocks, std::string> restore(std::string_view text);

 private:
  using Key = std::tuple<double, double, double>;  // p_max, r, alpha
  void add_pending(const Key& key);

  BlockRules rules_;
  ConversionStats stats_;
  std::map<Key, std::uint64_t> pending_;         ///< key -> age serial
  std::map<std::uint64_t, Key> pending_by_age_;  ///< age serial -> key
  std::uint64_t next_serial_ = 0;
};

}  // namespace peritwin::loads
