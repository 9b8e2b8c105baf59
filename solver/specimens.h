// The benchmark specimens of ../shared/benchmarks/README.md, built as ready-to-solve models.
// Units: SI (m, N, Pa).
#pragma once

#include <string>
#include <vector>

#include "solver/discretization.h"
#include "solver/geometry.h"
#include "solver/pd_model.h"
#include "solver/static_solver.h"

namespace peritwin {

/// A detail's geometry, discretization, model, supports and load pattern, owned together.
struct Specimen {
  std::string name;
  DetailGeometry geometry;
  Material material;
  Discretization disc;
  PdModel model;
  std::vector<Support> supports;
  std::vector<LoadTerm> loads;
  Point initial_crack_tip;
};

/// B1: ASTM E647 compact tension in Al 6061-T6 (after 000 Sec. 6.1), proportions of the
/// benchmarks README: W = 50 mm, 1.25W × 1.2W, B = 10 mm, pin holes Ø0.25W at (0.25W, ±0.275W)
/// filled with rigid material, notch + pre-crack along y = 0 to x = 0.25W + a0, a0 = 0.3W.
/// Load pattern: +P at the upper pin (in +y), −P at the lower pin, spread over the pin material;
/// the two nodes nearest (1.25W, ±Δx/2) are fixed.
struct CompactTensionSpec {
  double width = 0.050;               ///< W
  double thickness = 0.010;           ///< B
  double initial_crack = 0.3 * 0.050; ///< a0, measured from the load line
  Material material{68e9, 0.33, 48.7e6};
};

/// Grid spacing giving about `target_nodes` nodes on the CT outline, rounded so that the crack
/// line y = 0 falls midway between two rows of nodes.
double compact_tension_spacing(const CompactTensionSpec& spec, double target_nodes);

Specimen make_compact_tension(const CompactTensionSpec& spec, const ModelOptions& options,
                              double dx, double horizon_ratio = 3.015);

}  // namespace peritwin
