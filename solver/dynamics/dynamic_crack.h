// A crack running under explicit dynamics: its tip and speed from the bonds the integrator has
// broken (critical stretch), measured by the crack tracker (solver/crack) on the damage index.
// Units: SI (m, s, m/s).
#pragma once

#include <vector>

#include "solver/crack/crack_tracker.h"
#include "solver/dynamics/explicit_dynamics.h"

namespace peritwin::dynamics {

struct CrackTipSample {
  double time = 0.0;    ///< s
  mesh::Point tip;      ///< the crack tracker's tip (the notch tip before anything grew)
  double length = 0.0;  ///< grown length along the path from the notch tip (m)
  double speed = 0.0;   ///< (length − previous length)/(time − previous time); 0 at the first
};

/// Samples one notch's crack whenever asked; keep one per run.
class DynamicCrackMonitor {
 public:
  DynamicCrackMonitor(const mesh::Discretization& disc, std::vector<mesh::Notch> notches,
                      crack::CrackTrackerOptions options = {});
  /// The crack from `notch` at the integrator's current step.
  const CrackTipSample& sample(const ExplicitDynamics& dynamics, int notch = 0);
  [[nodiscard]] const std::vector<CrackTipSample>& history() const { return history_; }

 private:
  const mesh::Discretization& disc_;
  crack::CrackTracker tracker_;
  std::vector<double> damage_;
  std::vector<CrackTipSample> history_;
};

}  // namespace peritwin::dynamics
