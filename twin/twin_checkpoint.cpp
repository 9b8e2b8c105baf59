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
//   RollingSpectrum                   -> f64 arrays <key>_p_max, <key>_r, <key>_alpha, i64
//   <key>_count
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
  if (!reader.missing.empty()) return fail("missing entries: " + reader.missing);
  if (!reader.bad.empty()) return fail(reader.bad);
  for (const auto& e : engine.events) {
    if (e.bond >= model_->disc().num_bonds()) return fail("event bond out of range");
  }
  if (!engine_->import_state(engine)) return fail("the engine state does not fit the model");
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
