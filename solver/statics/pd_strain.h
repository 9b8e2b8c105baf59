// The peridynamic strain at a node from a displacement field, for people to look at (results
// files): the deformation gradient by the peridynamic differential operator over the node's
// intact bonds (004 Eq. 6) and the Lagrange strain from it (004 Eq. 7). It needs no spatial
// derivative of u, so it is defined next to a crack too (broken bonds are left out).
// Units: SI (m); strains are dimensionless.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "solver/mesh/discretization.h"

namespace peritwin::statics {

/// In-plane Lagrange strain E at a node (tensor components; exy is E_12, not γ = 2E_12).
struct PlaneStrain {
  double xx = 0.0;
  double yy = 0.0;
  double xy = 0.0;
  /// tr E: the area change to first order (for an affine field u = H·x, E_xx + E_yy).
  [[nodiscard]] double dilatation() const { return xx + yy; }
  /// The larger principal strain of the 2x2 tensor.
  [[nodiscard]] double max_principal() const;
};

/// The displacement gradient H = F − I at a node (H_ij = ∂u_i/∂x_j): xy = ∂u_x/∂y.
struct DisplacementGradient {
  double xx = 0.0;
  double xy = 0.0;
  double yx = 0.0;
  double yy = 0.0;
};

/// H = F − I at node k with F of 004 Eq. (6) over the node's intact bonds (as below); nullopt
/// when those bonds do not span the plane. u: the full DOF vector.
std::optional<DisplacementGradient> pd_displacement_gradient(const mesh::Discretization& disc,
                                                             std::span<const std::uint8_t> intact,
                                                             std::span<const double> u,
                                                             mesh::NodeIndex k);

/// Per node: F = [Σ_j ω (ξ + η) ⊗ ξ V_j] · [Σ_j ω ξ ⊗ ξ V_j]⁻¹ over the intact bonds j of the
/// node (004 Eq. 6, ξ = x_j − x_k, η = u_j − u_k, V_j the partial volume of 001 Eq. 36, ω = 1:
/// the grid's families are symmetric, so the influence function only reweights them), then
/// E = ½(Hᵀ + H + HᵀH) with H = F − I the displacement gradient (004 Eq. 7). For an affine field
/// u = H·x this gives E of that H exactly, at boundary nodes too. A node whose intact bonds do not
/// span the plane (isolated, or all bonds on one line) gets NaN components.
/// `intact`: one flag per bond (empty = all intact); `u`: the full DOF vector [u0, v0, u1, ...].
std::vector<PlaneStrain> pd_lagrange_strain(const mesh::Discretization& disc,
                                            std::span<const std::uint8_t> intact,
                                            std::span<const double> u);

}  // namespace peritwin::statics
