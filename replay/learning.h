// peritwin-replay --in-process --observations FILE (issue 32): the twin and, beside it, the
// learning ensemble of the detail's [detail.uncertainty] (twin/ensemble.h), fed the same batches,
// with the inspections of the observations file taken in at their cycle counts (the batches are
// split there). Prints the ensemble's estimate (remaining life as percentiles, the posterior) as
// it starts, after every observation and at the end.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "messages/batch.h"
#include "messages/observation.h"
#include "twin/ensemble.h"
#include "twin/in_process_twin.h"

namespace peritwin::replay {

/// The batches with every batch that contains one of `cycles` strictly inside it split there (a
/// block split in two counts where needed), numbered again from the first batch's seq. The
/// cycles are cumulative counts from the first batch's start.
std::vector<messages::Batch> split_batches_at(const std::vector<messages::Batch>& batches,
                                              const std::vector<std::int64_t>& cycles);

/// One JSON line of an ensemble estimate: {"ensemble": what, "cycle", "end_of_life_percentiles":
/// {"p05", ...}, "remaining_percentiles": {...}, "probability_within_horizon", "horizon_cycles",
/// "posterior": {"a2": {"median", "cov"}, "load_scale": {...}}, "effective_sample_size"}, and with
/// an update {"observation": {"cycle", "kind", "origin", "log_evidence", "resampled"}}.
std::string ensemble_json(const std::string& what, const twin::EnsembleEstimate& estimate,
                          const messages::Observation* observation = nullptr,
                          const twin::ObservationUpdate* update = nullptr);
/// The same in words, for the text output.
std::string describe_ensemble(const std::string& what, const twin::EnsembleEstimate& estimate);

/// `summary` (messages::summary_json) with the final estimate's end_of_life_percentiles,
/// remaining_percentiles, probability_within_horizon and posterior added.
std::string summary_with_ensemble(const std::string& summary,
                                  const twin::EnsembleEstimate& estimate);

struct LearningResult {
  std::optional<peritwin_msgs::damage_state_t> final_state;
  std::optional<twin::EnsembleEstimate> final_estimate;
  std::string error;  ///< the model, the ensemble, a refused batch or a refused observation
};

/// Runs the batches (already split at the observations' cycles) through an InProcessTwin and the
/// ensemble. on_state as run_in_process; on_line gets each ensemble line (JSON when `json`);
/// on_twin (e.g. the results, outputs::DetailOutputs) as run_in_process's, also after each
/// observation taken in and after the final estimate (both at the state before them).
LearningResult run_learning_in_process(
    const config::DetailConfig& detail, const std::vector<messages::Batch>& batches,
    const std::vector<messages::Observation>& observations, bool json,
    const std::function<void(const peritwin_msgs::damage_state_t&)>& on_state,
    const std::function<void(const std::string&)>& on_line, const twin::TwinObserver& on_twin = {});

}  // namespace peritwin::replay
