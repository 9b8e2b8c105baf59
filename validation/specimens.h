// The benchmark specimens of docs/benchmarks.md, built as ready-to-solve models.
// Units: SI (m, N, Pa).
#pragma once

#include <string>
#include <vector>

#include "solver/mesh/discretization.h"
#include "solver/mesh/geometry.h"
#include "solver/model/pd_model.h"
#include "solver/statics/specimen.h"
#include "solver/statics/static_solver.h"

namespace peritwin::validation {

/// B1: ASTM E647 compact tension in Al 6061-T6 (after 000 Sec. 6.1), proportions of the
/// benchmarks README: W = 50 mm, 1.25W × 1.2W, B = 10 mm, pin holes Ø0.25W at (0.25W, ±0.275W)
/// filled with rigid material, notch + pre-crack along y = 0 to x = 0.25W + a0, a0 = 0.3W.
/// Load pattern: +P at the upper pin (in +y), −P at the lower pin, spread over the pin material;
/// the two nodes nearest (1.25W, ±Δx/2) are fixed.
struct CompactTensionSpec {
  double width = 0.050;                ///< W
  double thickness = 0.010;            ///< B
  double initial_crack = 0.3 * 0.050;  ///< a0, measured from the load line
  model::Material material{68e9, 0.33, 48.7e6};
  /// The pins: 000 Sec. 6.1's stiff material (B1's documented numbers), or rigid-body
  /// constraints (any ν; peritwin-calibrate's default).
  mesh::RigidModel rigid_model = mesh::RigidModel::stiff_material;
};

/// The oracle of the tied fixture (CompactTensionShearSpec::rigid_fixtures): the pin forces of
/// rigid loading fixtures from the specimen's flexibility, for its current bonds. `s.loads` are the
/// pins, three per fixture (its middle pin second); each fixture carries their resultant and
/// moment. The three pin points of a fixture move as one rigid body (translation U, turn θ): u_h =
/// U + θ·ẑ × (x_h − x_middle), 2 equations per pin, with u_h = Σ_j C_hj·F_j from unit solves (a
/// pin's displacement is the mean over its load's nodes, its point their centroid); the fixture is
/// in equilibrium, 3 equations per fixture: 2n + 3F equations for the 2n pin forces and 3F fixture
/// motions. Returns s.loads with the per_cos and per_sin parts replaced by that split (constant
/// parts kept). Costs ⌈2n/3⌉ factorizations.
std::vector<statics::LoadTerm> rigid_fixture_loads_by_flexibility(const statics::Specimen& s);

/// Grid spacing giving about `target_nodes` nodes on the CT outline, rounded so that the crack
/// line y = 0 falls midway between two rows of nodes.
double compact_tension_spacing(const CompactTensionSpec& spec, double target_nodes);

statics::Specimen make_compact_tension(const CompactTensionSpec& spec,
                                       const model::ModelOptions& options, double dx,
                                       double horizon_ratio = 3.015);

/// B2: compact tension shear (Richard-type CTS) in Al 6061-T6 after 000 Sec. 6.2, proportions of
/// the benchmarks README: W = 90 mm, height 90 mm, B = 10 mm, crack along y = 0 to x = 45 mm; three
/// loading holes per half at y = ±e (e = 30 mm), x = 45 ∓ f/2 (f = 70 mm) and x = 45 mm, filled
/// with rigid material (hole diameter 8 mm: not given by the paper, chosen here). The lower hole
/// material is fixed; the upper holes carry 000 Eq. (51) per unit P:
/// F1 = P(½cos α + (e/f) sin α) in +y (outer left), F2 = −P sin α in x (middle),
/// F3 = P(½cos α − (e/f) sin α) in +y (outer right).
struct CompactTensionShearSpec {
  double width = 0.090;
  double height = 0.090;
  double thickness = 0.010;
  double crack_length = 0.045;
  double hole_offset = 0.030;   ///< e
  double hole_spacing = 0.070;  ///< f
  double hole_diameter = 0.008;
  model::Material material{68e9, 0.33, 48.7e6};
  /// true: the lower hole material is fixed (benchmarks README). false: the lower holes carry the
  /// point reflection of the upper forces (−F3 left, +P sin α middle, −F1 right) as the lower half
  /// of the loading device does, and only rigid-body motion is suppressed (two nodes).
  bool lower_holes_fixed = true;
  /// false: each pin carries its 000 Eq. (51) force (statically determinate, as 000 and Sajith et
  /// al. load the model). true: the pins of each loaded half belong to a rigid loading fixture
  /// (Richard's device): stiff ties (Specimen::ties) hold the three pin centres of each half to a
  /// rigid-body motion, the holes turning freely on their pins. The pins keep the Eq. (51) forces,
  /// and the fixture shares them out by compatibility in every solve, so the split follows the
  /// crack as it grows.
  bool rigid_fixtures = false;
  mesh::GridPerturbation grid;  ///< irregular node arrangement (default: the regular grid)
};

/// Richard's K formulas for his CTS in its loading device (H. A. Richard, VDI-Forschungsheft 631,
/// 1985, as quoted throughout the mixed-mode literature; stated accurate for 0.5 ≤ a/W ≤ 0.7):
///   K_I  = P√(πa)/(W t)·cos α/(1 − a/W)·√[(0.26 + 2.65 q)/(1 + 0.55 q − 0.08 q²)]
///   K_II = P√(πa)/(W t)·sin α/(1 − a/W)·√[(−0.23 + 1.40 q)/(1 − 0.67 q + 2.08 q²)]
/// with q = a/(W − a).
/// An independent calibration of the specimen: at a/W = 0.5 K_II/K_I = 0.495 tan α.
struct CtsStressIntensity {
  double k_i = 0.0;
  double k_ii = 0.0;
};
CtsStressIntensity richard_cts_stress_intensity(const CompactTensionShearSpec& spec, double p,
                                                double alpha);

/// `dx` itself, unless a node row would lie within dx/4 of the crack line y = 0 (then the nodes
/// on the cut lose their bonds to both faces: debris, their material lost); in that case the
/// nearest spacing with an even number of rows over the height, which puts y = 0 midway between
/// two rows.
double compact_tension_shear_grid_spacing(const CompactTensionShearSpec& spec, double dx);

statics::Specimen make_compact_tension_shear(const CompactTensionShearSpec& spec,
                                             const model::ModelOptions& options, double dx,
                                             double horizon_ratio = 3.015);

/// A square plate [−L, L]² with a straight crack from its left edge to the centre (the tip at the
/// origin), loaded on its outer edges by the tractions σ·n of the Williams near-tip field
/// (Anderson, Fracture Mechanics, Table 2.1) plus a T-stress, each spread over an edge node's Δx·h.
/// Per unit P at load angle α: K_I = P cos α, K_II = −P sin α (the sign of a crack that kinks
/// upward, as the CTS's), T = t_over_ki·K_I. It isolates what the near-tip mixity and T do to a
/// kink, without the rest of a specimen. Rigid-body motion: the node at (L, 0) is pinned, the one
/// at (L, −L/2) holds x.
struct KFieldPlateSpec {
  double half_size = 0.030;  ///< L
  double t_over_ki = 0.0;    ///< T/K_I (1/√m)
  double thickness = 0.010;
  model::Material material{68e9, 0.33, 48.7e6};
  mesh::GridPerturbation grid;  ///< irregular node arrangement (default: the regular grid)
};

statics::Specimen make_k_field_plate(const KFieldPlateSpec& spec,
                                     const model::ModelOptions& options, double dx,
                                     double horizon_ratio = 3.015);

}  // namespace peritwin::validation
