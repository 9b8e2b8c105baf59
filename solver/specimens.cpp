#include "solver/specimens.h"

#include <cmath>
#include <numbers>

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

namespace {

struct PlaneStress {
  double xx, yy, xy;
};

/// Williams near-tip stresses per unit K_I and per unit K_II at (r, θ), crack along θ = π
/// (Anderson, Fracture Mechanics, Table 2.1).
PlaneStress mode_i_stress(double r, double th) {
  const double f = 1.0 / std::sqrt(2.0 * std::numbers::pi * r);
  const double c = std::cos(th / 2), s = std::sin(th / 2);
  const double c3 = std::cos(1.5 * th), s3 = std::sin(1.5 * th);
  return {f * c * (1 - s * s3), f * c * (1 + s * s3), f * s * c * c3};
}

PlaneStress mode_ii_stress(double r, double th) {
  const double f = 1.0 / std::sqrt(2.0 * std::numbers::pi * r);
  const double c = std::cos(th / 2), s = std::sin(th / 2);
  const double c3 = std::cos(1.5 * th), s3 = std::sin(1.5 * th);
  return {-f * s * (2 + c * c3), f * s * c * c3, f * c * (1 - s * s3)};
}

Point traction(const PlaneStress& sigma, Point normal) {
  return {sigma.xx * normal.x + sigma.xy * normal.y, sigma.xy * normal.x + sigma.yy * normal.y};
}

}  // namespace

Specimen make_k_field_plate(const KFieldPlateSpec& spec, const ModelOptions& options, double dx,
                            double horizon_ratio) {
  const double l = std::round(spec.half_size / dx) * dx;  // y = 0 falls between node rows
  Specimen s;
  s.name = "K-field plate";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back({-l, -l, l, l});
  s.initial_crack_tip = {0.0, 0.0};
  s.geometry.notches.push_back({{-l - dx, 0.0}, s.initial_crack_tip});
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx, spec.grid);
  s.model = build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  const double area = dx * spec.thickness;
  for (NodeIndex n = 0; n < s.disc.num_nodes(); ++n) {
    const Point p = s.disc.position[n];
    const Point normal{(p.x > l - dx ? 1.0 : 0.0) - (p.x < -l + dx ? 1.0 : 0.0),
                       (p.y > l - dx ? 1.0 : 0.0) - (p.y < -l + dx ? 1.0 : 0.0)};
    if (normal.x == 0.0 && normal.y == 0.0) continue;
    const double r = std::hypot(p.x, p.y);
    const double th = std::atan2(p.y, p.x);
    PlaneStress mode_i = mode_i_stress(r, th);
    mode_i.xx += spec.t_over_ki;
    const Point f_i = traction(mode_i, normal);
    const Point f_ii = traction(mode_ii_stress(r, th), normal);
    s.loads.push_back({{n}, {}, {f_i.x * area, f_i.y * area}, {-f_ii.x * area, -f_ii.y * area}});
  }
  s.supports.push_back({{s.disc.nearest_node({l, 0.0})}, true, true});
  s.supports.push_back({{s.disc.nearest_node({l, -0.5 * l})}, true, false});
  return s;
}

}  // namespace peritwin
