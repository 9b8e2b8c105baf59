// B2 (benchmarks/README.md): mixed-mode fatigue of the CTS specimen after 000 Sec. 6.2 — kink angle
// of the grown crack and K_II/K_I at the initial tip.
#pragma once

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

/// Runs B2 at α with P = 16 kN, R = 0.1 until the crack has grown `growth` (m).
KinkResult run_compact_tension_shear(double alpha, double dx, const fatigue::StrainLawParams& law,
                                     double growth, bool lower_holes_fixed = true);

/// Maximum tangential stress criterion: β = 2·atan((1 − √(1 + 8ρ²))/(4ρ)), ρ = K_II/K_I.
double mts_kink_angle(double kii_over_ki);

}  // namespace peritwin::validation
