// B2 (docs/benchmarks.md): mixed-mode fatigue of the CTS specimen after 000 Sec. 6.2 — kink angle
// of the grown crack and K_II/K_I at the initial tip.
#pragma once

#include <string>

#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/strain_range.h"
#include "validation/specimens.h"

namespace peritwin::validation {

struct KinkResult {
  double alpha = 0.0;        ///< load angle (rad)
  double beta = 0.0;         ///< kink angle measured on the grown crack (rad, CCW +)
  double kii_over_ki = 0.0;  ///< at the initial tip, 001 Eq. (62)-(63)
  double mts_beta = 0.0;     ///< maximum tangential stress prediction from that ratio (rad)
  double t_over_ki = 0.0;    ///< T-stress over K_I at the initial tip (1/√m), from the faces
  /// The same two from a Williams-series fit to the nodes 3δ to `williams_fit_outer_radius` from
  /// the initial tip (williams_series_fit), an independent check of both; NaN when the annulus
  /// holds too few nodes for the fit.
  double kii_over_ki_fit = 0.0;
  double t_over_ki_fit = 0.0;
  double k_i_fit_per_newton = 0.0;   ///< K_I of that fit per N of P (Pa·√m/N)
  double k_ii_fit_per_newton = 0.0;  ///< K_II of that fit per N of P (Pa·√m/N)
  /// CTS only: the fitted K_I and |K_II| over Richard's formulas (richard_cts_stress_intensity);
  /// NaN where Richard's K is 0.
  double ki_over_richard = 0.0;
  double kii_over_richard = 0.0;
  double growth = 0.0;               ///< crack length grown when β was measured (m)
  double phase_switch_damage = 0.0;  ///< φ0 used (000 Sec. 4.4)
  std::int64_t cycles = 0;
  double wall_s = 0.0;
  /// Empty when the initial static solve succeeded; else why it failed (nothing was measured).
  std::string failure;
};

struct KinkRun {
  double alpha = 0.0;  ///< load angle (rad)
  double dx = 0.001;
  double horizon_ratio = 3.015;  ///< δ/Δx (000 Fig. 15 compares 2, 3 and 4)
  fatigue::StrainLawParams law;  ///< A, m (and the energy law's via 000 Eq. 44-46)
  fatigue::FatigueLaw fatigue_law =
      fatigue::FatigueLaw::energy;       ///< 000 Sec. 6.2 uses its energy-based law
  double growth = 0.010;                 ///< crack growth at which β is measured (m)
  bool lower_holes_fixed = true;         ///< see CompactTensionShearSpec
  bool rigid_fixtures = false;           ///< see CompactTensionShearSpec
  bool compressed_bonds_fatigue = true;  ///< see FatigueSettings
  mesh::GridPerturbation grid;           ///< irregular node arrangement
  /// 000 Sec. 6.2 is state-based; bond-based (ν = 1/3 instead of 0.33) runs about 6× faster.
  model::ModelKind model = model::ModelKind::state_based;
  /// φ0 (000 Sec. 4.4); 0 = phase_switch_damage_for_horizon(horizon_ratio).
  double phase_switch_damage = 0.0;
  std::string snapshot_csv;                  ///< final node damage (x_m,y_m,damage) unless empty
  double williams_fit_outer_radius = 0.015;  ///< outer radius of the K/T fit's annulus (m)
};

/// Runs B2 at α with P = 16 kN, R = 0.1 until the crack has grown `growth`.
KinkResult run_compact_tension_shear(const KinkRun& run);

/// The CTS's tip loading without the specimen: a square plate of half-size `half_size` with a
/// straight crack from its left edge to its centre, loaded on its outer edges by the tractions of
/// the Williams near-tip field (K_I, K_II and a T-stress). It tells whether the PD crack's kink
/// angle follows the mixity alone (MTS) or the specimen. K_II has the CTS's sign (the crack kinks
/// upward), as in run_compact_tension_shear.
struct KFieldRun {
  double kii_over_ki = 0.466;  ///< |K_II|/K_I of the applied field
  double t_over_ki = 0.0;      ///< T/K_I (1/√m)
  double k_i = 13.3e6;       ///< K_I at P_max (Pa·√m): Richard's CTS formula at 16 kN, α = 45°
  double half_size = 0.030;  ///< m
  double dx = 0.0005;
  fatigue::StrainLawParams law;
  fatigue::FatigueLaw fatigue_law = fatigue::FatigueLaw::energy;
  double growth = 0.010;
  mesh::GridPerturbation grid;  ///< irregular node arrangement
  std::string snapshot_csv;
};

KinkResult run_k_field_plate(const KFieldRun& run);

/// Maximum tangential stress criterion: β = 2·atan((K_I − √(K_I² + 8K_II²))/(4K_II)).
double mts_kink_angle(double k_i, double k_ii);

}  // namespace peritwin::validation
