// B2 (benchmarks/README.md): mixed-mode fatigue of the CTS specimen after 000 Sec. 6.2 — kink angle
// of the grown crack and K_II/K_I at the initial tip.
#pragma once

#include <string>

#include "solver/fatigue_engine.h"
#include "solver/fatigue_law.h"
#include "solver/specimens.h"

namespace peritwin::validation {

struct KinkResult {
  double alpha = 0.0;        ///< load angle (rad)
  double beta = 0.0;         ///< kink angle measured on the grown crack (rad, CCW +)
  double kii_over_ki = 0.0;  ///< at the initial tip, 001 Eq. (62)-(63)
  double mts_beta = 0.0;     ///< maximum tangential stress prediction from that ratio (rad)
  double growth = 0.0;       ///< crack length grown when β was measured (m)
  std::int64_t cycles = 0;
  double wall_s = 0.0;
};

struct KinkRun {
  double alpha = 0.0;  ///< load angle (rad)
  double dx = 0.001;
  fatigue::StrainLawParams law;                 ///< A, m (and the energy law's via 000 Eq. 44-46)
  FatigueLaw fatigue_law = FatigueLaw::energy;  ///< 000 Sec. 6.2 uses its energy-based law
  double growth = 0.010;                        ///< crack growth at which β is measured (m)
  bool lower_holes_fixed = true;                ///< see CompactTensionShearSpec
  GridPerturbation grid;                        ///< irregular node arrangement
  std::string snapshot_csv;                     ///< final node damage (x_m,y_m,damage) unless empty
};

/// Runs B2 at α with P = 16 kN, R = 0.1 until the crack has grown `growth`.
KinkResult run_compact_tension_shear(const KinkRun& run);

/// Maximum tangential stress criterion: β = 2·atan((1 − √(1 + 8ρ²))/(4ρ)), ρ = K_II/K_I.
double mts_kink_angle(double kii_over_ki);

}  // namespace peritwin::validation
