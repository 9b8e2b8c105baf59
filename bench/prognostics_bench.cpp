// peritwin-bench-prognostics (also `peritwin-bench prognostics`): how well the learning twin
// (twin/ensemble.h) predicts the end of life of a detail whose parameters it does not know (issue
// 32 item 7; docs/benchmarks.md "Prognostics").
//
// Per trial t (0 … --trials − 1):
//  * the truth: its hidden parameters drawn from the detail's own prior ([detail.uncertainty]: A2
//    and the load scale, lognormal) by a stream of its own (prognostics::Random(--seed), jumped t
//    times: independent of the ensemble's stream and of the number of trials). A fatigue engine of
//    the detail with the truth's A2 (DetailModel::make_engine(A2/A2_config)) applies the loads
//    (the reference spectrum of [detail.life], or --history: pass after pass, the blocks as
//    written) with P_max × the truth's load scale until its end of life (end_of_life_check: the
//    exact cycle): the true end-of-life cycle T.
//  * the inspections: --inspections at fixed intervals of --interval × a base life: the nominal
//    life (default; the life of an engine at the prior's medians under the same loads, what an
//    operator schedules by, the same for every trial) or, --basis truth, each truth's own T. An
//    inspection at or after T is not made (the detail has failed). What it reports: the truth's
//    crack at the criterion's origin (observed_crack_length) + N(0, --sigma), clamped at 0; when
//    the truth has no crack yet, "no crack found" with the POD curve (--pod-a50, --pod-slope). With
//    --random-detection a crack is found only with probability POD(a) (else "no crack found").
//    Every inspection draws one uniform and one normal from the trial's stream, found or not.
//  * the twin: an Ensemble of the detail (seed [detail.uncertainty] seed + t, --particles) fed the
//    same nominal blocks (it applies them × each particle's load scale), split at the inspection
//    cycles; each inspection is taken in at its own cycle (Ensemble::observe), and an estimate
//    (Ensemble::estimate under the reference spectrum) is made before any inspection and after
//    each; one more estimate without an inspection at t_λ = λ·T (unless an inspection is there),
//    the prediction α-λ evaluates.
// Measured: the coverage of the 90 % interval [p05, p95] of the end-of-life cycle, |p50 − T|/T,
// ProgPy's α-λ (metrics.h: α, λ, β) over the profile of predictions, the wall time of each
// observation update (Ensemble::observe) and of each estimate, the load ingest time, peak RSS.
// The estimates publish the 1st … 99th percentiles: α-λ's probability in bounds is the fraction
// of these 99 equally likely points strictly inside the bounds (the ensemble's weighted end-of-life
// samples are not exposed by Ensemble::estimate; this is ProgPy's count on the quantile
// representation of the weighted ensemble, within about one particle's weight of it).
//
// One JSON line per trial ("bench":"prognostics-trial"), then a summary ("bench":"prognostics").
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/cli_checks.h"
#include "core/json_line.h"
#include "core/proc_files.h"
#include "loads/load_history.h"
#include "messages/observation.h"
#include "prognostics/metrics.h"
#include "prognostics/observation_likelihood.h"
#include "prognostics/random.h"
#include "prognostics/uncertain_parameter.h"
#include "solver/fatigue/laws/strain_range.h"
#include "twin/detail_model.h"
#include "twin/ensemble.h"
#include "twin/life.h"

namespace {

using namespace peritwin;

constexpr double kInf = std::numeric_limits<double>::infinity();
/// The truth's life is sought up to this multiple of the nominal life (beyond: the trial has no
/// finite truth and is left out of the metrics).
constexpr double kTruthCapFactor = 100.0;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Options {
  std::string config = std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml";
  std::string detail;   ///< "" = the first detail
  std::string history;  ///< "" = the reference spectrum is also the applied load
  std::string history_format = "cycles";
  int trials = 20;
  std::int64_t particles = 0;  ///< 0 = the config's
  std::uint64_t seed = 2032;   ///< the truths' stream
  int inspections = 3;
  double interval = 0.2;
  std::string basis = "nominal";
  double sigma = 3e-4;
  double pod_a50 = 1e-3;
  double pod_slope = 3.0;
  bool random_detection = false;
  double dx = 0.0;       ///< 0 = the config's grid
  double life_dx = 0.0;  ///< 0 = the config's [detail.life] dx
  double alpha = 0.2;
  double lambda = 0.5;
  double beta = 0.5;
  bool lambda_estimate = true;
};

/// A load list (the reference spectrum, a history) repeated pass after pass, handed out in blocks
/// as written, a block split where a requested count ends (exact in the engine's block stepping).
class SpectrumCursor {
 public:
  explicit SpectrumCursor(std::vector<core::LoadBlock> spectrum) : spectrum_(std::move(spectrum)) {}
  /// The rest of the current block.
  core::LoadBlock next_block() { return take_from_current(kMaxCount); }
  /// The next blocks totalling `cycles`.
  std::vector<core::LoadBlock> take(std::int64_t cycles) {
    std::vector<core::LoadBlock> out;
    while (cycles > 0) {
      out.push_back(take_from_current(cycles));
      cycles -= out.back().count;
    }
    return out;
  }

 private:
  static constexpr std::int64_t kMaxCount = std::numeric_limits<std::int64_t>::max();
  core::LoadBlock take_from_current(std::int64_t most) {
    core::LoadBlock b = spectrum_[index_];
    b.count = std::min(most, b.count - used_);
    used_ += b.count;
    if (used_ == spectrum_[index_].count) {
      index_ = (index_ + 1) % spectrum_.size();
      used_ = 0;
    }
    return b;
  }
  std::vector<core::LoadBlock> spectrum_;
  std::size_t index_ = 0;
  std::int64_t used_ = 0;
};

struct TruthRun {
  double end_of_life = kInf;    ///< cycle of the end criterion; +Inf beyond the cap
  std::vector<double> lengths;  ///< the criterion's crack at each requested cycle below the end
  double wall_s = 0.0;
};

/// An engine with `a2_factor` applying the spectrum × `load_scale` from cycle 0 to its end of life
/// (or `cap` cycles), the crack at the origin measured at each cycle of `at` (increasing) it
/// reaches before its end.
TruthRun run_truth(const twin::DetailModel& model, const std::vector<core::LoadBlock>& spectrum,
                   double a2_factor, double load_scale, const std::vector<std::int64_t>& at,
                   double cap, const std::string& origin) {
  const auto t0 = std::chrono::steady_clock::now();
  TruthRun run;
  const auto engine = model.make_engine(a2_factor);
  if (!engine->initialize()) {
    std::fprintf(stderr, "peritwin-bench prognostics: %s\n", engine->failure_reason().c_str());
    std::exit(3);
  }
  const auto stop = twin::end_of_life_check(model);
  SpectrumCursor cursor(spectrum);
  std::size_t next = 0;
  while (static_cast<double>(engine->total_cycles()) < cap) {
    const core::LoadBlock block = cursor.next_block();
    // Split at the inspection cycles inside the block.
    std::int64_t remaining = block.count;
    bool ended = false;
    while (remaining > 0) {
      core::LoadBlock piece = block;
      piece.count = remaining;
      if (next < at.size()) piece.count = std::min(remaining, at[next] - engine->total_cycles());
      piece.p_max *= load_scale;
      const fatigue::EngineStatus status = engine->apply(piece, stop);
      remaining -= piece.count;
      if (status != fatigue::EngineStatus::ok ||
          twin::end_of_life(model, *engine) != twin::Failure::none) {
        ended = true;
        break;
      }
      while (next < at.size() && engine->total_cycles() == at[next]) {
        run.lengths.push_back(twin::observed_crack_length(model, *engine, origin));
        ++next;
      }
    }
    if (ended) {
      run.end_of_life = static_cast<double>(engine->total_cycles());
      break;
    }
  }
  run.wall_s = seconds_since(t0);
  return run;
}

struct Prediction {
  std::string kind;  ///< "prior", "inspection", "lambda"
  int after = 0;     ///< inspections taken in before it
  std::int64_t cycle = 0;
  twin::EnsembleEstimate estimate;
  double wall_s = 0.0;
};

struct TrialResult {
  bool valid = false;  ///< a finite truth
  double truth = kInf;
  /// |p50 − T|/T and whether [p05, p95] covers T, per number of inspections taken in (the
  /// estimate after the k-th), for k = 0 … inspections made.
  std::vector<double> errors;
  std::vector<prognostics::Interval> intervals;
  bool alpha_lambda_defined = false;
  bool alpha_lambda_met = false;
  std::vector<double> observe_s, estimate_s;
  double apply_s = 0.0;
  std::int64_t applied_cycles = 0;
};

double percentile(const twin::EnsembleEstimate& e, double p) {
  for (std::size_t i = 0; i < e.percentiles.size() && i < e.end_of_life.size(); ++i) {
    if (e.percentiles[i] == p) return e.end_of_life[i];
  }
  return std::numeric_limits<double>::quiet_NaN();
}

core::JsonLine estimate_json(const Prediction& p, double truth) {
  core::JsonLine j;
  j["kind"] = p.kind;
  j["after"] = p.after;
  j["cycle"] = static_cast<long long>(p.cycle);
  const double p05 = percentile(p.estimate, 5), p50 = percentile(p.estimate, 50),
               p95 = percentile(p.estimate, 95);
  j["p05"] = core::whole(p05);
  j["p50"] = core::whole(p50);
  j["p95"] = core::whole(p95);
  j["covers"] = prognostics::covers({p05, p95}, truth);
  j["relative_error"] = core::significant(std::abs(p50 - truth) / truth, 4);
  j["ess"] = core::fixed(p.estimate.effective_sample_size, 2);
  for (const auto& q : p.estimate.posterior) {
    j[q.name] = {{"median", core::significant(q.median, 5)},
                 {"cov", core::significant(q.coefficient_of_variation, 3)}};
  }
  j["wall_s"] = core::fixed(p.wall_s, 3);
  return j;
}

struct Setup {
  config::DetailConfig config;
  std::vector<core::LoadBlock> spectrum;  ///< the estimates' future loads (reference spectrum)
  std::vector<core::LoadBlock> applied;   ///< the loads applied, pass after pass (--history)
  std::string origin;
  std::vector<prognostics::UncertainParameter> priors;  ///< the truths' (a2 and/or load_scale)
  double nominal_life = kInf;
  int nodes = 0;
  long long bonds = 0;
};

/// The truth's parameters: (A2 factor, load scale), drawn in the order a2, load_scale.
std::pair<double, double> draw_truth(const Setup& s, prognostics::Random& random) {
  const config::UncertaintyConfig& u = s.config.uncertainty;
  double a2 = u.a2.median, scale = u.load_scale.median;
  for (const auto& p : s.priors) {
    const double v = std::exp(p.sample_log(random));
    (p.name() == "a2" ? a2 : scale) = v;
  }
  const double a2_config = s.config.fatigue.strain.A2;
  return {a2_config > 0 ? a2 / a2_config : 1.0, scale};
}

TrialResult run_trial(const Setup& s, const Options& o, int trial, prognostics::Random random) {
  TrialResult result;
  const auto t_trial = std::chrono::steady_clock::now();
  config::DetailConfig config = s.config;
  config.uncertainty.seed = s.config.uncertainty.seed + static_cast<std::uint64_t>(trial);
  auto built = twin::DetailModel::build(config);
  if (!built) {
    std::fprintf(stderr, "peritwin-bench prognostics: %s\n", built.error().message().c_str());
    std::exit(3);
  }
  const std::shared_ptr<const twin::DetailModel> model = *built;
  const auto [a2_factor, load_scale] = draw_truth(s, random);
  const double cap = kTruthCapFactor * s.nominal_life;

  // The truth's life, then the schedule, then its cracks at the inspections.
  TruthRun truth = run_truth(*model, s.applied, a2_factor, load_scale, {}, cap, s.origin);
  const double T = truth.end_of_life;
  double truth_s = truth.wall_s;
  core::JsonLine line;
  line["bench"] = "prognostics-trial";
  line["trial"] = trial;
  line["truth"] = {{"a2_factor", core::significant(a2_factor, 5)},
                   {"a2", core::significant(a2_factor * s.config.fatigue.strain.A2, 5)},
                   {"load_scale", core::significant(load_scale, 5)},
                   {"end_of_life", core::whole(T)}};
  const double base = o.basis == "truth" ? T : s.nominal_life;
  std::vector<std::int64_t> at;
  for (int k = 1; k <= o.inspections && std::isfinite(T); ++k) {
    const auto c = static_cast<std::int64_t>(std::llround(o.interval * k * base));
    if (c > 0 && static_cast<double>(c) < T && (at.empty() || c > at.back())) at.push_back(c);
  }
  if (!at.empty()) {
    const TruthRun again = run_truth(*model, s.applied, a2_factor, load_scale, at, cap, s.origin);
    truth.lengths = again.lengths;
    truth_s += again.wall_s;
  }
  line["truth_s"] = core::fixed(truth_s, 2);
  if (!std::isfinite(T)) {
    line["skipped"] = "no end of life within " + std::to_string(kTruthCapFactor) + " nominal lives";
    core::print_line(line);
    std::fflush(stdout);
    return result;
  }
  result.valid = true;
  result.truth = T;

  // The inspections' reports, drawn before the twin runs (the same draws whatever it does).
  const prognostics::PodCurve pod{o.pod_a50, o.pod_slope};
  std::vector<messages::Observation> reports;
  core::JsonLine inspections = core::JsonLine::array();
  for (std::size_t k = 0; k < at.size() && k < truth.lengths.size(); ++k) {
    const double a = truth.lengths[k];
    const double u = random.uniform();
    const double z = random.standard_normal();
    messages::Observation obs;
    obs.cycle = at[k];
    obs.origin = s.origin;
    const bool found = a > 0 && (!o.random_detection || u < pod.probability_of_detection(a));
    if (found) {
      obs.kind = messages::ObservationKind::crack_length;
      obs.length_m = std::max(0.0, a + o.sigma * z);
      obs.sigma_m = o.sigma;
    } else {
      obs.kind = messages::ObservationKind::no_crack;
      obs.pod_a50_m = o.pod_a50;
      obs.pod_slope = o.pod_slope;
    }
    reports.push_back(obs);
    core::JsonLine j;
    j["cycle"] = static_cast<long long>(at[k]);
    j["truth_m"] = core::significant(a, 4);
    j["kind"] = found ? "crack_length" : "no_crack";
    if (found) j["measured_m"] = core::significant(obs.length_m, 4);
    inspections.push_back(j);
  }

  // The twin.
  auto t0 = std::chrono::steady_clock::now();
  auto created = twin::Ensemble::create(model);
  if (!created) {
    std::fprintf(stderr, "peritwin-bench prognostics: %s\n", created.error().message().c_str());
    std::exit(3);
  }
  twin::Ensemble& ensemble = **created;
  const double create_s = seconds_since(t0);
  SpectrumCursor loads(s.applied);
  std::vector<Prediction> predictions;
  int taken = 0;
  const auto predict = [&](const std::string& kind) {
    Prediction p;
    p.kind = kind;
    p.after = taken;
    p.cycle = ensemble.total_cycles();
    const auto t = std::chrono::steady_clock::now();
    p.estimate = ensemble.estimate(s.spectrum);
    p.wall_s = seconds_since(t);
    result.estimate_s.push_back(p.wall_s);
    predictions.push_back(std::move(p));
  };
  const auto advance_to = [&](std::int64_t cycle) {
    if (cycle <= ensemble.total_cycles()) return;
    const auto blocks = loads.take(cycle - ensemble.total_cycles());
    const auto t = std::chrono::steady_clock::now();
    if (const core::Status st = ensemble.apply(blocks); !st) {
      std::fprintf(stderr, "peritwin-bench prognostics: %s\n", st.error().message().c_str());
      std::exit(3);
    }
    result.apply_s += seconds_since(t);
  };
  predict("prior");
  const auto t_lambda =
      static_cast<std::int64_t>(std::llround(prognostics::lambda_time(0.0, T, o.lambda)));
  bool lambda_done =
      !o.lambda_estimate || std::find(at.begin(), at.end(), t_lambda) != at.end() || t_lambda <= 0;
  core::JsonLine updates = core::JsonLine::array();
  for (std::size_t k = 0; k <= reports.size(); ++k) {
    if (!lambda_done && (k == reports.size() || t_lambda < reports[k].cycle)) {
      advance_to(t_lambda);
      predict("lambda");
      lambda_done = true;
    }
    if (k == reports.size()) break;
    advance_to(reports[k].cycle);
    const auto t = std::chrono::steady_clock::now();
    auto update = ensemble.observe(reports[k]);
    const double observe_s = seconds_since(t);
    core::JsonLine j;
    j["cycle"] = static_cast<long long>(reports[k].cycle);
    j["wall_s"] = core::fixed(observe_s, 3);
    if (!update) {
      // Not taken in (no particle explains it): the ensemble is unchanged; no estimate.
      j["refused"] = update.error().message();
      updates.push_back(j);
      continue;
    }
    result.observe_s.push_back(observe_s);
    ++taken;
    j["log_evidence"] = core::significant(update->log_evidence, 4);
    j["ess"] = core::fixed(update->ess_before_resampling, 2);
    j["resampled"] = update->resampled;
    j["predicted_median_m"] = core::significant(update->predicted_median_m, 4);
    updates.push_back(j);
    predict("inspection");
  }
  result.applied_cycles = ensemble.total_cycles();

  // Metrics.
  core::JsonLine estimates = core::JsonLine::array();
  std::vector<prognostics::TimeOfEventPrediction> profile;
  for (const Prediction& p : predictions) {
    estimates.push_back(estimate_json(p, T));
    if (p.kind != "lambda") {
      const double p50 = percentile(p.estimate, 50);
      result.errors.push_back(std::abs(p50 - T) / T);
      result.intervals.push_back({percentile(p.estimate, 5), percentile(p.estimate, 95)});
    }
    prognostics::TimeOfEventPrediction q;
    q.prediction_time = static_cast<double>(p.cycle);
    q.times_of_event = p.estimate.end_of_life;
    q.weights.assign(q.times_of_event.size(), 1.0);
    profile.push_back(std::move(q));
  }
  line["inspections"] = inspections;
  line["updates"] = updates;
  line["estimates"] = estimates;
  auto al = prognostics::alpha_lambda(profile, T, prognostics::lambda_time(0.0, T, o.lambda),
                                      o.alpha, o.beta);
  if (al) {
    result.alpha_lambda_defined = true;
    result.alpha_lambda_met = al->met;
    line["alpha_lambda"] = {{"met", al->met},
                            {"prediction_cycle", core::whole(al->prediction_time)},
                            {"lower", core::whole(al->bounds.lower)},
                            {"upper", core::whole(al->bounds.upper)},
                            {"probability_in_bounds", core::fixed(al->probability_in_bounds, 3)}};
  } else {
    line["alpha_lambda"] = nullptr;
  }
  line["create_s"] = core::fixed(create_s, 2);
  line["apply_s"] = core::fixed(result.apply_s, 2);
  line["applied_cycles"] = static_cast<long long>(result.applied_cycles);
  line["wall_s"] = core::fixed(seconds_since(t_trial), 2);
  core::print_line(line);
  std::fflush(stdout);
  return result;
}

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double mean(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double sum = 0;
  for (double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

double max_of(const std::vector<double>& v) {
  return v.empty() ? std::numeric_limits<double>::quiet_NaN()
                   : *std::max_element(v.begin(), v.end());
}

int run(const Options& o) {
  const auto t_start = std::chrono::steady_clock::now();
  config::ConfigLimits limits;
  limits.max_memory_bytes = UINT64_MAX;
  auto loaded = config::load_config(o.config, limits);
  if (!loaded.ok()) {
    std::fprintf(stderr, "peritwin-bench prognostics: %s\n", loaded.error_text().c_str());
    return 3;
  }
  Setup s;
  const auto& details = loaded.config->details;
  const auto found = std::find_if(details.begin(), details.end(), [&](const auto& d) {
    return o.detail.empty() || d.id == o.detail;
  });
  if (found == details.end()) {
    std::fprintf(stderr, "peritwin-bench prognostics: no detail \"%s\" in %s\n", o.detail.c_str(),
                 o.config.c_str());
    return 2;
  }
  s.config = *found;
  config::DetailConfig& c = s.config;
  config::UncertaintyConfig& u = c.uncertainty;
  if (!u.enabled) {
    std::fprintf(stderr, "peritwin-bench prognostics: the detail has no [detail.uncertainty]\n");
    return 2;
  }
  if (c.life.reference_spectrum.empty()) {
    std::fprintf(stderr,
                 "peritwin-bench prognostics: the detail's [detail.life] reference_spectrum is "
                 "\"empirical\"; the bench needs blocks\n");
    return 2;
  }
  if (o.dx > 0) {
    // Another grid: A2 (and the prior's median) rescaled to the horizon by 000 Eq. (29).
    auto& strain = c.fatigue.strain;
    const double a2 =
        fatigue::a2_scaled(strain.A2, c.horizon_ratio * c.dx, c.horizon_ratio * o.dx, strain.m2);
    if (strain.A2 > 0) u.a2.median *= a2 / strain.A2;
    strain.A2 = a2;
    c.dx = o.dx;
  }
  if (o.life_dx > 0) {
    if (o.life_dx <= c.dx) {
      std::fprintf(stderr, "peritwin-bench prognostics: --life-dx must exceed the grid's dx\n");
      return 2;
    }
    c.life.dx = o.life_dx;
  }
  if (o.particles > 0) u.particles = o.particles;
  // The 1st … 99th percentiles (5, 50, 95 among them): the quantile representation α-λ reads.
  u.percentiles.clear();
  for (int p = 1; p <= 99; ++p) u.percentiles.push_back(p);
  s.spectrum = c.life.reference_spectrum;
  s.applied = s.spectrum;
  if (!o.history.empty()) {
    const auto format = o.history_format == "spectrum" ? loads::HistoryFormat::spectrum
                        : o.history_format == "series" ? loads::HistoryFormat::series
                                                       : loads::HistoryFormat::cycles;
    loads::SeriesRules rules;
    rules.gate = c.sensor.gate;
    rules.alpha_bin = c.sensor.alpha_bin;
    rules.compressed_bonds_fatigue = c.fatigue.mirrors_compressive_cycles();
    auto read = loads::read_blocks(o.history, format, rules);
    if (!read) {
      std::fprintf(stderr, "peritwin-bench prognostics: %s\n", read.error().message().c_str());
      return 2;
    }
    s.applied = std::move(read->blocks);
  }
  s.origin = c.life.crack_origin.empty() ? "longest" : c.life.crack_origin;
  if (u.a2.cov > 0) {
    auto p = prognostics::UncertainParameter::lognormal("a2", u.a2.median, u.a2.cov);
    if (!p) return 2;
    s.priors.push_back(*p);
  }
  if (u.load_scale.cov > 0) {
    auto p = prognostics::UncertainParameter::lognormal("load_scale", u.load_scale.median,
                                                        u.load_scale.cov);
    if (!p) return 2;
    s.priors.push_back(*p);
  }
  auto built = twin::DetailModel::build(c);
  if (!built) {
    std::fprintf(stderr, "peritwin-bench prognostics: %s\n", built.error().message().c_str());
    return 3;
  }
  s.nodes = (*built)->disc().num_nodes();
  s.bonds = static_cast<long long>((*built)->disc().num_bonds());
  // The nominal life: an engine at the prior's medians.
  const double a2_config = c.fatigue.strain.A2;
  // Sought as far as a truth: by passes until twin::kMaxSimulatedCycles (a pass without breaks
  // doubles the next; the same as the truths' run for a constant-amplitude load).
  {
    const auto engine = (*built)->make_engine(a2_config > 0 ? u.a2.median / a2_config : 1.0);
    if (!engine->initialize()) {
      std::fprintf(stderr, "peritwin-bench prognostics: %s\n", engine->failure_reason().c_str());
      return 3;
    }
    std::vector<core::LoadBlock> scaled = s.applied;
    for (auto& b : scaled) b.p_max *= u.load_scale.median;
    s.nominal_life = twin::run_to_end(*engine, scaled, twin::end_of_life_check(**built));
  }
  if (!std::isfinite(s.nominal_life)) {
    std::fprintf(stderr, "peritwin-bench prognostics: no end of life at the prior's medians\n");
    return 3;
  }
  built->reset();

  prognostics::Random stream(o.seed);
  std::vector<TrialResult> results;
  for (int t = 0; t < o.trials; ++t) {
    results.push_back(run_trial(s, o, t, stream));
    stream.jump();
  }

  // Summary.
  const std::size_t stages = static_cast<std::size_t>(o.inspections) + 1;
  core::JsonLine coverage = core::JsonLine::array(), errors = core::JsonLine::array(),
                 counts = core::JsonLine::array();
  std::vector<double> cov_by_stage(stages, std::numeric_limits<double>::quiet_NaN());
  std::vector<double> err_by_stage(stages, std::numeric_limits<double>::quiet_NaN());
  std::vector<double> observe_s, estimate_s, apply_s;
  int valid = 0, al_defined = 0, al_met = 0;
  std::int64_t cycles = 0;
  for (const TrialResult& r : results) {
    if (!r.valid) continue;
    ++valid;
    al_defined += r.alpha_lambda_defined;
    al_met += r.alpha_lambda_met;
    observe_s.insert(observe_s.end(), r.observe_s.begin(), r.observe_s.end());
    estimate_s.insert(estimate_s.end(), r.estimate_s.begin(), r.estimate_s.end());
    apply_s.push_back(r.apply_s);
    cycles += r.applied_cycles;
  }
  // Stage k: the estimate after the k-th inspection, over the trials that made k; "final": each
  // trial's estimate after its last inspection (at most --inspections; fewer when the truth
  // failed first).
  const auto stage = [&](std::size_t k, bool final, double& cov, double& err) {
    std::vector<prognostics::Interval> intervals;
    std::vector<double> truths, errs;
    for (const TrialResult& r : results) {
      if (!r.valid || (!final && r.errors.size() <= k)) continue;
      const std::size_t i = final ? r.errors.size() - 1 : k;
      intervals.push_back(r.intervals[i]);
      truths.push_back(r.truth);
      errs.push_back(r.errors[i]);
    }
    cov = std::numeric_limits<double>::quiet_NaN();
    if (auto f = prognostics::coverage(intervals, truths)) cov = *f;
    err = median(errs);
    return static_cast<long long>(truths.size());
  };
  for (std::size_t k = 0; k < stages; ++k) {
    const long long n = stage(k, false, cov_by_stage[k], err_by_stage[k]);
    coverage.push_back(core::fixed(cov_by_stage[k], 3));
    errors.push_back(core::significant(err_by_stage[k], 4));
    counts.push_back(n);
  }
  double cov_final = 0, err_final = 0;
  stage(0, true, cov_final, err_final);
  double apply_total = 0;
  for (double a : apply_s) apply_total += a;
  core::JsonLine line;
  line["bench"] = "prognostics";
  line["config"] = o.config;
  line["detail"] = c.id;
  line["history"] = o.history.empty() ? core::JsonLine(nullptr) : core::JsonLine(o.history);
  line["nodes"] = s.nodes;
  line["bonds"] = s.bonds;
  line["dx_m"] = core::significant(c.dx, 4);
  line["life_dx_m"] = core::significant(c.life.dx, 4);
  line["particles"] = static_cast<long long>(u.particles);
  line["trials"] = o.trials;
  line["valid_trials"] = valid;
  line["seed"] = static_cast<unsigned long long>(o.seed);
  line["ensemble_seed"] = static_cast<unsigned long long>(u.seed);
  line["prior"] = {{"a2_median", core::significant(u.a2.median, 5)},
                   {"a2_cov", u.a2.cov},
                   {"load_scale_median", u.load_scale.median},
                   {"load_scale_cov", u.load_scale.cov}};
  line["nominal_life"] = core::whole(s.nominal_life);
  line["inspections"] = o.inspections;
  line["interval"] = o.interval;
  line["basis"] = o.basis;
  line["sigma_m"] = o.sigma;
  line["random_detection"] = o.random_detection;
  line["trials_per_stage"] = counts;
  line["coverage_90"] = coverage;
  line["median_relative_error"] = errors;
  line["alpha_lambda"] = {
      {"alpha", o.alpha},
      {"lambda", o.lambda},
      {"beta", o.beta},
      {"defined", al_defined},
      {"met", al_met},
      {"fraction_met", core::fixed(static_cast<double>(al_met) / al_defined, 3)}};  // 0/0: null
  line["observe_s"] = {{"mean", core::fixed(mean(observe_s), 3)},
                       {"max", core::fixed(max_of(observe_s), 3)},
                       {"count", static_cast<long long>(observe_s.size())}};
  line["estimate_s"] = {{"mean", core::fixed(mean(estimate_s), 3)},
                        {"max", core::fixed(max_of(estimate_s), 3)},
                        {"count", static_cast<long long>(estimate_s.size())}};
  line["apply_s"] = core::fixed(apply_total, 2);
  line["applied_cycles"] = static_cast<long long>(cycles);
  line["coverage_90_final"] = core::fixed(cov_final, 3);
  line["median_relative_error_final"] = core::significant(err_final, 4);
  // The goals: after three inspections (or --inspections when fewer), over the trials
  // that made them; before any.
  const std::size_t goal_stage = std::min<std::size_t>(3, stages - 1);
  line["goals"] = {
      {"after_inspections", static_cast<long long>(goal_stage)},
      {"trials", counts[goal_stage]},
      {"median_error_le_0.10", err_by_stage[goal_stage] <= 0.10},
      {"coverage_ge_0.80", cov_by_stage[goal_stage] >= 0.80},
      {"prior_coverage_ge_0.80", cov_by_stage[0] >= 0.80},
  };
  line["peak_rss_mb"] = core::fixed(core::proc_status_mb("VmHWM"), 1);
  line["wall_s"] = core::fixed(seconds_since(t_start), 1);
  core::print_line(line);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench prognostics: the learning twin against hidden truths"};
  Options o;
  app.add_option("--config", o.config, "the detail's config (default: the B1 example)")
      ->check(CLI::ExistingFile);
  app.add_option("--detail", o.detail, "the detail's id (default: the first)");
  app.add_option("--history", o.history,
                 "the loads the truth and the twin get, repeated until the truth's end of life "
                 "(default: the reference spectrum; the estimates always use it)")
      ->check(CLI::ExistingFile);
  app.add_option("--format", o.history_format,
                 "--history's format: cycles (default), spectrum, series")
      ->check(CLI::IsMember({"cycles", "spectrum", "series"}));
  app.add_option("--trials", o.trials, "truths (default 20)")->check(CLI::Range(1, 100000));
  app.add_option("--particles", o.particles, "particles (default: the config's)")
      ->check(CLI::Range(std::int64_t{2}, std::int64_t{4096}));
  app.add_option("--seed", o.seed, "seed of the truths' stream (parameters, inspection noise)");
  app.add_option("--inspections", o.inspections, "inspections per trial (default 3)")
      ->check(CLI::Range(0, 1000));
  app.add_option("--interval", o.interval,
                 "inspection k at k x interval x the base life (default 0.2)")
      ->check(peritwin::core::finite_in(1e-6, 1.0));
  app.add_option("--basis", o.basis,
                 "base life of the schedule: nominal (the prior medians' life, default) or truth")
      ->check(CLI::IsMember({"nominal", "truth"}));
  app.add_option("--sigma", o.sigma, "inspection noise (m, default 3e-4)")
      ->check(peritwin::core::finite_in(1e-9, 1.0));
  app.add_option("--pod-a50", o.pod_a50, "POD a50 of a no-crack report (m, default 1e-3)")
      ->check(peritwin::core::finite_in(1e-9, 1.0));
  app.add_option("--pod-slope", o.pod_slope, "POD slope (default 3)")
      ->check(peritwin::core::finite_in(1e-6, 1e3));
  app.add_flag("--random-detection", o.random_detection,
               "a crack is found with probability POD(a) (default: whenever there is one)");
  app.add_option("--dx", o.dx, "grid spacing (m; A2 rescaled by 000 Eq. 29; default: config's)")
      ->check(peritwin::core::finite_in(1e-6, 1.0));
  app.add_option("--life-dx", o.life_dx, "sets [detail.life] dx (m, the coarser estimate grid)")
      ->check(peritwin::core::finite_in(1e-6, 1.0));
  app.add_option("--alpha", o.alpha, "alpha of alpha-lambda (default 0.2)")
      ->check(peritwin::core::finite_in(0.0, 10.0));
  app.add_option("--lambda", o.lambda, "lambda, a fraction of the true life (default 0.5)")
      ->check(peritwin::core::finite_in(0.0, 1.0));
  app.add_option("--beta", o.beta, "beta of alpha-lambda (default 0.5)")
      ->check(peritwin::core::finite_in(0.0, 1.0));
  bool no_lambda = false;
  app.add_flag("--no-lambda-estimate", no_lambda,
               "no extra estimate at lambda x the true life (alpha-lambda then uses the first "
               "inspection's at or after it)");
  CLI11_PARSE(app, argc, argv);
  o.lambda_estimate = !no_lambda;
  return run(o);
}
