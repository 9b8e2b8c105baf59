// Hand-built STATE messages for the tests that feed a dashboard (the store, its event fan-out, the
// HTTP API and the page): the smallest damage_state_t the codec decodes, and the learning
// ensemble's fields (message set version 9) filled in on one.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <peritwin_msgs/damage_state_t.hpp>
#include <peritwin_msgs/observation_t.hpp>
#include <string>
#include <utility>
#include <vector>

namespace peritwin::testing {

/// STATE `seq` of `detail` after `cycles`: one source (`source`, its batch `seq` applied), no
/// crack, no remaining-life estimate (NaN, remaining_life_seq −1), alive, unsigned, utime 1 s per
/// state.
inline peritwin_msgs::damage_state_t minimal_state(const std::string& detail, std::int64_t seq,
                                                   std::int64_t cycles,
                                                   const std::string& source = "gauge") {
  peritwin_msgs::damage_state_t m{};
  m.utime = 1'000'000 * (seq + 1);
  m.detail_id = detail;
  m.state_seq = seq;
  m.num_sources = 1;
  m.source_ids = {source};
  m.applied_seq = {seq};
  m.checkpointed_seq = {0};
  m.history = {0};  // message set version 8: one per source
  m.history_start = {0};
  m.total_cycles = cycles;
  m.k_i = m.k_ii = std::nan("");
  m.remaining_cycles = m.remaining_cycles_low = m.remaining_cycles_high = std::nan("");
  m.remaining_life_seq = -1;
  m.end_of_life_cycle = -1;
  m.state_hash = "00112233aabbccdd";
  m.engine_hash = "ffeeddccbbaa0099";
  m.tag_length = 0;
  return m;
}

/// One observation as STATE carries it.
struct StateObservation {
  std::int64_t cycle = 0;
  bool no_crack = false;
  double length_m = std::nan("");  ///< crack length; NaN for no crack
  double sigma_m = std::nan("");
  double pod_a50_m = std::nan("");  ///< no crack; NaN for a crack length
  double predicted_m = std::nan("");
};

/// The learning ensemble's fields on `m`: `particles` particles, the estimate made at
/// `estimate_cycle`, end of life at the 5/50/95th percentiles `eol` (three) (remaining = eol −
/// cycles, not below 0), P(end within `horizon`) `p_horizon`, the posterior of "a2" and
/// "load_scale" (median, CoV), and `observations` (all of them: observation_count = their number).
inline void set_ensemble(peritwin_msgs::damage_state_t& m, std::int32_t particles,
                         std::int64_t estimate_cycle, const std::vector<double>& eol,
                         double horizon, double p_horizon, double ess,
                         const std::vector<std::pair<double, double>>& posterior,
                         const std::vector<StateObservation>& observations) {
  m.num_particles = particles;
  m.ensemble_estimate_cycle = estimate_cycle;
  m.effective_sample_size = ess;
  m.num_percentiles = static_cast<std::int32_t>(eol.size());
  m.percentiles = {5.0, 50.0, 95.0};
  m.end_of_life_percentiles = eol;
  m.remaining_percentiles.clear();
  for (const double e : eol) {
    m.remaining_percentiles.push_back(std::max(0.0, e - static_cast<double>(m.total_cycles)));
  }
  m.horizon_cycles = horizon;
  m.probability_within_horizon = p_horizon;
  const std::vector<std::string> names{"a2", "load_scale"};
  m.num_parameters = static_cast<std::int32_t>(posterior.size());
  m.parameter_names.clear();
  m.parameter_medians.clear();
  m.parameter_covs.clear();
  for (std::size_t i = 0; i < posterior.size(); ++i) {
    std::string name = i < names.size() ? names[i] : std::string("p");
    if (i >= names.size()) name += std::to_string(i);
    m.parameter_names.push_back(name);
    m.parameter_medians.push_back(posterior[i].first);
    m.parameter_covs.push_back(posterior[i].second);
  }
  m.observation_count = static_cast<std::int32_t>(observations.size());
  m.num_observations = m.observation_count;
  m.observation_cycles.clear();
  m.observation_kinds.clear();
  m.observation_lengths_m.clear();
  m.observation_sigmas_m.clear();
  m.observation_pod_a50s_m.clear();
  m.observation_predicted_m.clear();
  for (const auto& o : observations) {
    m.observation_cycles.push_back(o.cycle);
    m.observation_kinds.push_back(o.no_crack ? peritwin_msgs::observation_t::KIND_NO_CRACK
                                             : peritwin_msgs::observation_t::KIND_CRACK_LENGTH);
    m.observation_lengths_m.push_back(o.length_m);
    m.observation_sigmas_m.push_back(o.sigma_m);
    m.observation_pod_a50s_m.push_back(o.pod_a50_m);
    m.observation_predicted_m.push_back(o.predicted_m);
  }
}

}  // namespace peritwin::testing
