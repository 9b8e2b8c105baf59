// What a detail will cost before anything is built (issue 14, item 6): nodes, bonds, solver
// unknowns, stiffness and Cholesky-factor nonzeros and bytes, from the outline's lattice points,
// dx and horizon_ratio alone, in O(rectangles²·holes) time (at most 5·10⁷ steps, beyond which the
// bounding box stands in) and O(rectangles + holes) memory — no discretization, no allocation
// that grows with the grid. parse_config refuses a config whose
// estimate exceeds ConfigLimits::max_memory_bytes or the solver's 32-bit indices (config.h).
//
// The model (docs/limits.md has the derivation and the measured ratios):
//  - nodes: the grid's cell centres inside the union of the outline rectangles, counted per
//    rectangle slab exactly as discretize() places them, less each hole's area / Δx²; when the
//    outline has polygons or circles or a hole is a polygon: the entries' areas less the holes'
//    over Δx², the perimeter their boundaries' lengths (over-estimates where entries overlap).
//  - bonds: ½·(N·F − (P/Δx)·S), F the lattice offsets within δ (an interior node's family, 28 at
//    δ = 3.015Δx), S = Σ q over the offsets (p, q) with q > 0 (the family members a node loses per
//    Δx of a straight edge, summed over the rows near it: 18 at 3.015Δx), P the body's perimeter.
//  - factor: nested dissection of a 2D mesh-like graph (George 1973; Lipton, Rose, Tarjan 1979)
//    leaves nnz(L) = O(n log n); with d unknowns per node and a coupling reach of w grid spacings
//    the separators are w nodes wide, giving nnz(L) ≈ κ·d²·w²·N·log2(√N / w). κ = 5 bounds
//    CHOLMOD's supernodal factor (METIS or AMD, the better) on every measured B1/B2 grid from
//    3,720 to 60,000 nodes and δ/Δx from 2 to 6, by 7-44 % (the condensed state-based form by
//    26-79 %; docs/limits.md); capped at the dense triangle.
//  - bytes: the arrays each part allocates per node, bond, matrix entry and factor entry (read
//    off solver/ and twin/model; the constants below name them), times the fatigue engines that
//    can be alive at once: the live one and the remaining-life simulations (3 with the A2 band).
#pragma once

#include "config/config.h"

namespace peritwin::config {

struct ResourceEstimate {
  double nodes = 0.0;            ///< material points N
  double bonds = 0.0;            ///< bonds (each stored once)
  double family_size = 0.0;      ///< F: bonds of an interior node (lattice offsets within δ)
  double unknowns = 0.0;         ///< 2 per node, 3 in the state-based mixed form (docs/solver.md)
  double matrix_nonzeros = 0.0;  ///< upper triangle of the assembled stiffness
  double factor_nonzeros = 0.0;  ///< entries of the Cholesky factor (supernodal, with padding)
  int engines = 1;               ///< fatigue engines alive at once: live + life simulations
  double model_bytes = 0.0;      ///< discretization and PD model, shared by the engines
  double engine_bytes = 0.0;     ///< one engine: bond state, solver arrays, matrix, factor
  double bytes = 0.0;            ///< model_bytes + engines · engine_bytes
};

/// The estimate of a detail parse_config accepted (geometry valid, dx > 0, 1 <= horizon_ratio).
/// Counts are doubles: a grid of 10^12 nodes is a number here, not an overflow; anything
/// degenerate gives 0 or +inf, never NaN. Throws nothing.
[[nodiscard]] ResourceEstimate estimate_resources(const DetailConfig& detail) noexcept;

/// The largest count the solver's 32-bit indices hold (NodeIndex, BondIndex, the CSR offsets of
/// the families, Eigen's and CHOLMOD's int indices): the estimate's 2·bonds, unknowns, matrix and
/// factor nonzeros must stay below it.
inline constexpr double kMaxSolverIndex = 2147483647.0;

}  // namespace peritwin::config
