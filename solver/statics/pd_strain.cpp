#include "solver/statics/pd_strain.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace peritwin::statics {

double PlaneStrain::max_principal() const {
  const double mean = 0.5 * (xx + yy);
  const double radius = std::hypot(0.5 * (xx - yy), xy);
  return mean + radius;
}

std::optional<DisplacementGradient> pd_displacement_gradient(const mesh::Discretization& disc,
                                                             std::span<const std::uint8_t> intact,
                                                             std::span<const double> u,
                                                             mesh::NodeIndex node) {
  const auto k = static_cast<std::size_t>(node);
  // Shape tensor K = Σ ω ξ⊗ξ V and deformed moment M = Σ ω (ξ + η)⊗ξ V (004 Eq. 6).
  double kxx = 0.0, kxy = 0.0, kyy = 0.0;
  double mxx = 0.0, mxy = 0.0, myx = 0.0, myy = 0.0;
  const auto first = static_cast<std::size_t>(disc.family_offset[k]);
  const auto last = static_cast<std::size_t>(disc.family_offset[k + 1]);
  for (std::size_t f = first; f < last; ++f) {
    const mesh::BondIndex b = disc.family_bonds[f];
    if (!intact.empty() && intact[static_cast<std::size_t>(b)] == 0) continue;
    const auto j = static_cast<std::size_t>(disc.other_end(b, node));
    const double xi_x = disc.position[j].x - disc.position[k].x;
    const double xi_y = disc.position[j].y - disc.position[k].y;
    const double eta_x = u[2 * j] - u[2 * k];
    const double eta_y = u[2 * j + 1] - u[2 * k + 1];
    const double v = disc.volume[j] * disc.bond_volume_factor[static_cast<std::size_t>(b)];
    kxx += xi_x * xi_x * v;
    kxy += xi_x * xi_y * v;
    kyy += xi_y * xi_y * v;
    mxx += (xi_x + eta_x) * xi_x * v;
    mxy += (xi_x + eta_x) * xi_y * v;
    myx += (xi_y + eta_y) * xi_x * v;
    myy += (xi_y + eta_y) * xi_y * v;
  }
  const double det = kxx * kyy - kxy * kxy;
  // Bonds on one line (or none) leave K singular: no gradient in the other direction.
  if (!(det > 1e-12 * (kxx * kyy)) || !(kxx > 0.0) || !(kyy > 0.0)) return std::nullopt;
  // F = M·K⁻¹ with K⁻¹ = [kyy, −kxy; −kxy, kxx]/det; H = F − I.
  return DisplacementGradient{(mxx * kyy - mxy * kxy) / det - 1.0, (mxy * kxx - mxx * kxy) / det,
                              (myx * kyy - myy * kxy) / det, (myy * kxx - myx * kxy) / det - 1.0};
}

std::vector<PlaneStrain> pd_lagrange_strain(const mesh::Discretization& disc,
                                            std::span<const std::uint8_t> intact,
                                            std::span<const double> u) {
  const auto nodes = static_cast<std::size_t>(disc.num_nodes());
  if (u.size() != 2 * nodes) {
    throw std::invalid_argument("pd_lagrange_strain: " + std::to_string(u.size()) +
                                " displacement components for " + std::to_string(nodes) + " nodes");
  }
  if (!intact.empty() && intact.size() != static_cast<std::size_t>(disc.num_bonds())) {
    throw std::invalid_argument("pd_lagrange_strain: intact flags do not match the bonds");
  }
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<PlaneStrain> out(nodes, PlaneStrain{nan, nan, nan});
  for (std::size_t k = 0; k < nodes; ++k) {
    const auto h = pd_displacement_gradient(disc, intact, u, static_cast<mesh::NodeIndex>(k));
    if (!h) continue;
    // E = ½(Hᵀ + H + HᵀH) (004 Eq. 7).
    out[k].xx = h->xx + 0.5 * (h->xx * h->xx + h->yx * h->yx);
    out[k].yy = h->yy + 0.5 * (h->xy * h->xy + h->yy * h->yy);
    out[k].xy = 0.5 * (h->xy + h->yx) + 0.5 * (h->xx * h->xy + h->yx * h->yy);
  }
  return out;
}

}  // namespace peritwin::statics
