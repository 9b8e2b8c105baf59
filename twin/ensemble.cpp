#include "twin/ensemble.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "core/fnv1a.h"
#include "prognostics/observation_likelihood.h"
#include "prognostics/weighted_statistics.h"
#include "twin/life.h"

namespace peritwin::twin {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

Ensemble::Ensemble(std::shared_ptr<const DetailModel> model, prognostics::ParticleEnsemble filter)
    : model_(std::move(model)), filter_(std::move(filter)) {}

template <typename F>
void Ensemble::for_each_particle(F&& f) const {
  const std::size_t n = particles_.size();
  const std::size_t threads = std::min<std::size_t>(
      n, std::max<std::size_t>(1, std::min(2u, std::thread::hardware_concurrency())));
  if (threads <= 1) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  // A static split: particle i always runs the same operations, whatever the thread.
  std::thread other([&] {
    for (std::size_t i = 1; i < n; i += 2) f(i);
  });
  for (std::size_t i = 0; i < n; i += 2) f(i);
  other.join();
}

core::Expected<std::unique_ptr<Ensemble>> Ensemble::create(
    std::shared_ptr<const DetailModel> model) {
  const config::UncertaintyConfig& u = model->config().uncertainty;
  if (!u.enabled) return core::failure("the detail has no [detail.uncertainty]");
  std::vector<prognostics::UncertainParameter> parameters;
  int a2_column = -1, load_column = -1;
  if (u.a2.cov > 0) {
    auto p = prognostics::UncertainParameter::lognormal("a2", u.a2.median, u.a2.cov);
    if (!p) return p.error().within("uncertainty.a2.");
    a2_column = static_cast<int>(parameters.size());
    parameters.push_back(std::move(*p));
  }
  if (u.load_scale.cov > 0) {
    auto p = prognostics::UncertainParameter::lognormal("load_scale", u.load_scale.median,
                                                        u.load_scale.cov);
    if (!p) return p.error().within("uncertainty.load_scale.");
    load_column = static_cast<int>(parameters.size());
    parameters.push_back(std::move(*p));
  }
  if (parameters.empty()) {
    return core::failure("[detail.uncertainty]: no parameter is uncertain (every cov is 0)");
  }
  prognostics::EnsembleSettings settings;
  settings.particles = static_cast<std::size_t>(u.particles);  // >= 2 (the config's bound)
  settings.seed = u.seed;
  // Liu-West shrinkage (h = 0.14 at δ = 0.98): a jittered particle keeps its parent's damage, so
  // its parameters should move little (docs/prognostics.md).
  settings.bandwidth = prognostics::KernelBandwidth::liu_west;
  auto filter = prognostics::ParticleEnsemble::create(std::move(parameters), settings);
  if (!filter) return filter.error();
  filter->initialize(u.seed);
  std::unique_ptr<Ensemble> e(new Ensemble(model, std::move(*filter)));
  e->a2_column_ = a2_column;
  e->load_scale_column_ = load_column;
  e->particles_.resize(settings.particles);
  for (std::size_t i = 0; i < e->particles_.size(); ++i) e->set_parameters(e->particles_[i], i);
  std::vector<int> ok(e->particles_.size(), 0);
  e->for_each_particle([&](std::size_t i) {
    Particle& p = e->particles_[i];
    p.engine = e->model_->make_engine(p.a2_factor);
    ok[i] = p.engine->initialize() ? 1 : 0;
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end()) {
    return core::failure("a particle's engine cannot solve the virgin detail");
  }
  return e;
}

void Ensemble::set_parameters(Particle& p, std::size_t i) const {
  const config::UncertaintyConfig& u = model_->config().uncertainty;
  const double a2_config = model_->config().fatigue.strain.A2;
  if (a2_column_ >= 0) {
    p.a2_factor = filter_.parameter_value(i, static_cast<std::size_t>(a2_column_)) / a2_config;
  } else {
    // Known A2: the config's, or the prior's median when given (a law without an A2, e.g.
    // bilinear, keeps its own coefficients: factor 1).
    p.a2_factor = a2_config > 0 && u.a2.median > 0 ? u.a2.median / a2_config : 1.0;
  }
  p.load_scale = load_scale_column_ >= 0
                     ? filter_.parameter_value(i, static_cast<std::size_t>(load_scale_column_))
                     : u.load_scale.median;
}

core::Status Ensemble::apply(std::span<const core::LoadBlock> blocks) {
  const fatigue::FatigueEngine::StopCheck stop = end_of_life_check(*model_);
  for_each_particle([&](std::size_t i) {
    Particle& p = particles_[i];
    for (const core::LoadBlock& block : blocks) {
      if (p.ended_at >= 0) break;
      core::LoadBlock scaled = block;
      scaled.p_max *= p.load_scale;
      p.engine->apply(scaled, stop);
      if (end_of_life(*model_, *p.engine) != Failure::none) p.ended_at = p.engine->total_cycles();
    }
  });
  for (const core::LoadBlock& block : blocks) total_cycles_ += block.count;
  return {};
}

core::Expected<ObservationUpdate> Ensemble::observe(const messages::Observation& o) {
  if (const core::Status st = messages::check_observation(o); !st) return st.error();
  if (o.cycle > total_cycles_) {
    return core::Error{"cycle", "is in the future of the twin (" + std::to_string(o.cycle) + " > " +
                                    std::to_string(total_cycles_) + " cycles applied)"};
  }
  if (o.cycle < total_cycles_) {
    return core::Error{"cycle", "is in the past of the ensemble (" + std::to_string(o.cycle) +
                                    " < " + std::to_string(total_cycles_) +
                                    "): an observation is taken in at its own cycle count"};
  }
  std::vector<double> predicted(particles_.size());
  for_each_particle([&](std::size_t i) {
    predicted[i] = observed_crack_length(*model_, *particles_[i].engine, o.origin);
  });
  std::vector<double> log_likelihood;
  if (o.kind == messages::ObservationKind::crack_length) {
    log_likelihood = prognostics::log_likelihoods(
        prognostics::CrackLengthObservation{o.length_m, o.sigma_m}, predicted);
  } else {
    log_likelihood = prognostics::log_likelihoods(
        prognostics::NoCrackObservation{prognostics::PodCurve{o.pod_a50_m, o.pod_slope}},
        predicted);
  }
  ObservationUpdate out;
  out.cycle = o.cycle;
  const auto w = filter_.weights();
  if (auto median = prognostics::weighted_median(predicted, w)) out.predicted_median_m = *median;
  auto evidence = filter_.update(log_likelihood);
  if (!evidence) {
    return core::Error{"", "no particle can explain the observation (" +
                               evidence.error().message() + "); the ensemble is unchanged"};
  }
  out.log_evidence = *evidence;
  out.ess_before_resampling = filter_.effective_sample_size();
  const auto parents =
      filter_.resample_if_needed(model_->config().uncertainty.resample_ess_fraction);
  if (!parents) return out;
  out.resampled = true;
  filter_.rejuvenate();
  std::vector<Particle> next(particles_.size());
  for (std::size_t i = 0; i < next.size(); ++i) set_parameters(next[i], i);
  for_each_particle([&](std::size_t i) {
    const Particle& parent = particles_[(*parents)[i]];
    next[i].engine = parent.engine->fork(model_->engine_settings(next[i].a2_factor));
    next[i].ended_at = parent.ended_at;
  });
  particles_ = std::move(next);
  return out;
}

EnsembleEstimate Ensemble::estimate(const std::vector<core::LoadBlock>& spectrum) const {
  const config::UncertaintyConfig& u = model_->config().uncertainty;
  EnsembleEstimate out;
  out.cycle = total_cycles_;
  out.percentiles = u.percentiles;
  out.horizon_cycles = u.horizon_cycles;
  out.effective_sample_size = filter_.effective_sample_size();
  std::vector<double> end(particles_.size(), kInf);
  for_each_particle([&](std::size_t i) {
    const Particle& p = particles_[i];
    if (p.ended_at >= 0) {
      end[i] = static_cast<double>(p.ended_at);
      return;
    }
    std::vector<core::LoadBlock> scaled = spectrum;
    for (auto& b : scaled) b.p_max *= p.load_scale;
    const double life = simulate_life(*model_, p.engine->export_state(), scaled, p.a2_factor,
                                      nullptr, p.engine.get());
    // NaN (no spectrum, or the state cannot be imported) counts as not reached.
    end[i] = std::isnan(life) ? kInf : static_cast<double>(total_cycles_) + life;
  });
  const auto w = filter_.weights();
  std::vector<double> probabilities;
  for (double q : u.percentiles) probabilities.push_back(q / 100.0);
  if (auto q = prognostics::weighted_quantiles(end, w, probabilities)) out.end_of_life = *q;
  // A particle at its end of life has 0 remaining (its end may lie before the ensemble's count:
  // it stops there while the load goes on).
  std::vector<double> remaining(end.size());
  for (std::size_t i = 0; i < end.size(); ++i) {
    remaining[i] = std::max(0.0, end[i] - static_cast<double>(total_cycles_));
  }
  if (auto q = prognostics::weighted_quantiles(remaining, w, probabilities)) out.remaining = *q;
  out.probability_within_horizon = std::numeric_limits<double>::quiet_NaN();
  if (u.horizon_cycles > 0) {
    if (auto pr = prognostics::probability_at_or_below(remaining, w, u.horizon_cycles)) {
      out.probability_within_horizon = *pr;
    }
  }
  for (const auto& p : filter_.posterior()) {
    out.posterior.push_back({p.name, p.summary.median, p.summary.coefficient_of_variation});
  }
  if (a2_column_ < 0) out.posterior.push_back({"a2", u.a2.median, 0.0});
  if (load_scale_column_ < 0) out.posterior.push_back({"load_scale", u.load_scale.median, 0.0});
  return out;
}

std::uint64_t Ensemble::state_hash() const {
  core::Fnv1a64 h;
  for (const Particle& p : particles_) {
    const std::uint64_t e = p.engine->state_hash();
    h.bytes(&e, sizeof e);
    h.bytes(&p.a2_factor, sizeof p.a2_factor);
    h.bytes(&p.load_scale, sizeof p.load_scale);
    h.bytes(&p.ended_at, sizeof p.ended_at);
  }
  const std::vector<std::uint8_t> f = filter_.serialize();
  h.bytes(f.data(), f.size());
  h.bytes(&total_cycles_, sizeof total_cycles_);
  return h.get();
}

}  // namespace peritwin::twin
