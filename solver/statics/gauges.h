// Strain gauges on the model (issue 33, docs/gauges.md): the nodes a gauge averages over and its
// influence coefficients, the strain it reads per N of P in each basis load case of the affine
// load pattern (constant, cos α, sin α; static_solver.h). A gauge reads the linear (small) PD
// strain n·sym(H)·n along its direction n, H the displacement gradient of 004 Eq. (6) (F − I),
// averaged over its nodes: the first-order part of 004 Eq. (7)'s Lagrange strain, which is what a
// foil gauge or a fibre Bragg grating measures at structural strains (the quadratic term is
// ~10⁻³ of it at ε = 10⁻³, and the coefficients are per N, where it is ~10⁻¹⁰ of it).
// Units: SI (m); strains dimensionless; coefficients in 1/N.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "solver/mesh/discretization.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

/// Where a gauge sits and what it measures.
struct GaugeGeometry {
  mesh::Point at;       ///< centre (m)
  double angle = 0.0;   ///< measuring direction from +x (rad)
  double length = 0.0;  ///< gauge length (m); 0 = one node
};

/// The nodes of a gauge: those whose position lies within dx/2 (plus a relative 1e-9 for the
/// grid's rounding) of the segment of `length` centred at `at` along `angle`, measured across
/// the segment, and within length/2 along it; when none (a gauge shorter than the grid, or
/// length 0), the node nearest `at`. Sorted by index (the averaging order is fixed).
std::vector<mesh::NodeIndex> gauge_nodes(const mesh::Discretization& disc, const GaugeGeometry& g);

/// The linear strain n·sym(H)·n at node k along `angle`, H = F − I from 004 Eq. (6) over the
/// node's intact bonds (see pd_strain.h); NaN when those bonds do not span the plane.
double pd_normal_strain(const mesh::Discretization& disc, std::span<const std::uint8_t> intact,
                        std::span<const double> u, mesh::NodeIndex k, double angle);

/// A gauge's influence coefficients (1/N) for the solver's current bond state: per basis case
/// b, the mean over `nodes` of pd_normal_strain of the basis displacement U_b (nodes whose
/// strain is NaN left out; NaN when all are). A cycle's reading is then
/// ε = P·(c[0] + cos α·c[1] + sin α·c[2]).
std::array<double, 3> gauge_influence(const StaticSolver& solver,
                                      const std::vector<mesh::NodeIndex>& nodes, double angle);

/// The strain of a gauge with coefficients c under the load (P, α).
[[nodiscard]] double gauge_strain(const std::array<double, 3>& c, double p, double alpha);

}  // namespace peritwin::statics
