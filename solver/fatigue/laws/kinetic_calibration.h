// The calibration of the kinetic law's U and γ on an S-N curve, 004 Sec. "KTF symmetric cyclic
// loading model" (Fig. 4a, 8b): per stress segment, the U, γ that make Eq. (15)'s single-bond life
// closest to the curve's.
#pragma once

#include <cstddef>
#include <span>

#include "core/expected.h"
#include "solver/fatigue/laws/kinetic.h"

namespace peritwin::fatigue {

/// One point of an S-N curve: the stress amplitude σ_a (Pa) and the cycles to failure N there.
struct SnPoint {
  double stress_amplitude = 0.0;
  double cycles = 0.0;
};

struct KineticFit {
  double U = 0.0;      ///< J
  double gamma = 0.0;  ///< m^3
  /// max_i |ln N_i − ln N(σ_a,i)|, N(σ) the fitted single-bond life (kt_sn_life).
  double max_abs_log_error = 0.0;
  /// sqrt(mean of the squared errors), the quantity minimized.
  double rms_log_error = 0.0;
};

/// The life of one bond (cycles, real) from the virgin state at constant amplitude σ_a and load
/// ratio R < 1: N = r0/Φ(σ_max, R) with σ_max = 2σ_a/(1 − R), Φ = kt_cycle_dose and
/// r0 = kt_remaining_life(0, λ, n0) (= 1 when n0 = kt_n0_for_unit_life(λ)). 004 Eq. (15) at n = 1.
double kt_sn_life(double stress_amplitude, double load_ratio, double frequency, double U,
                  double gamma, double lambda, double n0, double thermal_energy);

/// U and γ minimizing Σ (ln N_i − ln kt_sn_life(σ_a,i))² over the points, with λ, n0 and f taken
/// from `fixed` (its U, γ are ignored) and θ given (kT, or Eq. 26's kT + ψA).
///
/// Method: with b = γ/θ fixed, ln N is linear in u = U/θ with unit slope (004 Eq. 15: Φ ∝ e^(−u)),
/// so the best u is a closed-form mean and the residual is the spread of ln N_i + g_i(b), g_i the
/// log of the bracket. That spread is scanned on a fixed logarithmic grid of b (γσ_max/θ from 1e-3
/// to 1e4 at the points' stresses), and its derivative's sign change next to the best grid point
/// is bisected to the last bit: deterministic, no tolerance to tune.
/// Errors: fewer than 2 points, a non-finite or non-positive σ_a or N, fewer than 2 distinct
/// stresses, R >= 1, θ <= 0, invalid λ/n0/f, or a minimum at the edge of the grid (the points ask
/// for γ → 0 or ∞, e.g. N rising with stress).
core::Expected<KineticFit> kt_calibrate_segment(std::span<const SnPoint> points, double load_ratio,
                                                const KineticParams& fixed, double thermal_energy);

}  // namespace peritwin::fatigue
