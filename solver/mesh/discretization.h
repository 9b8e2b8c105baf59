// Uniform-grid discretization of a detail: material points (nodes), their families (bonds within
// the horizon, found with the grid itself as the cell list) and the partial-volume correction.
// Optionally the nodes are moved off their grid points by a small deterministic perturbation, so
// that cracks are not pulled towards the lattice directions (0°, 45°, 63.4°, ...).
// Units: SI (m, m^3).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "solver/mesh/geometry.h"

namespace peritwin::mesh {

using NodeIndex = std::int32_t;
using BondIndex = std::int32_t;

/// 001 Eq. (36): fraction of node j's cell inside the horizon of a bond of length xi.
double partial_volume_factor(double bond_length, double horizon, double dx);

/// Irregular node arrangement: node (i, j) sits at its grid point plus amplitude·Δx·(u, v), with
/// u, v uniform in [−1, 1) drawn from a hash of (i, j, seed), so the arrangement is reproducible
/// and does not depend on the order nodes are visited. amplitude = 0: the regular grid.
struct GridPerturbation {
  double amplitude = 0.0;  ///< fraction of Δx, in [0, 0.25) (then a node stays nearest its cell)
  std::uint64_t seed = 0;
};

/// Nodes and bonds of one detail. Every bond is stored once (i < j); per-node families are a CSR
/// index into the bond list. All per-bond arrays have num_bonds() entries (structure of arrays).
struct Discretization {
  double dx = 0.0;         ///< grid spacing Δx (m)
  double horizon = 0.0;    ///< δ (m)
  double thickness = 0.0;  ///< h (m)
  Rectangle box;  ///< grid origin: node (i, j) sits at (x_min + (i+½)Δx, y_min + (j+½)Δx)
  GridPerturbation perturbation;  ///< node (i, j) is moved off that point by at most amplitude·Δx

  std::vector<Point> position;
  std::vector<double> volume;         ///< V = Δx²·h
  std::vector<std::uint8_t> rigid;    ///< node inside a rigid region
  std::vector<std::uint8_t> no_fail;  ///< node inside a no-fail zone

  std::vector<NodeIndex> bond_i, bond_j;
  std::vector<double> bond_length;         ///< ξ (m)
  std::vector<double> bond_cos, bond_sin;  ///< unit vector from i to j (000 Eq. 3e-3f)
  std::vector<double> bond_volume_factor;  ///< 001 Eq. (36)
  std::vector<std::uint8_t> bond_precut;   ///< cut by a notch/pre-crack at construction

  std::vector<std::int32_t> family_offset;  ///< size num_nodes()+1
  std::vector<BondIndex> family_bonds;      ///< bonds of node k: [offset[k], offset[k+1])

  [[nodiscard]] std::int32_t num_nodes() const {
    return static_cast<std::int32_t>(position.size());
  }
  [[nodiscard]] std::int32_t num_bonds() const { return static_cast<std::int32_t>(bond_i.size()); }
  [[nodiscard]] NodeIndex other_end(BondIndex b, NodeIndex k) const {
    return bond_i[b] == k ? bond_j[b] : bond_i[b];
  }

  /// Nearest node to p (ties broken by the lower index), or -1 when there are no nodes.
  [[nodiscard]] NodeIndex nearest_node(Point p) const;
  /// All nodes inside a region, in index order.
  [[nodiscard]] std::vector<NodeIndex> nodes_in(const Region& region) const;
  /// Mean position of the given nodes (NaN for none): where a load spread equally over them acts.
  [[nodiscard]] Point centroid(std::span<const NodeIndex> nodes) const;
};

/// Builds nodes on the grid (perturbed as asked) clipped to the geometry, families within δ
/// weighted by the partial volumes of 001 Eq. (36), cuts bonds crossing any segment of
/// a notch path. horizon = δ in
/// metres. Throws std::invalid_argument for a perturbation amplitude outside [0, 0.25).
Discretization discretize(const DetailGeometry& geometry, double dx, double horizon,
                          const GridPerturbation& perturbation = {});

}  // namespace peritwin::mesh
