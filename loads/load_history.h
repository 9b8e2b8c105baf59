// Load histories -> load blocks for the replay tool (no LCM here; see loads/rainflow.h for the
// cycle counting). SI units: loads in N, angles in rad, time in s.
//
// A series becomes blocks in series_to_blocks: every sample through RainflowCounter
// (loads/rainflow.h: hysteresis gate, ASTM E1049-85 counting, the residue by the ResidueRule),
// every cycle through CycleBlocks (loads/cycle_blocks.h: P_max, R, alpha at the peak and its bin,
// the R floor, fully compressive cycles, half-cycle pairing), then merge_consecutive. Blocks come
// out in the order the cycles are counted (ASTM order, residue last).
//
// File formats (CSV, ',' separated, fields may carry surrounding blanks, CRLF accepted). Blank
// lines and lines whose first non-blank character is '#' are comments and may appear anywhere. The
// first non-comment line is the header and must match exactly:
//  * series:   time_s,load_N[,angle_rad]   one sample per row; time finite and strictly
//              increasing; a load or angle "nan"/"inf" is a sample to skip (a sensor dropout),
//              counted in ConversionStats::nonfinite_samples. -> series_to_blocks.
//  * cycles:   p_max_N,r,angle_rad,count   one block per row, kept as given (not merged).
//  * spectrum: p_max_N,r,angle_rad,count   a list of blocks; an optional directive "# repeat N" as
//              the very first line (line 1) means the whole list is applied N times (N >= 1,
//              default 1). "# repeat" anywhere else, or in a series/cycles file, is an error;
//              so is a repeat that expands the list to more than kMaxSpectrumBlocks blocks.
// Row checks: every number finite (except a series' load and angle); exactly as many fields as
// the header; cycles/spectrum rows also count an integer (digits only) and the block valid by
// check_load_block (core/load_block.h: p_max_N > 0, -10 <= r < 1, count >= 1; a series'
// cycles below R = -10 are remapped, loads/cycle_blocks.h). A file without data rows is an
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

#include "core/expected.h"
#include "core/load_block.h"
#include "loads/cycle_blocks.h"
#include "loads/rainflow.h"
#include "messages/observation.h"

namespace peritwin::loads {

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
using ReadResult = core::Expected<T, ParseError>;

struct BlockConversion {
  std::vector<core::LoadBlock> blocks;
  ConversionStats stats;
};

/// Merges runs of consecutive identical (p_max, r, alpha) blocks into one with the summed count.
[[nodiscard]] std::vector<core::LoadBlock> merge_consecutive(
    std::span<const core::LoadBlock> blocks);

/// A sampled load history (series CSV). angle_rad is empty when the file has no angle column.
struct LoadSeries {
  std::vector<double> time_s;
  std::vector<double> load_n;
  std::vector<double> angle_rad;
};

/// How a series becomes blocks (loads/rainflow.h, loads/cycle_blocks.h).
struct SeriesRules {
  double gate = 0.0;       ///< N, hysteresis gate of the reversals (>= 0)
  double alpha_bin = 0.0;  ///< rad, alpha rounded to its multiples (0 = none)
  ResidueRule residue = ResidueRule::half;
  bool compressed_bonds_fatigue = true;  ///< the detail's; decides fully compressive cycles
};

/// RainflowCounter -> CycleBlocks -> merge_consecutive; the stats are CycleBlocks' with the
/// counter's reversals and nonfinite_samples. Throws std::invalid_argument for rules the two
/// classes refuse, or an angle column whose length differs from the loads'.
[[nodiscard]] BlockConversion series_to_blocks(const LoadSeries& series,
                                               const SeriesRules& rules = {});

/// Most blocks a spectrum expands to (blocks x repeat): 32 MB of blocks, e.g. 100 levels
/// repeated 10 000 times. Each block is a solve in the engine; more is a units slip, not a life.
inline constexpr std::size_t kMaxSpectrumBlocks = 1'000'000;

/// A block spectrum: `blocks` applied `repeat` times as a whole.
struct Spectrum {
  std::vector<core::LoadBlock> blocks;
  std::int64_t repeat = 1;
};

/// The spectrum's blocks repeated `repeat` times (no merging across the seams).
/// Throws std::length_error when that is more than kMaxSpectrumBlocks blocks (the readers refuse
/// such a file).
[[nodiscard]] std::vector<core::LoadBlock> expand(const Spectrum& spectrum);

[[nodiscard]] ReadResult<LoadSeries> read_series_csv(const std::filesystem::path& file);
[[nodiscard]] ReadResult<std::vector<core::LoadBlock>> read_cycles_csv(
    const std::filesystem::path& file);
[[nodiscard]] ReadResult<Spectrum> read_spectrum_csv(const std::filesystem::path& file);

/// The same readers on a stream (open it in binary mode); errors name the file `name`.
[[nodiscard]] ReadResult<LoadSeries> read_series_csv(std::istream& in, const std::string& name);
[[nodiscard]] ReadResult<std::vector<core::LoadBlock>> read_cycles_csv(std::istream& in,
                                                                       const std::string& name);
[[nodiscard]] ReadResult<Spectrum> read_spectrum_csv(std::istream& in, const std::string& name);

/// An observations file (issue 32, fed by peritwin-replay --observations): header
/// `cycle,kind,origin,length_m,sigma_m,pod_a50_m,pod_slope`, one inspection per row in
/// non-decreasing cycle order; kind `crack_length` (length_m, sigma_m given, the POD fields empty)
/// or `no_crack` (pod_a50_m, pod_slope given, length_m and sigma_m empty); origin `longest` or a
/// crack origin as STATE reports it (empty = longest). Each row checked by
/// messages::check_observation; the error names the line and field.
[[nodiscard]] ReadResult<std::vector<messages::Observation>> read_observations_csv(
    const std::filesystem::path& file);
[[nodiscard]] ReadResult<std::vector<messages::Observation>> read_observations_csv(
    std::istream& in, const std::string& name);

enum class HistoryFormat { series, cycles, spectrum };

/// Reads `file` in `format` and returns its blocks (series: converted by `rules`; spectrum:
/// expanded). The stats are those of series_to_blocks for a series and zero otherwise.
[[nodiscard]] ReadResult<BlockConversion> read_blocks(const std::filesystem::path& file,
                                                      HistoryFormat format,
                                                      const SeriesRules& rules = {});
[[nodiscard]] ReadResult<BlockConversion> read_blocks(std::istream& in, const std::string& name,
                                                      HistoryFormat format,
                                                      const SeriesRules& rules = {});

/// Splits `blocks` into consecutive batches of at most `max_blocks` blocks (the last may be
/// shorter; none is empty; empty input -> no batches). The spans view `blocks`' storage.
/// Throws std::invalid_argument when max_blocks == 0.
[[nodiscard]] std::vector<std::span<const core::LoadBlock>> make_batches(
    std::span<const core::LoadBlock> blocks, std::size_t max_blocks);

}  // namespace peritwin::loads
