#include "replay/learning.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "messages/codec.h"
#include "twin/life.h"

namespace peritwin::replay {

namespace {

using Json = nlohmann::ordered_json;

/// A cycle count as JSON: rounded to a whole cycle (a weighted percentile interpolates between
/// particles), null for +Inf (beyond the simulated horizon) or NaN.
Json cycles_json(double v) {
  if (!std::isfinite(v) || std::abs(v) >= 0x1p53) return nullptr;
  return static_cast<std::int64_t>(std::llround(v));
}

Json estimate_fields(const twin::EnsembleEstimate& e) {
  Json j;
  Json eol = Json::object(), rem = Json::object();
  for (std::size_t k = 0; k < e.percentiles.size() && k < e.end_of_life.size(); ++k) {
    eol[messages::percentile_key(e.percentiles[k])] = cycles_json(e.end_of_life[k]);
    rem[messages::percentile_key(e.percentiles[k])] = cycles_json(e.remaining[k]);
  }
  j["end_of_life_percentiles"] = eol;
  j["remaining_percentiles"] = rem;
  if (e.horizon_cycles > 0 && std::isfinite(e.probability_within_horizon)) {
    j["probability_within_horizon"] = e.probability_within_horizon;
    j["horizon_cycles"] = cycles_json(e.horizon_cycles);
  }
  Json post = Json::object();
  for (const auto& p : e.posterior) {
    post[p.name] = Json{{"median", p.median}, {"cov", p.coefficient_of_variation}};
  }
  j["posterior"] = post;
  j["effective_sample_size"] = e.effective_sample_size;
  return j;
}

}  // namespace

std::vector<messages::Batch> split_batches_at(const std::vector<messages::Batch>& batches,
                                              const std::vector<std::int64_t>& cycles) {
  std::vector<messages::Batch> out;
  if (batches.empty()) return out;
  std::int64_t at = 0;  // cycles before the current block
  std::size_t next = 0;
  messages::Batch current{batches.front().detail_id, batches.front().source_id, 0, {}};
  auto flush = [&] {
    if (current.blocks.empty()) return;
    current.seq = batches.front().seq + static_cast<std::int64_t>(out.size());
    out.push_back(current);
    current.blocks.clear();
  };
  for (const messages::Batch& b : batches) {
    for (core::LoadBlock block : b.blocks) {
      while (next < cycles.size() && cycles[next] <= at) ++next;
      // Split the block at every observation cycle strictly inside it.
      while (next < cycles.size() && cycles[next] < at + block.count) {
        core::LoadBlock head = block;
        head.count = cycles[next] - at;
        current.blocks.push_back(head);
        flush();
        block.count -= head.count;
        at += head.count;
        ++next;
      }
      current.blocks.push_back(block);
      at += block.count;
      if (next < cycles.size() && cycles[next] == at) flush();
    }
    flush();  // the original batch boundaries are kept
  }
  return out;
}

std::string ensemble_json(const std::string& what, const twin::EnsembleEstimate& estimate,
                          const messages::Observation* observation,
                          const twin::ObservationUpdate* update) {
  Json j;
  j["ensemble"] = what;
  j["cycle"] = estimate.cycle;
  if (observation != nullptr && update != nullptr) {
    j["observation"] =
        Json{{"cycle", observation->cycle},
             {"kind", observation->kind == messages::ObservationKind::crack_length ? "crack_length"
                                                                                   : "no_crack"},
             {"origin", observation->origin},
             {"predicted_median_m", update->predicted_median_m},
             {"log_evidence", update->log_evidence},
             {"resampled", update->resampled}};
  }
  j.update(estimate_fields(estimate));
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string describe_ensemble(const std::string& what, const twin::EnsembleEstimate& e) {
  std::ostringstream s;
  s << "ensemble " << what << " at " << e.cycle << " cycles: end of life";
  for (std::size_t k = 0; k < e.percentiles.size() && k < e.end_of_life.size(); ++k) {
    s << " " << messages::percentile_key(e.percentiles[k]) << " ";
    if (std::isfinite(e.end_of_life[k])) {
      s << static_cast<std::int64_t>(e.end_of_life[k]);
    } else {
      s << "beyond";
    }
  }
  for (const auto& p : e.posterior) {
    s << "; " << p.name << " " << p.median << " (CoV " << p.coefficient_of_variation << ")";
  }
  return s.str();
}

std::string summary_with_ensemble(const std::string& summary,
                                  const twin::EnsembleEstimate& estimate) {
  Json j = Json::parse(summary);
  j.update(estimate_fields(estimate));
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

LearningResult run_learning_in_process(
    const config::DetailConfig& detail, const std::vector<messages::Batch>& batches,
    const std::vector<messages::Observation>& observations, bool json,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<void(const std::string&)>& on_line, const twin::TwinObserver& on_twin) {
  LearningResult result;
  auto created = twin::InProcessTwin::create(detail);
  if (!created) {
    result.error = created.error();
    return result;
  }
  twin::InProcessTwin& t = **created;
  if (t.twin().ensemble() == nullptr) {
    result.error = "detail " + detail.id + " has no [detail.uncertainty]: no ensemble to learn";
    return result;
  }
  const twin::Ensemble& e = *t.twin().ensemble();
  auto line = [&](const std::string& what, const messages::Observation* o,
                  const twin::ObservationUpdate* u) {
    const twin::EnsembleEstimate est = e.summary();
    if (on_line) on_line(json ? ensemble_json(what, est, o, u) : describe_ensemble(what, est));
  };
  if (on_state) on_state(t.state());
  if (on_twin) on_twin(t.twin(), false);
  line("prior", nullptr, nullptr);
  // The results (on_twin) closed on every way out.
  auto fail = [&](std::string error) {
    result.error = std::move(error);
    if (on_twin) on_twin(t.twin(), true);
    return result;
  };
  std::size_t next = 0;
  auto take_observations = [&]() -> bool {
    while (next < observations.size() && observations[next].cycle <= e.total_cycles()) {
      const messages::Observation& o = observations[next++];
      if (const core::Status taken = t.observe(o); !taken) {
        result.error = taken.error().message();
        return false;
      }
      if (on_state) on_state(t.state());
      if (on_twin) on_twin(t.twin(), false);
      line("observation", &o, &e.observations().back().update);
    }
    return true;
  };
  for (const messages::Batch& b : batches) {
    if (!take_observations()) return fail(result.error);
    if (const core::Status applied = t.apply(b); !applied) {
      return fail(applied.error().message());
    }
    if (t.ended()) break;
    if (on_state) on_state(t.state());
    if (on_twin) on_twin(t.twin(), false);
  }
  if (!take_observations()) return fail(result.error);
  if (next < observations.size()) {
    return fail("observation at cycle " + std::to_string(observations[next].cycle) +
                " is beyond the history (" + std::to_string(e.total_cycles()) + " cycles applied" +
                (t.ended() ? ", the end of life reached" : "") + ")");
  }
  if (e.estimate_cycle() < e.total_cycles()) {
    t.estimate_ensemble_now();
    if (on_twin) on_twin(t.twin(), false);
  }
  if (on_twin) on_twin(t.twin(), true);
  line("final", nullptr, nullptr);
  result.final_state = t.state();
  result.final_estimate = e.summary();
  return result;
}

}  // namespace peritwin::replay
