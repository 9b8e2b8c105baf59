#include "solver/dynamics/dynamic_crack.h"

namespace peritwin::dynamics {

DynamicCrackMonitor::DynamicCrackMonitor(const mesh::Discretization& disc,
                                         std::vector<mesh::Notch> notches,
                                         crack::CrackTrackerOptions options)
    : disc_(disc), tracker_(disc, std::move(notches), options) {}

const CrackTipSample& DynamicCrackMonitor::sample(const ExplicitDynamics& dynamics, int notch) {
  model::damage_index(disc_, dynamics.intact_bonds(), damage_);  // 000 Eq. (13)
  const auto metrics = tracker_.measure(damage_);
  const crack::CrackMetrics& m = metrics.at(static_cast<std::size_t>(notch));
  CrackTipSample s;
  s.time = dynamics.time();
  s.tip = m.length > 0 ? m.tip : m.origin;
  s.length = m.length;
  if (!history_.empty() && s.time > history_.back().time) {
    s.speed = (s.length - history_.back().length) / (s.time - history_.back().time);
  }
  history_.push_back(s);
  return history_.back();
}

}  // namespace peritwin::dynamics
