// The replay tool's engine room: recorded histories -> batches of load blocks -> the twin, either
// over LCM to a daemon (LcmReplayer) or in-process (run_in_process). See replay/replay_main.cpp.
//
// Batching (make_twin_batches): blocks are packed in history order into batches of at most
// `max_blocks` blocks, and a batch is closed as soon as it holds `max_cycles` cycles or more.
// Seq numbers are 1, 2, 3, ... per run, so a daemon that already applied some of them drops those
// as duplicates and a replay is exactly-once across restarts of either side.
//
// Over LCM (LcmReplayer): batches are published on PERITWIN_<DETAIL>_LOAD with at most `window`
// batches beyond the last applied one (lockstep: window 1, i.e. wait for the daemon's STATE to
// show seq k applied before sending k + 1). The daemon's applied seq comes from
// PERITWIN_<DETAIL>_STATE. When it goes backwards (the daemon restarted from an older
// checkpoint) or nothing progresses for `resend_after_s`, sending restarts at applied + 1. The
// run ends when a STATE shows the last seq applied (or the detail failed), or fails after
// `give_up_after_s` without progress.
//
// Authentication (ReplayAuth, messages/README.md "Authentication"): with a batch key every batch
// is signed before it is published; with a daemon key every STATE and REJECT on the detail's
// channels is checked on its bytes before it is decoded, and the first one that is unsigned or
// wrongly signed ends the run with an error naming the channel, the message and why. A CODE_AUTH
// reject of one of our batches ends it too (signed or not: the daemon refuses what we send).
// Without keys nothing is signed or checked, and anyone on the bus can forge the states the run
// reports.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <istream>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <vector>

#include "messages/auth.h"
#include "replay/load_history.h"
#include "solver/fatigue/fatigue_engine.h"
#include "twin/config/config.h"
#include "twin/lcm/messages_io.h"

namespace peritwin::replay {

enum class InputFormat { series, cycles, spectrum, lcm_log };

/// The blocks of a history file. lcm-log: the load_batch_t events on `detail_id`'s LOAD channel
/// in log order, each (source, seq) once, undecodable events skipped. Errors as "file: reason".
/// series: converted by `series_rules` (replay/load_history.h), `conversion` holds its stats.
struct HistoryBlocks {
  std::vector<LoadBlock> blocks;
  std::string note;                           ///< e.g. rainflow statistics, for the log
  std::optional<ConversionStats> conversion;  ///< series only
};
Expected<HistoryBlocks> read_history(const std::filesystem::path& file, InputFormat format,
                                     const std::string& detail_id,
                                     const SeriesRules& series_rules = {});

/// The cycles a series conversion did not apply as counted, and the samples it skipped:
/// {"compressive", "mirrored_compressive", "remapped_below_floor", "degenerate",
/// "nonfinite_samples"} in that order (the summary's "skipped_cycles" object).
std::vector<std::pair<std::string, double>> skipped_cycles(const ConversionStats& stats);
/// The same as one line: "skipped cycles: compressive 0, mirrored_compressive 1.5, ...".
std::string describe_skipped(const ConversionStats& stats);
/// The lcm-log case on a stream (binary); errors name `name`. Malformed logs are refused with
/// the event's byte offset (replay/lcm_log.h), events above kMaxBatchPayload skipped unread.
Expected<HistoryBlocks> read_lcm_log(std::istream& in, const std::string& name,
                                     const std::string& detail_id);

struct BatchingOptions {
  // 1024 blocks = 32 KB of payload: below LCM 1.3.1's 64 KB UDP fragmentation limit, and large
  // enough that a rainflow-counted history of 1-cycle blocks is not limited by round trips.
  std::size_t max_blocks = 1024;
  std::int64_t max_cycles = 1000;
};

std::vector<twin::Batch> make_twin_batches(const std::vector<LoadBlock>& blocks,
                                           const std::string& detail_id,
                                           const std::string& source_id,
                                           const BatchingOptions& options);

/// Every block of a history by the daemon's own rule (check_load_blocks), the total capped only
/// by what int64 holds (the per-batch cap is the batches' business); the error names the first
/// invalid block as "blocks[i].<field>".
Status check_blocks(std::span<const LoadBlock> blocks);

struct ReplayOptions {
  bool lockstep = false;
  std::size_t window = 256;        ///< batches in flight beyond the last applied (not lockstep)
  double resend_after_s = 3.0;     ///< no progress for this long: resend from applied + 1
  double give_up_after_s = 120.0;  ///< no progress for this long: fail
};

struct ReplayResult {
  bool ok = false;
  std::string error;
  std::optional<peritwin_msgs::damage_state_t> final_state;
  std::int64_t published = 0;  ///< batch messages sent (resends included)
  std::int64_t rewinds = 0;    ///< times sending restarted at applied + 1
};

/// Keys of an authenticated run (see the top of this file).
struct ReplayAuth {
  std::optional<messages::AuthKey> batch_key;   ///< the key of the batches' source id
  std::optional<messages::AuthKey> daemon_key;  ///< the daemon's key, for its STATE and REJECT
  std::string daemon_key_id;                    ///< named in errors
};

class LcmReplayer {
 public:
  LcmReplayer(lcm::LCM& lcm, std::vector<twin::Batch> batches, ReplayOptions options,
              ReplayAuth auth = {});
  ~LcmReplayer();
  LcmReplayer(const LcmReplayer&) = delete;
  LcmReplayer& operator=(const LcmReplayer&) = delete;

  /// Runs to the end. `on_state` sees every STATE of the detail; `idle` (optional) is called
  /// after every LCM wait and may return false to abort (e.g. a signal, or to drive an
  /// in-process daemon's tick()).
  ReplayResult run(const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
                   const std::function<bool()>& idle = {});

 private:
  // Raw handlers: the bytes are checked (tag, then layout) before anything is decoded.
  void on_state_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_reject_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void publish(std::int64_t seq);

  lcm::LCM& lcm_;
  std::vector<twin::Batch> batches_;
  ReplayOptions options_;
  ReplayAuth auth_;
  std::string fatal_;  ///< set by a handler: a message that must end the run (auth)
  std::string detail_id_, source_id_, load_channel_;
  lcm::Subscription* state_sub_ = nullptr;
  lcm::Subscription* reject_sub_ = nullptr;
  std::vector<peritwin_msgs::damage_state_t> inbox_;
  std::int64_t rejected_failed_ = 0;
  std::int64_t published_ = 0;
};

/// Applies the batches to a fresh Twin of `detail` (deterministic mode: remaining life
/// synchronously at the fixed points), calling on_state after every batch and once for the
/// initial state. Returns the final state message; error set when the model cannot be built.
struct InProcessResult {
  std::optional<peritwin_msgs::damage_state_t> final_state;
  std::string error;
};
InProcessResult run_in_process(
    const twin::DetailConfig& detail, const std::vector<twin::Batch>& batches,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state);

/// "state 12: 12000 cycles, 36 broken bonds, crack 1.00 mm, remaining 48000 cycles [40000,
/// 56000] (estimated at seq 10)".
std::string describe(const peritwin_msgs::damage_state_t& state);

}  // namespace peritwin::replay
