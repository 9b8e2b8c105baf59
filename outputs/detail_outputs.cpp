#include "outputs/detail_outputs.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <system_error>

#include "outputs/damage_png.h"
#include "solver/statics/pd_strain.h"

namespace peritwin::outputs {

TimeSeriesRow results_row(const twin::Twin& twin) {
  TimeSeriesRow row;
  row.state_seq = twin.state_seq();
  row.total_cycles = twin.engine().total_cycles();
  row.broken_bonds = twin.broken_bonds();
  const twin::CrackReport& r = twin.cracks();
  if (!r.cracks.empty()) {
    const crack::FoundCrack& c = r.cracks.front().crack;
    row.crack_length_m = c.length;
    row.crack_projected_length_m = c.projected_length;
    row.tip_x = c.tips[0].position.x;
    row.tip_y = c.tips[0].position.y;
    row.kink_angle_rad = c.kink_angle;
  }
  row.crack_count = static_cast<std::int64_t>(r.cracks.size());
  for (const auto& rc : r.cracks) {
    for (std::size_t t = 0; t < rc.crack.tips.size(); ++t) {
      const auto& tip = rc.crack.tips[t];
      CrackRow c;
      c.state_seq = row.state_seq;
      c.crack_id = rc.crack.id;
      c.origin_kind = static_cast<std::int64_t>(rc.crack.origin);
      c.k_status = static_cast<std::int64_t>(rc.k[t].status);
      c.length_m = rc.crack.length;
      c.projected_length_m = rc.crack.projected_length;
      c.tip_x = tip.position.x;
      c.tip_y = tip.position.y;
      c.tip_angle_rad = std::atan2(tip.direction.y, tip.direction.x);
      c.k_i = rc.k[t].k_i;
      c.k_ii = rc.k[t].k_ii;
      row.cracks.push_back(c);
    }
  }
  row.k_i = r.k_i;
  row.k_ii = r.k_ii;
  row.remaining_cycles = twin.life().central;
  row.remaining_low = twin.life().low;
  row.remaining_high = twin.life().high;
  row.remaining_state_seq = twin.life().state_seq;
  return row;
}

core::LoadBlock snapshot_load(const twin::Twin& twin) {
  if (twin.last_block()) return *twin.last_block();
  core::LoadBlock load{1.0, 0.0, 0.0, 0};
  double largest = 0.0;
  for (const auto& b : twin.model().config().life.reference_spectrum) {
    if (b.p_max > largest) {
      largest = b.p_max;
      load = b;
    }
  }
  load.count = 0;
  return load;
}

SnapshotFields snapshot_fields(const twin::Twin& twin) {
  const statics::StaticSolver& solver = twin.engine().solver();
  const mesh::Discretization& disc = twin.model().disc();
  const std::size_t nodes = disc.position.size();
  const core::LoadBlock load = snapshot_load(twin);
  SnapshotFields out;
  out.attributes = {{"load_p_max_n", load.p_max}, {"load_alpha_rad", load.alpha}};
  auto vector_field = [&](std::string name, const std::vector<double>& u) {
    NodeField f{std::move(name), NodeField::Kind::vector, "m", std::vector<double>(3 * nodes)};
    for (std::size_t k = 0; k < nodes; ++k) {
      f.values[3 * k] = u[2 * k];
      f.values[3 * k + 1] = u[2 * k + 1];
    }
    return f;
  };
  std::vector<double> u;
  solver.displacement(load.p_max, load.alpha, u);
  out.fields.push_back(vector_field("displacement", u));
  // Each loaded basis at P_max, when there is more than the constant one.
  const std::array<std::pair<statics::Basis, const char*>, 3> bases{
      {{statics::basis_constant, "displacement_constant"},
       {statics::basis_cos, "displacement_cos"},
       {statics::basis_sin, "displacement_sin"}}};
  std::vector<std::pair<statics::Basis, const char*>> loaded;
  for (const auto& [basis, name] : bases) {
    const auto& ub = solver.basis_displacement(basis);
    if (std::any_of(ub.begin(), ub.end(), [](double v) { return v != 0.0; })) {
      loaded.emplace_back(basis, name);
    }
  }
  if (loaded.size() > 1 || (loaded.size() == 1 && loaded[0].first != statics::basis_constant)) {
    for (const auto& [basis, name] : loaded) {
      std::vector<double> ub = solver.basis_displacement(basis);
      for (double& v : ub) v *= load.p_max;
      out.fields.push_back(vector_field(name, ub));
    }
  }
  // 004 Eq. (6)-(7) on the displacement at the load.
  const auto strain = statics::pd_lagrange_strain(disc, solver.intact(), u);
  NodeField tensor{"strain", NodeField::Kind::tensor6, "1", std::vector<double>(6 * nodes, 0.0)};
  NodeField dilatation{"dilatation", NodeField::Kind::scalar, "1", std::vector<double>(nodes)};
  NodeField principal{"max_principal_strain", NodeField::Kind::scalar, "1",
                      std::vector<double>(nodes)};
  for (std::size_t k = 0; k < nodes; ++k) {
    tensor.values[6 * k] = strain[k].xx;  // Tensor6: xx, xy, xz, yy, yz, zz
    tensor.values[6 * k + 1] = strain[k].xy;
    tensor.values[6 * k + 3] = strain[k].yy;
    dilatation.values[k] = strain[k].dilatation();
    principal.values[k] = strain[k].max_principal();
  }
  out.fields.push_back(std::move(tensor));
  out.fields.push_back(std::move(dilatation));
  out.fields.push_back(std::move(principal));
  return out;
}

NamedRow gauge_row(const twin::Twin& twin) {
  const auto& gauges = twin.model().gauges();
  NamedRow row;
  row.ints = {{"state_seq", twin.state_seq()}, {"total_cycles", twin.engine().total_cycles()}};
  row.units = {{"total_cycles", "cycles"}};
  const auto influences = twin.gauge_influences();
  const twin::GaugeResiduals residuals = twin.gauge_residuals().for_gauges(gauges);
  constexpr std::array<const char*, 3> kBases{"_per_constant", "_per_cos", "_per_sin"};
  for (std::size_t k = 0; k < gauges.size(); ++k) {
    const std::string& id = gauges[k].config.id;
    for (std::size_t b = 0; b < kBases.size(); ++b) {
      row.doubles.emplace_back(id + kBases[b], influences.at(k)[b]);
      row.units.emplace_back(id + kBases[b], "1/N");
    }
    row.doubles.emplace_back(id + "_residual", residuals.residual[k]);
    row.doubles.emplace_back(id + "_sigma", residuals.sigma[k]);
    row.ints.emplace_back(id + "_in_a_row", residuals.in_a_row[k]);
  }
  return row;
}

namespace {
std::unique_ptr<ResultsWriter> open_writer(const std::filesystem::path& h5,
                                           const twin::Twin& twin) {
  ResultsOptions options;
  options.detail = twin.detail_id();
  auto writer = std::make_unique<ResultsWriter>(h5, options);
  std::vector<double> x, y;
  for (const auto& p : twin.model().disc().position) {
    x.push_back(p.x);
    y.push_back(p.y);
  }
  writer->write_mesh(x, y);
  return writer;
}
}  // namespace

DetailOutputs::DetailOutputs(const twin::Twin& twin) : id_(twin.detail_id()) {
  const auto& config = twin.model().config();
  dir_ = config.output.directory;
  h5_path_ = dir_ / (id_ + ".h5");
  try {
    std::filesystem::create_directories(dir_);
    try {
      writer_ = open_writer(h5_path_, twin);
    } catch (const std::exception& e) {
      // Another mesh (the config changed) or a damaged file: keep it aside, start a new one.
      writer_.reset();
      if (!std::filesystem::exists(h5_path_)) throw;
      const auto aside = std::filesystem::path(h5_path_.string() + ".old");
      spdlog::warn("[{}] {}: {}; moved to {}", id_, h5_path_.string(), e.what(), aside.string());
      std::filesystem::rename(h5_path_, aside);
      writer_ = open_writer(h5_path_, twin);
    }
    keep_an_earlier_history(twin);
    writer_->rewind_to(twin.state_seq() - 1);
    std::vector<GaugeInfo> gauges;
    for (const auto& g : twin.model().gauges()) {
      const config::GaugeConfig& c = g.config;
      gauges.push_back({c.id, c.at.x, c.at.y, c.angle, c.length, c.noise});
    }
    writer_->describe_gauges(gauges);
    for (const auto& s : writer_->snapshots()) last_snapshot_seq_ = s.state_seq;
    for (const auto& row : writer_->read_rows()) history_.add(row);
    const TimeSeriesRow row = results_row(twin);
    writer_->append(row);
    history_.add(row);
    record_ensemble(twin);
    record_gauges(twin, false);
    const auto every = config.output.field_every_batches;
    if (every > 0 && twin.state_seq() % every == 0) snapshot(twin);
    spdlog::info("[{}] results: {} ({} rows)", id_, h5_path_.string(), writer_->rows());
  } catch (const std::exception& e) {
    disable("cannot open the results file", e);
  }
}

void DetailOutputs::keep_an_earlier_history(const twin::Twin& twin) {
  // A start from the initial state (no checkpoint: a fresh run, or a restart before the first
  // checkpoint) over a file with later states begins a new history. rewind_to() would cut the old
  // one to its first row without a word: keep it whole under the first free <id>.run<N>.h5.
  if (twin.state_seq() != 0) return;  // a resume: the rows after the checkpoint are re-applied
  std::int64_t last = 0;
  for (const auto& row : writer_->read_rows()) last = std::max(last, row.state_seq);
  if (last == 0) return;
  const std::uint64_t rows = writer_->rows();
  writer_.reset();
  std::filesystem::path kept;
  for (int n = 1;; ++n) {
    kept = dir_ / (id_ + ".run" + std::to_string(n) + ".h5");
    if (!std::filesystem::exists(kept)) break;
  }
  std::filesystem::rename(h5_path_, kept);
  spdlog::warn(
      "[{}] {} held an earlier run's history ({} rows, to state_seq {}); this run starts "
      "from the initial state, so that file is kept as {} and a new one begins",
      id_, h5_path_.string(), rows, last, kept.string());
  writer_ = open_writer(h5_path_, twin);
}

void DetailOutputs::disable(const char* what, const std::exception& e) {
  spdlog::error("[{}] {} {}: {}; results of this detail are off from now on", id_, what,
                h5_path_.string(), e.what());
  writer_.reset();
}

void DetailOutputs::snapshot(const twin::Twin& twin) {
  writer_->write_snapshot(twin.state_seq(), twin.engine().total_cycles(),
                          std::span<const double>(twin.engine().node_damage()),
                          snapshot_fields(twin));
  last_snapshot_seq_ = twin.state_seq();
  pictures(twin);
}

namespace {
/// "p05", "p50", "p95" (a whole percentile, two digits at least), else "p<%g>" with '.' as '_'.
std::string percentile_key(double q) {
  char buf[32];
  if (q == std::floor(q) && q >= 0 && q < 100) {
    std::snprintf(buf, sizeof buf, "p%02d", static_cast<int>(q));
  } else {
    std::snprintf(buf, sizeof buf, "p%g", q);
  }
  std::string key = buf;
  std::replace(key.begin(), key.end(), '.', '_');
  return key;
}
}  // namespace

void DetailOutputs::record_ensemble(const twin::Twin& twin) {
  const twin::Ensemble* ensemble = twin.ensemble();
  const auto estimate = twin.ensemble_estimate();
  if (ensemble == nullptr || !estimate) return;
  NamedRow row;
  row.ints = {{"state_seq", twin.state_seq()},
              {"total_cycles", twin.engine().total_cycles()},
              {"estimate_cycle", ensemble->estimate_cycle()},
              {"observation_count", static_cast<std::int64_t>(ensemble->observations().size())},
              {"particles", static_cast<std::int64_t>(ensemble->size())}};
  row.doubles = {{"effective_sample_size", estimate->effective_sample_size},
                 {"horizon_cycles", estimate->horizon_cycles},
                 {"probability_within_horizon", estimate->probability_within_horizon}};
  row.units = {
      {"total_cycles", "cycles"}, {"estimate_cycle", "cycles"}, {"horizon_cycles", "cycles"}};
  std::string percentiles;
  for (std::size_t k = 0; k < estimate->percentiles.size(); ++k) {
    const std::string key = percentile_key(estimate->percentiles[k]);
    char value[32];
    std::snprintf(value, sizeof value, "%g", estimate->percentiles[k]);
    percentiles += (k ? "," : "") + std::string(value);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    row.doubles.emplace_back("end_of_life_" + key,
                             k < estimate->end_of_life.size() ? estimate->end_of_life[k] : nan);
    row.doubles.emplace_back("remaining_" + key,
                             k < estimate->remaining.size() ? estimate->remaining[k] : nan);
    row.units.emplace_back("end_of_life_" + key, "cycles");
    row.units.emplace_back("remaining_" + key, "cycles");
  }
  for (const auto& p : estimate->posterior) {
    row.doubles.emplace_back(p.name + "_median", p.median);
    row.doubles.emplace_back(p.name + "_cov", p.coefficient_of_variation);
  }
  writer_->append_named("ensemble", row, {{"percentiles", percentiles}});
  // The observations taken in since the last row (all of them in a new file; after a rewind,
  // those whose rows were dropped).
  const auto& records = ensemble->observations();
  for (auto i = static_cast<std::size_t>(writer_->named_rows("observations")); i < records.size();
       ++i) {
    const twin::ObservationRecord& r = records[i];
    const messages::Observation& o = r.observation;
    NamedRow obs;
    obs.ints = {{"index", static_cast<std::int64_t>(i)},
                {"state_seq", twin.state_seq()},
                {"cycle", o.cycle},
                {"taken_at", r.taken_at},
                {"kind", o.kind == messages::ObservationKind::no_crack           ? 2
                         : o.kind == messages::ObservationKind::gauge_compliance ? 3
                                                                                 : 1},
                {"seq", o.seq},
                {"resampled", r.update.resampled ? 1 : 0}};
    obs.doubles = {{"length_m", o.length_m},
                   {"sigma_m", o.sigma_m},
                   {"pod_a50_m", o.pod_a50_m},
                   {"pod_slope", o.pod_slope},
                   {"predicted_median_m", r.update.predicted_median_m},
                   {"log_evidence", r.update.log_evidence},
                   {"ess_before_resampling", r.update.ess_before_resampling}};
    obs.strings = {{"origin", o.origin}, {"source", o.source_id}};
    obs.units = {{"cycle", "cycles"},   {"taken_at", "cycles"},
                 {"length_m", "m"},     {"sigma_m", "m"},
                 {"pod_a50_m", "m"},    {"predicted_median_m", "m"},
                 {"log_evidence", "1"}, {"ess_before_resampling", "1"}};
    writer_->append_named("observations", obs);
  }
}

void DetailOutputs::record_gauges(const twin::Twin& twin, bool same_state) {
  const auto& gauges = twin.model().gauges();
  if (gauges.empty()) return;
  const twin::GaugeResiduals r = twin.gauge_residuals().for_gauges(gauges);
  std::vector<double> residuals;
  for (std::size_t k = 0; k < gauges.size(); ++k) {
    residuals.push_back(r.residual[k]);
    residuals.push_back(r.sigma[k]);
    residuals.push_back(static_cast<double>(r.in_a_row[k]));
  }
  const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
  if (same_state && std::equal(residuals.begin(), residuals.end(), last_gauge_residuals_.begin(),
                               last_gauge_residuals_.end(), same)) {
    return;
  }
  writer_->append_named("gauges", gauge_row(twin));
  last_gauge_residuals_ = std::move(residuals);
}

void DetailOutputs::record(const twin::Twin& twin) {
  if (!writer_) return;
  try {
    // Again at the same state (after an observation, or a new estimate of the ensemble): the
    // time series has it; the ensemble's row and the observations only.
    if (!history_.state_seq.empty() && history_.state_seq.back() == twin.state_seq()) {
      record_ensemble(twin);
      record_gauges(twin, true);
      return;
    }
    const TimeSeriesRow row = results_row(twin);
    writer_->append(row);
    history_.add(row);
    record_ensemble(twin);
    record_gauges(twin, false);
    const auto every = twin.model().config().output.field_every_batches;
    if (every > 0 && twin.state_seq() % every == 0) snapshot(twin);
  } catch (const std::exception& e) {
    disable("cannot write", e);
  }
}

std::filesystem::path DetailOutputs::damage_png() const { return dir_ / (id_ + "-damage.png"); }
std::filesystem::path DetailOutputs::crack_png() const {
  return dir_ / (id_ + "-crack-length.png");
}

void DetailOutputs::finish(const twin::Twin& twin) {
  if (!writer_) return;
  try {
    if (last_snapshot_seq_ != twin.state_seq()) snapshot(twin);
    writer_->close();
    writer_.reset();
  } catch (const std::exception& e) {
    disable("cannot finish", e);
    return;
  }
  if (twin.model().config().output.png) {
    spdlog::info("[{}] pictures: {} {}", id_, damage_png().string(), crack_png().string());
  }
}

void DetailOutputs::PictureHistory::add(const TimeSeriesRow& row) {
  state_seq.push_back(row.state_seq);
  cycles.push_back(static_cast<double>(row.total_cycles));
  lengths_m.push_back(row.crack_length_m);
  // A new estimate: its end of life counts from the state it was made on.
  if (row.remaining_state_seq >= 0 && row.remaining_state_seq != last_estimate_seq) {
    const auto it = std::lower_bound(state_seq.begin(), state_seq.end(), row.remaining_state_seq);
    if (it != state_seq.end() && *it == row.remaining_state_seq) {
      const auto i = static_cast<std::size_t>(it - state_seq.begin());
      predictions.push_back(
          {cycles[i], lengths_m[i], row.remaining_cycles, row.remaining_low, row.remaining_high});
      last_estimate_seq = row.remaining_state_seq;
    }
  }
  // Each crack tip's track over the states: the crack paths of the damage map.
  std::map<std::int64_t, int> tip_of;  // the next tip index per crack in this row
  for (const auto& c : row.cracks) {
    const int tip = tip_of[c.crack_id]++;
    if (!(c.length_m > 0.0) || !std::isfinite(c.tip_x) || !std::isfinite(c.tip_y)) continue;
    auto& track = tip_tracks[{c.crack_id, tip}];
    if (track.empty() || track.back().x != c.tip_x || track.back().y != c.tip_y) {
      track.push_back({c.tip_x, c.tip_y});
    }
  }
}

void DetailOutputs::pictures(const twin::Twin& twin) {
  const auto& config = twin.model().config();
  if (!config.output.png) return;
  try {
    const auto& disc = twin.model().disc();
    std::vector<double> x, y;
    for (const auto& p : disc.position) {
      x.push_back(p.x);
      y.push_back(p.y);
    }
    const std::int64_t cycles = twin.engine().total_cycles();
    const double length_mm = history_.lengths_m.empty() ? 0.0 : 1e3 * history_.lengths_m.back();
    char title[160];
    std::snprintf(title, sizeof title, "%s   N = %lld cycles   crack %.2f mm", id_.c_str(),
                  static_cast<long long>(cycles), length_mm);
    DamageMap map;
    map.title = title;
    std::vector<std::uint8_t> not_cut(disc.bond_precut.size());
    std::transform(disc.bond_precut.begin(), disc.bond_precut.end(), not_cut.begin(),
                   [](std::uint8_t cut) { return static_cast<std::uint8_t>(cut == 0); });
    model::damage_index(disc, not_cut, map.notch_damage);
    for (const auto& notch : config.geometry.notches) {
      std::vector<MapPoint> line;
      for (const auto& p : notch.path) line.push_back({p.x, p.y});
      map.notches.push_back(std::move(line));
    }
    for (const auto& [key, track] : history_.tip_tracks) map.crack_paths.push_back(track);
    for (const auto& g : twin.model().gauges()) {
      map.gauges.push_back(
          {g.config.id, {g.config.at.x, g.config.at.y}, g.config.angle, g.config.length});
    }
    write_damage_map_png(damage_png(), x, y, twin.engine().node_damage(), disc.dx, map);

    CrackGrowthPlot plot;
    plot.title = id_ + "   crack length and predicted end of life";
    plot.cycles = history_.cycles;
    plot.lengths_m = history_.lengths_m;
    plot.predictions = history_.predictions;
    if (config.life.criterion == config::LifeCriterion::crack_length) {
      plot.critical_length_m = config.life.critical_crack_length;
    }
    plot.end_of_life_cycle = twin.end_of_life_cycle();
    write_crack_growth_png(crack_png(), plot);
  } catch (const std::exception& e) {
    spdlog::error("[{}] cannot write the PNG pictures: {}", id_, e.what());
  }
}

}  // namespace peritwin::outputs
