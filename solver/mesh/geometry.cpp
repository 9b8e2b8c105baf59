#include "solver/mesh/geometry.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

namespace peritwin::mesh {

Rectangle Region::bounding_box() const {
  switch (shape) {
    case Shape::rectangle:
      return rectangle;
    case Shape::circle:
      return {circle.centre.x - circle.radius, circle.centre.y - circle.radius,
              circle.centre.x + circle.radius, circle.centre.y + circle.radius};
    case Shape::polygon:
      return polygon.bounding_box();
  }
  return {};
}

double Region::boundary_distance(Point p) const {
  switch (shape) {
    case Shape::rectangle: {
      const Rectangle& r = rectangle;
      return std::min({distance_to_segment(p, {r.x_min, r.y_min}, {r.x_max, r.y_min}),
                       distance_to_segment(p, {r.x_max, r.y_min}, {r.x_max, r.y_max}),
                       distance_to_segment(p, {r.x_max, r.y_max}, {r.x_min, r.y_max}),
                       distance_to_segment(p, {r.x_min, r.y_max}, {r.x_min, r.y_min})});
    }
    case Shape::circle:
      return std::abs(std::hypot(p.x - circle.centre.x, p.y - circle.centre.y) - circle.radius);
    case Shape::polygon:
      return polygon.distance(p);
  }
  return std::numeric_limits<double>::infinity();
}

double Region::area() const {
  switch (shape) {
    case Shape::rectangle:
      return (rectangle.x_max - rectangle.x_min) * (rectangle.y_max - rectangle.y_min);
    case Shape::circle:
      return std::numbers::pi * circle.radius * circle.radius;
    case Shape::polygon:
      return polygon.area();
  }
  return 0.0;
}

Point Notch::direction() const {
  const Segment s = last_segment();
  const double len = std::hypot(s.b.x - s.a.x, s.b.y - s.a.y);
  return {(s.b.x - s.a.x) / len, (s.b.y - s.a.y) / len};
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
double exposed_side_distance(Point p, const RectangleSide& side, const std::vector<Region>& others,
                             std::size_t self) {
  std::vector<std::pair<double, double>> covered;
  for (std::size_t j = 0; j < others.size(); ++j) {
    if (j == self || others[j].shape != Region::Shape::rectangle) continue;
    const Rectangle& b = others[j].rectangle;
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
    if (outline[k].shape != Region::Shape::rectangle) {
      consider(SurfacePlace::Kind::outline, k, outline[k].boundary_distance(p));
      continue;
    }
    for (const RectangleSide& side : sides_of(outline[k].rectangle)) {
      consider(SurfacePlace::Kind::outline, k, exposed_side_distance(p, side, outline, k));
    }
  }
  for (std::size_t k = 0; k < holes.size(); ++k) {
    consider(SurfacePlace::Kind::hole, k, holes[k].boundary_distance(p));
  }
  for (std::size_t k = 0; k < notches.size(); ++k) {
    const std::vector<Point>& path = notches[k].path;
    for (std::size_t i = 0; i + 1 < path.size(); ++i) {
      consider(SurfacePlace::Kind::notch, k, distance_to_segment(p, path[i], path[i + 1]));
    }
  }
  return best;
}

bool DetailGeometry::is_material(Point p) const {
  const bool in_outline =
      std::any_of(outline.begin(), outline.end(), [p](const Region& r) { return r.contains(p); });
  if (!in_outline) return false;
  return std::none_of(holes.begin(), holes.end(), [p](const Region& h) { return h.contains(p); });
}

Rectangle DetailGeometry::bounding_box() const {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Rectangle box{inf, inf, -inf, -inf};
  for (const auto& entry : outline) {
    const Rectangle r = entry.bounding_box();
    box.x_min = std::min(box.x_min, r.x_min);
    box.y_min = std::min(box.y_min, r.y_min);
    box.x_max = std::max(box.x_max, r.x_max);
    box.y_max = std::max(box.y_max, r.y_max);
  }
  return box;
}

core::Status DetailGeometry::validate() const {
  if (outline.empty()) return core::failure("outline: at least one entry is required");
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const Region& entry = outline[i];
    const std::string name = "outline[" + std::to_string(i) + "]";
    if (entry.shape == Region::Shape::rectangle) {
      const auto& r = entry.rectangle;
      if (!(r.x_max > r.x_min && r.y_max > r.y_min)) {
        return core::failure(name + ": x_max > x_min and y_max > y_min are required");
      }
    } else if (!(entry.area() > 0)) {
      return core::failure(name + ": the shape encloses no area");
    }
  }
  const Rectangle box = bounding_box();
  for (std::size_t i = 0; i < holes.size(); ++i) {
    const Region& h = holes[i];
    const std::string name = "holes[" + std::to_string(i) + "]";
    if (h.shape == Region::Shape::circle && !(h.circle.radius > 0)) {
      return core::failure(name + ": radius must be > 0");
    }
    if (!(h.area() > 0)) return core::failure(name + ": the hole encloses no area");
    const Rectangle hole_box = h.bounding_box();
    if (hole_box.x_max < box.x_min || hole_box.x_min > box.x_max || hole_box.y_max < box.y_min ||
        hole_box.y_min > box.y_max) {
      return core::failure(name + ": the hole lies outside the body");
    }
  }
  for (std::size_t i = 0; i < notches.size(); ++i) {
    const std::vector<Point>& path = notches[i].path;
    const std::string name = "notches[" + std::to_string(i) + "]";
    if (path.size() < 2) return core::failure(name + ": a notch path needs at least 2 points");
    for (std::size_t k = 1; k < path.size(); ++k) {
      if (path[k].x == path[k - 1].x && path[k].y == path[k - 1].y) {
        return core::failure(name + ": point " + std::to_string(k) + " repeats the previous one");
      }
    }
  }
  if (!(thickness > 0)) return core::failure("thickness must be > 0");
  if (!(rigid_factor >= 1)) return core::failure("rigid_factor must be >= 1");
  if (!(rigid_penalty >= 1)) return core::failure("rigid_penalty must be >= 1");
  return {};
}

}  // namespace peritwin::mesh
