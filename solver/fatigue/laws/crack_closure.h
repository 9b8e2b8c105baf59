// Crack closure: the effective part of a load cycle when the crack faces touch (issue 34,
// docs/compression.md). Newman's crack-opening function (J. C. Newman Jr., "A crack opening
// stress equation for fatigue crack growth", Int. J. Fracture 24 (1984) R131-R135; the form
// NASGRO uses): the crack opens at S_o = f·S_max, and the effective range is
//   ΔK_eff = (1 − f)·K_max,  U = ΔK_eff/ΔK = (1 − f)/(1 − R),
// with, for a constraint factor α (1 plane stress, 3 plane strain) and the ratio S_max/σ0 of the
// peak stress to the flow stress,
//   A0 = (0.825 − 0.34α + 0.05α²)·[cos(π S_max/(2σ0))]^(1/α)
//   A1 = (0.415 − 0.071α)·S_max/σ0
//   A3 = 2A0 + A1 − 1,   A2 = 1 − A0 − A1 − A3
//   f = max(R, A0 + A1 R + A2 R² + A3 R³)   for R ≥ 0
//   f = A0 + A1 R                           for −2 ≤ R < 0
//   f = A0 − 2A1                            for R < −2 (NASGRO's continuation: Newman's fit
//                                           covers −2 ≤ R; beyond it the opening level is held)
// In the twin the bond strain range of a cycle becomes |s⁺|(1 − f) instead of |s⁺|(1 − R) (000
// Eq. 15-16 with R replaced by f): the same factor on every bond, as ΔK_eff is on K.
#pragma once

#include "core/expected.h"

namespace peritwin::fatigue {

struct NewmanClosure {
  /// α: 1 (plane stress) to 3 (plane strain). 2: between them, as NASGRO's constraint-loss
  /// curves put an aluminium alloy's through-crack in the middle of its growth.
  double constraint = 2.0;
  /// S_max/σ0 in (0, 1): NASGRO's default 0.3.
  double smax_over_flow_stress = 0.3;
};

/// OK, or why not: constraint in [1, 3], S_max/σ0 in (0, 1), both finite.
core::Status validate(const NewmanClosure& c);

/// Newman's opening ratio f = S_o/S_max at load ratio R (the file comment).
double newman_opening_ratio(double load_ratio, const NewmanClosure& c);

/// U = (1 − f)/(1 − R), the effective fraction of the range (R < 1).
double newman_effective_range_fraction(double load_ratio, const NewmanClosure& c);

}  // namespace peritwin::fatigue
