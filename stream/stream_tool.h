// peritwin-stream's engine room (stream/stream_main.cpp): samples -> [detail.sensor] scale and
// offset -> RainflowCounter (loads/rainflow.h) -> CycleBlocks (loads/cycle_blocks.h) -> Batcher
// (loads/batcher.h) -> batches; and the state file that makes a restart neither lose nor double a
// cycle.
//
// State file (StreamState::save/restore): text, written atomically (temporary file, fsync, rename,
// fsync of the directory) whenever batches were closed, and at the end. It holds the counter's and
// the converter's exact states, the open batch, the next seq, the batches not yet acknowledged by
// the daemon, the input position (lines consumed; a FILE input skips them at a restart), the last
// load_samples_t seq taken per source (version 2) and the counts; its last line is "checksum
// <FNV-1a 64 of every byte before it>". Next to it,
// "<state file>.received" holds the number of samples read so far (rewritten in place, no fsync:
// it survives a SIGKILL of the process, the page cache keeps it), so that a restart can report
// the samples read after the last state was written (lost_samples) for an input it cannot re-read.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"
#include "core/expected.h"
#include "loads/batcher.h"
#include "loads/cycle_blocks.h"
#include "loads/rainflow.h"

namespace peritwin::stream {

struct StreamCounts {
  std::uint64_t input_lines = 0;   ///< lines consumed from the input (header, comments included)
  std::uint64_t samples = 0;       ///< data lines / samples taken (non-finite ones included)
  std::uint64_t bad_lines = 0;     ///< lines that are no sample (skipped, reported)
  std::uint64_t batches = 0;       ///< batches closed
  std::uint64_t lost_samples = 0;  ///< samples read but never in a persisted state (restarts)
  std::uint64_t block_cycles = 0;  ///< cycles in the closed batches
};

/// The pipeline from samples to batches, and everything a restart needs.
class Pipeline {
 public:
  Pipeline(const config::DetailConfig& detail, const std::string& source_id,
           loads::BatchingOptions batching, std::int64_t first_seq);

  /// One sample (measured value in the sensor's unit, angle in rad, time in s); closed batches
  /// go to `out`.
  void sample(double t, double measured, double alpha, std::vector<messages::Batch>& out);
  /// The load of a measured value: scale * measured + offset (N).
  [[nodiscard]] double load(double measured) const { return scale_ * measured + offset_; }
  /// End of the input: the residue by `rule`, then the open batch.
  void finish(loads::ResidueRule rule, std::vector<messages::Batch>& out);

  [[nodiscard]] const loads::RainflowStats& rainflow() const { return counter_.stats(); }
  [[nodiscard]] const loads::ConversionStats& conversion() const { return blocks_.stats(); }
  [[nodiscard]] std::int64_t next_seq() const { return batcher_.next_seq(); }
  StreamCounts counts;
  std::optional<double> last_time;  ///< of the last sample taken (times must increase)
  /// --input lcm: the last seq of each source's load_samples_t whose samples were taken (so a
  /// restart neither takes a resent message twice nor calls the next seq a gap).
  std::map<std::string, std::int64_t> samples_taken;

  /// The state text (without the unacknowledged batches and checksum: StreamState adds them).
  [[nodiscard]] std::string save() const;
  static core::Expected<Pipeline, std::string> restore(std::string_view text,
                                                       const config::DetailConfig& detail,
                                                       const std::string& source_id,
                                                       loads::BatchingOptions batching);

 private:
  void emit(std::vector<messages::Batch>& out);
  double scale_, offset_;
  loads::RainflowCounter counter_;
  loads::CycleBlocks blocks_;
  loads::Batcher batcher_;
  std::vector<loads::CountedCycle> cycles_;
  std::vector<core::LoadBlock> new_blocks_;
};

/// Writes the pipeline and the unacknowledged batches to `file` atomically (see the top).
core::Status save_state(const std::filesystem::path& file, const Pipeline& pipeline,
                        const std::vector<messages::Batch>& unacknowledged);
struct RestoredState {
  Pipeline pipeline;
  std::vector<messages::Batch> unacknowledged;
};
/// The state in `file`, or why it is none ("<file>: checksum mismatch", "...: truncated", ...).
core::Expected<RestoredState, std::string> load_state(const std::filesystem::path& file,
                                                      const config::DetailConfig& detail,
                                                      const std::string& source_id,
                                                      loads::BatchingOptions batching);
/// "<file>.received": samples read so far (see the top of the file).
void write_received(const std::filesystem::path& state_file, std::uint64_t samples);
std::optional<std::uint64_t> read_received(const std::filesystem::path& state_file);

/// Bounds of the input (README "Streaming from sensors"): a line of a descriptor input (stdin, a
/// FILE, a FIFO, TCP) longer than this without its newline ends the input with an error (a sample
/// line is some 40 bytes; without the bound an endless line grows the memory without end).
inline constexpr std::size_t kMaxLineBytes = 4096;
/// A sample time later than the wall clock's now (as Unix seconds) plus this is no measurement
/// (e.g. "1e308,5"): skipped and counted. Times relative to a start are far below it.
inline constexpr double kMaxFutureSeconds = 86400.0;
/// Samples refused as not after the previous time, in a row and increasing among themselves,
/// after which that previous time is taken as the outlier: the stream goes on from them.
inline constexpr int kRebaseAfter = 5;
/// Without [detail.limits] max_p: the largest |P| (N) of a sample taken (a larger one is a
/// glitch or garbage, no structural detail's load).
inline constexpr double kAbsurdLoad = 1e9;

/// The range of a sample's load P (N) the stream takes: P <= bound and P >= -10 bound (the
/// compressive side of a cycle at R = -10, core/load_block.h), bound being [detail.limits]
/// max_p when configured (a sample above it would make the daemon refuse its whole batch),
/// else kAbsurdLoad. (--in-process, where the model is built, bounds by the twin's max_p,
/// configured or derived.)
double sample_load_bound(const config::DetailConfig& detail);

/// One input line: a sample (t, measured, alpha), nothing (blank, '#' comment, the series header
/// "time_s,load_N[,angle_rad]") or an error (why).
struct ParsedLine {
  enum class Kind { sample, nothing, bad } kind = Kind::nothing;
  double t = 0.0, p = 0.0, alpha = 0.0;
  std::string why;
};
ParsedLine parse_line(std::string_view line);

}  // namespace peritwin::stream
