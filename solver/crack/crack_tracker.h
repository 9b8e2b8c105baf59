// Crack metrics from the damage field: a crack is the connected set of nodes with φ ≥ φ0 grown
// from a notch tip (docs/design.md "Crack metrics"); per crack its tip, length along the path,
// projected length and kink angle β. Stress intensity by displacement extrapolation
// (001 Eq. 60-63) and the ASTM E647 compact-tension ΔK (000 Eq. A2).
// Units: SI (m, rad, Pa·√m).
#pragma once

#include <cstdint>
#include <vector>

#include "solver/mesh/discretization.h"
#include "solver/mesh/geometry.h"
#include "solver/model/pd_model.h"

namespace peritwin::crack {

struct CrackMetrics {
  int notch = 0;        ///< index of the notch it grows from
  mesh::Point origin;   ///< the notch tip
  mesh::Point tip;      ///< the crack-path node farthest along the path
  double length = 0.0;  ///< length along the path from the notch tip to the tip node (m)
  /// The sub-grid length (subgrid_crack_length(), within Δx/2 of `length`): measure() with the
  /// intact flags only, else 0. What the twin publishes.
  double subgrid_length = 0.0;
  double projected_length = 0.0;  ///< (tip − origin)·notch direction (m)
  double kink_angle = 0.0;  ///< β: angle from the notch direction to the early path (rad, CCW +)
  std::int32_t nodes = 0;   ///< damaged nodes in the crack
};

struct CrackTrackerOptions {
  double phase_switch_damage = 0.398;  ///< φ0 (000 Sec. 4.4)
  /// β is the direction from the notch tip to the centroid of the crack nodes whose path distance
  /// lies within Δx of this distance (or of the crack length when the crack is shorter) and that
  /// lie within a horizon of the tip's own path (a branched crack is measured on the branch that
  /// leads to its tip). 0 = 8δ/3.
  double kink_distance = 0.0;
};

class CrackTracker {
 public:
  CrackTracker(const mesh::Discretization& disc, std::vector<mesh::Notch> notches,
               CrackTrackerOptions options = {});
  /// One entry per notch, in notch order (length 0 when nothing has grown yet).
  [[nodiscard]] std::vector<CrackMetrics> measure(const std::vector<double>& node_damage) const;
  /// The same with each crack's subgrid_length from the intact flags the damage came from.
  [[nodiscard]] std::vector<CrackMetrics> measure(const std::vector<double>& node_damage,
                                                  const std::vector<std::uint8_t>& intact) const;

 private:
  [[nodiscard]] std::vector<CrackMetrics> measure(const std::vector<double>& node_damage,
                                                  const std::vector<std::uint8_t>* intact) const;
  const mesh::Discretization& disc_;
  std::vector<mesh::Notch> notches_;
  CrackTrackerOptions options_;
};

/// A crack's line at a tip: a point on it and its direction of growth (unit; 0 when unknown).
struct CrackLine {
  mesh::Point point;
  mesh::Point direction;
};
/// The line of the crack nodes whose path distance `dist` lies within `back` of the tip's: their
/// centroid and principal axis, oriented from the centroid towards the tip (the path itself
/// zig-zags between the two node rows or columns either side of a crack line; the axis of the
/// nodes does not, and their centroid lies between the rows). Direction 0 when the tip is the only
/// such node.
CrackLine tip_line(const mesh::Discretization& disc, const std::vector<double>& dist,
                   std::size_t tip, double back);

/// Sub-grid crack length (docs/design.md "Sub-grid crack length"). The node-based length L (the
/// path to the tip node, the last node with φ ≥ φ0) moves in steps of about Δx while the bonds
/// ahead of the tip break one group after the other. Those bonds cross the crack's line: with s
/// the coordinate along `line` (s_t at the tip node) and c(s) the fraction of the bonds crossing
/// the line within the Δx-wide bin around s that are broken (notch cuts included), the cut ahead
/// of the tip node is
///   p = Σ_bins c_i·Δx − Δx,   bins of width Δx over [s_t − Δx, s_t + δ + Δx)
/// (the bin behind the tip is cut through: p is the cut's extent beyond s_t, the equivalent
/// sharp cut; about 19 bonds cross a Δx of line at δ = 3Δx, so p moves in steps of ~Δx/19).
/// Computed over the bonds of the nodes within 2δ + 2Δx of the tip (cheap: ~100 nodes).
double front_progress(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                      mesh::Point tip, const CrackLine& line);

/// The published crack length from the node-based length L and the cut ahead of the tip p (the
/// sum over the crack's tips when it has two):
///   a = max(0, min(max(L + p − lag, L − Δx/2), L + Δx/2)),   lag = kSubgridLag·Δx.
/// L + p, the path to the tip node plus the cut beyond it, rises with every break near the tip;
/// the tip node lags the cut's end (a node reaches φ0 only once the cut runs past it, and the
/// tip node is the last such node), so L + p − L is about `lag` on average over a node step
/// (measured on the demo's break sequence: tests/twin/test_subgrid_crack.cpp). Subtracting it
/// keeps a on L's mean (the criterion and the A2 calibration on L keep their meaning); the clamp
/// keeps |a − L| ≤ Δx/2. L, p and the clamp bounds only grow as bonds break on a straight
/// crack, so a is monotone there (tested on the demo; a new direction of the line can move p).
inline constexpr double kSubgridLag = 1.2;
double subgrid_crack_length(double node_length, double progress, double dx);

/// Mode I and II stress intensity factors from the crack-face displacement jump at r1 < r2 behind
/// a tip, 001 Eq. (62)-(63), for a crack running along `direction` (unit vector) with its faces
/// on either side of the line through `tip`. `kappa` from 001 Eq. (59), `mu` the shear modulus.
struct StressIntensity {
  double k_i = 0.0;
  double k_ii = 0.0;
};
/// The node pair whose displacement jump gives the face opening at distance r behind a tip: the
/// nodes nearest to the points r behind the tip and Δx/2 either side of the crack line.
struct FaceNodePair {
  mesh::NodeIndex upper = -1;
  mesh::NodeIndex lower = -1;
  mesh::Point upper_target;  ///< the point the upper node is nearest to
  mesh::Point lower_target;
};
FaceNodePair extrapolation_face_nodes(const mesh::Discretization& disc, mesh::Point tip,
                                      mesh::Point direction, double r);

/// Whether nodes a and b are separated by the crack: a bond joins them and it is broken.
bool separated_by_crack(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                        mesh::NodeIndex a, mesh::NodeIndex b);

StressIntensity stress_intensity_by_extrapolation(const mesh::Discretization& disc,
                                                  const std::vector<double>& u, mesh::Point tip,
                                                  mesh::Point direction, double r1, double r2,
                                                  double mu, double kappa);

/// T-stress (Pa) at a crack tip on a straight crack along +x (the tip at `tip`): on a traction-free
/// face the singular mode I σ_xx vanishes and mode II's has opposite signs on the two faces, so the
/// mean of E·ε_xx over the face rows (y = tip.y ± Δx/2; plane stress, σ_yy = 0 on the face) is T.
/// ε_xx by central differences along each row, averaged over r1 ≤ r ≤ r2 behind the tip.
double t_stress_from_crack_faces(const mesh::Discretization& disc, const std::vector<double>& u,
                                 mesh::Point tip, double r1, double r2, double youngs_modulus);

/// K_I, K_II and T at a tip from a least-squares fit of the Williams series to the displacements of
/// every node in the annulus r_in ≤ r ≤ r_out around it (the over-deterministic method): per mode
/// the terms r^(n/2), n = 1…`terms`, plus a rigid translation (the mode II n = 2 term is the rigid
/// turn). K_I = √(2π)·a₁, K_II = √(2π)·b₁ and T = 4·a₂ in the normalization
///   u_x = Σ aₙ r^(n/2)/(2μ)·[(κ + n/2 + (−1)ⁿ) cos(nθ/2) − (n/2) cos((n/2 − 2)θ)] + mode II,
/// which gives 001 Eq. (57)-(58) at n = 1 and the uniform σ_xx = T at n = 2. An independent check
/// of the two-point extrapolation (its K) and of the crack-face T (which the r¹ term biases).
struct WilliamsFit {
  double k_i = 0.0;
  double k_ii = 0.0;
  double t_stress = 0.0;
  int nodes = 0;        ///< nodes in the annulus
  bool fitted = false;  ///< false: fewer nodes than unknowns, no fit (the values stay 0)
};
WilliamsFit williams_series_fit(const mesh::Discretization& disc, const std::vector<double>& u,
                                mesh::Point tip, mesh::Point direction, double r_in, double r_out,
                                int terms, double mu, double kappa);

/// Kolosov constant of 001 Eq. (59) and the shear modulus of the model's effective material.
double kolosov_kappa(double poisson_ratio, model::PlaneCondition plane);

/// 000 Eq. (A2): ASTM E647 ΔK (Pa·√m) of a compact-tension specimen, crack length q from the
/// load line, width W, thickness h, load range ΔP = P_max(1 − R).
double compact_tension_delta_k(double delta_p, double thickness, double width, double q);

}  // namespace peritwin::crack
