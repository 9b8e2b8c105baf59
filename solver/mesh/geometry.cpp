#include "solver/mesh/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace peritwin {

namespace {
double orientation(Point a, Point b, Point c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}
bool on_segment(Point a, Point b, Point p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}
}  // namespace

bool segments_cross(Point p1, Point p2, Point q1, Point q2) {
  const double d1 = orientation(q1, q2, p1);
  const double d2 = orientation(q1, q2, p2);
  const double d3 = orientation(p1, p2, q1);
  const double d4 = orientation(p1, p2, q2);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    return true;
  }
  // Degenerate cases: an end point lying on the other segment.
  if (d1 == 0 && on_segment(q1, q2, p1)) return true;
  if (d2 == 0 && on_segment(q1, q2, p2)) return true;
  if (d3 == 0 && on_segment(p1, p2, q1)) return true;
  if (d4 == 0 && on_segment(p1, p2, q2)) return true;
  return false;
}

bool DetailGeometry::is_material(Point p) const {
  const bool in_outline = std::any_of(outline.begin(), outline.end(),
                                      [p](const Rectangle& r) { return r.contains(p); });
  if (!in_outline) return false;
  return std::none_of(holes.begin(), holes.end(), [p](const Circle& c) { return c.contains(p); });
}

Rectangle DetailGeometry::bounding_box() const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Rectangle box{inf, inf, -inf, -inf};
  for (const auto& r : outline) {
    box.x_min = std::min(box.x_min, r.x_min);
    box.y_min = std::min(box.y_min, r.y_min);
    box.x_max = std::max(box.x_max, r.x_max);
    box.y_max = std::max(box.y_max, r.y_max);
  }
  return box;
}

Status DetailGeometry::validate() const {
  if (outline.empty()) return failure("outline: at least one rectangle is required");
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const auto& r = outline[i];
    if (!(r.x_max > r.x_min && r.y_max > r.y_min)) {
      return failure("outline[" + std::to_string(i) +
                     "]: x_max > x_min and y_max > y_min are required");
    }
  }
  const Rectangle box = bounding_box();
  for (std::size_t i = 0; i < holes.size(); ++i) {
    const auto& c = holes[i];
    if (!(c.radius > 0)) return failure("holes[" + std::to_string(i) + "]: radius must be > 0");
    const Rectangle hole_box{c.centre.x - c.radius, c.centre.y - c.radius, c.centre.x + c.radius,
                             c.centre.y + c.radius};
    if (hole_box.x_max < box.x_min || hole_box.x_min > box.x_max || hole_box.y_max < box.y_min ||
        hole_box.y_min > box.y_max) {
      return failure("holes[" + std::to_string(i) + "]: the hole lies outside the body");
    }
  }
  if (!(thickness > 0)) return failure("thickness must be > 0");
  if (!(rigid_factor >= 1)) return failure("rigid_factor must be >= 1");
  return {};
}

}  // namespace peritwin
