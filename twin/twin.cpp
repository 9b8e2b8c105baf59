#include "twin/twin.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string_view>

#include "core/fnv1a.h"

namespace peritwin::twin {

Twin::Twin(std::shared_ptr<const DetailModel> model, Options options)
    : model_(std::move(model)),
      options_(options),
      gauge_residuals_(GaugeResiduals::none(model_->gauges())) {}

core::Expected<std::unique_ptr<Twin>> Twin::create(std::shared_ptr<const DetailModel> model,
                                                   Options options) {
  std::unique_ptr<Twin> twin(new Twin(std::move(model), options));
  twin->engine_ = twin->model_->make_engine(1.0, true);
  if (!twin->engine_->initialize()) {
    return core::failure("detail " + twin->detail_id() +
                         ": the virgin model cannot be solved: " + twin->engine_->failure_reason());
  }
  twin->refresh();
  if (options.learn && twin->model_->config().uncertainty.enabled) {
    auto ensemble = Ensemble::create(twin->model_);
    if (!ensemble) {
      return core::failure("detail " + twin->detail_id() +
                           ": [detail.uncertainty]: " + ensemble.error().message());
    }
    twin->ensemble_ = std::move(*ensemble);
    twin->catch_up_ensemble(true);  // the prior's percentiles
  }
  twin->first_break_load_ = ::peritwin::twin::first_break_load(*twin->model_, *twin->engine_);
  if (const auto& configured = twin->model_->config().limits.max_p) {
    twin->max_p_ = *configured;
    twin->max_p_configured_ = true;
  } else {
    twin->max_p_ = kDefaultMaxPOverFirstBreak * twin->first_break_load_;  // +inf without s_c
  }
  return twin;
}

double first_break_load(const DetailModel& model, const fatigue::FatigueEngine& engine) {
  const config::DetailConfig& config = model.config();
  const fatigue::FatigueSettings& f = config.fatigue;
  double s_ref = 0.0;
  if (f.law == fatigue::FatigueLaw::bilinear) {
    s_ref = f.bilinear.sc;  // 003 Eq. (44)
  } else if (f.critical_stretch > 0.0) {
    s_ref = f.critical_stretch;
  } else if (config.material.fracture_toughness > 0.0) {
    s_ref = fatigue::critical_stretch(config.material, model.disc().horizon);  // 000 Eq. (8)
  }
  if (!(s_ref > 0.0)) return std::numeric_limits<double>::infinity();
  // Stretch of bond b under P at angle α: P·(s_b + cos α·c_b + sin α·n_b) from the basis
  // solutions; over α its tensile peak is P·(s_b + hypot(c_b, n_b)) (static failure is tensile,
  // s >= s_c).
  const statics::StaticSolver& solver = engine.solver();
  const auto& s = solver.basis_stretch(statics::basis_constant);
  const auto& c = solver.basis_stretch(statics::basis_cos);
  const auto& n = solver.basis_stretch(statics::basis_sin);
  const auto& intact = solver.intact();
  auto at = [](const std::vector<double>& v, std::size_t b) { return b < v.size() ? v[b] : 0.0; };
  double peak = 0.0;
  for (std::size_t b = 0; b < intact.size(); ++b) {
    if (intact[b] == 0) continue;
    peak = std::max(peak, at(s, b) + std::hypot(at(c, b), at(n, b)));
  }
  return peak > 0.0 ? s_ref / peak : std::numeric_limits<double>::infinity();
}

namespace {

std::string format_load(double p) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", p);
  return text;
}

}  // namespace

messages::Outcome Twin::check_limits(const messages::Batch& batch) const {
  for (std::size_t i = 0; i < batch.blocks.size(); ++i) {
    const double p = batch.blocks[i].p_max;
    if (p > max_p_) {
      return {messages::Verdict::invalid, "blocks[" + std::to_string(i) + "].p_max",
              "p_max = " + format_load(p) + " N is above the detail's bound max_p = " +
                  format_load(max_p_) + " N ([detail.limits] max_p" +
                  (max_p_configured_ ? ")"
                                     : "; by default 10x the load at which the virgin detail's "
                                       "peak bond stretch reaches the critical stretch)")};
    }
  }
  // The running total stays <= kMaxTotalCycles: check_batch capped this batch's sum at 2^50, so
  // the sum below cannot wrap.
  std::int64_t cycles = 0;
  for (const core::LoadBlock& b : batch.blocks) cycles += b.count;
  if (const std::int64_t total = engine_->total_cycles(); cycles > core::kMaxTotalCycles - total) {
    return {messages::Verdict::invalid, "blocks",
            "the batch's " + std::to_string(cycles) +
                " cycles would take the detail's total from " + std::to_string(total) +
                " past the cap of " + std::to_string(core::kMaxTotalCycles) +
                " cycles (2^53, core::kMaxTotalCycles: counts stay exact as doubles)"};
  }
  const auto max_sources = static_cast<std::size_t>(model_->config().limits.max_sources);
  if (!applied_.contains(batch.source_id) && applied_.size() >= max_sources) {
    return {messages::Verdict::limit, "source_id",
            "the detail already has " + std::to_string(applied_.size()) +
                " load sources, the most [detail.limits] max_sources allows; source \"" +
                batch.source_id + "\" is new"};
  }
  return {};
}

std::int64_t Twin::applied_seq(const std::string& source) const {
  const auto it = applied_.find(source);
  return it == applied_.end() ? 0 : it->second;
}

std::int64_t Twin::broken_bonds() const { return engine_->broken_bonds() - model_->precut_bonds(); }

void Twin::refresh() {
  const ReportKey key{engine_->break_events().size(),
                      engine_->solves(),
                      engine_->rebuilds(),
                      engine_->increments(),
                      engine_->failed(),
                      last_block_.has_value(),
                      last_block_ ? last_block_->p_max : 0.0,
                      last_block_ ? last_block_->alpha : 0.0};
  if (report_key_ != key) {
    report_ = measure_cracks(*model_, *engine_, last_block_ ? &*last_block_ : nullptr);
    report_key_ = key;
  }
  failure_ = end_of_life(*model_, *engine_);
}

messages::Outcome Twin::apply(const messages::Batch& batch) {
  messages::Outcome o = messages::check_batch(batch, detail_id());
  if (o.applied()) o = check_limits(batch);
  if (!o.applied()) {
    ++counters_.rejected;
    return o;
  }
  const std::int64_t last = applied_seq(batch.source_id);
  if (batch.seq <= last) {
    ++counters_.duplicates;
    return {messages::Verdict::duplicate, "seq",
            "seq " + std::to_string(batch.seq) + " of source \"" + batch.source_id +
                "\" is already applied (last applied " + std::to_string(last) + ")"};
  }
  if (batch.seq > last + 1) {
    ++counters_.gaps;
    ++counters_.rejected;
    return {messages::Verdict::gap, "seq",
            "seq " + std::to_string(batch.seq) + " of source \"" + batch.source_id +
                "\" skips ahead: expected " + std::to_string(last + 1) + ", missing " +
                std::to_string(batch.seq - last - 1) + " batch(es); resend from " +
                std::to_string(last + 1)};
  }
  if (failure_ != Failure::none) {
    ++counters_.rejected;
    return {messages::Verdict::failed, "message",
            failure_ == Failure::singular
                ? "the detail has reached final failure: " + engine_->failure_reason()
                : "the detail reached its end-of-life criterion at cycle " +
                      std::to_string(end_of_life_cycle()) + "; it applies no more cycles"};
  }
  // The engine stops at the exact cycle at which the end criterion is met (end_of_life_check):
  // the rest of the batch is not applied (see "End of life" in twin.h).
  const fatigue::FatigueEngine::StopCheck stop = end_of_life_check(*model_);
  cycles_before_state_ = engine_->total_cycles();
  std::vector<core::LoadBlock> applied_blocks;  // what the engine applied, for the ensemble
  for (const core::LoadBlock& block : batch.blocks) {
    const std::int64_t before = engine_->total_cycles();
    const fatigue::EngineStatus status = engine_->apply(block, stop);
    core::LoadBlock applied = block;
    applied.count = engine_->total_cycles() - before;
    if (applied.count > 0) spectrum_.add(applied);
    if (applied.count > 0) applied_blocks.push_back(applied);
    if (applied.count > 0 || status != fatigue::EngineStatus::ok) last_block_ = block;
    if (status != fatigue::EngineStatus::ok) break;
  }
  applied_[batch.source_id] = batch.seq;
  histories_[batch.source_id] = {batch.history, batch.history_start};
  ++state_seq_;
  last_source_ = batch.source_id;
  last_seq_ = batch.seq;
  ++counters_.applied;
  refresh();
  if (ensemble_) {
    (void)ensemble_->apply(applied_blocks);
    catch_up_ensemble(false);
  }
  if (failure_ != Failure::none) {
    // No simulation: the remaining life is 0. start_cycles (a diagnostic) says where it ended.
    LifeEstimate ended{0.0, 0.0, 0.0, state_seq_, last_seq_, last_source_};
    ended.start_cycles = engine_->total_cycles();
    set_life(ended);
  } else if (options_.life == LifeMode::synchronous) {
    catch_up_life();
  }
  return {};
}

messages::Outcome Twin::observe(const messages::Observation& o) {
  const auto refuse = [this](messages::Verdict verdict, const std::string& field,
                             std::string why) -> messages::Outcome {
    if (verdict != messages::Verdict::duplicate) ++counters_.rejected;
    return {verdict, "observation" + (field.empty() ? std::string() : "." + field), std::move(why)};
  };
  if (messages::Outcome checked = messages::check_observation_message(o, detail_id());
      !checked.applied()) {
    ++counters_.rejected;
    return checked;
  }
  const auto it = observed_.find(o.source_id);
  const std::int64_t last = it == observed_.end() ? 0 : it->second;
  if (o.seq <= last) {
    return refuse(messages::Verdict::duplicate, "seq",
                  "observation seq " + std::to_string(o.seq) + " of source \"" + o.source_id +
                      "\" is already taken in (last " + std::to_string(last) + ")");
  }
  if (o.seq > last + 1) {
    return refuse(messages::Verdict::gap, "seq",
                  "observation seq " + std::to_string(o.seq) + " of source \"" + o.source_id +
                      "\" skips ahead: expected " + std::to_string(last + 1));
  }
  if (o.kind == messages::ObservationKind::gauge_compliance) {
    // Gauges are read with or without a learning ensemble: the residual and its alarm
    // (twin/gauges.h) need none.
    if (o.cycle > engine_->total_cycles()) {
      return refuse(messages::Verdict::invalid, "cycle",
                    "is in the future of the twin (" + std::to_string(o.cycle) + " > " +
                        std::to_string(engine_->total_cycles()) + " cycles applied)");
    }
    const auto indices = observed_gauge_indices(o, model_->gauges());
    if (!indices) {
      return refuse(messages::Verdict::invalid, indices.error().field, indices.error().reason);
    }
    // The ensemble learns from gauges when its particles can read them (Ensemble::reads_gauges).
    // One that cannot explain the observation (every particle's gauge reads nothing) stays as it
    // was: the residual and its alarm, the safety side, are taken in all the same.
    const bool learns = ensemble_ && ensemble_->reads_gauges() && ensemble_->observe(o).ok();
    take_in(gauge_residuals_, o, *indices,
            predicted_compliance(o, *indices, model_->gauges(), gauge_influences()));
    observed_[o.source_id] = o.seq;
    if (learns) catch_up_ensemble(true);
    return {};
  }
  if (!ensemble_) {
    return refuse(messages::Verdict::invalid, "",
                  "detail " + detail_id() +
                      " does not learn: it has no [detail.uncertainty] (the priors an observation "
                      "updates)");
  }
  auto update = ensemble_->observe(o);
  if (!update) {
    return refuse(messages::Verdict::invalid, update.error().field, update.error().reason);
  }
  observed_[o.source_id] = o.seq;
  catch_up_ensemble(true);
  return {};
}

std::vector<std::array<double, 3>> Twin::gauge_influences() const {
  return twin::gauge_influences(model_->gauges(), engine_->solver());
}

std::optional<EnsembleEstimate> Twin::ensemble_estimate() const {
  if (!ensemble_) return std::nullopt;
  return ensemble_->summary();
}

void Twin::catch_up_ensemble(bool force) {
  const std::int64_t every = model_->config().uncertainty.every_batches;
  const bool due =
      force || ensemble_->estimate_cycle() < 0 || (every > 0 && state_seq_ % every == 0) ||
      (failure_ != Failure::none && ensemble_->estimate_cycle() < ensemble_->total_cycles());
  if (due) (void)ensemble_->estimate(reference_spectrum(*model_, spectrum_));
}

namespace {

template <class Hash>
void hash_field(Hash& h, const std::map<std::string, std::int64_t>& applied) {
  h.integer(static_cast<std::int64_t>(applied.size()));
  for (const auto& [source, seq] : applied) {
    h.packed(source);
    h.integer(seq);
  }
}
template <class Hash>
void hash_field(Hash& h, const GaugeResiduals& r) {
  // Nothing while no gauge observation has been taken in (no gauges, or none observed yet): the
  // gauges' state is then the config's, and the state_hash what it was before gauges.
  const bool observed =
      std::any_of(r.residual.begin(), r.residual.end(), [](double v) { return !std::isnan(v); }) ||
      std::any_of(r.in_a_row.begin(), r.in_a_row.end(), [](std::int64_t n) { return n != 0; });
  if (!observed) return;
  h.integer(static_cast<std::int64_t>(r.ids.size()));
  for (std::size_t k = 0; k < r.ids.size(); ++k) {
    h.packed(r.ids[k]);
    h.real(r.residual[k]);
    h.real(r.sigma[k]);
    h.integer(r.in_a_row[k]);
  }
}
template <class Hash>
void hash_field(Hash& h, const HistoryBySource& histories) {  // not hashed (Hashed::no)
  h.integer(static_cast<std::int64_t>(histories.size()));
  for (const auto& [source, history] : histories) {
    h.packed(source);
    h.word(history.fingerprint);
    h.integer(history.start);
  }
}
template <class Hash>
void hash_field(Hash& h, const std::optional<core::LoadBlock>& block) {
  h.integer(block ? 1 : 0);
  if (block) fatigue::hash_field(h, *block);
}
template <class Hash>
void hash_field(Hash& h, Failure failure) {
  h.integer(static_cast<std::int64_t>(failure));
}
template <class Hash>
void hash_field(Hash& h, const RollingSpectrum& spectrum) {
  h.integer(static_cast<std::int64_t>(spectrum.blocks().size()));
  for (const auto& b : spectrum.blocks()) fatigue::hash_field(h, b);
}
using fatigue::hash_field;

}  // namespace

core::Fnv1a64 Twin::own_fields_hash() const {
  core::Fnv1a64 h;
  for_each_own_field(*this, [&h](std::string_view, const auto& field, Hashed hashed) {
    if (hashed == Hashed::yes) hash_field(h, field);
  });
  return h;
}

std::uint64_t Twin::state_hash() const {
  // Equal hashes <=> bit-identical states (up to 64-bit collisions).
  core::Fnv1a64 h = own_fields_hash();
  engine_->hash_state(h);
  if (ensemble_) h.word(ensemble_->state_hash());
  return h.get();
}

Twin::Hashes Twin::hashes() const {
  core::Fnv1a64Pair pair{own_fields_hash(), core::Fnv1a64{}};
  engine_->hash_state(pair);
  if (ensemble_) pair.first.word(ensemble_->state_hash());
  return {pair.first.get(), pair.second.get()};
}

std::string Twin::state_hash_hex() const { return core::hex64(state_hash()); }

LifeJob Twin::life_job_state_only() const {
  return {model_,
          engine_->export_state(),
          reference_spectrum(*model_, spectrum_),
          state_seq_,
          last_seq_,
          last_source_,
          nullptr};
}

LifeJob Twin::life_job() const {
  LifeJob job = life_job_state_only();
  // The coarse estimate ([detail.life] dx) maps the state onto its own grid: no fork needed.
  if (can_fork(*model_) && !(model_->config().life.dx > 0)) {
    job.engine = engine_->fork(model_->engine_settings());
  }
  return job;
}

void Twin::set_life(const LifeEstimate& estimate) {
  if (estimate.state_seq < life_.state_seq) return;
  life_ = estimate;
}

bool Twin::life_due() const {
  const config::LifeConfig& life = model_->config().life;
  if (failure_ != Failure::none || !life.estimates() || life_.state_seq == state_seq_) {
    return false;
  }
  const std::int64_t every = life.every_cycles;
  const bool passed_cycles =
      every > 0 && engine_->total_cycles() / every > cycles_before_state_ / every;
  return state_seq_ == 0 || passed_cycles ||
         (life.every_batches > 0 && state_seq_ % life.every_batches == 0);
}

void Twin::estimate_life_now() {
  // Synchronous: the simulations fork the live engine itself (no snapshot needed).
  const LifeJob job = life_job_state_only();
  LifeEstimate e = estimate_life(*model_, job.state, job.spectrum, options_.parallel_band, nullptr,
                                 engine_.get());
  e.state_seq = job.state_seq;
  e.seq = job.seq;
  e.source = job.source;
  set_life(e);
}

void Twin::catch_up_life() {
  if (options_.life == LifeMode::synchronous && life_due()) estimate_life_now();
}

}  // namespace peritwin::twin
