// Twin <-> CheckpointData (twin/checkpoint_data.h), format_version Twin::kCheckpointFormat.
// The keys come from the two field tables: Twin::for_each_own_field (the twin's bookkeeping) and
// peritwin::for_each_field of EngineState (the engine's history). A field of type
//   double / int64 / bool / Failure   -> f64 or i64 scalar <key> (bool and Failure as int64)
//   string                            -> string <key>
//   LoadBlock                         -> f64 scalars <key>_p_max, <key>_r, <key>_alpha, i64
//   <key>_count optional<LoadBlock>               -> i64 <key>_present and the LoadBlock keys
//   vector<double | int64 | uint8>    -> array <key>
//   vector<BreakEvent>                -> i64 arrays <key>_cycle, <key>_bond, u8 array <key>_cause
//   map<string, int64> (seq by source)-> string <key>_ids (ids joined by '\n'; ids are printable
//                                        ASCII without blanks) and i64 array <key>_seq
//   HistoryBySource                   -> string <key>_ids as above, i64 arrays
//                                        <key>_fingerprint (the bits) and <key>_start; optional:
//                                        a checkpoint written before them (message set version 7)
//                                        restores with no histories (same format_version, whose
//                                        other keys mean what they meant)
//   GaugeResiduals                    -> string <key>_ids (as above), f64 arrays <key>_residual,
//                                        <key>_sigma, i64 array <key>_in_a_row; optional: a
//                                        checkpoint written before gauges (issue 33) has none
//   RollingSpectrum                   -> f64 arrays <key>_p_max, <key>_r, <key>_alpha, i64
//   <key>_count
// With a learning ensemble (Twin::ensemble(), twin/ensemble.h), its EnsembleCheckpoint under
// "ensemble_*" keys (write_ensemble below) and each particle's EngineState under the engine's keys
// prefixed "particle<i>_".
// plus the header: strings detail_id and blas_kernel (not restored: the daemon compares it on
// resume, the state's last bits depend on it), i64 signature (DetailModel::signature's bits).
#include <bit>
#include <sstream>

#include "core/blas_kernel.h"
#include "twin/twin.h"

namespace peritwin::twin {

namespace {

std::string key_of(std::string_view key, std::string_view suffix) {
  return std::string(key) + std::string(suffix);
}

/// The ids of a <key>_ids string (joined by '\n').
std::vector<std::string> split_ids(const std::string& ids) {
  std::vector<std::string> split;
  if (!ids.empty()) {
    std::istringstream in(ids);
    for (std::string id; std::getline(in, id, '\n');) split.push_back(id);
  }
  return split;
}

/// Puts every field it visits into a CheckpointData under the keys of the file comment.
struct CheckpointWriter {
  CheckpointData& d;

  void put(std::string_view key, double v) { d.f64_scalars[std::string(key)] = v; }
  void put(std::string_view key, std::int64_t v) { d.i64_scalars[std::string(key)] = v; }
  void put(std::string_view key, bool v) { put(key, std::int64_t{v ? 1 : 0}); }
  void put(std::string_view key, Failure v) { put(key, static_cast<std::int64_t>(v)); }
  void put(std::string_view key, const std::string& v) { d.strings[std::string(key)] = v; }
  void put(std::string_view key, const core::LoadBlock& b) {
    put(key_of(key, "_p_max"), b.p_max);
    put(key_of(key, "_r"), b.r);
    put(key_of(key, "_alpha"), b.alpha);
    put(key_of(key, "_count"), b.count);
  }
  void put(std::string_view key, const std::optional<core::LoadBlock>& b) {
    put(key_of(key, "_present"), b.has_value());
    put(key, b.value_or(core::LoadBlock{}));
  }
  void put(std::string_view key, const std::vector<double>& v) {
    d.f64_arrays[std::string(key)] = v;
  }
  void put(std::string_view key, const std::vector<std::int64_t>& v) {
    d.i64_arrays[std::string(key)] = v;
  }
  void put(std::string_view key, const std::vector<std::uint8_t>& v) {
    d.u8_arrays[std::string(key)] = v;
  }
  void put(std::string_view key, const std::vector<fatigue::BreakEvent>& events) {
    std::vector<std::int64_t> cycle, bond;
    std::vector<std::uint8_t> cause;
    for (const auto& e : events) {
      cycle.push_back(e.cycle);
      bond.push_back(e.bond);
      cause.push_back(static_cast<std::uint8_t>(e.cause));
    }
    put(key_of(key, "_cycle"), cycle);
    put(key_of(key, "_bond"), bond);
    put(key_of(key, "_cause"), cause);
  }
  void put(std::string_view key, const std::map<std::string, std::int64_t>& applied) {
    std::string ids;
    std::vector<std::int64_t> seqs;
    for (const auto& [id, seq] : applied) {
      if (!ids.empty()) ids += '\n';
      ids += id;
      seqs.push_back(seq);
    }
    put(key_of(key, "_ids"), ids);
    put(key_of(key, "_seq"), seqs);
  }
  void put(std::string_view key, const HistoryBySource& histories) {
    std::string ids;
    std::vector<std::int64_t> fingerprints, starts;
    for (const auto& [id, history] : histories) {
      if (!ids.empty()) ids += '\n';
      ids += id;
      fingerprints.push_back(std::bit_cast<std::int64_t>(history.fingerprint));
      starts.push_back(history.start);
    }
    put(key_of(key, "_ids"), ids);
    put(key_of(key, "_fingerprint"), fingerprints);
    put(key_of(key, "_start"), starts);
  }
  void put(std::string_view key, const GaugeResiduals& r) {
    std::string ids;
    for (const auto& id : r.ids) ids += (ids.empty() ? "" : "\n") + id;
    put(key_of(key, "_ids"), ids);
    put(key_of(key, "_residual"), r.residual);
    put(key_of(key, "_sigma"), r.sigma);
    put(key_of(key, "_in_a_row"), r.in_a_row);
  }
  void put(std::string_view key, const RollingSpectrum& spectrum) {
    std::vector<double> p, r, a;
    std::vector<std::int64_t> n;
    for (const auto& b : spectrum.blocks()) {
      p.push_back(b.p_max);
      r.push_back(b.r);
      a.push_back(b.alpha);
      n.push_back(b.count);
    }
    put(key_of(key, "_p_max"), p);
    put(key_of(key, "_r"), r);
    put(key_of(key, "_alpha"), a);
    put(key_of(key, "_count"), n);
  }
};

/// Takes every field it visits out of a CheckpointData; collects the keys it does not find and
/// the entries that do not fit (ok() says whether all went well).
struct CheckpointReader {
  const CheckpointData& d;
  std::string missing;
  std::string bad;

  template <class Map>
  const typename Map::mapped_type* find(const Map& map, const std::string& key) {
    const auto it = map.find(key);
    if (it != map.end()) return &it->second;
    if (!missing.empty()) missing += ", ";
    missing += key;
    return nullptr;
  }
  template <class Map, class T>
  void take(const Map& map, std::string_view key, T& out) {
    if (const auto* v = find(map, std::string(key))) out = *v;
  }
  void get(std::string_view key, double& v) { take(d.f64_scalars, key, v); }
  void get(std::string_view key, std::int64_t& v) { take(d.i64_scalars, key, v); }
  void get(std::string_view key, bool& v) {
    std::int64_t i = 0;
    get(key, i);
    v = i != 0;
  }
  void get(std::string_view key, Failure& v) {
    std::int64_t i = 0;
    get(key, i);
    v = static_cast<Failure>(i);
  }
  void get(std::string_view key, std::string& v) { take(d.strings, key, v); }
  void get(std::string_view key, core::LoadBlock& b) {
    get(key_of(key, "_p_max"), b.p_max);
    get(key_of(key, "_r"), b.r);
    get(key_of(key, "_alpha"), b.alpha);
    get(key_of(key, "_count"), b.count);
  }
  void get(std::string_view key, std::optional<core::LoadBlock>& b) {
    bool present = false;
    core::LoadBlock block;
    get(key_of(key, "_present"), present);
    get(key, block);
    b = present ? std::optional<core::LoadBlock>(block) : std::nullopt;
  }
  void get(std::string_view key, std::vector<double>& v) { take(d.f64_arrays, key, v); }
  void get(std::string_view key, std::vector<std::int64_t>& v) { take(d.i64_arrays, key, v); }
  void get(std::string_view key, std::vector<std::uint8_t>& v) { take(d.u8_arrays, key, v); }
  void get(std::string_view key, std::vector<fatigue::BreakEvent>& events) {
    std::vector<std::int64_t> cycle, bond;
    std::vector<std::uint8_t> cause;
    get(key_of(key, "_cycle"), cycle);
    get(key_of(key, "_bond"), bond);
    get(key_of(key, "_cause"), cause);
    if (cycle.size() != bond.size() || cause.size() != bond.size()) {
      bad = std::string(key) + " arrays of different lengths";
      return;
    }
    events.clear();
    for (std::size_t k = 0; k < bond.size(); ++k) {
      events.push_back({cycle[k], static_cast<mesh::BondIndex>(bond[k]),
                        static_cast<fatigue::BreakCause>(cause[k])});
      if (bond[k] < 0 || bond[k] > std::numeric_limits<mesh::BondIndex>::max())
        bad = "event bond out of range";
    }
  }
  void get(std::string_view key, std::map<std::string, std::int64_t>& applied) {
    std::string ids;
    std::vector<std::int64_t> seqs;
    get(key_of(key, "_ids"), ids);
    get(key_of(key, "_seq"), seqs);
    const std::vector<std::string> split = split_ids(ids);
    if (split.size() != seqs.size()) {
      bad = std::string(key) + "_ids and " + std::string(key) + "_seq disagree";
      return;
    }
    applied.clear();
    for (std::size_t k = 0; k < split.size(); ++k) applied[split[k]] = seqs[k];
  }
  void get(std::string_view key, HistoryBySource& histories) {
    histories.clear();
    if (!d.strings.contains(key_of(key, "_ids"))) return;  // written before them: none known
    std::string ids;
    std::vector<std::int64_t> fingerprints, starts;
    get(key_of(key, "_ids"), ids);
    get(key_of(key, "_fingerprint"), fingerprints);
    get(key_of(key, "_start"), starts);
    const std::vector<std::string> split = split_ids(ids);
    if (split.size() != fingerprints.size() || split.size() != starts.size()) {
      bad = std::string(key) + "_ids, " + std::string(key) + "_fingerprint and " +
            std::string(key) + "_start disagree";
      return;
    }
    for (std::size_t k = 0; k < split.size(); ++k) {
      histories[split[k]] = {std::bit_cast<std::uint64_t>(fingerprints[k]), starts[k]};
    }
  }
  void get(std::string_view key, GaugeResiduals& r) {
    r = GaugeResiduals{};
    if (!d.strings.contains(key_of(key, "_ids"))) return;  // written before gauges (issue 33)
    std::string ids;
    get(key_of(key, "_ids"), ids);
    get(key_of(key, "_residual"), r.residual);
    get(key_of(key, "_sigma"), r.sigma);
    get(key_of(key, "_in_a_row"), r.in_a_row);
    r.ids = ids.empty() ? std::vector<std::string>{} : split_ids(ids);
    if (r.ids.size() != r.residual.size() || r.ids.size() != r.sigma.size() ||
        r.ids.size() != r.in_a_row.size()) {
      bad = std::string(key) + "_ids, _residual, _sigma and _in_a_row disagree";
    }
  }
  void get(std::string_view key, RollingSpectrum& spectrum) {
    std::vector<double> p, r, a;
    std::vector<std::int64_t> n;
    get(key_of(key, "_p_max"), p);
    get(key_of(key, "_r"), r);
    get(key_of(key, "_alpha"), a);
    get(key_of(key, "_count"), n);
    if (r.size() != p.size() || a.size() != p.size() || n.size() != p.size()) {
      bad = std::string(key) + " arrays of different lengths";
      return;
    }
    std::vector<core::LoadBlock> blocks;
    for (std::size_t k = 0; k < p.size(); ++k) blocks.push_back({p[k], r[k], a[k], n[k]});
    spectrum.assign(std::move(blocks));
  }
};

/// The string <key> of ids joined by '\n' (each without one: check_observation_message).
std::string join_lines(const std::vector<std::string>& lines) {
  std::string joined;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i > 0) joined += '\n';
    joined += lines[i];
  }
  return joined;
}

std::string particle_key(std::size_t i, std::string_view key) {
  return "particle" + std::to_string(i) + "_" + std::string(key);
}

void write_ensemble(CheckpointWriter& w, const EnsembleCheckpoint& e) {
  w.put("ensemble_filter", e.filter);
  w.put("ensemble_a2_factor", e.a2_factor);
  w.put("ensemble_load_scale", e.load_scale);
  w.put("ensemble_predicted_end", e.predicted_end);
  w.put("ensemble_ended_at", e.ended_at);
  w.put("ensemble_total_cycles", e.total_cycles);
  w.put("ensemble_estimate_cycle", e.estimate_cycle);
  std::vector<std::string> sources, origins;
  std::vector<std::int64_t> seq, cycle, taken_at;
  std::vector<std::uint8_t> kind, resampled;
  std::vector<double> length, sigma, a50, slope, evidence, ess, predicted;
  for (const ObservationRecord& r : e.observations) {
    const messages::Observation& o = r.observation;
    sources.push_back(o.source_id);
    origins.push_back(o.origin);
    seq.push_back(o.seq);
    cycle.push_back(o.cycle);
    taken_at.push_back(r.taken_at);
    kind.push_back(static_cast<std::uint8_t>(o.kind));
    resampled.push_back(r.update.resampled ? 1 : 0);
    length.push_back(o.length_m);
    sigma.push_back(o.sigma_m);
    a50.push_back(o.pod_a50_m);
    slope.push_back(o.pod_slope);
    evidence.push_back(r.update.log_evidence);
    ess.push_back(r.update.ess_before_resampling);
    predicted.push_back(r.update.predicted_median_m);
  }
  w.put("observation_source", join_lines(sources));
  w.put("observation_origin", join_lines(origins));
  w.put("observation_seq", seq);
  w.put("observation_cycle", cycle);
  w.put("observation_taken_at", taken_at);
  w.put("observation_kind", kind);
  w.put("observation_resampled", resampled);
  w.put("observation_length_m", length);
  w.put("observation_sigma_m", sigma);
  w.put("observation_pod_a50_m", a50);
  w.put("observation_pod_slope", slope);
  w.put("observation_log_evidence", evidence);
  w.put("observation_ess", ess);
  w.put("observation_predicted_m", predicted);
  // Gauge observations (issue 33): per observation its gauge count and angle, the gauges
  // flattened in that order.
  std::vector<std::int64_t> gauge_count;
  std::vector<std::string> gauge_ids;
  std::vector<double> gauge_angle, compliance, gauge_sigma, gauge_model;
  std::vector<std::uint8_t> identifies;
  for (const ObservationRecord& r : e.observations) {
    gauge_count.push_back(static_cast<std::int64_t>(r.observation.gauges.size()));
    gauge_angle.push_back(r.observation.gauge_angle_rad);
    for (const auto& g : r.observation.gauges) {
      gauge_ids.push_back(g.id);
      compliance.push_back(g.compliance);
      gauge_sigma.push_back(g.sigma);
      gauge_model.push_back(g.model);
      identifies.push_back(g.identifies ? 1 : 0);
    }
  }
  w.put("observation_gauge_count", gauge_count);
  w.put("observation_gauge_angle", gauge_angle);
  w.put("observation_gauge_ids", join_lines(gauge_ids));
  w.put("observation_gauge_compliance", compliance);
  w.put("observation_gauge_sigma", gauge_sigma);
  w.put("observation_gauge_model", gauge_model);
  w.put("observation_gauge_identifies", identifies);
  for (std::size_t i = 0; i < e.engines.size(); ++i) {
    fatigue::for_each_field(e.engines[i], [&](std::string_view key, const auto& field) {
      w.put(particle_key(i, key), field);
    });
  }
}

/// The ensemble of `particles` particles back from its keys; `r.missing`/`r.bad` say what failed.
EnsembleCheckpoint read_ensemble(CheckpointReader& r, std::size_t particles) {
  EnsembleCheckpoint e;
  r.get("ensemble_filter", e.filter);
  r.get("ensemble_a2_factor", e.a2_factor);
  r.get("ensemble_load_scale", e.load_scale);
  r.get("ensemble_predicted_end", e.predicted_end);
  r.get("ensemble_ended_at", e.ended_at);
  r.get("ensemble_total_cycles", e.total_cycles);
  r.get("ensemble_estimate_cycle", e.estimate_cycle);
  std::string sources, origins;
  std::vector<std::int64_t> seq, cycle, taken_at;
  std::vector<std::uint8_t> kind, resampled;
  std::vector<double> length, sigma, a50, slope, evidence, ess, predicted;
  r.get("observation_source", sources);
  r.get("observation_origin", origins);
  r.get("observation_seq", seq);
  r.get("observation_cycle", cycle);
  r.get("observation_taken_at", taken_at);
  r.get("observation_kind", kind);
  r.get("observation_resampled", resampled);
  r.get("observation_length_m", length);
  r.get("observation_sigma_m", sigma);
  r.get("observation_pod_a50_m", a50);
  r.get("observation_pod_slope", slope);
  r.get("observation_log_evidence", evidence);
  r.get("observation_ess", ess);
  r.get("observation_predicted_m", predicted);
  const std::vector<std::string> source_list = split_ids(sources);
  const std::vector<std::string> origin_list = split_ids(origins);
  const std::size_t n = seq.size();
  for (std::size_t size : {source_list.size(), origin_list.size(), cycle.size(), taken_at.size(),
                           kind.size(), resampled.size(), length.size(), sigma.size(), a50.size(),
                           slope.size(), evidence.size(), ess.size(), predicted.size()}) {
    if (size != n) r.bad = "observation arrays of different lengths";
  }
  if (r.bad.empty()) {
    for (std::size_t k = 0; k < n; ++k) {
      ObservationRecord rec;
      messages::Observation& o = rec.observation;
      o.source_id = source_list[k];
      o.origin = origin_list[k];
      o.seq = seq[k];
      o.cycle = cycle[k];
      o.kind = kind[k] == static_cast<std::uint8_t>(messages::ObservationKind::no_crack)
                   ? messages::ObservationKind::no_crack
               : kind[k] == static_cast<std::uint8_t>(messages::ObservationKind::gauge_compliance)
                   ? messages::ObservationKind::gauge_compliance
                   : messages::ObservationKind::crack_length;
      o.length_m = length[k];
      o.sigma_m = sigma[k];
      o.pod_a50_m = a50[k];
      o.pod_slope = slope[k];
      rec.taken_at = taken_at[k];
      rec.update = {cycle[k], evidence[k], ess[k], resampled[k] != 0, predicted[k]};
      e.observations.push_back(std::move(rec));
    }
  }
  // Gauge observations: optional (a checkpoint written before gauges has none).
  if (r.bad.empty() && r.d.strings.contains("observation_gauge_ids")) {
    std::vector<std::int64_t> gauge_count;
    std::string gauge_ids;
    std::vector<double> gauge_angle, compliance, gauge_sigma, gauge_model;
    r.get("observation_gauge_count", gauge_count);
    r.get("observation_gauge_angle", gauge_angle);
    r.get("observation_gauge_ids", gauge_ids);
    r.get("observation_gauge_compliance", compliance);
    r.get("observation_gauge_sigma", gauge_sigma);
    r.get("observation_gauge_model", gauge_model);
    std::vector<std::uint8_t> identifies;
    r.get("observation_gauge_identifies", identifies);
    const std::vector<std::string> ids =
        gauge_ids.empty() ? std::vector<std::string>{} : split_ids(gauge_ids);
    std::size_t next = 0;
    const bool sized = gauge_count.size() == n && gauge_angle.size() == n &&
                       compliance.size() == ids.size() && gauge_sigma.size() == ids.size() &&
                       gauge_model.size() == ids.size() && identifies.size() == ids.size();
    for (std::size_t k = 0; sized && k < n; ++k) {
      auto& o = e.observations[k].observation;
      o.gauge_angle_rad = gauge_angle[k];
      for (std::int64_t g = 0; g < gauge_count[k] && next < ids.size(); ++g, ++next) {
        o.gauges.push_back({ids[next], compliance[next], gauge_sigma[next], gauge_model[next],
                            identifies[next] != 0});
      }
    }
    if (!sized || next != ids.size()) r.bad = "observation_gauge arrays of different lengths";
  }
  e.engines.resize(particles);
  for (std::size_t i = 0; i < particles; ++i) {
    fatigue::for_each_field(e.engines[i], [&](std::string_view key, auto& field) {
      r.get(particle_key(i, key), field);
    });
  }
  return e;
}

}  // namespace

CheckpointData Twin::to_checkpoint() const {
  CheckpointData d;
  d.format_version = kCheckpointFormat;
  d.strings["detail_id"] = detail_id();
  d.strings["blas_kernel"] = core::blas_kernel_name();
  d.i64_scalars["signature"] = std::bit_cast<std::int64_t>(model_->signature());
  CheckpointWriter writer{d};
  for_each_own_field(
      *this, [&](std::string_view key, const auto& field, Hashed) { writer.put(key, field); });
  const fatigue::EngineState engine = engine_->export_state();
  fatigue::for_each_field(engine,
                          [&](std::string_view key, const auto& field) { writer.put(key, field); });
  if (ensemble_) write_ensemble(writer, ensemble_->export_state());
  return d;
}

core::Status Twin::check_checkpoint(const CheckpointData& d,
                                    std::optional<std::int64_t> state_seq) const {
  auto fail = [&](const std::string& why) -> core::Status {
    return core::failure("checkpoint of detail " + detail_id() + ": " + why);
  };
  if (d.format_version != kCheckpointFormat) {
    return fail("format_version " + std::to_string(d.format_version) + " is not " +
                std::to_string(kCheckpointFormat) +
                ", the version this build reads; resume it with the build that wrote it, or move "
                "it away to start afresh");
  }
  const auto detail = d.strings.find("detail_id");
  if (detail == d.strings.end()) return fail("missing entries: detail_id");
  if (detail->second != detail_id()) return fail("it belongs to detail \"" + detail->second + "\"");
  const auto signature = d.i64_scalars.find("signature");
  if (signature == d.i64_scalars.end()) return fail("missing entries: signature");
  if (std::bit_cast<std::uint64_t>(signature->second) != model_->signature()) {
    return fail(
        "it was written for a different model (the detail's geometry, grid, material, "
        "boundary or fatigue parameters changed since); move it away to start afresh");
  }
  if (state_seq) {
    const auto stored = d.i64_scalars.find("state_seq");
    if (stored == d.i64_scalars.end()) return fail("missing entries: state_seq");
    if (stored->second != *state_seq) {
      return fail("it holds state_seq " + std::to_string(stored->second) +
                  " but its file name says " + std::to_string(*state_seq) +
                  " (renamed or copied from elsewhere?)");
    }
  }
  return {};
}

core::Status Twin::restore(const CheckpointData& d) {
  auto fail = [&](const std::string& why) -> core::Status {
    return core::failure("checkpoint of detail " + detail_id() + ": " + why);
  };
  if (const core::Status matches = check_checkpoint(d, std::nullopt); !matches) return matches;
  CheckpointReader reader{d, {}, {}};
  fatigue::EngineState engine;
  fatigue::for_each_field(engine,
                          [&](std::string_view key, auto& field) { reader.get(key, field); });
  for_each_own_field(*this,
                     [&](std::string_view key, auto& field, Hashed) { reader.get(key, field); });
  EnsembleCheckpoint ensemble;
  if (ensemble_) ensemble = read_ensemble(reader, ensemble_->size());
  if (!reader.missing.empty()) {
    return fail("missing entries: " + reader.missing +
                (ensemble_ && !d.u8_arrays.contains("ensemble_filter")
                     ? " (written without [detail.uncertainty]: move it away to start the "
                       "learning twin afresh)"
                     : ""));
  }
  if (!reader.bad.empty()) return fail(reader.bad);
  for (const auto& e : engine.events) {
    if (e.bond >= model_->disc().num_bonds()) return fail("event bond out of range");
  }
  if (!engine_->import_state(engine)) return fail("the engine state does not fit the model");
  if (ensemble_) {
    for (const auto& p : ensemble.engines) {
      for (const auto& e : p.events) {
        if (e.bond >= ensemble_->particle_model().disc().num_bonds()) {
          return fail("a particle's event bond out of range");
        }
      }
    }
    if (core::Status st = ensemble_->import_state(ensemble); !st) return fail(st.error().message());
  }
  // The gauges as configured now (a gauge added or removed since the checkpoint: by id).
  gauge_residuals_ = gauge_residuals_.for_gauges(model_->gauges());
  const Failure stored = failure_;
  report_key_.reset();  // a new engine state: measured afresh
  refresh();
  cycles_before_state_ = engine_->total_cycles();
  if (failure_ != stored) {
    return fail("the restored state's failure code " + std::to_string(static_cast<int>(failure_)) +
                " differs from the stored " + std::to_string(static_cast<int>(stored)));
  }
  return {};
}

}  // namespace peritwin::twin
