#include "twin/in_process_twin.h"

namespace peritwin::twin {

core::Expected<std::unique_ptr<InProcessTwin>, std::string> InProcessTwin::create(
    const config::DetailConfig& detail) {
  auto model = twin::DetailModel::build(detail);
  if (!model) return model.error().message();
  auto created = twin::Twin::create(*model, {twin::LifeMode::synchronous, true, true});
  if (!created) return created.error().message();
  auto t = std::make_unique<InProcessTwin>();
  t->twin_ = std::move(*created);
  t->twin_->catch_up_life();
  t->state_ = twin::state_message(*t->twin_, messages::now_utime());
  return t;
}

core::Status InProcessTwin::apply(const messages::Batch& batch) {
  if (ended_) return {};  // the end of life was reached: the rest is not applied
  const auto outcome = twin_->apply(batch);
  if (outcome.verdict == messages::Verdict::failed) {
    ended_ = true;
    return {};
  }
  if (!outcome.applied()) {
    return core::failure("batch " + std::to_string(batch.seq) + ": " + outcome.what + ": " +
                         outcome.why);
  }
  state_ = twin::state_message(*twin_, messages::now_utime());
  return {};
}

core::Status InProcessTwin::observe(const messages::Observation& observation) {
  const auto outcome = twin_->observe(observation);
  if (!outcome.applied()) {
    return core::failure("observation " + std::to_string(observation.seq) + " at cycle " +
                         std::to_string(observation.cycle) + ": " + outcome.what + ": " +
                         outcome.why);
  }
  state_ = twin::state_message(*twin_, messages::now_utime());
  return {};
}

void InProcessTwin::estimate_ensemble_now() {
  twin_->estimate_ensemble_now();
  state_ = twin::state_message(*twin_, messages::now_utime());
}

InProcessResult run_in_process(
    const config::DetailConfig& detail, const std::vector<messages::Batch>& batches,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const TwinObserver& on_twin) {
  InProcessResult result;
  auto created = InProcessTwin::create(detail);
  if (!created) {
    result.error = created.error();
    return result;
  }
  InProcessTwin& t = **created;
  if (on_state) on_state(t.state());
  if (on_twin) on_twin(t.twin(), false);
  for (const auto& b : batches) {
    if (const core::Status applied = t.apply(b); !applied) {
      result.error = applied.error().message();
      if (on_twin) on_twin(t.twin(), true);
      return result;
    }
    if (t.ended()) break;
    if (on_state) on_state(t.state());
    if (on_twin) on_twin(t.twin(), false);
  }
  if (on_twin) on_twin(t.twin(), true);
  result.final_state = t.state();
  return result;
}

}  // namespace peritwin::twin
