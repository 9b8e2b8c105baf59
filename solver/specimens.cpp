#include "solver/specimens.h"

#include <cmath>

namespace peritwin {

double compact_tension_spacing(const CompactTensionSpec& spec, double target_nodes) {
  const double w = spec.width;
  const double area = 1.25 * w * 1.2 * w;
  const double height = 1.2 * w;
  const double rows = 2.0 * std::round(height / std::sqrt(area / target_nodes) / 2.0);
  return height / rows;
}

Specimen make_compact_tension(const CompactTensionSpec& spec, const ModelOptions& options,
                              double dx, double horizon_ratio) {
  const double w = spec.width;
  Specimen s;
  s.name = "B1-CT";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back({0.0, -0.6 * w, 1.25 * w, 0.6 * w});
  const Circle upper_pin{{0.25 * w, 0.275 * w}, 0.125 * w};
  const Circle lower_pin{{0.25 * w, -0.275 * w}, 0.125 * w};
  s.geometry.rigid_regions = {Region::of(upper_pin), Region::of(lower_pin)};
  s.initial_crack_tip = {0.25 * w + spec.initial_crack, 0.0};
  s.geometry.notches.push_back({{-dx, 0.0}, s.initial_crack_tip});
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx);
  s.model = build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  for (const double side : {1.0, -1.0}) {
    const NodeIndex k = s.disc.nearest_node({1.25 * w, side * 0.5 * dx});
    s.supports.push_back({{k}, true, true});
  }
  s.loads.push_back({s.disc.nodes_in(Region::of(upper_pin)), {0.0, 1.0}, {}, {}});
  s.loads.push_back({s.disc.nodes_in(Region::of(lower_pin)), {0.0, -1.0}, {}, {}});
  return s;
}

double compact_tension_shear_spacing(const CompactTensionShearSpec& spec, double target_nodes) {
  const double rows =
      2.0 * std::round(spec.height / std::sqrt(spec.width * spec.height / target_nodes) / 2.0);
  return spec.height / rows;
}

Specimen make_compact_tension_shear(const CompactTensionShearSpec& spec,
                                    const ModelOptions& options, double dx, double horizon_ratio) {
  Specimen s;
  s.name = "B2-CTS";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back({0.0, -0.5 * spec.height, spec.width, 0.5 * spec.height});
  s.initial_crack_tip = {spec.crack_length, 0.0};
  s.geometry.notches.push_back({{-dx, 0.0}, s.initial_crack_tip});
  const double xc = 0.5 * spec.width;
  const double r = 0.5 * spec.hole_diameter;
  const double xs[3] = {xc - 0.5 * spec.hole_spacing, xc, xc + 0.5 * spec.hole_spacing};
  std::vector<Circle> upper, lower;
  for (double x : xs) {
    upper.push_back({{x, spec.hole_offset}, r});
    lower.push_back({{x, -spec.hole_offset}, r});
  }
  for (const auto& c : upper) s.geometry.rigid_regions.push_back(Region::of(c));
  for (const auto& c : lower) s.geometry.rigid_regions.push_back(Region::of(c));
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx, spec.grid);
  s.model = build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  const double ef = spec.hole_offset / spec.hole_spacing;
  s.loads.push_back({s.disc.nodes_in(Region::of(upper[0])), {}, {0.0, 0.5}, {0.0, ef}});   // F1
  s.loads.push_back({s.disc.nodes_in(Region::of(upper[1])), {}, {}, {-1.0, 0.0}});         // F2
  s.loads.push_back({s.disc.nodes_in(Region::of(upper[2])), {}, {0.0, 0.5}, {0.0, -ef}});  // F3
  if (spec.lower_holes_fixed) {
    for (const auto& c : lower) s.supports.push_back({s.disc.nodes_in(Region::of(c)), true, true});
  } else {
    // The lower half of the device applies the point reflection of the upper forces (the CTS
    // loading is antisymmetric under a half turn): −F3 at the lower left, +P sin α in x at the
    // middle, −F1 at the lower right; each half is then in force and moment equilibrium.
    s.loads.push_back({s.disc.nodes_in(Region::of(lower[0])), {}, {0.0, -0.5}, {0.0, ef}});
    s.loads.push_back({s.disc.nodes_in(Region::of(lower[1])), {}, {}, {1.0, 0.0}});
    s.loads.push_back({s.disc.nodes_in(Region::of(lower[2])), {}, {0.0, -0.5}, {0.0, -ef}});
    s.supports.push_back({{s.disc.nearest_node(lower[1].centre)}, true, true});
    s.supports.push_back({{s.disc.nearest_node(lower[2].centre)}, false, true});
  }
  return s;
}

}  // namespace peritwin
