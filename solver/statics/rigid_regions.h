// Rigid regions (pins, clamps, load introductions) as the detail's geometry says to model them
// (mesh::RigidModel, issue 31): as rigid-body constraints, or as 000 Sec. 6.1's stiff material.
#pragma once

#include <vector>

#include "solver/mesh/discretization.h"
#include "solver/mesh/geometry.h"
#include "solver/model/pd_model.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

/// The factor on the material inside rigid regions that build_model takes: rigid_factor for
/// RigidModel::stiff_material (000 Sec. 6.1's E_rigid/E), 1 for RigidModel::constraint.
double material_rigid_factor(const mesh::DetailGeometry& geometry);

/// RigidModel::constraint: ties that make each rigid region move as one rigid body. Every bond
/// (not precut) between two nodes of the same region is tied on its elongation,
/// e·(u_j − u_i) = 0, with the stiffness k = rigid_penalty·k_b (k_b the bond's pair stiffness,
/// PdModel::bond_stiffness). A region's bonds reach every node within δ of every other, a network
/// that is infinitesimally rigid, so the ties' sum Σ k·g·gᵀ is positive semidefinite with exactly
/// the region's three rigid motions as its null space: the nodes follow one rigid motion up to the
/// tie forces over k, and a load or a support on any of them acts on that motion. Ties add energy
/// only (no negative dilatation term, unlike a stiff state-based material at ν < 1/3), so the
/// model stays positive definite for every Poisson's ratio. A node belongs to the first region
/// (in the geometry's order) that contains its position, as the discretization decided
/// Discretization::rigid. Empty for RigidModel::stiff_material and for no rigid regions.
std::vector<Tie> rigid_region_ties(const mesh::Discretization& disc, const model::PdModel& model,
                                   const mesh::DetailGeometry& geometry);

}  // namespace peritwin::statics
