#include "validation/b2_compact_tension_shear.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "solver/crack/crack_tracker.h"
#include "solver/fatigue/fatigue_engine.h"
#include "validation/damage_csv.h"

namespace peritwin::validation {

double mts_kink_angle(double k_i, double k_ii) {
  if (k_ii == 0.0) return 0.0;
  // Written in K_I and K_II rather than their ratio: near α = 90° the extracted K_I can be slightly
  // negative, and the ratio's sign would then turn the kink the wrong way (→ ∓70.5° by K_II alone).
  return 2.0 * std::atan((k_i - std::sqrt(k_i * k_i + 8.0 * k_ii * k_ii)) / (4.0 * k_ii));
}

namespace {

/// Grows the crack under P_max = `p_max`, R = 0.1 at `alpha` until it is `growth` long; K at the
/// initial tip from the elastic solution; β on the grown crack.
KinkResult grow_and_measure(const statics::Specimen& s, fatigue::FatigueLaw law,
                            const fatigue::StrainLawParams& params, double p_max, double alpha,
                            double growth, const std::string& snapshot_csv,
                            double williams_fit_outer_radius, double phase_switch_damage = 0.0,
                            bool compressed_bonds_fatigue = true) {
  const auto t0 = std::chrono::steady_clock::now();
  fatigue::FatigueSettings settings;
  settings.law = law;
  settings.strain = params;
  settings.incremental = true;
  settings.compressed_bonds_fatigue = compressed_bonds_fatigue;
  settings.phase_switch_damage =
      phase_switch_damage > 0.0
          ? phase_switch_damage
          : fatigue::phase_switch_damage_for_horizon(s.disc.horizon / s.disc.dx);
  fatigue::FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings, s.ties);
  KinkResult result;
  result.alpha = alpha;
  result.phase_switch_damage = settings.phase_switch_damage;
  if (!engine.initialize()) {
    result.failure = "the initial static solve failed: " + engine.failure_reason();
    return result;
  }
  std::vector<double> u;
  engine.solver().displacement(1.0, alpha, u);
  const double nu = s.material.poisson_ratio;
  const double mu = s.material.youngs_modulus / (2 * (1 + nu));
  const auto k = crack::stress_intensity_by_extrapolation(
      s.disc, u, s.initial_crack_tip, {1.0, 0.0}, 3 * s.disc.horizon, 6 * s.disc.horizon, mu,
      crack::kolosov_kappa(nu, model::PlaneCondition::plane_stress));
  result.kii_over_ki = k.k_ii / k.k_i;
  result.mts_beta = mts_kink_angle(k.k_i, k.k_ii);
  result.t_over_ki =
      crack::t_stress_from_crack_faces(s.disc, u, s.initial_crack_tip, 3 * s.disc.horizon,
                                       6 * s.disc.horizon, s.material.youngs_modulus) /
      k.k_i;
  const auto fit = crack::williams_series_fit(
      s.disc, u, s.initial_crack_tip, {1.0, 0.0}, 3 * s.disc.horizon, williams_fit_outer_radius, 7,
      mu, crack::kolosov_kappa(nu, model::PlaneCondition::plane_stress));
  // Too few nodes in the annulus (3δ beyond the outer radius at a coarse --dx): no fit, NaN.
  const bool fitted = fit.fitted && fit.k_i != 0.0;
  const double none = std::numeric_limits<double>::quiet_NaN();
  result.kii_over_ki_fit = fitted ? fit.k_ii / fit.k_i : none;
  result.t_over_ki_fit = fitted ? fit.t_stress / fit.k_i : none;
  result.k_i_fit_per_newton = fitted ? fit.k_i : none;
  result.k_ii_fit_per_newton = fitted ? fit.k_ii : none;
  crack::CrackTrackerOptions o;
  o.phase_switch_damage = settings.phase_switch_damage;
  o.kink_distance = 0.5 * growth;
  const crack::CrackTracker tracker(s.disc, s.geometry.notches, o);
  while (engine.apply({p_max, 0.1, alpha, 200}) == fatigue::EngineStatus::ok) {
    const auto cracks = tracker.measure(engine.node_damage());
    if (cracks.front().length >= growth || engine.total_cycles() > 10'000'000) break;
  }
  const auto cracks = tracker.measure(engine.node_damage());
  if (!snapshot_csv.empty()) write_damage_csv(snapshot_csv, s.disc, engine.node_damage());
  result.beta = cracks.front().kink_angle;
  result.growth = cracks.front().length;
  result.cycles = engine.total_cycles();
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace

KinkResult run_k_field_plate(const KFieldRun& run) {
  KFieldPlateSpec spec;
  spec.half_size = run.half_size;
  spec.t_over_ki = run.t_over_ki;
  spec.grid = run.grid;
  model::ModelOptions options;
  options.kind = model::ModelKind::state_based;
  const statics::Specimen s = make_k_field_plate(spec, options, run.dx);
  const double alpha = std::atan(run.kii_over_ki);
  return grow_and_measure(s, run.fatigue_law, run.law, run.k_i / std::cos(alpha), alpha, run.growth,
                          run.snapshot_csv, 0.6 * run.half_size);
}

KinkResult run_compact_tension_shear(const KinkRun& run) {
  CompactTensionShearSpec spec;
  spec.lower_holes_fixed = run.lower_holes_fixed;
  spec.grid = run.grid;
  spec.rigid_fixtures = run.rigid_fixtures;
  model::ModelOptions options;
  options.kind = run.model;
  const statics::Specimen s = make_compact_tension_shear(spec, options, run.dx, run.horizon_ratio);
  // The fit stays inside the ligament and clear of the middle pin hole 30 mm above the tip.
  KinkResult result = grow_and_measure(s, run.fatigue_law, run.law, 16000.0, run.alpha, run.growth,
                                       run.snapshot_csv, run.williams_fit_outer_radius,
                                       run.phase_switch_damage, run.compressed_bonds_fatigue);
  if (!result.failure.empty()) return result;
  const auto richard = richard_cts_stress_intensity(spec, 1.0, run.alpha);
  // No ratio where Richard's K vanishes (K_II at α = 0): NaN, printed as null.
  const double none = std::numeric_limits<double>::quiet_NaN();
  result.ki_over_richard = richard.k_i > 0 ? result.k_i_fit_per_newton / richard.k_i : none;
  result.kii_over_richard =
      richard.k_ii > 0 ? std::abs(result.k_ii_fit_per_newton) / richard.k_ii : none;
  return result;
}

}  // namespace peritwin::validation
