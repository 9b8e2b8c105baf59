#include "solver/mesh/geometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

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

double distance_to_segment(Point p, Point a, Point b) {
  const double ux = b.x - a.x;
  const double uy = b.y - a.y;
  const double length2 = ux * ux + uy * uy;
  double t = length2 > 0 ? ((p.x - a.x) * ux + (p.y - a.y) * uy) / length2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(p.x - (a.x + t * ux), p.y - (a.y + t * uy));
}

namespace {

/// One side of an axis-aligned rectangle: the points (along, across) with along in [lo, hi] at
/// the fixed coordinate `across` (x for a vertical side, y for a horizontal one); the body lies on
/// the side opposite `outward` (+1 or -1 along the across axis).
struct RectangleSide {
  bool vertical = false;
  double across = 0.0;
  double lo = 0.0;
  double hi = 0.0;
  double outward = 1.0;
};

/// The sides of r: bottom, right, top, left.
std::array<RectangleSide, 4> sides_of(const Rectangle& r) {
  return {{{false, r.y_min, r.x_min, r.x_max, -1.0},
           {true, r.x_max, r.y_min, r.y_max, 1.0},
           {false, r.y_max, r.x_min, r.x_max, 1.0},
           {true, r.x_min, r.y_min, r.y_max, -1.0}}};
}

/// Distance from p to the parts of `side` whose outward side no rectangle of `others` (other than
/// `self`) covers: those parts are the boundary of the union. Infinity when all of it is covered.
double exposed_side_distance(Point p, const RectangleSide& side,
                             const std::vector<Rectangle>& others, std::size_t self) {
  std::vector<std::pair<double, double>> covered;
  for (std::size_t j = 0; j < others.size(); ++j) {
    if (j == self) continue;
    const Rectangle& b = others[j];
    const double lo = side.vertical ? b.x_min : b.y_min;
    const double hi = side.vertical ? b.x_max : b.y_max;
    // b covers the points just outside the side when it spans the side's line towards outward.
    const bool spans = side.outward > 0 ? (lo <= side.across && side.across < hi)
                                        : (lo < side.across && side.across <= hi);
    if (!spans) continue;
    const double a0 = std::max(side.lo, side.vertical ? b.y_min : b.x_min);
    const double a1 = std::min(side.hi, side.vertical ? b.y_max : b.x_max);
    if (a0 < a1) covered.emplace_back(a0, a1);
  }
  std::sort(covered.begin(), covered.end());
  const auto point_at = [&side](double along) {
    return side.vertical ? Point{side.across, along} : Point{along, side.across};
  };
  double best = std::numeric_limits<double>::infinity();
  double start = side.lo;  // start of the part not yet known to be covered
  for (const auto& [a0, a1] : covered) {
    if (a0 > start) best = std::min(best, distance_to_segment(p, point_at(start), point_at(a0)));
    start = std::max(start, a1);
  }
  if (start < side.hi || (start == side.hi && covered.empty())) {
    best = std::min(best, distance_to_segment(p, point_at(start), point_at(side.hi)));
  }
  return best;
}

}  // namespace

SurfacePlace DetailGeometry::nearest_surface(Point p) const {
  SurfacePlace best{SurfacePlace::Kind::outline, -1, std::numeric_limits<double>::infinity()};
  const auto consider = [&best](SurfacePlace::Kind kind, std::size_t index, double distance) {
    if (distance < best.distance) best = {kind, static_cast<int>(index), distance};
  };
  for (std::size_t k = 0; k < outline.size(); ++k) {
    for (const RectangleSide& side : sides_of(outline[k])) {
      consider(SurfacePlace::Kind::outline, k, exposed_side_distance(p, side, outline, k));
    }
  }
  for (std::size_t k = 0; k < holes.size(); ++k) {
    const Circle& c = holes[k];
    consider(SurfacePlace::Kind::hole, k,
             std::abs(std::hypot(p.x - c.centre.x, p.y - c.centre.y) - c.radius));
  }
  for (std::size_t k = 0; k < notches.size(); ++k) {
    consider(SurfacePlace::Kind::notch, k, distance_to_segment(p, notches[k].a, notches[k].b));
  }
  return best;
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
