// Dispersion of 1D bond-based peridynamics, 001 Sec. 4.1: ω(k) of a harmonic wave (Eq. 45) on the
// discrete bar (Eq. 48; Eq. 49 constant kernel, Eq. 50 Gaussian), its group speed, and the
// dispersion of the central finite difference scheme (Eq. 51-52) the paper compares with.
// Units: SI (m, s, 1/m, rad/s).
#pragma once

#include "solver/dynamics/explicit_dynamics.h"

namespace peritwin::dynamics {

/// ω(k) of 001 Eq. (48) with δ = mΔx, for v = √(E/ρ) (A = 1): Eq. (49) for the constant kernel,
/// Eq. (50) for the Gaussian. `volume_correction`: weight the j-th neighbour by the partial
/// volume of Eq. (36), as Eq. (35) does and the integrator does — the paper's Eq. (48) omits it;
/// with δ = mΔx exactly the j = ±m neighbours get ½.
double dispersion_omega(const KernelChoice& kernel, double wave_speed, int m, double dx, double k,
                        bool volume_correction);

/// dω/dk of the same sum: Σ a_j j Δx sin(jkΔx) / (2ω), a_j the coefficients of ω² (for k > 0).
double dispersion_group_speed(const KernelChoice& kernel, double wave_speed, int m, double dx,
                              double k, bool volume_correction);

}  // namespace peritwin::dynamics
