#include "twin/lcm/messages_io.h"

#include <algorithm>
#include <cmath>

namespace peritwin::twin {

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
  }
  m.num_sources = static_cast<std::int32_t>(m.source_ids.size());
  const FatigueEngine& engine = twin.engine();
  m.total_cycles = engine.total_cycles();
  m.broken_bonds = twin.broken_bonds();
  const CrackReport& report = twin.cracks();
  m.max_damage = report.max_damage;
  bool overload = false;
  for (const auto& e : engine.break_events())
    overload = overload || e.cause == BreakCause::overload;
  // Every crack that has started (a notch crack without crack nodes has not), longest first;
  // at most MAX_CRACKS listed.
  m.crack_count = 0;
  for (const auto& rc : report.cracks) {
    const FoundCrack& c = rc.crack;
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
  m.state_hash = twin.state_hash_hex();
  m.engine_hash = hex64(twin.engine_hash());
  return m;
}

std::vector<peritwin_msgs::damage_field_t> field_messages(const Twin& twin, std::int64_t utime) {
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
