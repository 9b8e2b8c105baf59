// Geometry of one monitored structural detail: an outline made of rectangles, circular holes,
// notches/pre-cracks (segments that cut bonds), rigid regions and no-fail zones.
// Units: SI (m) throughout.
#pragma once

#include <string>
#include <vector>

#include "solver/core/expected.h"

namespace peritwin {

struct Point {
  double x = 0.0;
  double y = 0.0;
};

struct Rectangle {
  double x_min = 0.0;
  double y_min = 0.0;
  double x_max = 0.0;
  double y_max = 0.0;
  [[nodiscard]] bool contains(Point p) const {
    return p.x >= x_min && p.x <= x_max && p.y >= y_min && p.y <= y_max;
  }
};

struct Circle {
  Point centre;
  double radius = 0.0;
  [[nodiscard]] bool contains(Point p) const {
    const double dx = p.x - centre.x;
    const double dy = p.y - centre.y;
    return dx * dx + dy * dy <= radius * radius;
  }
};

/// A region is a rectangle or a circle (rigid regions, no-fail zones, load regions).
struct Region {
  enum class Shape { rectangle, circle } shape = Shape::rectangle;
  Rectangle rectangle;
  Circle circle;
  [[nodiscard]] bool contains(Point p) const {
    return shape == Shape::rectangle ? rectangle.contains(p) : circle.contains(p);
  }
  static Region of(Rectangle r) { return Region{Shape::rectangle, r, {}}; }
  static Region of(Circle c) { return Region{Shape::circle, {}, c}; }
};

/// A notch or pre-crack: every bond whose segment crosses it is cut.
struct Segment {
  Point a;
  Point b;
};

/// True when the open segments p1-p2 and q1-q2 properly intersect (touching at an end point of
/// p1-p2 counts, so a bond ending on a crack line is cut; collinear overlap counts as a cut).
bool segments_cross(Point p1, Point p2, Point q1, Point q2);

/// Distance from p to the segment a-b (m).
double distance_to_segment(Point p, Point a, Point b);

/// The boundary piece nearest to a point: the outline (index of the outline entry), a hole (index),
/// or a notch (index), with the distance (m).
struct SurfacePlace {
  enum class Kind { outline, hole, notch } kind = Kind::outline;
  int index = 0;
  double distance = 0.0;
};

struct DetailGeometry {
  std::vector<Rectangle> outline;     ///< union of rectangles = the body before holes
  std::vector<Circle> holes;          ///< material removed
  std::vector<Segment> notches;       ///< cut every bond that crosses them
  std::vector<Region> rigid_regions;  ///< material with E_rigid = rigid_factor * E (000 Sec. 6.1)
  std::vector<Region> no_fail_zones;  ///< bonds touching these never break (002 Sec. 7)
  double thickness = 1.0;             ///< plate thickness h (m)
  double rigid_factor = 200.0;        ///< E_rigid / E (000 Sec. 6.1)

  [[nodiscard]] bool is_material(Point p) const;
  [[nodiscard]] Rectangle bounding_box() const;
  /// The surface nearest to p. The outline's surface is the boundary of the union of its entries:
  /// a rectangle's edge counts only where no other rectangle covers its outward side (an edge
  /// shared by two rectangles, or inside another, is not surface). A hole's surface is its
  /// circle, a notch's its segment (both faces). Ties go to the outline, then holes, then notches,
  /// each by the lowest index; with no surface at all: {outline, -1, +inf}.
  [[nodiscard]] SurfacePlace nearest_surface(Point p) const;
  /// OK, or a message naming what is wrong.
  [[nodiscard]] Status validate() const;
};

}  // namespace peritwin
