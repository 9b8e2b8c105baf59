// Twin <-> CheckpointData (twin/checkpoint_io.h), format_version Twin::kCheckpointFormat = 2:
//   strings      detail_id, failure_reason, last_source, life_source, sources (ids joined by
//                '\n'; ids are printable ASCII without blanks)
//   i64 scalars  signature (DetailModel::signature, bit pattern), state_seq, failure,
//                total_cycles, failed, rates_valid, rate_key_count, last_seq, has_last_block,
//                last_block_count, life_state_seq, life_seq, pending_cycles, pending_count
//   f64 scalars  dose0, dose1, rate_key_p_max, rate_key_r, rate_key_alpha, last_block_p_max,
//                last_block_r, last_block_alpha, life_central, life_low, life_high,
//                pending_p_max, pending_r, pending_alpha
//   f64 arrays   anchor_life, spectrum_p_max, spectrum_r, spectrum_alpha, damage, max_stretch
//                (the last two empty unless the law is bilinear)
//   i64 arrays   event_cycle, event_bond, resolve_groups, source_seq, spectrum_count
//   u8 arrays    intact, event_cause
#include <bit>
#include <sstream>

#include "solver/blas_kernel.h"
#include "twin/twin.h"

namespace peritwin::twin {

CheckpointData Twin::to_checkpoint() const {
  CheckpointData d;
  d.format_version = kCheckpointFormat;
  const EngineState e = engine_->export_state();
  d.strings["detail_id"] = detail_id();
  d.strings["failure_reason"] = e.failure_reason;
  d.strings["last_source"] = last_source_;
  d.strings["life_source"] = life_.source;
  // Not restored: the daemon compares it on resume (the state's last bits depend on it).
  d.strings["blas_kernel"] = blas_kernel_name();
  std::string sources;
  std::vector<std::int64_t> seqs;
  for (const auto& [source, seq] : applied_) {
    if (!sources.empty()) sources += '\n';
    sources += source;
    seqs.push_back(seq);
  }
  d.strings["sources"] = sources;
  d.i64_arrays["source_seq"] = seqs;

  auto& i = d.i64_scalars;
  i["signature"] = std::bit_cast<std::int64_t>(model_->signature());
  i["state_seq"] = state_seq_;
  i["failure"] = static_cast<std::int64_t>(failure_);
  i["total_cycles"] = e.total_cycles;
  i["failed"] = e.failed ? 1 : 0;
  i["rates_valid"] = e.rates_valid ? 1 : 0;
  i["rate_key_count"] = e.rate_key.count;
  i["last_seq"] = last_seq_;
  i["has_last_block"] = last_block_ ? 1 : 0;
  i["last_block_count"] = last_block_ ? last_block_->count : 0;
  i["life_state_seq"] = life_.state_seq;
  i["life_seq"] = life_.seq;
  i["pending_cycles"] = e.pending_cycles;
  i["pending_count"] = e.pending_key.count;

  auto& f = d.f64_scalars;
  f["dose0"] = e.dose[0];
  f["dose1"] = e.dose[1];
  f["rate_key_p_max"] = e.rate_key.p_max;
  f["rate_key_r"] = e.rate_key.r;
  f["rate_key_alpha"] = e.rate_key.alpha;
  const LoadBlock lb = last_block_.value_or(LoadBlock{});
  f["last_block_p_max"] = lb.p_max;
  f["last_block_r"] = lb.r;
  f["last_block_alpha"] = lb.alpha;
  f["life_central"] = life_.central;
  f["life_low"] = life_.low;
  f["life_high"] = life_.high;
  f["pending_p_max"] = e.pending_key.p_max;
  f["pending_r"] = e.pending_key.r;
  f["pending_alpha"] = e.pending_key.alpha;
  d.f64_arrays["damage"] = e.damage;
  d.f64_arrays["max_stretch"] = e.max_stretch;

  d.f64_arrays["anchor_life"] = e.anchor_life;
  d.u8_arrays["intact"] = e.intact;
  std::vector<std::int64_t> cycle, bond;
  std::vector<std::uint8_t> cause;
  for (const auto& ev : e.events) {
    cycle.push_back(ev.cycle);
    bond.push_back(ev.bond);
    cause.push_back(static_cast<std::uint8_t>(ev.cause));
  }
  d.i64_arrays["event_cycle"] = cycle;
  d.i64_arrays["event_bond"] = bond;
  d.u8_arrays["event_cause"] = cause;
  d.i64_arrays["resolve_groups"] = e.resolve_groups;

  std::vector<double> sp, sr, sa;
  std::vector<std::int64_t> sc;
  for (const auto& b : spectrum_.blocks()) {
    sp.push_back(b.p_max);
    sr.push_back(b.r);
    sa.push_back(b.alpha);
    sc.push_back(b.count);
  }
  d.f64_arrays["spectrum_p_max"] = sp;
  d.f64_arrays["spectrum_r"] = sr;
  d.f64_arrays["spectrum_alpha"] = sa;
  d.i64_arrays["spectrum_count"] = sc;
  return d;
}

namespace {

template <class Map>
const typename Map::mapped_type* find(const Map& map, const std::string& key,
                                      std::string& missing) {
  const auto it = map.find(key);
  if (it == map.end()) {
    if (!missing.empty()) missing += ", ";
    missing += key;
    return nullptr;
  }
  return &it->second;
}

}  // namespace

bool Twin::restore(const CheckpointData& d, std::string* error) {
  auto fail = [&](const std::string& why) {
    if (error != nullptr) *error = "checkpoint of detail " + detail_id() + ": " + why;
    return false;
  };
  if (d.format_version != kCheckpointFormat) {
    return fail("format_version " + std::to_string(d.format_version) + " is not " +
                std::to_string(kCheckpointFormat));
  }
  std::string missing;
  const auto s = [&](const char* k) { return find(d.strings, k, missing); };
  const auto i = [&](const char* k) { return find(d.i64_scalars, k, missing); };
  const auto f = [&](const char* k) { return find(d.f64_scalars, k, missing); };
  const auto fa = [&](const char* k) { return find(d.f64_arrays, k, missing); };
  const auto ia = [&](const char* k) { return find(d.i64_arrays, k, missing); };
  const auto ua = [&](const char* k) { return find(d.u8_arrays, k, missing); };
  const auto *detail = s("detail_id"), *reason = s("failure_reason"),
             *last_source = s("last_source"), *life_source = s("life_source"),
             *sources = s("sources");
  const auto *signature = i("signature"), *state_seq = i("state_seq"), *failure = i("failure"),
             *total = i("total_cycles"), *failed = i("failed"), *rates_valid = i("rates_valid"),
             *rk_count = i("rate_key_count"), *last_seq = i("last_seq"),
             *has_lb = i("has_last_block"), *lb_count = i("last_block_count"),
             *life_state = i("life_state_seq"), *life_seq = i("life_seq"),
             *pending = i("pending_cycles"), *pending_count = i("pending_count");
  const auto *dose0 = f("dose0"), *dose1 = f("dose1"), *rk_p = f("rate_key_p_max"),
             *rk_r = f("rate_key_r"), *rk_a = f("rate_key_alpha"), *lb_p = f("last_block_p_max"),
             *lb_r = f("last_block_r"), *lb_a = f("last_block_alpha"), *life_c = f("life_central"),
             *life_l = f("life_low"), *life_h = f("life_high"), *pending_p = f("pending_p_max"),
             *pending_r = f("pending_r"), *pending_a = f("pending_alpha");
  const auto *anchor = fa("anchor_life"), *sp = fa("spectrum_p_max"), *sr = fa("spectrum_r"),
             *sa = fa("spectrum_alpha"), *damage = fa("damage"), *max_stretch = fa("max_stretch");
  const auto *ev_cycle = ia("event_cycle"), *ev_bond = ia("event_bond"),
             *groups = ia("resolve_groups"), *source_seq = ia("source_seq"),
             *sc = ia("spectrum_count");
  const auto *intact = ua("intact"), *ev_cause = ua("event_cause");
  if (!missing.empty()) return fail("missing entries: " + missing);
  if (*detail != detail_id()) return fail("it belongs to detail \"" + *detail + "\"");
  if (std::bit_cast<std::uint64_t>(*signature) != model_->signature()) {
    return fail(
        "it was written for a different model (the detail's geometry, grid, material, "
        "boundary or fatigue parameters changed since); move it away to start afresh");
  }
  if (ev_cycle->size() != ev_bond->size() || ev_cause->size() != ev_bond->size() ||
      sp->size() != sr->size() || sa->size() != sr->size() || sc->size() != sr->size()) {
    return fail("array lengths disagree");
  }

  EngineState e;
  e.anchor_life = *anchor;
  e.intact = *intact;
  e.dose[0] = *dose0;
  e.dose[1] = *dose1;
  e.rates_valid = *rates_valid != 0;
  e.rate_key = {*rk_p, *rk_r, *rk_a, *rk_count};
  e.total_cycles = *total;
  for (std::size_t k = 0; k < ev_bond->size(); ++k) {
    const auto bond = (*ev_bond)[k];
    if (bond < 0 || bond >= model_->disc().num_bonds()) return fail("event bond out of range");
    e.events.push_back(
        {(*ev_cycle)[k], static_cast<BondIndex>(bond), static_cast<BreakCause>((*ev_cause)[k])});
  }
  e.resolve_groups = *groups;
  e.failed = *failed != 0;
  e.failure_reason = *reason;
  e.damage = *damage;
  e.max_stretch = *max_stretch;
  e.pending_cycles = *pending;
  e.pending_key = {*pending_p, *pending_r, *pending_a, *pending_count};
  if (!engine_->import_state(e)) return fail("the engine state does not fit the model");

  applied_.clear();
  std::vector<std::string> ids;
  if (!sources->empty()) {
    std::istringstream in(*sources);
    for (std::string id; std::getline(in, id, '\n');) ids.push_back(id);
  }
  if (ids.size() != source_seq->size()) return fail("sources and source_seq disagree");
  for (std::size_t k = 0; k < ids.size(); ++k) applied_[ids[k]] = (*source_seq)[k];
  state_seq_ = *state_seq;
  last_source_ = *last_source;
  last_seq_ = *last_seq;
  if (*has_lb != 0) {
    last_block_ = LoadBlock{*lb_p, *lb_r, *lb_a, *lb_count};
  } else {
    last_block_.reset();
  }
  std::vector<LoadBlock> blocks;
  for (std::size_t k = 0; k < sp->size(); ++k)
    blocks.push_back({(*sp)[k], (*sr)[k], (*sa)[k], (*sc)[k]});
  spectrum_.assign(std::move(blocks));
  life_ = {*life_c, *life_l, *life_h, *life_state, *life_seq, *life_source};
  refresh();
  if (static_cast<std::int64_t>(failure_) != *failure) {
    return fail("the restored state's failure code " + std::to_string(static_cast<int>(failure_)) +
                " differs from the stored " + std::to_string(*failure));
  }
  return true;
}

}  // namespace peritwin::twin
