// The producer side of the batch protocol, shared by peritwin-replay and peritwin-stream: batches
// of one (detail, source) to a daemon over LCM, exactly once per (source, seq).
//
// Batches are given incrementally (add(), consecutive seqs) and published on PERITWIN_<DETAIL>_LOAD
// with at most `window` batches beyond the last applied one (lockstep: window 1, i.e. wait for the
// daemon's STATE to show seq k applied before sending k + 1). The daemon's applied seq comes from
// PERITWIN_<DETAIL>_STATE. When it goes backwards (the daemon restarted from an older checkpoint)
// or nothing progresses for `resend_after_s`, sending restarts at applied + 1. After finish() the
// sender is done when a STATE shows the last seq applied (or the detail failed); it fails after
// `give_up_after_s` without progress while batches are outstanding. Batches are kept until the
// daemon reports them durable (damage_state_t.checkpointed_seq), at most kMaxRetained beyond it,
// so that a daemon that restarts from its checkpoint gets them again.
//
// A reject of one of this run's batches (or of the probe) that no resend can cure ends the run
// at once with the daemon's reason ("the daemon refused batch 1 of source "replay" (CODE_INVALID):
// blocks[0].p_max: ..."): INVALID (the batch is out of the detail's domain, e.g. p_max above
// max_p), AUTH and LIMIT (max_sources) fail the run; FAILED (the detail reached its end of life)
// is done when a batch of this run was applied before it (this run brought the detail there; the
// rest of the batches is not applied: end_of_life() says why) and fails it otherwise (the detail
// had ended before). DUPLICATE and GAP are the protocol (resend from the STATE's applied seq).
//
// Authentication (ReplayAuth, messages/README.md "Authentication"): with a batch key every batch
// is signed before it is published; with a daemon key every STATE and REJECT on the detail's
// channels is checked on its bytes before it is decoded, and the first one that is unsigned or
// wrongly signed ends the run with an error naming the channel, the message and why. A CODE_AUTH
// reject of one of our batches ends it too (signed or not: the daemon refuses what we send).
// Without keys nothing is signed or checked, and anyone on the bus can forge the states reported.
//
// Freshness (issue 30; messages/README.md, "Authentication"): a tag proves who made a message,
// not when. Every sender draws a random 64-bit nonce at construction (messages::random_nonce)
// and puts it in every batch it publishes, the probe included; the daemon echoes the nonce of
// the last batch it took in every STATE (damage_state_t.echo_source, echo_nonce, signed with the
// rest) and the rejected batch's in every REJECT (reject_t.nonce). The sender takes as progress,
// reports to on_state() and keeps as last_state() only the STATEs that echo (its source, its
// nonce), and acts only on the rejects that carry its nonce: a STATE or REJECT signed before
// this run started, published again, is ignored (counted, stale_states()). A STATE that answers
// no batch of this run but shows another applied seq of the source than the sender knows (a
// restarted daemon's start-up STATE, or an old one) prompts a probe (at most one a second),
// whose answer tells.
//
// probe_applied(): what the daemon has applied of this source before anything is sent. It
// publishes a probe batch (one 1-cycle block) with seq 2^63 - 1, which no daemon applies (it
// skips ahead: the daemon answers with a GAP reject and its STATE, echoing the probe's nonce),
// until a STATE that answers this run arrives (every STATE carries the applied seq of every
// source).
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/expected.h"
#include "messages/auth.h"
#include "messages/codec.h"

namespace peritwin::loads {

struct ReplayOptions {
  bool lockstep = false;
  std::size_t window = 256;        ///< batches in flight beyond the last applied (not lockstep)
  double resend_after_s = 3.0;     ///< no progress for this long: resend from applied + 1
  double give_up_after_s = 120.0;  ///< no progress for this long: fail
};

/// Keys of an authenticated run (see the top of this file).
struct ReplayAuth {
  std::optional<messages::AuthKey> batch_key;   ///< the key of the batches' source id
  std::optional<messages::AuthKey> daemon_key;  ///< the daemon's key, for its STATE and REJECT
  std::string daemon_key_id;                    ///< named in errors
};

class BatchSender {
 public:
  enum class Progress { running, done, failed };
  using StateFn = std::function<void(const peritwin_msgs::damage_state_t&)>;
  /// Batches held beyond the daemon's checkpointed seq after they are applied.
  static constexpr std::size_t kMaxRetained = 4096;

  BatchSender(lcm::LCM& lcm, std::string detail_id, std::string source_id, ReplayOptions options,
              ReplayAuth auth = {});
  ~BatchSender();
  BatchSender(const BatchSender&) = delete;
  BatchSender& operator=(const BatchSender&) = delete;

  /// Called with every STATE of the detail that answers this run (verified when a daemon key is
  /// set; see "Freshness" above).
  void on_state(StateFn fn) { on_state_ = std::move(fn); }
  /// This run's nonce (load_batch_t.nonce of every batch it publishes).
  [[nodiscard]] std::uint64_t nonce() const { return nonce_; }
  /// STATEs of the detail that answered no batch of this run, not taken (see "Freshness").
  [[nodiscard]] std::int64_t stale_states() const { return stale_states_; }

  /// The daemon's applied seq of this source before anything is sent (see the top of the file);
  /// an error after give_up_after_s without a STATE, on a lost transport or an auth failure.
  /// `idle` as for pump callers: false aborts ("interrupted").
  core::Expected<std::int64_t> probe_applied(const std::function<bool()>& idle = {});

  /// Queues a batch of this detail and source; its seq is the previous batch's + 1 (the first
  /// one may start anywhere >= 1).
  void add(messages::Batch batch);
  /// No more batches: done once the last is applied.
  void finish();
  /// Publishes what the window allows, processes LCM for up to timeout_ms, takes the STATEs.
  Progress pump(int timeout_ms);

  /// The daemon's applied seq of the source, -1 until the first STATE.
  [[nodiscard]] std::int64_t acked_seq() const { return applied_; }
  /// Batches added and not yet applied (seq > acked_seq()), in seq order.
  [[nodiscard]] std::vector<messages::Batch> unacknowledged() const;
  /// Seq of the last batch added (0 before any).
  [[nodiscard]] std::int64_t last_seq() const { return last_seq_; }
  [[nodiscard]] const std::string& error() const { return error_; }
  /// After a done pump(): the daemon's FAILED reject when the detail reached its end of life
  /// during the run (the batches from its seq on are not applied); empty otherwise.
  [[nodiscard]] const std::string& end_of_life() const { return end_of_life_; }
  [[nodiscard]] const std::optional<peritwin_msgs::damage_state_t>& last_state() const {
    return last_state_;
  }
  [[nodiscard]] std::int64_t published() const { return published_; }
  [[nodiscard]] std::int64_t rewinds() const { return rewinds_; }

 private:
  // Raw handlers: the bytes are checked (tag, then layout) before anything is decoded.
  void on_state_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void on_reject_msg(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
  void publish(const messages::Batch& batch);
  void publish_probe();
  /// LCM for up to timeout_ms; false (error_ set) on a failure of LCM, the transport or auth.
  bool receive(int timeout_ms);
  void take_states();
  [[nodiscard]] bool outstanding() const { return last_seq_ > std::max<std::int64_t>(applied_, 0); }

  lcm::LCM& lcm_;
  std::string detail_id_, source_id_, load_channel_;
  ReplayOptions options_;
  ReplayAuth auth_;
  std::uint64_t nonce_;  ///< this run's (messages::random_nonce)
  StateFn on_state_;
  std::string fatal_;  ///< set by a handler: a message that must end the run (auth)
  std::string error_;
  lcm::Subscription* state_sub_ = nullptr;
  lcm::Subscription* reject_sub_ = nullptr;
  std::vector<peritwin_msgs::damage_state_t> inbox_;
  std::optional<peritwin_msgs::damage_state_t> last_state_;
  std::deque<messages::Batch> batches_;  ///< seqs front_seq .. last_seq_, consecutive
  std::int64_t last_seq_ = 0;
  std::int64_t applied_ = -1;  ///< unknown until the first STATE
  std::int64_t durable_ = 0;   ///< the daemon's checkpointed seq of the source
  std::int64_t next_ = 1;      ///< next seq to publish
  bool finished_ = false;
  std::int64_t first_seq_ = 0;   ///< seq of the first batch added (0 before any)
  std::int64_t failed_seq_ = 0;  ///< lowest seq of ours the daemon refused FAILED (0: none)
  std::string failed_why_, end_of_life_;
  std::int64_t published_ = 0;
  std::int64_t rewinds_ = 0;
  std::int64_t stale_states_ = 0;
  bool reprobe_ = false;  ///< a STATE not answering this run disagreed with it: probe
  std::chrono::steady_clock::time_point last_progress_, last_send_, last_probe_{};
  double resend_after_;
};

}  // namespace peritwin::loads
