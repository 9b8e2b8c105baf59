// The learning twin (issue 32): a particle ensemble over the uncertain parameters of
// [detail.uncertainty], each particle a peridynamic fatigue engine of the detail that has seen the
// same load history, updated by inspections.
//
//  * Parameters: A2 (000 Eq. 15, the phase II coefficient; lognormal prior, median the calibrated
//    A2 unless given) and a load scale s (a factor on every received P_max: the sensors' or the
//    spectrum's bias; lognormal, median 1). A parameter with CoV 0 is known and held at its
//    median. A particle's engine is DetailModel::make_engine(A2/A2_config) and applies every block
//    with P_max·s.
//  * Observations (messages::Observation) at the ensemble's current cycle count: each particle's
//    crack at the observed origin (observed_crack_length) is compared with the inspection,
//    Gaussian in the measured length or 1 − POD for "no crack found"
//    (prognostics/observation_likelihood.h); the weights are updated; when the effective sample
//    size falls below resample_ess_fraction·N the particles are resampled (systematic) and
//    rejuvenated (regularized kernel in log-parameter space; prognostics::ParticleEnsemble), each
//    new particle a fork of its parent's engine (FatigueEngine::fork: same bonds, lives and
//    factor) continuing with its moved parameters. The damage a parent accumulated under its own
//    parameters is kept (the regularized particle filter's approximation; docs/prognostics.md).
//  * Remaining life: each particle's end of life under the reference spectrum (its P_max·s, its
//    A2) by forward simulation from a fork of its engine (twin/life.h simulate_life); the weighted
//    percentiles of the end-of-life cycle, the remaining cycles, P(end of life within the
//    horizon) and each parameter's posterior median and CoV.
// Deterministic: particles are independent, so running them on several threads gives the same
// bits; the random stream is the ensemble's own (seeded by the config).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/expected.h"
#include "core/load_block.h"
#include "messages/observation.h"
#include "prognostics/particle_ensemble.h"
#include "twin/detail_model.h"

namespace peritwin::twin {

/// One posterior summary: an uncertain or a known (CoV 0) parameter.
struct ParameterEstimate {
  std::string name;  ///< "a2", "load_scale"
  double median = 0.0;
  double coefficient_of_variation = 0.0;
};

/// Remaining life as a probability, at the ensemble's cycle count.
struct EnsembleEstimate {
  std::int64_t cycle = 0;
  std::vector<double> percentiles;  ///< as configured, in (0, 100)
  std::vector<double> end_of_life;  ///< cycle of the end of life at each percentile (+Inf: beyond)
  std::vector<double> remaining;    ///< percentiles of max(0, end of life − cycle)
  /// P(end of life within horizon_cycles from now); NaN when no horizon is configured.
  double probability_within_horizon = 0.0;
  double horizon_cycles = 0.0;
  std::vector<ParameterEstimate> posterior;
  double effective_sample_size = 0.0;
};

/// What one observation did.
struct ObservationUpdate {
  std::int64_t cycle = 0;
  double log_evidence = 0.0;  ///< ln Σ w·L: how well the ensemble predicted the observation
  double ess_before_resampling = 0.0;
  bool resampled = false;
  double predicted_median_m = 0.0;  ///< weighted median of the particles' predicted lengths (prior)
};

class Ensemble {
 public:
  /// The particles of the detail's [detail.uncertainty], initialized (their first solve); an
  /// error when the table is absent, no parameter is uncertain, or an engine cannot solve.
  static core::Expected<std::unique_ptr<Ensemble>> create(std::shared_ptr<const DetailModel> model);

  /// Applies the blocks to every particle (P_max × its load scale); a particle at its end of life
  /// stops there.
  core::Status apply(std::span<const core::LoadBlock> blocks);
  /// Takes in an inspection made at the current cycle count (an error, nothing changed, for an
  /// observation whose cycle is not the current one, an invalid one, or one no particle can
  /// explain).
  core::Expected<ObservationUpdate> observe(const messages::Observation& observation);
  /// Remaining life under `spectrum` (the reference spectrum: each particle applies it with its
  /// own P_max scale), forward simulations from forks of the particles' engines.
  [[nodiscard]] EnsembleEstimate estimate(const std::vector<core::LoadBlock>& spectrum) const;

  [[nodiscard]] std::int64_t total_cycles() const { return total_cycles_; }
  [[nodiscard]] std::size_t size() const { return particles_.size(); }
  [[nodiscard]] const prognostics::ParticleEnsemble& weights() const { return filter_; }
  /// A particle's A2 factor (its A2 / the config's) and load scale.
  [[nodiscard]] double a2_factor(std::size_t i) const { return particles_[i].a2_factor; }
  [[nodiscard]] double load_scale(std::size_t i) const { return particles_[i].load_scale; }
  [[nodiscard]] const fatigue::FatigueEngine& engine(std::size_t i) const {
    return *particles_[i].engine;
  }
  /// FNV-1a 64 over every particle's engine state, parameters and the filter's bytes.
  [[nodiscard]] std::uint64_t state_hash() const;

 private:
  struct Particle {
    std::unique_ptr<fatigue::FatigueEngine> engine;
    double a2_factor = 1.0;
    double load_scale = 1.0;
    std::int64_t ended_at = -1;  ///< the cycle of its end of life, -1 while alive
  };
  Ensemble(std::shared_ptr<const DetailModel> model, prognostics::ParticleEnsemble filter);
  /// The particle's parameters from the filter's row i (known parameters at their medians).
  void set_parameters(Particle& p, std::size_t i) const;
  /// Runs f(i) for every particle, on up to two threads (a static split: the same bits).
  template <typename F>
  void for_each_particle(F&& f) const;

  std::shared_ptr<const DetailModel> model_;
  prognostics::ParticleEnsemble filter_;
  int a2_column_ = -1;          ///< the filter's column of ln A2, -1 when A2 is known
  int load_scale_column_ = -1;  ///< the filter's column of ln s, -1 when s is known
  std::vector<Particle> particles_;
  std::int64_t total_cycles_ = 0;
};

}  // namespace peritwin::twin
