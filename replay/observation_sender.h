// peritwin-replay --observations over LCM (issue 32): the history's batches, split at the
// observations' cycles, go to the daemon segment by segment (LcmReplayer); after the segment that
// ends at an observation's cycle is applied, the observation is published on the detail's
// OBSERVATION channel (signed with the batches' key) until a STATE shows it taken in
// (observation_applied_seq of the source >= its seq) or a REJECT of it ("observation…", this
// source and seq) says why not. So the daemon takes each observation in at its own cycle count, as
// the in-process run does, and the ensemble's bits are the in-process run's.
#pragma once

#include <functional>
#include <lcm/lcm-cpp.hpp>
#include <vector>

#include "loads/batch_sender.h"
#include "messages/batch.h"
#include "messages/observation.h"
#include "replay/replay_tool.h"

namespace peritwin::replay {

/// Publishes `observation` until the daemon took it in (ok; also when it had already: a
/// duplicate) or refused it (the error names the reject's field and reason), or no answer for
/// options.give_up_after_s. `on_state` sees the STATEs that arrive meanwhile.
core::Status send_observation(
    lcm::LCM& lcm, const messages::Observation& observation, const loads::ReplayOptions& options,
    const loads::ReplayAuth& auth,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle);

/// The batches (already split at the observations' cycles by split_batches_at) and the
/// observations (in cycle order, each with its detail, source and seq) to the daemon, each
/// observation after the batches up to its cycle are applied.
ReplayResult replay_with_observations(
    lcm::LCM& lcm, const std::vector<messages::Batch>& batches,
    const std::vector<messages::Observation>& observations, const loads::ReplayOptions& options,
    const loads::ReplayAuth& auth,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle);

}  // namespace peritwin::replay
