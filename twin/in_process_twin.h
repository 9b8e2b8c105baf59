// The twin of one detail in this process, without a daemon: what peritwin-replay --in-process
// and peritwin-stream --in-process run (one driver, so both apply batches the same way).
//
// Deterministic mode (remaining life synchronously at the fixed points, as a daemon with
// --deterministic). Once a batch reaches the end of life (Verdict::failed) the twin is ended: that
// batch and every later one are not applied and the state stays the last applied one.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/expected.h"
#include "twin/messages_io.h"

namespace peritwin::twin {

class InProcessTwin {
 public:
  /// The detail's model and twin, its remaining life caught up; state() is the initial state.
  /// The error is the model's or the twin's message.
  static core::Expected<std::unique_ptr<InProcessTwin>, std::string> create(
      const config::DetailConfig& detail);

  /// Applies one batch and updates state(). Ok when applied, and when not applied because the
  /// twin is ended (by this batch or before); the error "batch <seq>: <what>: <why>" when refused
  /// for another reason.
  core::Status apply(const messages::Batch& batch);

  /// Takes an observation in (Twin::observe) and updates state(); the error "observation <seq>
  /// at cycle <cycle>: <what>: <why>" when refused.
  core::Status observe(const messages::Observation& observation);
  /// Simulates the learning ensemble's ends of life now (Twin::estimate_ensemble_now).
  void estimate_ensemble_now();

  [[nodiscard]] const peritwin_msgs::damage_state_t& state() const { return state_; }
  [[nodiscard]] const twin::Twin& twin() const { return *twin_; }
  /// The end of life was reached: no batch is applied any more.
  [[nodiscard]] bool ended() const { return ended_; }

 private:
  std::unique_ptr<twin::Twin> twin_;
  peritwin_msgs::damage_state_t state_;
  bool ended_ = false;
};

/// Applies the batches to a fresh InProcessTwin of `detail`, calling on_state after every applied
/// batch and once for the initial state, up to the end of life. Returns the final state message;
/// error set when the model cannot be built or a batch is refused (then no final state).
/// on_twin (optional) sees the twin where on_state sees its message (`last` false), and once more
/// after the last batch (`last` true, also after a refused batch): where peritwin-replay
/// --results hangs the daemon's results writer (outputs/detail_outputs.h), which this library
/// does not link.
struct InProcessResult {
  std::optional<peritwin_msgs::damage_state_t> final_state;
  std::string error;
};
using TwinObserver = std::function<void(const twin::Twin&, bool last)>;
InProcessResult run_in_process(
    const config::DetailConfig& detail, const std::vector<messages::Batch>& batches,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const TwinObserver& on_twin = {});

}  // namespace peritwin::twin
