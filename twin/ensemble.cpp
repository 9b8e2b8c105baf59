#include "twin/ensemble.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "core/fnv1a.h"
#include "prognostics/observation_likelihood.h"
#include "prognostics/random.h"
#include "prognostics/weighted_statistics.h"
#include "solver/model/pd_model.h"
#include "twin/coarse_life.h"
#include "twin/gauges.h"
#include "twin/life.h"

namespace peritwin::twin {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

double crack_length_at(const DetailModel& model, const fatigue::FatigueEngine& engine,
                       std::int64_t cycle, const std::string& origin) {
  const auto& events = engine.break_events();
  if (events.empty() || events.back().cycle <= cycle) {
    return observed_crack_length(model, engine, origin);
  }
  std::vector<std::uint8_t> intact = engine.solver().intact();
  for (auto e = events.rbegin(); e != events.rend() && e->cycle > cycle; ++e) {
    intact[static_cast<std::size_t>(e->bond)] = 1;
  }
  std::vector<double> damage;
  model::damage_index(model.disc(), intact, damage);
  return observed_crack_length(model, damage, intact, origin);
}

double LengthMap::operator()(double coarse_length) const {
  if (coarse.size() < 2 || !(coarse_length > 0.0)) return coarse_length;
  if (coarse_length >= coarse.back()) return fine.back() + (coarse_length - coarse.back());
  // The first sample at or beyond the length, then linear in between (the median cycle at which
  // the coarse crack had this length), and the fine crack's length at that cycle.
  const auto k = static_cast<std::size_t>(
      std::lower_bound(coarse.begin(), coarse.end(), coarse_length) - coarse.begin());
  if (k == 0) return fine.front();
  const double t = (coarse_length - coarse[k - 1]) / (coarse[k] - coarse[k - 1]);
  return fine[k - 1] + t * (fine[k] - fine[k - 1]);
}

std::vector<std::array<double, 3>> GaugeMap::operator()(double crack_length) const {
  if (length.empty()) return {};
  if (!(crack_length > length.front())) return influences.front();
  if (crack_length >= length.back()) return influences.back();
  const auto k = static_cast<std::size_t>(
      std::lower_bound(length.begin(), length.end(), crack_length) - length.begin());
  const double t = (crack_length - length[k - 1]) / (length[k] - length[k - 1]);
  std::vector<std::array<double, 3>> out = influences[k - 1];
  for (std::size_t g = 0; g < out.size(); ++g) {
    for (std::size_t b = 0; b < 3; ++b) out[g][b] += t * (influences[k][g][b] - out[g][b]);
  }
  return out;
}

namespace {

/// The fine run's gauges at the cycles of the LengthMap's samples: the virgin solver copied and
/// the run's break events applied to it group by group (rank updates), the coefficients read
/// after each (issue 33). Strictly increasing lengths (a later state of an equal length replaces
/// the earlier). Stops at a break that leaves the stiffness singular.
GaugeMap gauge_map_of_run(const DetailModel& fine, const fatigue::FatigueEngine& end, double life,
                          int samples) {
  GaugeMap map;
  if (fine.gauges().empty()) return map;
  auto virgin = fine.make_engine();
  if (!virgin->initialize()) return map;
  statics::StaticSolver solver = virgin->solver();
  map.length.push_back(0.0);
  map.influences.push_back(gauge_influences(fine.gauges(), solver));
  const auto& events = end.break_events();
  std::size_t next = 0;
  for (int k = 1; k <= samples; ++k) {
    const auto cycle = static_cast<std::int64_t>(life * k / samples);
    std::vector<mesh::BondIndex> bonds;
    for (; next < events.size() && events[next].cycle <= cycle; ++next) {
      bonds.push_back(events[next].bond);
    }
    if (bonds.empty()) continue;
    if (!solver.break_bonds(bonds)) break;
    const double length = crack_length_at(fine, end, cycle, "longest");
    auto influences = gauge_influences(fine.gauges(), solver);
    if (length > map.length.back()) {
      map.length.push_back(length);
      map.influences.push_back(std::move(influences));
    } else {
      map.influences.back() = std::move(influences);
    }
  }
  return map;
}

}  // namespace

core::Expected<Surrogate> particle_surrogate(const DetailModel& fine, double dx) {
  auto coarse = coarse_model(fine, dx);
  if (!coarse) return coarse.error();
  Surrogate out{*coarse, 1.0, {}, {}};
  const std::vector<core::LoadBlock> spectrum = reference_spectrum(fine, RollingSpectrum{});
  if (spectrum.empty() || !can_fork(fine)) return out;
  // The virgin detail to its end of life under the reference spectrum on a grid, at an A2 factor:
  // the cycles and the engine at the end (its break events date every length on the way).
  const auto run = [&spectrum](const DetailModel& m, double a2_factor) {
    std::pair<double, std::unique_ptr<fatigue::FatigueEngine>> r{kNaN, m.make_engine(a2_factor)};
    if (r.second->initialize()) r.first = run_to_end(*r.second, spectrum, end_of_life_check(m));
    return r;
  };
  auto [fine_life, fine_end] = run(fine, 1.0);
  if (!(std::isfinite(fine_life) && fine_life > 0)) return out;
  // The coarse grid's A2 factor that gives the same life: phase II lives fall in proportion to A2
  // (000 Eq. 17), so cycles scale as 1/A2; up to 4 runs, to 1 %.
  double factor = 1.0;
  std::unique_ptr<fatigue::FatigueEngine> coarse_end;
  for (int attempt = 0; attempt < 4; ++attempt) {
    auto [coarse_life, engine] = run(**coarse, factor);
    if (!(std::isfinite(coarse_life) && coarse_life > 0)) return out;
    coarse_end = std::move(engine);
    const double ratio = coarse_life / fine_life;
    if (std::abs(ratio - 1.0) <= 0.01) break;
    factor *= ratio;
    coarse_end.reset();
  }
  if (coarse_end == nullptr) {
    auto [coarse_life, engine] = run(**coarse, factor);
    if (!(std::isfinite(coarse_life) && coarse_life > 0)) return out;
    coarse_end = std::move(engine);
  }
  // The two grids' cracks at the same cycles of that life (the particles compare an inspection
  // with the fine crack their coarse one stands for: LengthMap), nondecreasing.
  constexpr int kSamples = 200;
  LengthMap map;
  for (int k = 1; k <= kSamples; ++k) {
    const auto cycle = static_cast<std::int64_t>(fine_life * k / kSamples);
    double c = crack_length_at(**coarse, *coarse_end, cycle, "longest");
    double f = crack_length_at(fine, *fine_end, cycle, "longest");
    if (!map.coarse.empty()) {
      c = std::max(c, map.coarse.back());
      f = std::max(f, map.fine.back());
      if (c == map.coarse.back()) {  // a plateau of the coarse length: its first sample stands
        continue;
      }
    }
    map.coarse.push_back(c);
    map.fine.push_back(f);
  }
  config::DetailConfig config = (*coarse)->config();
  config.fatigue.strain.A2 *= factor;
  auto calibrated = DetailModel::build(config);
  if (!calibrated) return calibrated.error();
  return Surrogate{*calibrated, factor, std::move(map),
                   gauge_map_of_run(fine, *fine_end, fine_life, kSamples)};
}

Ensemble::Ensemble(std::shared_ptr<const DetailModel> model,
                   std::shared_ptr<const DetailModel> particle_model,
                   prognostics::ParticleEnsemble filter)
    : model_(std::move(model)),
      particle_model_(std::move(particle_model)),
      filter_(std::move(filter)) {}

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
  std::shared_ptr<const DetailModel> particle_model = model;
  LengthMap length_map;
  GaugeMap gauge_map;
  if (const double dx = u.particle_dx(model->config().life.dx); dx > 0) {
    auto coarse = particle_surrogate(*model, dx);
    if (!coarse) return coarse.error().within("uncertainty.dx: ");
    particle_model = coarse->model;
    length_map = std::move(coarse->length_map);
    gauge_map = std::move(coarse->gauge_map);
  }
  std::unique_ptr<Ensemble> e(new Ensemble(model, particle_model, std::move(*filter)));
  e->length_map_ = std::move(length_map);
  e->gauge_map_ = std::move(gauge_map);
  e->predicted_end_.assign(settings.particles, kNaN);
  e->a2_column_ = a2_column;
  e->load_scale_column_ = load_column;
  e->particles_.resize(settings.particles);
  for (std::size_t i = 0; i < e->particles_.size(); ++i) e->set_parameters(e->particles_[i], i);
  std::vector<int> ok(e->particles_.size(), 0);
  e->for_each_particle([&](std::size_t i) {
    Particle& p = e->particles_[i];
    p.engine = e->particle_model_->make_engine(p.a2_factor);
    ok[i] = p.engine->initialize() ? 1 : 0;
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end()) {
    return core::failure("a particle's engine cannot solve the virgin detail");
  }
  if (particle_model == model) {
    e->gauge_virgin_ = gauge_influences(model->gauges(), e->particles_[0].engine->solver());
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
  const DetailModel& pm = *particle_model_;
  const fatigue::FatigueEngine::StopCheck stop = end_of_life_check(pm);
  for_each_particle([&](std::size_t i) {
    Particle& p = particles_[i];
    for (const core::LoadBlock& block : blocks) {
      if (p.ended_at >= 0) break;
      core::LoadBlock scaled = block;
      scaled.p_max *= p.load_scale;
      // The engine checks the end criterion after every group of breaks and stops there (stopped,
      // or final_failure); the criterion is looked at again only after a block that broke bonds:
      // quiet blocks need no crack search (as the twin's own quiet batches, Twin::ReportKey).
      const std::size_t events = p.engine->break_events().size();
      if (p.engine->apply(scaled, stop) != fatigue::EngineStatus::ok ||
          (p.engine->break_events().size() != events &&
           end_of_life(pm, *p.engine) != Failure::none)) {
        p.ended_at = p.engine->total_cycles();
      }
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
  const bool gauges = o.kind == messages::ObservationKind::gauge_compliance;
  if (!gauges && !is_crack_origin(*model_, o.origin)) {
    return core::Error{"origin", "\"" + o.origin +
                                     "\" is no crack origin of this detail (\"longest\", a notch's "
                                     "name, \"hole <index>\", \"outline\" or \"interior\")"};
  }
  const DetailModel& pm = *particle_model_;
  std::vector<double> predicted(particles_.size());
  for_each_particle([&](std::size_t i) {
    predicted[i] = length_map_(crack_length_at(pm, *particles_[i].engine, o.cycle, o.origin));
  });
  std::vector<double> log_likelihood;
  if (gauges) {
    // Each particle's gauges read its current bond state (a gauge observation covers the last
    // blocks applied); on a coarser grid they are scaled by the detail's virgin gauges over the
    // particle grid's (gauge_calibration_): the coarse grid's smoothing at the gauge taken out.
    // A particle's crack moves in steps of its grid spacing, so does its compliance: beside the
    // gauge's σ, the rounding of its crack length (Δx_p/√12, as for an inspection) times the
    // compliance's change per length: without it a long record's tiny σ would let the grid's
    // steps decide. On the detail's own grid a particle's gauges read its own bond state (the
    // change per length: its secant since the virgin state); on a coarser grid they are the
    // detail's GaugeMap at the fine length the particle's crack stands for (the change per
    // length: the map's across ±Δx_p/2).
    if (!reads_gauges()) {
      return core::Error{"", "the particles' grid cannot read the gauges (no gauge map)"};
    }
    const auto indices = observed_gauge_indices(o, pm.gauges());
    if (!indices) return indices.error();
    const double step = pm.disc().dx;
    const double rounding = step / std::sqrt(12.0);
    const std::vector<double> virgin =
        gauge_map_.empty() ? predicted_compliance(o, *indices, pm.gauges(), gauge_virgin_)
                           : std::vector<double>{};
    log_likelihood.resize(particles_.size());
    for_each_particle([&](std::size_t i) {
      const double a = predicted[i];
      std::vector<double> model_sigma(o.gauges.size(), 0.0);
      std::vector<double> m;
      if (gauge_map_.empty()) {
        m = predicted_compliance(o, *indices, pm.gauges(),
                                 gauge_influences(pm.gauges(), particles_[i].engine->solver()));
        for (std::size_t g = 0; g < m.size() && a > 0; ++g) {
          model_sigma[g] = std::abs(m[g] - virgin[g]) / a * rounding;
        }
      } else {
        m = predicted_compliance(o, *indices, model_->gauges(), gauge_map_(a));
        const auto above =
            predicted_compliance(o, *indices, model_->gauges(), gauge_map_(a + step / 2));
        const auto below = predicted_compliance(o, *indices, model_->gauges(),
                                                gauge_map_(std::max(0.0, a - step / 2)));
        for (std::size_t g = 0; g < m.size(); ++g) {
          model_sigma[g] = std::abs(above[g] - below[g]) / step * rounding;
        }
      }
      log_likelihood[i] = gauge_log_likelihood(o, m, model_sigma);
    });
  } else if (o.kind == messages::ObservationKind::crack_length) {
    // The particle's length moves in steps of about its grid spacing: a uniform rounding error of
    // variance Δx_p²/12 beside the measurement's (docs/prognostics.md, "The twin's ensemble").
    const double rounding = pm.disc().dx / std::sqrt(12.0);
    log_likelihood = prognostics::log_likelihoods(
        prognostics::CrackLengthObservation{o.length_m, std::hypot(o.sigma_m, rounding)},
        predicted);
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
  if (parents) {
    out.resampled = true;
    filter_.rejuvenate();
    std::vector<Particle> next(particles_.size());
    std::vector<double> next_end(particles_.size());
    for (std::size_t i = 0; i < next.size(); ++i) {
      set_parameters(next[i], i);
      next_end[i] = predicted_end_[(*parents)[i]];
    }
    for_each_particle([&](std::size_t i) {
      const Particle& parent = particles_[(*parents)[i]];
      next[i].engine = parent.engine->fork(pm.engine_settings(next[i].a2_factor));
      next[i].ended_at = parent.ended_at;
    });
    particles_ = std::move(next);
    predicted_end_ = std::move(next_end);
  }
  observations_.push_back({o, total_cycles_, out});
  return out;
}

EnsembleEstimate Ensemble::estimate(const std::vector<core::LoadBlock>& spectrum) {
  const DetailModel& pm = *particle_model_;
  const config::UncertaintyConfig& u = model_->config().uncertainty;
  const bool shuffle = model_->config().life.empirical_spectrum() && spectrum.size() > 1;
  std::vector<double> end(particles_.size(), kInf);
  for_each_particle([&](std::size_t i) {
    const Particle& p = particles_[i];
    if (p.ended_at >= 0) {
      end[i] = static_cast<double>(p.ended_at);
      return;
    }
    std::vector<core::LoadBlock> scaled = spectrum;
    if (shuffle) {
      // The empirical spectrum's blocks in an order of the particle's own (Fisher-Yates), drawn
      // from a stream of the config's seed, the cycle count and the particle: the future's block
      // order is as uncertain as its parameters, and the same on any thread.
      prognostics::Random order(
          u.seed ^ (0x9e3779b97f4a7c15ULL * (static_cast<std::uint64_t>(total_cycles_) + 1)) ^
          (0xbf58476d1ce4e5b9ULL * (i + 1)));
      for (std::size_t k = scaled.size() - 1; k > 0; --k) {
        std::swap(scaled[k], scaled[static_cast<std::size_t>(order.uniform_below(k + 1))]);
      }
    }
    for (auto& b : scaled) b.p_max *= p.load_scale;
    const double life =
        simulate_life(pm, p.engine->export_state(), scaled, p.a2_factor, nullptr, p.engine.get());
    // NaN (no spectrum, or the state cannot be imported) counts as not reached.
    end[i] = std::isnan(life) ? kInf : static_cast<double>(total_cycles_) + life;
  });
  predicted_end_ = std::move(end);
  estimate_cycle_ = total_cycles_;
  return summary();
}

EnsembleEstimate Ensemble::summary() const {
  const config::UncertaintyConfig& u = model_->config().uncertainty;
  EnsembleEstimate out;
  out.cycle = total_cycles_;
  out.percentiles = u.percentiles;
  out.horizon_cycles = u.horizon_cycles;
  out.effective_sample_size = filter_.effective_sample_size();
  out.end_of_life.assign(u.percentiles.size(), kNaN);
  out.remaining.assign(u.percentiles.size(), kNaN);
  out.probability_within_horizon = kNaN;
  // A particle at its end of life has 0 remaining (its end may lie before the ensemble's count:
  // it stops there while the load goes on); so has one whose simulated end has passed.
  std::vector<double> end(particles_.size()), remaining(particles_.size());
  bool simulated = estimate_cycle_ >= 0;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    end[i] = particles_[i].ended_at >= 0 ? static_cast<double>(particles_[i].ended_at)
                                         : predicted_end_[i];
    simulated = simulated && !std::isnan(end[i]);
    remaining[i] = std::max(0.0, end[i] - static_cast<double>(total_cycles_));
  }
  const auto w = filter_.weights();
  if (simulated) {
    std::vector<double> probabilities;
    for (double q : u.percentiles) probabilities.push_back(q / 100.0);
    if (auto q = prognostics::weighted_quantiles(end, w, probabilities)) out.end_of_life = *q;
    if (auto q = prognostics::weighted_quantiles(remaining, w, probabilities)) {
      out.remaining = *q;
    }
    if (u.horizon_cycles > 0) {
      if (auto pr = prognostics::probability_at_or_below(remaining, w, u.horizon_cycles)) {
        out.probability_within_horizon = *pr;
      }
    }
  }
  const double a2_config = model_->config().fatigue.strain.A2;
  for (const auto& p : filter_.posterior()) {
    out.posterior.push_back({p.name, p.summary.median, p.summary.coefficient_of_variation});
  }
  if (a2_column_ < 0) out.posterior.push_back({"a2", a2_config * particles_[0].a2_factor, 0.0});
  if (load_scale_column_ < 0) out.posterior.push_back({"load_scale", u.load_scale.median, 0.0});
  return out;
}

EnsembleCheckpoint Ensemble::export_state() const {
  EnsembleCheckpoint s;
  s.filter = filter_.serialize();
  for (const Particle& p : particles_) {
    s.engines.push_back(p.engine->export_state());
    s.a2_factor.push_back(p.a2_factor);
    s.load_scale.push_back(p.load_scale);
    s.ended_at.push_back(p.ended_at);
  }
  s.predicted_end = predicted_end_;
  s.total_cycles = total_cycles_;
  s.estimate_cycle = estimate_cycle_;
  s.observations = observations_;
  return s;
}

core::Status Ensemble::import_state(const EnsembleCheckpoint& s) {
  const std::size_t n = particles_.size();
  if (s.engines.size() != n || s.a2_factor.size() != n || s.load_scale.size() != n ||
      s.ended_at.size() != n || s.predicted_end.size() != n) {
    return core::failure("the ensemble holds " + std::to_string(s.engines.size()) +
                         " particles, the config says " + std::to_string(n));
  }
  prognostics::ParticleEnsemble filter = filter_;
  if (core::Status read = filter.deserialize(s.filter); !read) {
    return core::failure("the ensemble's filter: " + read.error().message());
  }
  if (filter.size() != n || filter.dimension() != filter_.dimension()) {
    return core::failure("the ensemble's filter does not fit the config's parameters");
  }
  filter_ = std::move(filter);
  std::vector<int> ok(n, 0);
  for_each_particle([&](std::size_t i) {
    Particle& p = particles_[i];
    p.a2_factor = s.a2_factor[i];
    p.load_scale = s.load_scale[i];
    p.ended_at = s.ended_at[i];
    p.engine = particle_model_->make_engine(p.a2_factor);
    ok[i] = p.engine->initialize() && p.engine->import_state(s.engines[i]) ? 1 : 0;
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end()) {
    return core::failure("a particle's engine state does not fit the particles' model");
  }
  predicted_end_ = s.predicted_end;
  total_cycles_ = s.total_cycles;
  estimate_cycle_ = s.estimate_cycle;
  observations_ = s.observations;
  return {};
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
  for (const ObservationRecord& r : observations_) {
    const messages::Observation& o = r.observation;
    h.bytes(&o.cycle, sizeof o.cycle);
    const auto kind = static_cast<std::int32_t>(o.kind);
    h.bytes(&kind, sizeof kind);
    h.bytes(o.origin.data(), o.origin.size());
    for (double v : {o.length_m, o.sigma_m, o.pod_a50_m, o.pod_slope}) h.bytes(&v, sizeof v);
    h.bytes(&r.taken_at, sizeof r.taken_at);
    // Gauges (issue 33): nothing for the other kinds, whose bits stay as they were.
    for (const messages::GaugeCompliance& g : o.gauges) {
      h.bytes(g.id.data(), g.id.size());
      for (double v : {g.compliance, g.sigma, g.model}) h.bytes(&v, sizeof v);
      const std::uint8_t identifies = g.identifies ? 1 : 0;
      h.bytes(&identifies, sizeof identifies);
    }
    if (!o.gauges.empty()) h.bytes(&o.gauge_angle_rad, sizeof o.gauge_angle_rad);
  }
  return h.get();
}

}  // namespace peritwin::twin
