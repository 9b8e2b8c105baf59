#include "twin/messages_io.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <peritwin_msgs/observation_t.hpp>

namespace peritwin::twin {

namespace {

constexpr double kMaxChordRad = 5.0 * 3.14159265358979323846 / 180.0;

/// Points of an arc from `start` sweeping `sweep` (rad) about `centre`, without its first point.
void add_arc(messages::MeshPolyline& line, mesh::Point centre, double radius, double start,
             double sweep) {
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / kMaxChordRad)));
  for (int k = 1; k <= n; ++k) {
    const double a = start + sweep * k / n;
    line.x.push_back(centre.x + radius * std::cos(a));
    line.y.push_back(centre.y + radius * std::sin(a));
  }
}

messages::MeshPolyline region_line(const mesh::Region& region, std::int8_t kind, int index) {
  messages::MeshPolyline line;
  line.kind = kind;
  line.index = index;
  line.closed = true;
  switch (region.shape) {
    case mesh::Region::Shape::rectangle: {
      const mesh::Rectangle& r = region.rectangle;
      line.x = {r.x_min, r.x_max, r.x_max, r.x_min};
      line.y = {r.y_min, r.y_min, r.y_max, r.y_max};
      break;
    }
    case mesh::Region::Shape::circle:
      add_arc(line, region.circle.centre, region.circle.radius, 0.0, 2.0 * 3.14159265358979323846);
      line.x.pop_back();  // the last chord ends where the first began
      line.y.pop_back();
      break;
    case mesh::Region::Shape::polygon:
      for (const mesh::BoundaryPiece& piece : region.polygon.boundary()) {
        if (piece.arc) {
          line.x.push_back(piece.from.x);
          line.y.push_back(piece.from.y);
          add_arc(line, piece.centre, piece.radius, piece.start, piece.sweep);
          line.x.pop_back();  // the next piece starts there
          line.y.pop_back();
        } else {
          line.x.push_back(piece.from.x);
          line.y.push_back(piece.from.y);
        }
      }
      break;
  }
  return line;
}

}  // namespace

messages::Mesh detail_mesh(const DetailModel& model) {
  const mesh::Discretization& disc = model.disc();
  const mesh::DetailGeometry& geometry = model.geometry();
  messages::Mesh mesh;
  mesh.detail_id = model.config().id;
  mesh.dx = disc.dx;
  mesh.horizon = disc.horizon;
  const mesh::Rectangle box = geometry.bounding_box();
  mesh.x_min = box.x_min;
  mesh.y_min = box.y_min;
  mesh.x_max = box.x_max;
  mesh.y_max = box.y_max;
  mesh.x.reserve(disc.position.size());
  mesh.y.reserve(disc.position.size());
  for (const mesh::Point& p : disc.position) {
    mesh.x.push_back(p.x);
    mesh.y.push_back(p.y);
  }
  std::size_t bytes = 0;
  auto add = [&](messages::MeshPolyline line) {
    const std::size_t b = 10 + 16 * line.x.size();
    if (line.x.size() < 2 || bytes + b > kMaxMeshPolylineBytes) return;
    bytes += b;
    mesh.polylines.push_back(std::move(line));
  };
  using peritwin_msgs::mesh_polyline_t;
  for (std::size_t i = 0; i < geometry.outline.size(); ++i) {
    add(region_line(geometry.outline[i], mesh_polyline_t::KIND_OUTLINE, static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < geometry.holes.size(); ++i) {
    add(region_line(geometry.holes[i], mesh_polyline_t::KIND_HOLE, static_cast<int>(i)));
  }
  for (std::size_t i = 0; i < geometry.notches.size(); ++i) {
    messages::MeshPolyline line;
    line.kind = mesh_polyline_t::KIND_NOTCH;
    line.index = static_cast<std::int32_t>(i);
    line.closed = false;
    for (const mesh::Point& p : geometry.notches[i].path) {
      line.x.push_back(p.x);
      line.y.push_back(p.y);
    }
    add(std::move(line));
  }
  return mesh;
}

peritwin_msgs::damage_state_t state_message(const Twin& twin, std::int64_t utime,
                                            const SeqBySource& checkpointed) {
  peritwin_msgs::damage_state_t m{};
  m.utime = utime;
  m.detail_id = twin.detail_id();
  m.state_seq = twin.state_seq();
  for (const auto& [source, seq] : twin.applied()) {
    m.source_ids.push_back(source);
    m.applied_seq.push_back(seq);
    const auto durable = checkpointed.find(source);
    m.checkpointed_seq.push_back(durable == checkpointed.end() ? 0 : durable->second);
    const auto history = twin.histories().find(source);
    const SourceHistory h = history == twin.histories().end() ? SourceHistory{} : history->second;
    m.history.push_back(static_cast<std::int64_t>(h.fingerprint));
    m.history_start.push_back(h.start);
  }
  m.num_sources = static_cast<std::int32_t>(m.source_ids.size());
  const fatigue::FatigueEngine& engine = twin.engine();
  m.total_cycles = engine.total_cycles();
  m.broken_bonds = twin.broken_bonds();
  const CrackReport& report = twin.cracks();
  m.max_damage = report.max_damage;
  bool overload = false;
  for (const auto& e : engine.break_events())
    overload = overload || e.cause == fatigue::BreakCause::overload;
  // Every crack that has started (a notch crack without crack nodes has not), longest first;
  // at most MAX_CRACKS listed.
  m.crack_count = 0;
  for (const auto& rc : report.cracks) {
    const crack::FoundCrack& c = rc.crack;
    if (c.length <= 0.0 && c.nodes == 0) continue;  // not initiated
    ++m.crack_count;
    if (m.crack_count == 1) m.crack_length_m = c.length;
    if (static_cast<std::int32_t>(m.cracks.size()) >= peritwin_msgs::damage_state_t::MAX_CRACKS) {
      continue;
    }
    peritwin_msgs::crack_t k{};
    k.id = c.id;
    k.origin_kind = static_cast<std::int8_t>(c.origin);
    k.origin = rc.origin;
    k.notch_index = c.notch;
    k.origin_x = c.origin_point.x;
    k.origin_y = c.origin_point.y;
    k.tip_x = c.tips[0].position.x;
    k.tip_y = c.tips[0].position.y;
    k.length_m = c.length;
    k.projected_length_m = c.projected_length;
    k.kink_angle_rad = c.kink_angle;
    k.num_nodes = c.nodes;
    k.phase = twin.failure() != Failure::none || overload ? peritwin_msgs::crack_t::PHASE_FINAL
              : c.length > 0.0 ? peritwin_msgs::crack_t::PHASE_PROPAGATION
                               : peritwin_msgs::crack_t::PHASE_INITIATION;
    k.birth_cycle = c.birth_cycle;
    for (std::size_t t = 0; t < c.tips.size(); ++t) {
      peritwin_msgs::crack_tip_t tip{};
      tip.x = c.tips[t].position.x;
      tip.y = c.tips[t].position.y;
      tip.angle_rad = std::atan2(c.tips[t].direction.y, c.tips[t].direction.x);
      tip.k_i = rc.k[t].k_i;
      tip.k_ii = rc.k[t].k_ii;
      tip.k_status = static_cast<std::int8_t>(rc.k[t].status);
      k.tips.push_back(tip);
    }
    k.num_tips = static_cast<std::int32_t>(k.tips.size());
    k.absorbed_ids = c.absorbed;
    k.num_absorbed = static_cast<std::int32_t>(k.absorbed_ids.size());
    m.cracks.push_back(k);
  }
  m.num_cracks = static_cast<std::int32_t>(m.cracks.size());
  m.k_i = report.k_i;
  m.k_ii = report.k_ii;
  const LifeEstimate& life = twin.life();
  m.remaining_cycles = life.central;
  m.remaining_cycles_low = life.low;
  m.remaining_cycles_high = life.high;
  m.remaining_life_seq = life.seq;
  m.remaining_life_source = life.source;
  m.failure = static_cast<std::int8_t>(twin.failure());
  m.end_of_life_cycle = twin.end_of_life_cycle();
  m.ensemble_estimate_cycle = -1;
  m.horizon_cycles = std::numeric_limits<double>::quiet_NaN();
  m.probability_within_horizon = std::numeric_limits<double>::quiet_NaN();
  if (const auto e = twin.ensemble_estimate()) {
    const Ensemble& ensemble = *twin.ensemble();
    m.num_particles = static_cast<std::int32_t>(ensemble.size());
    m.ensemble_estimate_cycle = ensemble.estimate_cycle();
    m.effective_sample_size = e->effective_sample_size;
    m.percentiles = e->percentiles;
    m.end_of_life_percentiles = e->end_of_life;
    m.remaining_percentiles = e->remaining;
    m.num_percentiles = static_cast<std::int32_t>(m.percentiles.size());
    if (e->horizon_cycles > 0) {
      m.horizon_cycles = e->horizon_cycles;
      m.probability_within_horizon = e->probability_within_horizon;
    }
    for (const auto& p : e->posterior) {
      m.parameter_names.push_back(p.name);
      m.parameter_medians.push_back(p.median);
      m.parameter_covs.push_back(p.coefficient_of_variation);
    }
    m.num_parameters = static_cast<std::int32_t>(m.parameter_names.size());
    const auto& records = ensemble.observations();
    m.observation_count = static_cast<std::int32_t>(records.size());
    const std::size_t first =
        records.size() -
        std::min(records.size(),
                 static_cast<std::size_t>(peritwin_msgs::damage_state_t::MAX_OBSERVATIONS));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t k = first; k < records.size(); ++k) {
      const messages::Observation& o = records[k].observation;
      const bool crack = o.kind == messages::ObservationKind::crack_length;
      m.observation_cycles.push_back(o.cycle);
      const bool no_crack = o.kind == messages::ObservationKind::no_crack;
      m.observation_kinds.push_back(crack ? peritwin_msgs::observation_t::KIND_CRACK_LENGTH
                                    : no_crack
                                        ? peritwin_msgs::observation_t::KIND_NO_CRACK
                                        : peritwin_msgs::observation_t::KIND_GAUGE_COMPLIANCE);
      m.observation_lengths_m.push_back(crack ? o.length_m : nan);
      m.observation_sigmas_m.push_back(crack ? o.sigma_m : nan);
      m.observation_pod_a50s_m.push_back(no_crack ? o.pod_a50_m : nan);
      m.observation_predicted_m.push_back(records[k].update.predicted_median_m);
    }
    m.num_observations = static_cast<std::int32_t>(m.observation_cycles.size());
    for (const auto& [source, seq] : twin.observed()) {
      m.observation_source_ids.push_back(source);
      m.observation_applied_seq.push_back(seq);
    }
    m.num_observation_sources = static_cast<std::int32_t>(m.observation_source_ids.size());
  }
  // The gauges (issue 33): influence coefficients of this bond state, the last residuals.
  const auto& gauges = twin.model().gauges();
  const auto influences = twin.gauge_influences();
  const GaugeResiduals& residuals = twin.gauge_residuals();
  for (std::size_t g = 0; g < gauges.size(); ++g) {
    m.gauge_ids.push_back(gauges[g].config.id);
    m.gauge_per_constant.push_back(influences[g][0]);
    m.gauge_per_cos.push_back(influences[g][1]);
    m.gauge_per_sin.push_back(influences[g][2]);
    m.gauge_noise.push_back(gauges[g].config.noise);
    m.gauge_residuals.push_back(residuals.residual[g]);
    m.gauge_residual_sigmas.push_back(residuals.sigma[g]);
    m.gauge_alarm_counts.push_back(static_cast<std::int32_t>(residuals.in_a_row[g]));
  }
  m.num_gauges = static_cast<std::int32_t>(m.gauge_ids.size());
  m.gauge_alarm_sigmas = kGaugeAlarmSigmas;
  m.gauge_alarm_after = static_cast<std::int32_t>(kGaugeAlarmAfter);
  const Twin::Hashes hashes = twin.hashes();
  m.state_hash = core::hex64(hashes.state);
  m.engine_hash = core::hex64(hashes.engine);
  return m;
}

std::vector<peritwin_msgs::damage_field_t> field_messages(const Twin& twin, std::int64_t utime,
                                                          const std::string& mesh_hash) {
  const auto& damage = twin.engine().node_damage();
  const auto total = static_cast<std::int32_t>(damage.size());
  const std::int32_t per = peritwin_msgs::damage_field_t::MAX_NODES_PER_CHUNK;
  const std::int32_t chunks = std::max<std::int32_t>(1, (total + per - 1) / per);
  std::vector<peritwin_msgs::damage_field_t> out;
  for (std::int32_t c = 0; c < chunks; ++c) {
    peritwin_msgs::damage_field_t m;
    m.utime = utime;
    m.detail_id = twin.detail_id();
    m.state_seq = twin.state_seq();
    m.mesh_hash = mesh_hash;
    m.chunk_index = c;
    m.num_chunks = chunks;
    m.total_nodes = total;
    m.first_node = c * per;
    m.num_nodes = std::min(per, total - m.first_node);
    m.damage.reserve(static_cast<std::size_t>(m.num_nodes));
    for (std::int32_t k = 0; k < m.num_nodes; ++k) {
      m.damage.push_back(static_cast<float>(
          damage[static_cast<std::size_t>(m.first_node) + static_cast<std::size_t>(k)]));
    }
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace peritwin::twin
