#include "solver/statics/rigid_regions.h"

#include <cstddef>

namespace peritwin::statics {

double material_rigid_factor(const mesh::DetailGeometry& geometry) {
  return geometry.rigid_model == mesh::RigidModel::stiff_material ? geometry.rigid_factor : 1.0;
}

std::vector<Tie> rigid_region_ties(const mesh::Discretization& disc, const model::PdModel& model,
                                   const mesh::DetailGeometry& geometry) {
  std::vector<Tie> ties;
  if (geometry.rigid_model != mesh::RigidModel::constraint || geometry.rigid_regions.empty()) {
    return ties;
  }
  // The region of each node (−1: none), as Discretization::rigid was decided: by the position.
  const auto nn = static_cast<std::size_t>(disc.num_nodes());
  std::vector<int> region(nn, -1);
  for (std::size_t k = 0; k < nn; ++k) {
    if (disc.rigid[k] == 0) continue;
    for (std::size_t r = 0; r < geometry.rigid_regions.size(); ++r) {
      if (geometry.rigid_regions[r].contains(disc.position[k])) {
        region[k] = static_cast<int>(r);
        break;
      }
    }
  }
  const auto nb = static_cast<std::size_t>(disc.num_bonds());
  for (std::size_t b = 0; b < nb; ++b) {
    if (disc.bond_precut[b] != 0) continue;
    const mesh::NodeIndex i = disc.bond_i[b];
    const mesh::NodeIndex j = disc.bond_j[b];
    const int ri = region[static_cast<std::size_t>(i)];
    if (ri < 0 || ri != region[static_cast<std::size_t>(j)]) continue;
    const double c = disc.bond_cos[b];
    const double s = disc.bond_sin[b];
    // gᵀu = e·(u_j − u_i): the bond's elongation (m).
    ties.push_back(Tie{{{i, 0, -c}, {i, 1, -s}, {j, 0, c}, {j, 1, s}},
                       geometry.rigid_penalty * model.bond_stiffness[b]});
  }
  return ties;
}

}  // namespace peritwin::statics
