// The learning twin (issue 32): a particle ensemble over the uncertain parameters of
// [detail.uncertainty], each particle a peridynamic fatigue engine of the detail that has seen the
// same load history, updated by inspections.
//
//  * Parameters: A2 (000 Eq. 15, the phase II coefficient; lognormal prior, median the calibrated
//    A2 unless given) and a load scale s (a factor on every received P_max: the sensors' or the
//    spectrum's bias; lognormal, median 1). A parameter with CoV 0 is known and held at its
//    median. A particle's engine is DetailModel::make_engine(A2/A2_config) and applies every block
//    with P_max·s.
//  * The particles' model: the detail's own, or the same detail on the coarser grid of
//    [detail.uncertainty] dx (else [detail.life] dx), A2 rescaled by 000 Eq. (29) and calibrated
//    to the detail's own virgin life (particle_surrogate); A2's factor is then a factor on that
//    A2, and the posterior of "a2" is reported as factor × the config's A2.
//  * Observations (messages::Observation) at any cycle count up to the ensemble's: each
//    particle's crack at the observed origin at that cycle (crack_length_at: its state with the
//    breaks after that cycle undone; on a coarser grid, mapped to the detail's own by LengthMap)
//    is compared with the inspection, Gaussian in the measured
//    length with the measurement's σ and the particle grid's own, Δx_p/√12 (the crack length of a
//    particle moves in steps of about its grid spacing: a uniform rounding error), or 1 − POD for
//    "no crack found" (prognostics/observation_likelihood.h); the weights are updated; when the
//    effective sample
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

/// An observation the ensemble took in, and what it did (kept for STATE and the results file).
struct ObservationRecord {
  messages::Observation observation;
  std::int64_t taken_at = 0;  ///< the ensemble's cycle count when it was taken in
  ObservationUpdate update;
};

/// What a checkpoint keeps of an ensemble (twin/twin_checkpoint.cpp writes it).
struct EnsembleCheckpoint {
  std::vector<std::uint8_t> filter;  ///< prognostics::ParticleEnsemble::serialize()
  std::vector<fatigue::EngineState> engines;
  std::vector<double> a2_factor, load_scale, predicted_end;
  std::vector<std::int64_t> ended_at;
  std::int64_t total_cycles = 0;
  std::int64_t estimate_cycle = -1;
  std::vector<ObservationRecord> observations;
};

/// What a coarse particle's crack length stands for on the detail's own grid: the fine crack's
/// length at the cycle at which the coarse crack had that length, both run from the virgin state
/// at the prior's median under the reference spectrum (particle_surrogate). Under a change of A2
/// or of the load scale a particle's growth is, to first order, the median's in another time
/// (000 Eq. 17: cycles ∝ 1/(A2·Δε^m)), so the same map serves every particle. Identity when empty
/// (particles on the detail's own grid); 0 stays 0 (no crack); beyond the samples, shifted.
struct LengthMap {
  std::vector<double> coarse, fine;  ///< increasing coarse lengths and their fine ones (m)
  [[nodiscard]] double operator()(double coarse_length) const;
};

/// The detail's gauges along its median run on its own grid (particle_surrogate, issue 33): at
/// increasing crack lengths (m), every gauge's influence coefficients. A particle on a coarser
/// grid reads its gauges through it at the fine crack length its own stands for (LengthMap): its
/// coarse grid does not resolve a gauge a few mm from the crack path.
struct GaugeMap {
  std::vector<double> length;
  std::vector<std::vector<std::array<double, 3>>> influences;  ///< per length, per gauge
  [[nodiscard]] bool empty() const { return length.empty(); }
  /// Linear between the lengths, the ends' values beyond them.
  [[nodiscard]] std::vector<std::array<double, 3>> operator()(double crack_length) const;
};

class Ensemble {
 public:
  /// The particles of the detail's [detail.uncertainty], initialized (their first solve); an
  /// error when the table is absent, no parameter is uncertain, or an engine cannot solve.
  static core::Expected<std::unique_ptr<Ensemble>> create(std::shared_ptr<const DetailModel> model);

  /// Applies the blocks to every particle (P_max × its load scale); a particle at its end of life
  /// stops there.
  core::Status apply(std::span<const core::LoadBlock> blocks);
  /// Takes in an inspection made at or before the current cycle count (an error, nothing
  /// changed, for an observation in the ensemble's future, an invalid one, an origin the detail
  /// does not have, or one no particle can explain). An observation before the current count is
  /// compared with each particle's crack at its cycle; the resampling happens now.
  core::Expected<ObservationUpdate> observe(const messages::Observation& observation);
  /// Simulates each particle's end of life under `spectrum` (the reference spectrum: each
  /// particle applies it with its own P_max scale; the empirical one, [detail.life] without a
  /// reference_spectrum, in a block order of the particle's own, drawn from the config's seed,
  /// the cycle count and the particle's index) from a fork of its engine, keeps them, and
  /// returns summary().
  EnsembleEstimate estimate(const std::vector<core::LoadBlock>& spectrum);
  /// Remaining life at the current cycle count from the ends of life simulated last (the
  /// percentiles of max(0, end − cycle); a particle that reached its end since counts 0); NaN
  /// percentiles before any estimate.
  [[nodiscard]] EnsembleEstimate summary() const;
  /// The cycle count of the last estimate(), -1 before any.
  [[nodiscard]] std::int64_t estimate_cycle() const { return estimate_cycle_; }
  [[nodiscard]] const std::vector<ObservationRecord>& observations() const { return observations_; }
  /// The model the particles run on (the detail's, or its coarser grid).
  [[nodiscard]] const DetailModel& particle_model() const { return *particle_model_; }
  /// Whether gauge observations are evidence for the particles: on the detail's own grid (each
  /// particle's own gauges), or on a coarser one with the detail's GaugeMap.
  [[nodiscard]] bool reads_gauges() const {
    return particle_model_ == model_ || !gauge_map_.empty();
  }
  /// Checkpoints: everything the ensemble's future depends on; import_state on an ensemble
  /// created from the same config (an error, the ensemble unusable, when it does not fit).
  [[nodiscard]] EnsembleCheckpoint export_state() const;
  core::Status import_state(const EnsembleCheckpoint& state);

  [[nodiscard]] std::int64_t total_cycles() const { return total_cycles_; }
  [[nodiscard]] std::size_t size() const { return particles_.size(); }
  [[nodiscard]] const prognostics::ParticleEnsemble& weights() const { return filter_; }
  /// A particle's A2 factor (its A2 / the config's) and load scale.
  [[nodiscard]] double a2_factor(std::size_t i) const { return particles_[i].a2_factor; }
  [[nodiscard]] double load_scale(std::size_t i) const { return particles_[i].load_scale; }
  [[nodiscard]] const fatigue::FatigueEngine& engine(std::size_t i) const {
    return *particles_[i].engine;
  }
  /// FNV-1a 64 over every particle's engine state, parameters, the filter's bytes and the
  /// observations taken in (not over the simulated ends of life).
  [[nodiscard]] std::uint64_t state_hash() const;

 private:
  struct Particle {
    std::unique_ptr<fatigue::FatigueEngine> engine;
    double a2_factor = 1.0;
    double load_scale = 1.0;
    std::int64_t ended_at = -1;  ///< the cycle of its end of life, -1 while alive
  };
  Ensemble(std::shared_ptr<const DetailModel> model,
           std::shared_ptr<const DetailModel> particle_model, prognostics::ParticleEnsemble filter);
  /// The particle's parameters from the filter's row i (known parameters at their medians).
  void set_parameters(Particle& p, std::size_t i) const;
  /// Runs f(i) for every particle, on up to two threads (a static split: the same bits).
  template <typename F>
  void for_each_particle(F&& f) const;

  std::shared_ptr<const DetailModel> model_;           ///< the detail's (its config)
  std::shared_ptr<const DetailModel> particle_model_;  ///< what the particles run on
  prognostics::ParticleEnsemble filter_;
  int a2_column_ = -1;          ///< the filter's column of ln A2, -1 when A2 is known
  int load_scale_column_ = -1;  ///< the filter's column of ln s, -1 when s is known
  std::vector<Particle> particles_;
  std::int64_t total_cycles_ = 0;
  /// Each particle's simulated end of life (cycle; +Inf: not reached) at estimate_cycle_.
  std::vector<double> predicted_end_;
  std::int64_t estimate_cycle_ = -1;
  std::vector<ObservationRecord> observations_;
  LengthMap length_map_;  ///< the particles' crack lengths as the detail's (particle_surrogate)
  /// On a coarser particle grid: the detail's gauges by crack length (empty on its own grid).
  GaugeMap gauge_map_;
  /// The detail's virgin gauges (influence coefficients on its own grid).
  std::vector<std::array<double, 3>> gauge_virgin_;
};

/// The particles' model on the coarser grid of spacing `dx`: coarse_model (A2 by 000 Eq. 29) with
/// A2 calibrated so that the virgin detail's life under the reference spectrum equals the
/// detail's own (one forward simulation on the detail's grid, up to four on the coarse one, to
/// 1 %; the coarse grid grows its crack faster or slower than Eq. 29 says), and the LengthMap of
/// the two runs. Without a reference spectrum, or a life that does not end, coarse_model's alone.
struct Surrogate {
  std::shared_ptr<const DetailModel> model;
  double a2_calibration = 1.0;
  LengthMap length_map;
  GaugeMap gauge_map;  ///< empty without gauges or without the fine run
};
core::Expected<Surrogate> particle_surrogate(const DetailModel& fine, double dx);

/// The particle's crack at `origin` as it was at `cycle` (<= its cycle count): its state with the
/// break events after `cycle` undone (observed_crack_length's measure).
double crack_length_at(const DetailModel& model, const fatigue::FatigueEngine& engine,
                       std::int64_t cycle, const std::string& origin);

}  // namespace peritwin::twin
