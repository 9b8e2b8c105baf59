#include "dashboard/store.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <peritwin_msgs/observation_t.hpp>
#include <utility>

#include "messages/channels.h"
#include "messages/codec.h"

namespace peritwin::dashboard {
namespace {

using Json = nlohmann::ordered_json;

constexpr std::size_t kMaxEvents = 1000;

std::string dump(const Json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

/// null for NaN and ±Inf (JSON has neither), the number otherwise.
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

/// The detail id of a decoded message if it is valid and belongs to the channel's token.
bool belongs(const std::string& detail_id, const std::string& token) {
  return messages::is_valid_detail_id(detail_id) && messages::detail_token(detail_id) == token;
}

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

/// Integers a browser's JSON.parse reads exactly: below 2^53 in magnitude. A larger 64-bit integer
/// (a probe's seq 2^63 − 1, a hostile cycle count) goes as its decimal string.
constexpr std::int64_t kExactInJs = std::int64_t{1} << 53;
Json integer(std::int64_t v) {
  return v > -kExactInJs && v < kExactInJs ? Json(v) : Json(std::to_string(v));
}
/// A whole number held in a double (history columns, predicted cycles): rounded, as integer().
Json integer(double v) {
  if (!std::isfinite(v)) return nullptr;
  v = std::round(v);
  if (std::abs(v) < 0x1p53) return Json(static_cast<std::int64_t>(v));
  if (std::abs(v) < 0x1p63) return Json(std::to_string(static_cast<std::int64_t>(v)));
  char text[64];
  std::snprintf(text, sizeof text, "%.0f", v);
  return Json(text);
}
bool exact_in_js(std::int64_t v) { return v > -kExactInJs && v < kExactInJs; }

/// The learning ensemble of a STATE (null without one): its estimate and posterior.
Json ensemble_json(const peritwin_msgs::damage_state_t& s) {
  if (s.num_particles <= 0) return nullptr;
  const auto numbers = [](const std::vector<double>& v) {
    Json a = Json::array();
    for (const double x : v) a.push_back(number(x));
    return a;
  };
  Json posterior = Json::array();
  const std::size_t n =
      std::min({s.parameter_names.size(), s.parameter_medians.size(), s.parameter_covs.size()});
  for (std::size_t i = 0; i < n; ++i) {
    posterior.push_back({{"name", s.parameter_names[i]},
                         {"median", number(s.parameter_medians[i])},
                         {"cov", number(s.parameter_covs[i])}});
  }
  return {{"particles", s.num_particles},
          {"estimate_cycle", integer(s.ensemble_estimate_cycle)},
          {"effective_sample_size", number(s.effective_sample_size)},
          {"percentiles", numbers(s.percentiles)},
          {"end_of_life", numbers(s.end_of_life_percentiles)},
          {"remaining", numbers(s.remaining_percentiles)},
          {"horizon_cycles", number(s.horizon_cycles)},
          {"probability_within_horizon", number(s.probability_within_horizon)},
          {"posterior", std::move(posterior)},
          {"observation_count", s.observation_count}};
}

/// The ensemble's predicted end of life at the first, middle and last of the STATE's percentiles
/// (NaN without an ensemble).
std::array<double, 3> ensemble_end_of_life(const peritwin_msgs::damage_state_t& s) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto n = s.end_of_life_percentiles.size();
  if (s.num_particles <= 0 || n == 0) return {nan, nan, nan};
  return {s.end_of_life_percentiles[0], s.end_of_life_percentiles[n / 2],
          s.end_of_life_percentiles[n - 1]};
}

/// A producer's probe: a batch with seq 2^63 − 1 asking what the daemon has applied of its source
/// (README, "Replay"); the daemon answers it with GAP.
constexpr std::int64_t kProbeSeq = std::numeric_limits<std::int64_t>::max();

/// Bit-for-bit equal (NaN equals NaN): the same estimate, published again.
bool same(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// The "life" and "protocol" parts of the summary are written as text, the way dump() writes
// them, without building a JSON tree: the summary is built for every event, and as a tree these
// parts cost a quarter more instructions per event (callgrind, peritwin-bench-dashboard).

/// An integer as integer() dumps it.
void put_integer(std::string& out, std::int64_t v) {
  const bool quoted = !exact_in_js(v);
  char digits[24];
  const auto end = std::to_chars(digits, digits + sizeof digits, v).ptr;
  if (quoted) out += '"';
  out.append(digits, end);
  if (quoted) out += '"';
}

/// A double as number() dumps it. A whole one below 1e15 is its digits and ".0" (nlohmann's
/// form); the rest go through dump().
void put_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
  } else if (v == std::floor(v) && std::abs(v) < 1e15 && !(v == 0.0 && std::signbit(v))) {
    put_integer(out, static_cast<std::int64_t>(v));
    out += ".0";
  } else {
    out += dump(Json(v));
  }
}

/// A whole number in a double as integer(double) dumps it.
void put_whole(std::string& out, double v) {
  if (std::isfinite(v) && std::abs(std::round(v)) < 0x1p53) {
    put_integer(out, static_cast<std::int64_t>(std::round(v)));
  } else {
    out += dump(integer(v));
  }
}

/// The remaining life at a state of `cycles` (utime: its daemon time, 0 unknown) as the JSON
/// object "life": "state" says which of the cases below it is; remaining/low/high are counted
/// down to `cycles`.
///   end_of_life  the detail failed (failure != 0): remaining 0, end_cycle the cycle it failed at
///   none         no estimate yet
///   unanchored   the estimate's state was not received (a dashboard started after it): the
///                estimate as published, not counted down, no end cycle
///   never        the reference spectrum never ends the life (+Inf)
///   countdown    remaining = max(0, estimate_cycle + estimate − cycles)
void put_life(std::string& out, const std::optional<LifeAnchor>& life, std::int64_t cycles,
              std::int64_t utime, bool failed, std::int64_t end_of_life_cycle) {
  Countdown c;
  const char* kind = "none";
  if (life) {
    if (life->cycles) {
      c = count_down(life->central, life->low, life->high, *life->cycles, cycles);
      kind = std::isinf(life->central) ? "never" : "countdown";
    } else {
      c.remaining = life->central;
      c.low = life->low;
      c.high = life->high;
      kind = "unanchored";
    }
  }
  if (failed) {
    kind = "end_of_life";
    c.remaining = c.low = c.high = 0.0;
    c.end_cycle = end_of_life_cycle >= 0 ? static_cast<double>(end_of_life_cycle) : c.end_cycle;
  }
  const bool anchored = life && life->cycles;
  const bool keyed = life && life->keyed;
  out += R"({"state":")";
  out += kind;
  out += R"(","remaining":)";
  put_number(out, c.remaining);
  out += R"(,"low":)";
  put_number(out, c.low);
  out += R"(,"high":)";
  put_number(out, c.high);
  out += R"(,"end_cycle":)";
  if (failed || anchored) {
    put_whole(out, c.end_cycle);
  } else {
    out += "null";
  }
  out += R"(,"estimate_cycle":)";
  if (anchored) {
    put_integer(out, *life->cycles);
  } else {
    out += "null";
  }
  out += R"(,"estimate_source":)";
  out += keyed ? life->source_json : std::string("null");
  out += R"(,"estimate_seq":)";
  if (keyed) {
    put_integer(out, life->seq);
  } else {
    out += "null";
  }
  out += R"(,"age_cycles":)";
  if (anchored) {
    put_integer(out, c.age_cycles);
  } else {
    out += "null";
  }
  out += R"(,"age_s":)";
  if (anchored && life->utime > 0 && utime > 0) {
    put_number(out, static_cast<double>(utime - life->utime) * 1e-6);
  } else {
    out += "null";
  }
  out += '}';
}

/// A reject's JSON text, made once when it arrives (shown in every later event of its detail).
std::string reject_text(const peritwin_msgs::reject_t& r) {
  Json j;
  j["source"] = r.source_id;
  j["seq"] = integer(r.seq);
  j["code"] = static_cast<int>(r.code);
  j["what"] = r.what;
  j["why"] = r.why;
  return dump(j);
}

}  // namespace

Countdown count_down(double central, double low, double high, std::int64_t estimate_cycles,
                     std::int64_t cycles) {
  Countdown c;
  // Cycles applied since the estimate's state, exact as an integer (a restarted daemon on an
  // older checkpoint could go back: then the age is negative and the life counts up again).
  // Saturated: the numbers come off the bus, a hostile pair must not overflow.
  if (__builtin_sub_overflow(cycles, estimate_cycles, &c.age_cycles)) {
    c.age_cycles = cycles < estimate_cycles ? std::numeric_limits<std::int64_t>::min()
                                            : std::numeric_limits<std::int64_t>::max();
  }
  const double age = static_cast<double>(c.age_cycles);
  const auto left = [age](double v) { return std::isnan(v) ? v : std::max(0.0, v - age); };
  c.remaining = left(central);
  c.low = left(low);
  c.high = left(high);
  c.end_cycle = static_cast<double>(estimate_cycles) + central;
  return c;
}

std::uint64_t mesh_coordinates_hash(const std::vector<double>& x, const std::vector<double>& y) {
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a 64 offset basis
  const auto add = [&h](const std::vector<double>& v) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(v.data());
    for (std::size_t i = 0; i < v.size() * sizeof(double); ++i) {
      h = (h ^ bytes[i]) * 0x100000001b3ULL;
    }
  };
  add(x);
  add(y);
  return h;
}

void Store::on_message(const std::string& channel, const void* data, std::size_t size,
                       Clock::time_point now) {
  const auto parts = messages::parse_channel(channel);
  if (!parts) {
    const std::lock_guard lock(mutex_);
    count_undecodable("");
    return;
  }
  const std::lock_guard lock(mutex_);
  switch (parts->kind) {
    case messages::Kind::kState: {
      auto state = messages::decode_state(data, size);
      if (!state || !belongs(state->detail_id, parts->token))
        return count_undecodable(parts->token);
      auto& d = details_[state->detail_id];
      if (d.first_seen == Clock::time_point{}) d.first_seen = now;
      on_state_life(d, *state);
      // One point per state: a STATE published again (the daemon answers a duplicate batch with
      // it) adds none. A restarted daemon goes on from its checkpoint's seq, maybe a smaller one.
      // (Also the last point of a back-filled history.) Remaining life counted down to the state.
      const bool again =
          !d.history.empty() && d.history.rows().back()[5] == static_cast<double>(state->state_seq);
      if (!again) {
        double remaining = state->remaining_cycles, low = state->remaining_cycles_low,
               high = state->remaining_cycles_high;
        if (d.life && d.life->cycles) {
          const Countdown c =
              count_down(remaining, low, high, *d.life->cycles, state->total_cycles);
          remaining = c.remaining;
          low = c.low;
          high = c.high;
        }
        const auto eol = ensemble_end_of_life(*state);
        d.history.push({static_cast<double>(state->total_cycles), state->crack_length_m, remaining,
                        low, high, static_cast<double>(state->state_seq), eol[0], eol[1], eol[2]});
      }
      on_state_ensemble(d, *state);
      ++d.states;
      const std::string id = state->detail_id;
      d.state = std::move(*state);
      push_event("state", id, now);
      return;
    }
    case messages::Kind::kStatus: {
      auto status = messages::decode_status(data, size);
      if (!status || !belongs(status->detail_id, parts->token)) {
        return count_undecodable(parts->token);
      }
      auto& d = details_[status->detail_id];
      if (d.first_seen == Clock::time_point{}) d.first_seen = now;
      d.status_at = now;
      const std::string id = status->detail_id;
      d.status = std::move(*status);
      push_event("status", id, now);
      return;
    }
    case messages::Kind::kReject: {
      auto reject = messages::decode_reject(data, size);
      if (!reject || !belongs(reject->detail_id, parts->token)) {
        return count_undecodable(parts->token);
      }
      auto& d = details_[reject->detail_id];
      if (d.first_seen == Clock::time_point{}) d.first_seen = now;
      const std::string id = reject->detail_id;
      // DUPLICATE and GAP are the exactly-once protocol at work (messages/batch.h, twin/twin.cpp:
      // a resend of an applied seq, a seq ahead of the next, a producer's probe), not a refusal.
      switch (reject->code) {
        case peritwin_msgs::reject_t::CODE_DUPLICATE:
          ++d.duplicates;
          d.last_protocol = reject_text(*reject);
          break;
        case peritwin_msgs::reject_t::CODE_GAP:
          ++(reject->seq == kProbeSeq ? d.probes : d.gaps);
          d.last_protocol = reject_text(*reject);
          break;
        default:
          ++d.rejects;
          d.last_reject = reject_text(*reject);
          break;
      }
      push_event("reject", id, now);
      return;
    }
    case messages::Kind::kField: {
      const auto field = messages::decode_field(data, size);
      if (!field || !belongs(field->detail_id, parts->token)) {
        return count_undecodable(parts->token);
      }
      auto& d = details_[field->detail_id];
      if (d.first_seen == Clock::time_point{}) d.first_seen = now;
      ++d.fields;
      const std::string id = field->detail_id;
      on_field(id, d, std::move(*field), now);
      return;
    }
    case messages::Kind::kMesh:
      return on_mesh_chunk(parts->token, data, size, now);
    case messages::Kind::kLoad:
    case messages::Kind::kSamples:
    case messages::Kind::kMeshRequest:
    case messages::Kind::kObservation:  // what the twin took in is in its STATE
      return;                           // producers' and requesters' channels: not subscribed
  }
}

void Store::on_mesh_chunk(const std::string& token, const void* data, std::size_t size,
                          Clock::time_point now) {
  auto decoded = messages::decode_mesh_chunk(data, size);
  if (decoded.chunk && !belongs(decoded.chunk->detail_id, token)) {
    decoded.error = "detail_id \"" + decoded.chunk->detail_id + "\" is not the channel's";
  }
  if (!decoded.error.empty()) {
    count_undecodable(token);
    for (auto& [id, d] : details_) {
      if (messages::detail_token(id) == token) d.mesh_error = decoded.error;
    }
    return;
  }
  auto& d = details_[decoded.chunk->detail_id];
  if (d.first_seen == Clock::time_point{}) d.first_seen = now;
  if (decoded.chunk->mesh_hash == d.mesh_hash) return;  // we have it: a republication for others
  auto done = meshes_.add(std::move(*decoded.chunk));
  if (!done.error.empty()) d.mesh_error = done.error;
  if (done.mesh) {
    d.mesh_hash = messages::mesh_hash(*done.mesh);
    d.mesh = std::move(done.mesh);
    d.mesh_error.clear();
    match_file_field(d);
    push_event("mesh", d.mesh->detail_id, now);
  }
}

void Store::on_field(const std::string& id, DetailRecord& d, peritwin_msgs::damage_field_t field,
                     Clock::time_point now) {
  PartialField& p = d.partial_field;
  // A chunk of another state or layout starts a new set (an incomplete older one is dropped).
  if (p.state_seq != field.state_seq || p.mesh_hash != field.mesh_hash ||
      p.num_chunks != field.num_chunks || p.total_nodes != field.total_nodes) {
    p = PartialField{field.state_seq, field.mesh_hash, field.num_chunks, field.total_nodes, {}};
  }
  if (field.num_chunks < 1 || field.chunk_index < 0 || field.chunk_index >= field.num_chunks ||
      field.total_nodes < 1 || field.first_node < 0 ||
      static_cast<std::int64_t>(field.first_node) + field.num_nodes > field.total_nodes) {
    return;  // counted in "fields", not drawable
  }
  const std::int32_t index = field.chunk_index;
  p.chunks.insert_or_assign(index, std::move(field));
  if (static_cast<std::int32_t>(p.chunks.size()) < p.num_chunks) return;
  Field f{p.state_seq, p.mesh_hash, {}, std::nullopt};
  f.damage.reserve(static_cast<std::size_t>(p.total_nodes));
  for (const auto& [i, c] : p.chunks) {
    if (c.first_node != static_cast<std::int32_t>(f.damage.size())) {
      p = PartialField{};
      return;  // the chunks do not tile the nodes
    }
    f.damage.insert(f.damage.end(), c.damage.begin(), c.damage.end());
  }
  const std::int32_t total = p.total_nodes;
  p = PartialField{};
  if (static_cast<std::int32_t>(f.damage.size()) != total) return;
  if (!d.field || d.field->state_seq <= f.state_seq || d.field->mesh_hash != f.mesh_hash) {
    d.field = std::move(f);
    return push_event("field", id, now);
  }
}

std::vector<std::string> Store::take_mesh_requests(Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  std::vector<std::string> out;
  for (auto& [id, d] : details_) {
    const bool missing = !d.mesh || (d.field && d.field->mesh_hash != d.mesh_hash);
    if (!missing) continue;
    if (d.mesh_requested != Clock::time_point{} &&
        seconds(now - d.mesh_requested) < kMeshRequestPeriodS) {
      continue;
    }
    d.mesh_requested = now;
    out.push_back(id);
  }
  return out;
}

std::size_t Store::backfill(const std::string& id, const std::vector<HistoryPoint>& points,
                            Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  auto& d = details_[id];
  if (d.first_seen == Clock::time_point{}) d.first_seen = now;
  const bool live = !d.history.empty();
  const double first_live = live ? d.history.rows().front()[5] : 0.0;
  History merged{kHistoryPoints};
  std::size_t taken = 0;
  for (const auto& p : points) {
    if (live && static_cast<double>(p.state_seq) >= first_live) continue;
    merged.push({static_cast<double>(p.cycles), p.crack_length_m, p.remaining, p.low, p.high,
                 static_cast<double>(p.state_seq), p.eol_low, p.eol_median, p.eol_high});
    ++taken;
  }
  for (const auto& row : d.history.rows()) merged.push(row);
  d.history = std::move(merged);
  d.backfilled += taken;
  return taken;
}

void Store::on_state_ensemble(DetailRecord& d, const peritwin_msgs::damage_state_t& s) {
  if (s.num_particles <= 0) return;
  if (const auto np = s.percentiles.size(); np > 0) {
    d.eol_percentiles = {s.percentiles[0], s.percentiles[np / 2], s.percentiles[np - 1]};
  }
  const auto n = static_cast<std::size_t>(std::max(s.num_observations, 0));
  if (s.observation_cycles.size() < n || s.observation_kinds.size() < n ||
      s.observation_lengths_m.size() < n || s.observation_sigmas_m.size() < n ||
      s.observation_pod_a50s_m.size() < n || s.observation_predicted_m.size() < n) {
    return;  // (the codec's layout check makes this unreachable)
  }
  // The STATE carries the last n of observation_count: the i-th is number count − n + i.
  const std::int64_t first =
      static_cast<std::int64_t>(s.observation_count) - static_cast<std::int64_t>(n);
  for (std::size_t i = 0; i < n; ++i) {
    ObservationPoint o;
    o.index = first + static_cast<std::int64_t>(i);
    o.cycles = s.observation_cycles[i];
    o.kind = s.observation_kinds[i];
    o.length_m = s.observation_lengths_m[i];
    o.sigma_m = s.observation_sigmas_m[i];
    o.pod_a50_m = s.observation_pod_a50s_m[i];
    o.predicted_m = s.observation_predicted_m[i];
    if (o.index < 0) continue;
    if (d.observations.empty() || o.index > d.observations.back().index) {
      d.observations.push_back(o);
      continue;
    }
    // Known already (every STATE repeats the last ones); a daemon restarted from an older
    // checkpoint may say otherwise of it: its word is the newest.
    for (auto it = d.observations.rbegin(); it != d.observations.rend(); ++it) {
      if (it->index == o.index) {
        *it = o;
        break;
      }
      if (it->index < o.index) break;
    }
  }
  while (d.observations.size() > kObservationMemory) d.observations.pop_front();
}

void Store::on_state_life(DetailRecord& d, const peritwin_msgs::damage_state_t& s) {
  if (s.state_seq == 0) d.initial_utime = s.utime;
  // The batch that produced `s` is known when its predecessor was the last state received: it
  // is the one source whose applied seq moved. (Without the predecessor the first state seen with
  // that seq could be a later one: its cycles would date the estimate too late.)
  if (d.state && d.state->state_seq < std::numeric_limits<std::int64_t>::max() &&
      s.state_seq == d.state->state_seq + 1) {
    const std::size_t n = std::min(s.source_ids.size(), s.applied_seq.size());
    for (std::size_t i = 0; i < n; ++i) {
      if (s.applied_seq[i] == messages::applied_seq(*d.state, s.source_ids[i])) continue;
      auto& names = d.batch_sources;
      const auto source = static_cast<std::uint32_t>(
          std::find(names.begin(), names.end(), s.source_ids[i]) - names.begin());
      if (source == names.size()) names.push_back(s.source_ids[i]);
      d.batches.push_back({source, s.applied_seq[i], s.total_cycles, s.utime});
      if (d.batches.size() > kBatchMemory) d.batches.pop_front();
      break;
    }
  }
  if (std::isnan(s.remaining_cycles)) {
    d.life.reset();
    return;
  }
  if (d.life && d.life->keyed && d.life->source == s.remaining_life_source &&
      d.life->seq == s.remaining_life_seq) {
    return;  // the same estimate as before
  }
  if (d.life && !d.life->keyed && same(d.life->central, s.remaining_cycles) &&
      same(d.life->low, s.remaining_cycles_low) && same(d.life->high, s.remaining_cycles_high)) {
    // The results file's estimate (its rows do not name the batch): now we know which it is.
    d.life->keyed = true;
    d.life->source = s.remaining_life_source;
    d.life->source_json = dump(Json(s.remaining_life_source));
    d.life->seq = s.remaining_life_seq;
    return;
  }
  LifeAnchor a;
  a.source = s.remaining_life_source;
  a.source_json = dump(Json(a.source));
  a.seq = s.remaining_life_seq;
  a.central = s.remaining_cycles;
  a.low = s.remaining_cycles_low;
  a.high = s.remaining_cycles_high;
  if (a.seq < 0 && a.source.empty()) {
    a.cycles = 0;  // made on the initial state: the virgin detail, no cycles applied
    a.utime = d.initial_utime;
  } else {
    const auto& names = d.batch_sources;
    const auto source =
        static_cast<std::uint32_t>(std::find(names.begin(), names.end(), a.source) - names.begin());
    const auto it = std::find_if(
        d.batches.rbegin(), d.batches.rend(),
        [&a, source](const BatchState& b) { return b.seq == a.seq && b.source == source; });
    if (it != d.batches.rend()) {
      a.cycles = it->cycles;
      a.utime = it->utime;
      // Estimates are made on ever later states: the batches before this one are no longer needed.
      d.batches.erase(d.batches.begin(), std::prev(it.base()));
    }
  }
  d.life = std::move(a);
}

void Store::match_file_field(DetailRecord& d) {
  if (!d.field || !d.field->file_coordinates || !d.field->mesh_hash.empty() || !d.mesh) return;
  if (mesh_coordinates_hash(d.mesh->x, d.mesh->y) == *d.field->file_coordinates) {
    d.field->mesh_hash = d.mesh_hash;
  } else {
    d.field.reset();  // another grid than the file's (the daemon restarted on a new one)
  }
}

void Store::backfill_latest(const std::string& id, const FileState& state,
                            std::optional<Field> snapshot, Clock::time_point now) {
  const std::lock_guard lock(mutex_);
  auto& d = details_[id];
  if (d.first_seen == Clock::time_point{}) d.first_seen = now;
  // A STATE received live is newer than the file (which the daemon writes as it publishes).
  if (!d.state) {
    d.file_state = state;
    if (!std::isnan(state.remaining)) {
      LifeAnchor a;
      a.keyed = false;
      a.central = state.remaining;
      a.low = state.low;
      a.high = state.high;
      a.cycles = state.estimate_cycles;
      d.life = std::move(a);
    }
  }
  if (snapshot && (!d.field || d.field->state_seq < snapshot->state_seq)) {
    snapshot->mesh_hash.clear();
    d.field = std::move(snapshot);
    match_file_field(d);
  }
}

void Store::count_undecodable(const std::string& token) {
  ++undecodable_[token];
  ++undecodable_total_;
}

void Store::push_event(const std::string& kind, const std::string& detail, Clock::time_point now) {
  // The summary's text is spliced in as it is (parsing it back into a Json to dump it again
  // cost 44 % of the dashboard's CPU at 1000 states/s, docs/benchmarks.md "Dashboard"); the
  // detail id comes off the bus, so it is escaped.
  std::string text =
      R"({"kind":)" + dump(Json(kind)) + R"(,"detail":)" + dump(Json(detail)) + R"(,"summary":)";
  text += detail_json_locked(detail, details_.at(detail), now);
  text += '}';
  events_.push_back({next_event_++, kind, std::move(text)});
  while (events_.size() > kMaxEvents) events_.pop_front();
  changed_.notify_all();
  if (event_listener_) event_listener_();
}

std::string Store::detail_json_locked(const std::string& id, const DetailRecord& d,
                                      Clock::time_point now) const {
  // With a state, its fields as messages::state_json writes them, then the ones below: the
  // summary is state_json's text without its closing brace, a comma, and the dump of `j` without
  // its opening one — the same bytes as parsing state_json into `j` and dumping it all (a parse
  // cost a fifth of the dashboard's CPU, docs/benchmarks.md "Dashboard"). None of the keys below
  // is one of state_json's (a test checks that no key appears twice).
  Json j;
  if (d.state) {
    const auto& s = *d.state;
    j["k_ii"] = number(s.k_ii);
    j["remaining_life_source"] = s.remaining_life_source;
    j["signed"] = s.tag_length > 0;
    // K_I / K_II at the longest crack's (first) tip, when it has one.
    if (!s.cracks.empty() && !s.cracks.front().tips.empty()) {
      const auto& tip = s.cracks.front().tips.front();
      j["tip"] = {{"x", number(tip.x)},
                  {"y", number(tip.y)},
                  {"k_i", number(tip.k_i)},
                  {"k_ii", number(tip.k_ii)},
                  {"k_status", static_cast<int>(tip.k_status)}};
    } else {
      j["tip"] = nullptr;
    }
    // The crack paths to draw: origin, then the tips (listed cracks, the longest first).
    Json cracks = Json::array();
    for (const auto& c : s.cracks) {
      Json tips = Json::array();
      for (const auto& t : c.tips) tips.push_back({{"x", number(t.x)}, {"y", number(t.y)}});
      cracks.push_back({{"id", c.id},
                        {"origin", c.origin},
                        {"origin_x", number(c.origin_x)},
                        {"origin_y", number(c.origin_y)},
                        {"length_m", number(c.length_m)},
                        {"tips", std::move(tips)}});
    }
    j["cracks"] = std::move(cracks);
    j["from_results"] = false;
    j["ensemble"] = ensemble_json(s);
  } else if (d.file_state) {
    // No STATE since the dashboard started: the results file's last row, under state_json's keys
    // (what the file does not hold is null), so the card shows the detail as the file left it.
    const FileState& f = *d.file_state;
    j["detail"] = id;
    j["state_seq"] = integer(f.state_seq);
    j["cycles"] = integer(f.cycles);
    j["broken_bonds"] = integer(f.broken_bonds);
    j["crack_length_m"] = number(f.crack_length_m);
    j["crack_count"] = f.crack_count >= 0 ? integer(f.crack_count) : Json(nullptr);
    j["max_damage"] = number(f.max_damage);
    j["k_i"] = number(f.k_i);
    j["remaining_cycles"] = number(f.remaining);
    j["remaining_low"] = number(f.low);
    j["remaining_high"] = number(f.high);
    j["remaining_life_seq"] = nullptr;
    j["failure"] = nullptr;
    j["end_of_life_cycle"] = nullptr;
    j["state_hash"] = nullptr;
    j["engine_hash"] = nullptr;
    j["k_ii"] = number(f.k_ii);
    j["remaining_life_source"] = nullptr;
    j["signed"] = nullptr;
    j["tip"] = std::isfinite(f.tip_x) && std::isfinite(f.tip_y) ? Json{{"x", number(f.tip_x)},
                                                                       {"y", number(f.tip_y)},
                                                                       {"k_i", number(f.k_i)},
                                                                       {"k_ii", number(f.k_ii)},
                                                                       {"k_status", nullptr}}
                                                                : Json(nullptr);
    j["cracks"] = Json::array();
    j["from_results"] = true;
    j["ensemble"] = nullptr;
  } else {
    j["detail"] = id;
    j["state_seq"] = nullptr;
    j["from_results"] = false;
    j["ensemble"] = nullptr;
  }
  // Health: the daemon's own word, unless its heartbeat stopped (stale) or never came.
  const bool has_status = d.status.has_value();
  const double age = seconds(now - (has_status ? d.status_at : d.first_seen));
  j["health"] = age > kStaleAfterS ? "stale" : (has_status ? d.status->health : "waiting");
  j["status_age_s"] = has_status ? Json(age) : Json(nullptr);
  if (has_status) {
    const auto& st = *d.status;
    j["status"] = {{"health", st.health},
                   {"last_seq", integer(st.last_seq)},
                   {"pending", integer(static_cast<std::int64_t>(st.pending))},
                   {"lag_s", number(st.lag_s)},
                   {"uptime_s", number(st.uptime_s)},
                   {"errors", integer(static_cast<std::int64_t>(st.errors))},
                   {"duplicates", integer(static_cast<std::int64_t>(st.duplicates))},
                   {"gaps", integer(static_cast<std::int64_t>(st.gaps))},
                   {"busy_s", number(st.busy_s)},
                   {"auth_rejects", integer(static_cast<std::int64_t>(st.auth_rejects))},
                   {"reject_rate", number(st.reject_rate)}};
  } else {
    j["status"] = nullptr;
  }
  j["states_received"] = d.states;
  // Refusals only; the protocol's own answers (probe, duplicate, gap) apart.
  j["rejects"] = d.rejects;
  j["fields"] = d.fields;
  j["mesh_hash"] = d.mesh ? Json(d.mesh_hash) : Json(nullptr);
  j["mesh_nodes"] = d.mesh ? Json(d.mesh->x.size()) : Json(nullptr);
  j["mesh_error"] = d.mesh_error.empty() ? Json(nullptr) : Json(d.mesh_error);
  j["field_seq"] = d.field ? integer(d.field->state_seq) : Json(nullptr);
  j["field_from_results"] = d.field && d.field->file_coordinates.has_value();
  j["field_mesh_hash"] = d.field ? Json(d.field->mesh_hash) : Json(nullptr);
  j["backfilled"] = d.backfilled;
  const auto u = undecodable_.find(messages::detail_token(id));
  j["undecodable"] = u == undecodable_.end() ? 0 : u->second;
  // Then, as text (put_life): "life", "last_reject" (the last refusal) and "protocol".
  const auto tail = [&](std::string& text) {
    text.back() = ',';  // the closing brace of what is before
    text += R"("life":)";
    if (d.state) {
      const auto& s = *d.state;
      put_life(text, d.life, s.total_cycles, s.utime,
               s.failure != peritwin_msgs::damage_state_t::FAILURE_NONE, s.end_of_life_cycle);
    } else if (d.file_state) {
      put_life(text, d.life, d.file_state->cycles, 0, false, -1);
    } else {
      put_life(text, std::nullopt, 0, 0, false, -1);
    }
    text += R"(,"last_reject":)";
    text += d.last_reject.empty() ? std::string("null") : d.last_reject;
    text += R"(,"protocol":{"probes":)";
    put_integer(text, d.probes);
    text += R"(,"duplicates":)";
    put_integer(text, d.duplicates);
    text += R"(,"gaps":)";
    put_integer(text, d.gaps);
    text += R"(,"last":)";
    text += d.last_protocol.empty() ? std::string("null") : d.last_protocol;
    text += "}}";
  };
  if (!d.state) {
    std::string text = dump(j);
    tail(text);
    return text;
  }
  const auto& s = *d.state;
  std::string text = messages::state_json(s);
  if (!exact_in_js(s.state_seq) || !exact_in_js(s.total_cycles) || !exact_in_js(s.broken_bonds) ||
      !exact_in_js(s.remaining_life_seq) || !exact_in_js(s.end_of_life_cycle)) {
    // Rare (hostile counts): state_json's integers past 2^53 as strings, at the price of a parse.
    auto parsed = Json::parse(text);
    for (const char* key :
         {"state_seq", "cycles", "broken_bonds", "remaining_life_seq", "end_of_life_cycle"}) {
      if (parsed[key].is_number_integer()) parsed[key] = integer(parsed[key].get<std::int64_t>());
    }
    text = dump(parsed);
  }
  text.back() = ',';  // its closing brace
  const std::string extra = dump(j);
  text.append(extra, 1, std::string::npos);
  tail(text);
  return text;
}

std::string Store::details_json(Clock::time_point now, std::uint64_t* last_event) const {
  const std::lock_guard lock(mutex_);
  if (last_event) *last_event = next_event_ - 1;
  Json list = Json::array();
  for (const auto& [id, d] : details_) list.push_back(Json::parse(detail_json_locked(id, d, now)));
  Json j;
  j["details"] = std::move(list);
  j["undecodable"] = undecodable_total_;
  return dump(j);
}

std::optional<std::string> Store::detail_json(const std::string& id, Clock::time_point now) const {
  const std::lock_guard lock(mutex_);
  const auto it = details_.find(id);
  if (it == details_.end()) return std::nullopt;
  return detail_json_locked(id, it->second, now);
}

std::optional<std::string> Store::history_json(const std::string& id) const {
  const std::lock_guard lock(mutex_);
  const auto it = details_.find(id);
  if (it == details_.end()) return std::nullopt;
  const auto& h = it->second.history;
  static constexpr const char* kColumns[] = {"cycles",  "crack_length_m", "remaining",
                                             "low",     "high",           "state_seq",
                                             "eol_low", "eol_median",     "eol_high"};
  Json j;
  j["detail"] = id;
  j["pushed"] = h.pushed();
  j["backfilled"] = it->second.backfilled;
  for (std::size_t c = 0; c < std::size(kColumns); ++c) {
    Json column = Json::array();
    for (const auto& row : h.rows()) {
      // cycles, state_seq and the predicted ends of life are integers (numbers below 2^53,
      // strings above).
      if (c == 0 || c >= 5) {
        column.push_back(integer(row[c]));
      } else {
        column.push_back(number(row[c]));
      }
    }
    j[kColumns[c]] = std::move(column);
  }
  const auto& percentiles = it->second.eol_percentiles;
  j["eol_percentiles"] = percentiles.empty() ? Json(nullptr) : Json(percentiles);
  Json observations = Json::array();
  for (const auto& o : it->second.observations) {
    observations.push_back(
        {{"index", integer(o.index)},
         {"cycles", integer(o.cycles)},
         {"kind",
          o.kind == peritwin_msgs::observation_t::KIND_NO_CRACK ? "no_crack" : "crack_length"},
         {"length_m", number(o.length_m)},
         {"sigma_m", number(o.sigma_m)},
         {"pod_a50_m", number(o.pod_a50_m)},
         {"predicted_m", number(o.predicted_m)}});
  }
  j["observations"] = std::move(observations);
  return dump(j);
}

std::optional<std::string> Store::mesh_json(const std::string& id) const {
  const std::lock_guard lock(mutex_);
  const auto it = details_.find(id);
  if (it == details_.end()) return std::nullopt;
  if (!it->second.mesh) return std::string();
  const messages::Mesh& m = *it->second.mesh;
  Json j;
  j["detail"] = id;
  j["mesh_hash"] = it->second.mesh_hash;
  j["total_nodes"] = m.x.size();
  j["dx"] = m.dx;
  j["horizon"] = m.horizon;
  j["box"] = {m.x_min, m.y_min, m.x_max, m.y_max};
  j["x"] = m.x;
  j["y"] = m.y;
  Json lines = Json::array();
  for (const auto& line : m.polylines) {
    const char* kind = line.kind == peritwin_msgs::mesh_polyline_t::KIND_HOLE    ? "hole"
                       : line.kind == peritwin_msgs::mesh_polyline_t::KIND_NOTCH ? "notch"
                                                                                 : "outline";
    lines.push_back({{"kind", kind},
                     {"index", line.index},
                     {"closed", line.closed},
                     {"x", line.x},
                     {"y", line.y}});
  }
  j["polylines"] = std::move(lines);
  return dump(j);
}

std::optional<std::string> Store::field_json(const std::string& id) const {
  const std::lock_guard lock(mutex_);
  const auto it = details_.find(id);
  if (it == details_.end()) return std::nullopt;
  if (!it->second.field) return std::string();
  const Field& f = *it->second.field;
  Json j;
  j["detail"] = id;
  j["state_seq"] = integer(f.state_seq);
  j["mesh_hash"] = f.mesh_hash;
  j["from_results"] = f.file_coordinates.has_value();
  j["total_nodes"] = f.damage.size();
  j["damage"] = f.damage;
  return dump(j);
}

std::int64_t Store::undecodable_total() const {
  const std::lock_guard lock(mutex_);
  return undecodable_total_;
}

std::deque<Event> Store::events_after(std::uint64_t after, std::chrono::milliseconds wait) const {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, wait,
                    [&] { return closed_ || (!events_.empty() && events_.back().id > after); });
  std::deque<Event> out;
  if (events_.empty() || events_.back().id <= after) return out;
  const std::uint64_t first = events_.front().id;  // ids are consecutive
  const auto skip = after + 1 > first ? after + 1 - first : 0;
  for (auto it = events_.begin() + static_cast<std::ptrdiff_t>(skip); it != events_.end(); ++it) {
    out.push_back(*it);
  }
  return out;
}

std::uint64_t Store::last_event_id() const {
  const std::lock_guard lock(mutex_);
  return next_event_ - 1;
}

void Store::set_event_listener(std::function<void()> listener) {
  const std::lock_guard lock(mutex_);
  event_listener_ = std::move(listener);
}

void Store::close() {
  const std::lock_guard lock(mutex_);
  closed_ = true;
  changed_.notify_all();
}

bool Store::closed() const {
  const std::lock_guard lock(mutex_);
  return closed_;
}

}  // namespace peritwin::dashboard
