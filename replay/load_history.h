// Load histories -> load blocks for the replay tool (no LCM here; see replay/rainflow.h for the
// cycle counting). SI units: loads in N, angles in rad, time in s.
//
// Rainflow cycles -> blocks (cycles_to_blocks):
//  * P_max = max of the cycle's two reversals (= mean + range/2), P_min = the other (= mean -
//    range/2), R = P_min / P_max. Taking the reversal values directly keeps P_max bit-exact, so
//    cycles between the same two load levels get identical (P_max, R).
//  * COMPRESSIVE: a (half) cycle with P_max <= 0 has no tensile fatigue driving force; it becomes
//  no
//    block and is counted in ConversionStats::compressive_cycles (full = 1, half = 0.5).
//  * ANGLE: alpha is the angle sample at the reversal where P_max occurs (the first sample of a
//    plateau); without an angle column alpha = 0.
//  * HALF CYCLES (the engine takes integer counts): half cycles are paired per identical key
//    (P_max, R, alpha), compared exactly (==). A half cycle whose key has no pending half emits a
//    whole cycle at its position in the sequence and leaves a pending half; the next half cycle of
//    the same key consumes that pending half and emits nothing. So 2k halves of a key give k cycles
//    and 2k+1 halves give k+1: no damage is ever lost, the surplus is at most half a cycle per
//    distinct key (ConversionStats::rounded_up_half_cycles counts those), and damage is applied no
//    later than in the history (conservative for sequence effects).
//  * Blocks come out in the order the cycles are counted (ASTM order, residue last).
//
// File formats (CSV, ',' separated, fields may carry surrounding blanks, CRLF accepted). Blank
// lines and lines whose first non-blank character is '#' are comments and may appear anywhere. The
// first non-comment line is the header and must match exactly:
//  * series:   time_s,load_N[,angle_rad]   one sample per row; time strictly increasing.
//              -> reversals -> rainflow -> blocks; consecutive identical blocks merged (counts
//              summed).
//  * cycles:   p_max_N,r,angle_rad,count   one block per row, kept as given (not merged).
//  * spectrum: p_max_N,r,angle_rad,count   a list of blocks; an optional directive "# repeat N" as
//              the very first line (line 1) means the whole list is applied N times (N >= 1,
//              default 1). "# repeat" anywhere else, or in a series/cycles file, is an error;
//              so is a repeat that expands the list to more than kMaxSpectrumBlocks blocks.
// Row checks: every number finite; exactly as many fields as the header; cycles/spectrum rows also
// count an integer (digits only) and the block valid by check_load_block
// (solver/core/load_block.h: p_max_N > 0, -10 <= r < 1, count >= 1). A file without data rows is an
// error. A UTF-8 byte-order mark is skipped. Every error names file:line and the reason.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "replay/rainflow.h"
#include "solver/core/expected.h"
#include "solver/core/load_block.h"

namespace peritwin::replay {

using peritwin::LoadBlock;

/// A reader's failure: file, 1-based line (0 = the file as a whole), reason.
struct ParseError {
  std::string file;
  std::size_t line = 0;
  std::string reason;
  /// "file:line: reason", or "file: reason" when line == 0.
  [[nodiscard]] std::string message() const;
};

/// A reader's result: the value or where and why the file is wrong.
template <typename T>
using ReadResult = Expected<T, ParseError>;

struct ConversionStats {
  std::size_t reversals = 0;
  std::size_t full_cycles = 0;             ///< rainflow full cycles (incl. compressive ones)
  std::size_t half_cycles = 0;             ///< rainflow half cycles (incl. compressive ones)
  double compressive_cycles = 0.0;         ///< cycles with P_max <= 0, skipped (halves count 0.5)
  std::size_t rounded_up_half_cycles = 0;  ///< unpaired half cycles emitted as whole cycles
};

struct BlockConversion {
  std::vector<LoadBlock> blocks;
  ConversionStats stats;
};

/// Rainflow cycles -> blocks with the rules in the header comment (count 1 each, not merged).
/// `angle_by_sample` is indexed by Reversals::sample_index; empty means alpha = 0.
/// Throws std::invalid_argument when a non-empty `angle_by_sample` is too short.
[[nodiscard]] BlockConversion cycles_to_blocks(const Reversals& reversals,
                                               std::span<const RainflowCycle> cycles,
                                               std::span<const double> angle_by_sample = {});

/// Merges runs of consecutive identical (p_max, r, alpha) blocks into one with the summed count.
[[nodiscard]] std::vector<LoadBlock> merge_consecutive(std::span<const LoadBlock> blocks);

/// A sampled load history (series CSV). angle_rad is empty when the file has no angle column.
struct LoadSeries {
  std::vector<double> time_s;
  std::vector<double> load_n;
  std::vector<double> angle_rad;
};

/// extract_reversals -> rainflow_count -> cycles_to_blocks -> merge_consecutive.
[[nodiscard]] BlockConversion series_to_blocks(const LoadSeries& series);

/// Most blocks a spectrum expands to (blocks x repeat): 32 MB of blocks, e.g. 100 levels
/// repeated 10 000 times. Each block is a solve in the engine; more is a units slip, not a life.
inline constexpr std::size_t kMaxSpectrumBlocks = 1'000'000;

/// A block spectrum: `blocks` applied `repeat` times as a whole.
struct Spectrum {
  std::vector<LoadBlock> blocks;
  std::int64_t repeat = 1;
};

/// The spectrum's blocks repeated `repeat` times (no merging across the seams).
/// Throws std::length_error when that is more than kMaxSpectrumBlocks blocks (the readers refuse
/// such a file).
[[nodiscard]] std::vector<LoadBlock> expand(const Spectrum& spectrum);

[[nodiscard]] ReadResult<LoadSeries> read_series_csv(const std::filesystem::path& file);
[[nodiscard]] ReadResult<std::vector<LoadBlock>> read_cycles_csv(const std::filesystem::path& file);
[[nodiscard]] ReadResult<Spectrum> read_spectrum_csv(const std::filesystem::path& file);

/// The same readers on a stream (open it in binary mode); errors name the file `name`.
[[nodiscard]] ReadResult<LoadSeries> read_series_csv(std::istream& in, const std::string& name);
[[nodiscard]] ReadResult<std::vector<LoadBlock>> read_cycles_csv(std::istream& in,
                                                                 const std::string& name);
[[nodiscard]] ReadResult<Spectrum> read_spectrum_csv(std::istream& in, const std::string& name);

enum class HistoryFormat { series, cycles, spectrum };

/// Reads `file` in `format` and returns its blocks (series: converted; spectrum: expanded). The
/// stats are those of series_to_blocks for a series and zero otherwise.
[[nodiscard]] ReadResult<BlockConversion> read_blocks(const std::filesystem::path& file,
                                                      HistoryFormat format);
[[nodiscard]] ReadResult<BlockConversion> read_blocks(std::istream& in, const std::string& name,
                                                      HistoryFormat format);

/// Splits `blocks` into consecutive batches of at most `max_blocks` blocks (the last may be
/// shorter; none is empty; empty input -> no batches). The spans view `blocks`' storage.
/// Throws std::invalid_argument when max_blocks == 0.
[[nodiscard]] std::vector<std::span<const LoadBlock>> make_batches(
    std::span<const LoadBlock> blocks, std::size_t max_blocks);

}  // namespace peritwin::replay
