#include "validation/b2_compact_tension_shear.h"

#include <chrono>
#include <cmath>
#include <fstream>

#include "solver/crack_tracker.h"
#include "solver/fatigue_engine.h"

namespace peritwin::validation {

double mts_kink_angle(double rho) {
  if (rho == 0.0) return 0.0;
  return 2.0 * std::atan((1.0 - std::sqrt(1.0 + 8.0 * rho * rho)) / (4.0 * rho));
}

KinkResult run_compact_tension_shear(const KinkRun& run) {
  const auto t0 = std::chrono::steady_clock::now();
  const double alpha = run.alpha;
  const double growth = run.growth;
  CompactTensionShearSpec spec;
  spec.lower_holes_fixed = run.lower_holes_fixed;
  spec.grid = run.grid;
  ModelOptions options;
  options.kind = ModelKind::state_based;
  const Specimen s = make_compact_tension_shear(spec, options, run.dx);
  FatigueSettings settings;
  settings.law = run.fatigue_law;
  settings.strain = run.law;
  settings.incremental = true;
  FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings);
  KinkResult result;
  result.alpha = alpha;
  if (!engine.initialize()) return result;
  // K_I, K_II at the initial tip from the elastic solution at P = 1 N.
  std::vector<double> u;
  engine.solver().displacement(1.0, alpha, u);
  const double nu = s.material.poisson_ratio;
  const double mu = s.material.youngs_modulus / (2 * (1 + nu));
  const auto k = stress_intensity_by_extrapolation(s.disc, u, s.initial_crack_tip, {1.0, 0.0},
                                                   3 * s.disc.horizon, 6 * s.disc.horizon, mu,
                                                   kolosov_kappa(nu, PlaneCondition::plane_stress));
  result.kii_over_ki = k.k_ii / k.k_i;
  result.mts_beta = mts_kink_angle(result.kii_over_ki);
  CrackTrackerOptions o;
  o.kink_distance = 0.5 * growth;
  const CrackTracker tracker(s.disc, s.geometry.notches, o);
  while (engine.apply({16000.0, 0.1, alpha, 200}) == EngineStatus::ok) {
    const auto cracks = tracker.measure(engine.node_damage());
    if (cracks.front().length >= growth || engine.total_cycles() > 10'000'000) break;
  }
  const auto cracks = tracker.measure(engine.node_damage());
  if (!run.snapshot_csv.empty()) {
    std::ofstream out(run.snapshot_csv);
    out << "x_m,y_m,damage\n";
    for (NodeIndex n = 0; n < s.disc.num_nodes(); ++n) {
      out << s.disc.position[n].x << ',' << s.disc.position[n].y << ','
          << engine.node_damage()[static_cast<std::size_t>(n)] << '\n';
    }
  }
  result.beta = cracks.front().kink_angle;
  result.growth = cracks.front().length;
  result.cycles = engine.total_cycles();
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace peritwin::validation
