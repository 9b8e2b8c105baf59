// Geometry of one monitored structural detail: an outline made of rectangles, polygons (straight
// edges, circular arcs, fillets: solver/mesh/polygon.h) and circles, holes, notches/pre-cracks
// (polylines that cut bonds), rigid regions and no-fail zones.
// Units: SI (m) throughout.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/expected.h"
#include "solver/mesh/polygon.h"

namespace peritwin::mesh {

struct Circle {
  Point centre;
  double radius = 0.0;
  [[nodiscard]] bool contains(Point p) const {
    const double dx = p.x - centre.x;
    const double dy = p.y - centre.y;
    return dx * dx + dy * dy <= radius * radius;
  }
};

/// A rectangle, a circle or a polygon, each closed (a point on its boundary is inside): outline
/// entries, holes, rigid regions, no-fail zones, load and support regions.
struct Region {
  enum class Shape { rectangle, circle, polygon } shape = Shape::rectangle;
  Rectangle rectangle;
  Circle circle;
  Polygon polygon;

  Region() = default;
  Region(Rectangle r) : rectangle(r) {}                  // NOLINT(google-explicit-constructor)
  Region(Circle c) : shape(Shape::circle), circle(c) {}  // NOLINT(google-explicit-constructor)
  Region(Polygon p)
      : shape(Shape::polygon), polygon(std::move(p)) {}  // NOLINT(google-explicit-constructor)
  static Region of(Rectangle r) { return Region(r); }
  static Region of(Circle c) { return Region(c); }
  static Region of(Polygon p) { return Region(std::move(p)); }

  [[nodiscard]] bool contains(Point p) const {
    switch (shape) {
      case Shape::rectangle:
        return rectangle.contains(p);
      case Shape::circle:
        return circle.contains(p);
      case Shape::polygon:
        return polygon.contains(p);
    }
    return false;
  }
  [[nodiscard]] Rectangle bounding_box() const;
  /// Distance from p to the region's boundary (m).
  [[nodiscard]] double boundary_distance(Point p) const;
  /// Area (m²).
  [[nodiscard]] double area() const;
};

/// A two-point notch or pre-crack segment (what Notch::last_segment gives).
struct Segment {
  Point a;
  Point b;
};

/// A notch or pre-crack: a polyline from the mouth to the tip; every bond crossing any of its
/// segments is cut.
struct Notch {
  std::string name;         ///< from the config's `name`, default "notch <index>"
  std::vector<Point> path;  ///< >= 2 points, from the mouth to the tip
  [[nodiscard]] Point tip() const { return path.back(); }
  /// Unit vector of the last segment (towards the tip).
  [[nodiscard]] Point direction() const;
  /// The last segment, {path[n-2], tip}.
  [[nodiscard]] Segment last_segment() const { return {path[path.size() - 2], path.back()}; }
};

/// The boundary piece nearest to a point: the outline (index of the outline entry), a hole (index),
/// or a notch (index), with the distance (m).
struct SurfacePlace {
  enum class Kind { outline, hole, notch } kind = Kind::outline;
  int index = 0;
  double distance = 0.0;
};

/// How a rigid region (a pin, a clamp, a load introduction) is modelled (issue 31).
enum class RigidModel {
  /// Its nodes follow one rigid motion: every bond between two nodes of the same region is tied
  /// (statics::rigid_region_ties), the material inside it is the detail's own. No stiffness
  /// factor enters the material, so the model is positive definite for every Poisson's ratio.
  constraint,
  /// 000 Sec. 6.1: material of E_rigid = rigid_factor·E. Kept to reproduce the paper's B1/B2
  /// numbers; with the state-based model valid only where rigid_factor·(κ − 2μ)/μ ≥ −6
  /// (model::check_stiff_rigid_material), e.g. ν ≥ 0.325 in plane stress at 200·E.
  stiff_material,
};

struct DetailGeometry {
  std::vector<Region> outline;        ///< union of its entries = the body before holes
  std::vector<Region> holes;          ///< material removed (circles or polygons)
  std::vector<Notch> notches;         ///< cut every bond that crosses them
  std::vector<Region> rigid_regions;  ///< rigid parts, modelled as `rigid_model` says
  std::vector<Region> no_fail_zones;  ///< bonds touching these never break (002 Sec. 7)
  double thickness = 1.0;             ///< plate thickness h (m)
  RigidModel rigid_model = RigidModel::constraint;
  double rigid_factor = 200.0;  ///< stiff_material: E_rigid / E (000 Sec. 6.1)
  /// constraint: a tie's stiffness over its bond's pair stiffness (the constraint's penalty; its
  /// violation is the tie force over that stiffness, docs/solver.md "Rigid regions")
  double rigid_penalty = 1000.0;

  [[nodiscard]] bool is_material(Point p) const;
  [[nodiscard]] Rectangle bounding_box() const;
  /// The surface nearest to p. The outline's surface is the boundary of the union of its entries:
  /// a rectangle's edge counts only where no other rectangle covers its outward side (an edge
  /// shared by two rectangles, or inside another, is not surface); a polygon's or circle's
  /// boundary counts wherever it lies, so the union's boundary is exact for rectangles and for
  /// entries that do not overlap. A hole's surface is its boundary, a notch's its polyline (both
  /// faces). Ties go to the outline, then holes, then notches,
  /// each by the lowest index; with no surface at all: {outline, -1, +inf}.
  [[nodiscard]] SurfacePlace nearest_surface(Point p) const;
  /// OK, or a message naming what is wrong.
  [[nodiscard]] core::Status validate() const;
};

}  // namespace peritwin::mesh
