#include "replay/observation_sender.h"

#include <chrono>

#include "messages/auth.h"
#include "messages/codec.h"

namespace peritwin::replay {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// The daemon's answers to one observation: a STATE that lists it, or a REJECT of it.
struct Answers {
  const messages::Observation& observation;
  const loads::ReplayAuth& auth;
  const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state;
  bool taken = false;
  std::string refused;

  void state(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (auth.daemon_key && !messages::verify_encoded<peritwin_msgs::damage_state_t>(
                               rbuf->data, rbuf->data_size, *auth.daemon_key)) {
      return;  // not the daemon's
    }
    const auto s = messages::decode_state(rbuf->data, rbuf->data_size);
    if (!s || s->detail_id != observation.detail_id) return;
    if (on_state) on_state(*s);
    for (std::size_t i = 0; i < s->observation_source_ids.size(); ++i) {
      if (s->observation_source_ids[i] == observation.source_id &&
          s->observation_applied_seq[i] >= observation.seq) {
        taken = true;
      }
    }
  }
  void reject(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    if (auth.daemon_key && !messages::verify_encoded<peritwin_msgs::reject_t>(
                               rbuf->data, rbuf->data_size, *auth.daemon_key)) {
      return;
    }
    const auto r = messages::decode_reject(rbuf->data, rbuf->data_size);
    if (!r || r->source_id != observation.source_id || r->seq != observation.seq ||
        !r->what.starts_with("observation")) {
      return;
    }
    if (r->code == peritwin_msgs::reject_t::CODE_DUPLICATE) {
      taken = true;  // taken in before (a resumed run)
    } else {
      refused = r->what + ": " + r->why;
    }
  }
};

}  // namespace

core::Status send_observation(
    lcm::LCM& lcm, const messages::Observation& observation, const loads::ReplayOptions& options,
    const loads::ReplayAuth& auth,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle) {
  Answers answers{observation, auth, on_state, false, {}};
  auto* states = lcm.subscribe(messages::channel(observation.detail_id, messages::Kind::kState),
                               &Answers::state, &answers);
  auto* rejects = lcm.subscribe(messages::channel(observation.detail_id, messages::Kind::kReject),
                                &Answers::reject, &answers);
  auto m = messages::observation_message(observation, messages::now_utime());
  if (auth.batch_key) messages::sign(m, *auth.batch_key);
  const std::string channel =
      messages::channel(observation.detail_id, messages::Kind::kObservation);
  const auto started = Clock::now();
  auto sent = Clock::time_point{};
  core::Status out;
  while (!answers.taken && answers.refused.empty()) {
    if (sent == Clock::time_point{} || seconds_since(sent) >= options.resend_after_s) {
      lcm.publish(channel, &m);
      sent = Clock::now();
    }
    if (messages::handle_lcm(lcm, 20) < 0 || (idle && !idle())) {
      out = core::failure("interrupted while the observation at cycle " +
                          std::to_string(observation.cycle) + " was waiting for the daemon");
      break;
    }
    if (seconds_since(started) > options.give_up_after_s) {
      out = core::failure("no answer from the daemon to the observation at cycle " +
                          std::to_string(observation.cycle) + " for " +
                          std::to_string(options.give_up_after_s) + " s");
      break;
    }
  }
  lcm.unsubscribe(states);
  lcm.unsubscribe(rejects);
  if (!answers.refused.empty()) {
    return core::failure("the daemon refused the observation at cycle " +
                         std::to_string(observation.cycle) + ": " + answers.refused);
  }
  return out;
}

ReplayResult replay_with_observations(
    lcm::LCM& lcm, const std::vector<messages::Batch>& batches,
    const std::vector<messages::Observation>& observations, const loads::ReplayOptions& options,
    const loads::ReplayAuth& auth,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<bool()>& idle) {
  ReplayResult total;
  std::size_t next_batch = 0;
  std::int64_t cycles = 0;  // at the end of batches[0 .. next_batch)
  const auto run_until = [&](std::int64_t until) -> bool {
    std::vector<messages::Batch> segment;
    while (next_batch < batches.size()) {
      std::int64_t n = 0;
      for (const auto& b : batches[next_batch].blocks) n += b.count;
      if (cycles + n > until) break;
      cycles += n;
      segment.push_back(batches[next_batch++]);
    }
    if (segment.empty()) return true;
    LcmReplayer replayer(lcm, std::move(segment), options, auth);
    ReplayResult r = replayer.run(on_state, idle);
    total.published += r.published;
    total.rewinds += r.rewinds;
    total.stale_states += r.stale_states;
    if (r.final_state) total.final_state = r.final_state;
    total.end_of_life = r.end_of_life;
    if (!r.ok) total.error = r.error;
    return r.ok && r.end_of_life.empty();
  };
  for (const messages::Observation& o : observations) {
    if (!run_until(o.cycle)) {
      total.ok = total.error.empty();
      if (total.ok && !total.end_of_life.empty()) {
        total.error =
            "the end of life came before the observation at cycle " + std::to_string(o.cycle);
        total.ok = false;
      }
      return total;
    }
    if (cycles < o.cycle) {
      total.error = "the observation at cycle " + std::to_string(o.cycle) +
                    " is beyond the history (" + std::to_string(cycles) + " cycles)";
      return total;
    }
    if (const core::Status sent = send_observation(
            lcm, o, options, auth,
            [&](const auto& s) {
              total.final_state = s;
              if (on_state) on_state(s);
            },
            idle);
        !sent) {
      total.error = sent.error().message();
      return total;
    }
  }
  run_until(std::numeric_limits<std::int64_t>::max());
  total.ok = total.error.empty();
  return total;
}

}  // namespace peritwin::replay
