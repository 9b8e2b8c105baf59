// The replay tool's engine room: recorded histories -> batches of load blocks -> the twin, either
// over LCM to a daemon (LcmReplayer) or in-process (run_in_process, twin/in_process_twin.h). See
// replay/replay_main.cpp.
//
// Batching: loads/batcher.h (make_twin_batches, mark_history). Seq numbers are 1, 2, 3, ... per
// run by default, so a daemon that already applied some of them drops those as duplicates and a
// replay is exactly-once across restarts of either side (peritwin-replay --resume, which checks
// the history's fingerprint against the daemon's); --continue numbers them after what the daemon
// has applied of the source.
//
// Over LCM (LcmReplayer): a thin user of BatchSender (loads/batch_sender.h: lockstep/window,
// resend after a daemon restart, authentication) with every batch given up front.
#pragma once

#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <istream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "loads/batch_sender.h"
#include "loads/batcher.h"
#include "loads/load_history.h"
#include "messages/auth.h"
#include "solver/fatigue/fatigue_engine.h"
#include "twin/in_process_twin.h"
#include "twin/messages_io.h"

namespace peritwin::replay {

enum class InputFormat { series, cycles, spectrum, lcm_log };

/// The blocks of a history file. lcm-log: the load_batch_t events on `detail_id`'s LOAD channel
/// in log order, each (source, seq) once, undecodable events skipped. Errors as "file: reason".
/// series: converted by `series_rules` (loads/load_history.h), `conversion` holds its stats.
struct HistoryBlocks {
  std::vector<core::LoadBlock> blocks;
  std::string note;                                  ///< e.g. rainflow statistics, for the log
  std::optional<loads::ConversionStats> conversion;  ///< series only
};
core::Expected<HistoryBlocks> read_history(const std::filesystem::path& file, InputFormat format,
                                           const std::string& detail_id,
                                           const loads::SeriesRules& series_rules = {});

/// The cycles a series conversion did not apply as counted, and the samples it skipped:
/// {"compressive", "mirrored_compressive", "remapped_below_floor", "degenerate",
/// "nonfinite_samples"} in that order (the summary's "skipped_cycles" object).
std::vector<std::pair<std::string, double>> skipped_cycles(const loads::ConversionStats& stats);
/// The same as one line: "skipped cycles: compressive 0, mirrored_compressive 1.5, ...".
std::string describe_skipped(const loads::ConversionStats& stats);
/// The lcm-log case on a stream (binary); errors name `name`. Malformed logs are refused with
/// the event's byte offset (loads/lcm_log.h), events above kMaxBatchPayload skipped unread.
core::Expected<HistoryBlocks> read_lcm_log(std::istream& in, const std::string& name,
                                           const std::string& detail_id);

/// Every block of a history by the daemon's own rule (check_load_blocks), the total capped only
/// by what int64 holds (the per-batch cap is the batches' business); the error names the first
/// invalid block as "blocks[i].<field>".
core::Status check_blocks(std::span<const core::LoadBlock> blocks);

/// The history's peak against the detail's [detail.limits] max_p, when the config sets it (the
/// default max_p is derived from the model, which the tool does not build: then OK): the first
/// block above it named as "blocks[i].p_max", with the history's peak (a units slip is likely:
/// the daemon would refuse the batch INVALID).
core::Status check_peak(std::span<const core::LoadBlock> blocks,
                        const config::LimitsConfig& limits);

struct ReplayResult {
  bool ok = false;
  std::string error;  ///< when !ok: why (a reject no resend cures names the daemon's reason)
  /// ok, but the detail reached its end of life during the run: the daemon's FAILED reject of
  /// the first batch not applied (BatchSender::end_of_life()).
  std::string end_of_life;
  std::optional<peritwin_msgs::damage_state_t> final_state;
  std::int64_t published = 0;     ///< batch messages sent (resends included)
  std::int64_t rewinds = 0;       ///< times sending restarted at applied + 1
  std::int64_t stale_states = 0;  ///< STATEs not answering this run (BatchSender::stale_states)
};

class LcmReplayer {
 public:
  LcmReplayer(lcm::LCM& lcm, std::vector<messages::Batch> batches, loads::ReplayOptions options,
              loads::ReplayAuth auth = {});
  LcmReplayer(const LcmReplayer&) = delete;
  LcmReplayer& operator=(const LcmReplayer&) = delete;

  /// Runs to the end. `on_state` sees every STATE of the detail; `idle` (optional) is called
  /// after every LCM wait and may return false to abort (e.g. a signal, or to drive an
  /// in-process daemon's tick()).
  ReplayResult run(const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
                   const std::function<bool()>& idle = {});

 private:
  loads::BatchSender sender_;
};

/// The config as a producer (peritwin-replay, peritwin-stream) reads it: the memory bound (75 %
/// of physical memory) only in-process, where the model is built; over LCM, none.
[[nodiscard]] config::ConfigResult load_producer_config(const std::string& file, bool in_process);

/// "state 12: 12000 cycles, 36 broken bonds, crack 1.00 mm, remaining 48000 cycles [40000,
/// 56000] (estimated at seq 10)": the estimate as published.
std::string describe(const peritwin_msgs::damage_state_t& state);
/// With `estimate_cycles`, the total cycles C of the state the estimate was made on, the remaining
/// life counted down to this state: max(0, E + C - cycles) and the band likewise, "remaining 45000
/// cycles [37000, 53000] (estimated at cycle 10000, 3000 cycles ago)". Without, describe(state).
std::string describe(const peritwin_msgs::damage_state_t& state,
                     std::optional<std::int64_t> estimate_cycles);

/// Which total cycles each batch brought the detail to, from the STATEs seen in order: a STATE
/// names the batch its estimate was made after (remaining_life_source, remaining_life_seq), not
/// that state's cycles, so the countdown needs them. The batch that produced a state is the
/// source whose applied seq moved since its predecessor, known only when that predecessor
/// (state_seq − 1) was the last state seen: after a missed state, a source that moved in it
/// would be dated too late (the dashboard's store, Store::on_state_life, keeps the same rule).
/// At most kMaxBatches remembered.
class LifeCountdown {
 public:
  static constexpr std::size_t kMaxBatches = 4096;
  /// Records `state`; the cycles of the state its estimate was made on, when known (0 for an
  /// estimate of the initial state, remaining_life_seq < 0).
  std::optional<std::int64_t> observe(const peritwin_msgs::damage_state_t& state);

 private:
  std::optional<std::int64_t> last_state_seq_;   ///< of the last state seen
  std::map<std::string, std::int64_t> applied_;  ///< source -> applied seq at the last state
  std::map<std::pair<std::string, std::int64_t>, std::int64_t> cycles_;  ///< batch -> cycles
  std::deque<std::pair<std::string, std::int64_t>> order_;               ///< oldest first
};

/// The state lines of peritwin-replay and peritwin-stream on stdout: each state once (a new
/// state_seq, remaining_life_seq or observation taken in), as twin::state_json with `json`, else
/// describe(); flushed.
class StatePrinter {
 public:
  explicit StatePrinter(bool json) : json_(json) {}
  void print(const peritwin_msgs::damage_state_t& state);
  /// print() as the on_state callback of a BatchSender or run_in_process (refers to this).
  std::function<void(const peritwin_msgs::damage_state_t&)> callback() {
    return [this](const peritwin_msgs::damage_state_t& s) { print(s); };
  }

 private:
  bool json_;
  std::int64_t last_seq_ = -2, last_life_ = -2, last_observations_ = -1;
  LifeCountdown countdown_;  ///< the text lines count the remaining life down (JSON: as published)
};

}  // namespace peritwin::replay
