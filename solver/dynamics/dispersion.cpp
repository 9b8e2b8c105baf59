#include "solver/dynamics/dispersion.h"

#include <cmath>

namespace peritwin::dynamics {

namespace {

/// a_j with ω² = Σ_{j≠0} a_j (1 − cos jkΔx): 001 Eq. (48) with c0 of Eq. (26)/(33), A = 1, written
/// as Eq. (49)-(50): a_j = 2v²/(m²Δx²) · [p²/(1 − e^{−p²}) e^{−(pj/m)²}] / |j| (· β_j).
double coefficient(const KernelChoice& kernel, double wave_speed, int m, double dx, int j,
                   bool volume_correction) {
  const double md = m * dx;
  double a = 2.0 * wave_speed * wave_speed / (md * md) / std::abs(j);
  if (kernel.shape == KernelChoice::Shape::gaussian) {
    const double p = kernel.p;
    a *= p * p / (1.0 - std::exp(-p * p)) * kernel_weight(kernel, static_cast<double>(j) / m);
  }
  if (volume_correction) a *= mesh::partial_volume_factor(std::abs(j) * dx, md, dx);
  return a;
}

}  // namespace

double dispersion_omega(const KernelChoice& kernel, double wave_speed, int m, double dx, double k,
                        bool volume_correction) {
  double w2 = 0.0;
  for (int j = 1; j <= m; ++j) {  // ±j contribute equally
    w2 += 2.0 * coefficient(kernel, wave_speed, m, dx, j, volume_correction) *
          (1.0 - std::cos(j * k * dx));
  }
  return std::sqrt(w2);
}

double dispersion_group_speed(const KernelChoice& kernel, double wave_speed, int m, double dx,
                              double k, bool volume_correction) {
  double d = 0.0;
  for (int j = 1; j <= m; ++j) {
    d += 2.0 * coefficient(kernel, wave_speed, m, dx, j, volume_correction) * j * dx *
         std::sin(j * k * dx);
  }
  return d / (2.0 * dispersion_omega(kernel, wave_speed, m, dx, k, volume_correction));
}

}  // namespace peritwin::dynamics
