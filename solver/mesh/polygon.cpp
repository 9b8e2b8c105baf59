#include "solver/mesh/polygon.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace peritwin::mesh {

namespace {

constexpr double kPi = std::numbers::pi;

double orientation(Point a, Point b, Point c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

bool on_segment(Point a, Point b, Point p) {
  return std::min(a.x, b.x) <= p.x && p.x <= std::max(a.x, b.x) && std::min(a.y, b.y) <= p.y &&
         p.y <= std::max(a.y, b.y);
}

bool same(Point a, Point b) { return a.x == b.x && a.y == b.y; }

double point_distance(Point a, Point b) { return std::hypot(b.x - a.x, b.y - a.y); }

/// The angle in [0, 2π) equivalent to a.
double wrap(double a) {
  a = std::fmod(a, 2.0 * kPi);
  return a < 0 ? a + 2.0 * kPi : a;
}

/// "[k]". (Appended piecewise: GCC 12's -Wrestrict misfires on "[" + std::to_string(k).)
std::string vertex_name(std::size_t k) {
  std::string name(1, '[');
  name += std::to_string(k);
  name += ']';
  return name;
}

std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", v);
  return buffer;
}

/// The arc from `from` to `to` about `centre`, counterclockwise or clockwise (0 < |sweep| ≤ 2π).
BoundaryPiece make_arc(Point from, Point to, Point centre, bool counterclockwise, int vertex) {
  BoundaryPiece piece{from, to, true, centre, point_distance(centre, from), 0.0, 0.0, vertex};
  piece.start = std::atan2(from.y - centre.y, from.x - centre.x);
  const double end = std::atan2(to.y - centre.y, to.x - centre.x);
  double sweep = wrap(end - piece.start);
  if (counterclockwise) {
    if (sweep == 0.0) sweep = 2.0 * kPi;
  } else {
    sweep = sweep == 0.0 ? -2.0 * kPi : sweep - 2.0 * kPi;
  }
  piece.sweep = sweep;
  return piece;
}

/// The angles a = π/2·j strictly inside the arc's angular range (in the order of travel), with j.
std::vector<std::pair<double, long>> quarter_angles(const BoundaryPiece& arc) {
  const double lo = std::min(arc.start, arc.start + arc.sweep);
  const double hi = std::max(arc.start, arc.start + arc.sweep);
  constexpr double tiny = 1e-12;
  std::vector<std::pair<double, long>> out;
  for (auto j = static_cast<long>(std::ceil(lo / (0.5 * kPi)));
       0.5 * kPi * static_cast<double>(j) < hi; ++j) {
    const double a = 0.5 * kPi * static_cast<double>(j);
    if (a > lo + tiny && a < hi - tiny) out.emplace_back(a, j);
  }
  if (arc.sweep < 0) std::reverse(out.begin(), out.end());
  return out;
}

/// The point of the circle at angle π/2·j, exactly on the axis through the centre.
Point quarter_point(const BoundaryPiece& arc, long j) {
  switch (((j % 4) + 4) % 4) {
    case 0:
      return {arc.centre.x + arc.radius, arc.centre.y};
    case 1:
      return {arc.centre.x, arc.centre.y + arc.radius};
    case 2:
      return {arc.centre.x - arc.radius, arc.centre.y};
    default:
      return {arc.centre.x, arc.centre.y - arc.radius};
  }
}

/// A rounded corner: the tangent points on the two edges at its vertex and the arc's centre.
struct Corner {
  double tangent = 0.0;  ///< distance from the vertex to each tangent point
  Point in, out, centre;
  bool counterclockwise = true;
};

/// Each vertex on its own: finite, distinct from the previous one, a finite fillet radius >= 0,
/// and an arc edge's radii at its two ends that agree.
core::Status check_vertices(const std::vector<PolygonVertex>& vertices) {
  const std::size_t n = vertices.size();
  const auto prev = [n](std::size_t k) { return (k + n - 1) % n; };
  for (std::size_t k = 0; k < n; ++k) {
    const PolygonVertex& v = vertices[k];
    const Point from = vertices[prev(k)].at;
    if (!std::isfinite(v.at.x) || !std::isfinite(v.at.y)) {
      return core::Error{vertex_name(k), "coordinates must be finite"};
    }
    if (same(v.at, from)) {
      return core::Error{vertex_name(k),
                         "coincides with the previous vertex " + vertex_name(prev(k))};
    }
    if (!(v.fillet >= 0.0) || !std::isfinite(v.fillet)) {
      return core::Error{vertex_name(k), "the fillet radius must be finite and >= 0"};
    }
    if (v.edge != PolygonVertex::Edge::straight) {
      const double r0 = point_distance(v.arc_centre, from);
      const double r1 = point_distance(v.arc_centre, v.at);
      if (!(r0 > 0.0)) {
        return core::Error{vertex_name(k), "the arc centre coincides with the previous vertex"};
      }
      if (std::abs(r1 - r0) > 1e-6 * r0) {
        return core::Error{vertex_name(k), "the arc ends " + number(r1) +
                                               " m from its centre but starts (at vertex " +
                                               vertex_name(prev(k)) + ") " + number(r0) +
                                               " m from it: the radii must agree to 1e-6"};
      }
    }
  }
  return {};
}

/// Fillets: the tangent points on the two edges at the corner and the arc's centre; each straight
/// edge must then hold its two ends' tangents.
core::Expected<std::vector<Corner>> fillet_corners(const std::vector<PolygonVertex>& vertices) {
  const std::size_t n = vertices.size();
  const auto prev = [n](std::size_t k) { return (k + n - 1) % n; };
  const auto next = [n](std::size_t k) { return (k + 1) % n; };
  std::vector<Corner> corners(n);
  for (std::size_t k = 0; k < n; ++k) {
    const PolygonVertex& v = vertices[k];
    if (v.fillet == 0.0) continue;
    if (v.edge != PolygonVertex::Edge::straight ||
        vertices[next(k)].edge != PolygonVertex::Edge::straight) {
      return core::Error{vertex_name(k),
                         "a fillet needs straight edges on both sides of its vertex"};
    }
    const Point a = vertices[prev(k)].at;
    const Point b = vertices[next(k)].at;
    const double la = point_distance(v.at, a);
    const double lb = point_distance(v.at, b);
    const Point u1{(a.x - v.at.x) / la, (a.y - v.at.y) / la};
    const Point u2{(b.x - v.at.x) / lb, (b.y - v.at.y) / lb};
    const double cross = u1.x * u2.y - u1.y * u2.x;
    const double dot = std::clamp(u1.x * u2.x + u1.y * u2.y, -1.0, 1.0);
    if (cross == 0.0) {
      return core::Error{vertex_name(k),
                         "no corner to round: the edges at the vertex are collinear"};
    }
    const double half = 0.5 * std::acos(dot);  // half the corner angle θ between the edges
    Corner& c = corners[k];
    c.tangent = v.fillet / std::tan(half);  // tangent length r·cot(θ/2)
    c.in = {v.at.x + c.tangent * u1.x, v.at.y + c.tangent * u1.y};
    c.out = {v.at.x + c.tangent * u2.x, v.at.y + c.tangent * u2.y};
    const double bx = u1.x + u2.x;
    const double by = u1.y + u2.y;
    const double bl = std::hypot(bx, by);
    const double reach = v.fillet / std::sin(half);  // vertex to centre along the bisector
    c.centre = {v.at.x + reach * bx / bl, v.at.y + reach * by / bl};
    c.counterclockwise = orientation(c.centre, c.in, c.out) > 0;
  }
  for (std::size_t k = 0; k < n; ++k) {  // each straight edge holds its two ends' tangents
    if (vertices[k].edge != PolygonVertex::Edge::straight) continue;
    const double need = corners[prev(k)].tangent + corners[k].tangent;
    const double have = point_distance(vertices[prev(k)].at, vertices[k].at);
    if (need > have * (1.0 + 1e-12)) {
      return core::Error{vertex_name(k), "the fillets need " + number(need) +
                                             " m of the edge from vertex " + vertex_name(prev(k)) +
                                             ", which is " + number(have) + " m long"};
    }
  }
  return corners;
}

/// The boundary pieces in drawing order: each vertex's edge from the previous vertex (or the end
/// of its fillet) to this vertex (or the start of its fillet), then this vertex's fillet arc.
std::vector<BoundaryPiece> boundary_pieces(const std::vector<PolygonVertex>& vs,
                                           const std::vector<Corner>& corners) {
  const std::size_t n = vs.size();
  const auto prev = [n](std::size_t k) { return (k + n - 1) % n; };
  std::vector<BoundaryPiece> boundary;
  for (std::size_t k = 0; k < n; ++k) {
    const PolygonVertex& v = vs[k];
    const std::size_t p = prev(k);
    const Point from = vs[p].fillet > 0 ? corners[p].out : vs[p].at;
    const Point to = v.fillet > 0 ? corners[k].in : v.at;
    const int index = static_cast<int>(k);
    if (v.edge == PolygonVertex::Edge::straight) {
      if (!same(from, to)) boundary.push_back({from, to, false, {}, 0.0, 0.0, 0.0, index});
    } else {
      boundary.push_back(
          make_arc(from, to, v.arc_centre, v.edge == PolygonVertex::Edge::arc_ccw, index));
    }
    if (v.fillet > 0) {
      boundary.push_back(make_arc(corners[k].in, corners[k].out, corners[k].centre,
                                  corners[k].counterclockwise, index));
    }
  }
  return boundary;
}

/// The flattened boundary (segments flat[i] -> flat[i + 1], closed) is simple: no segment turns
/// back along the next one, and no two non-adjacent segments meet.
core::Status check_simple(const std::vector<Point>& flat, const std::vector<int>& flat_vertex) {
  const std::size_t m = flat.size();
  for (std::size_t i = 0; i < m; ++i) {
    const Point a0 = flat[i];
    const Point a1 = flat[(i + 1) % m];
    // Adjacent segments may only share their common end: no turning back along the same line.
    const Point b1 = flat[(i + 2) % m];
    if (orientation(a0, a1, b1) == 0.0 &&
        (a1.x - a0.x) * (b1.x - a1.x) + (a1.y - a0.y) * (b1.y - a1.y) < 0.0) {
      return core::Error{vertex_name(static_cast<std::size_t>(flat_vertex[i])),
                         "the boundary turns back on itself"};
    }
    for (std::size_t j = i + 2; j < m; ++j) {
      if (i == 0 && j + 1 == m) continue;  // the last segment is adjacent to the first
      if (segments_cross(a0, a1, flat[j], flat[(j + 1) % m])) {
        return core::Error{vertex_name(static_cast<std::size_t>(flat_vertex[j])),
                           "the boundary crosses itself (the edge to this vertex meets the edge to "
                           "vertex " +
                               vertex_name(static_cast<std::size_t>(flat_vertex[i])) + ")"};
      }
    }
  }
  return {};
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

double BoundaryPiece::length() const {
  return arc ? radius * std::abs(sweep) : point_distance(from, to);
}

double BoundaryPiece::distance(Point p) const {
  if (!arc) return distance_to_segment(p, from, to);
  const double d = std::hypot(p.x - centre.x, p.y - centre.y);
  if (d == 0.0) return radius;
  const double angle = std::atan2(p.y - centre.y, p.x - centre.x);
  const double along = sweep > 0 ? wrap(angle - start) : wrap(start - angle);
  if (along <= std::abs(sweep)) return std::abs(d - radius);
  return std::min(point_distance(p, from), point_distance(p, to));
}

core::Expected<Polygon> Polygon::make(std::vector<PolygonVertex> vertices) {
  const std::size_t n = vertices.size();
  if (n < 3)
    return core::failure("a polygon needs at least 3 vertices (got " + std::to_string(n) + ")");
  if (n > kMaxVertices) {
    return core::failure("a polygon may have at most " + std::to_string(kMaxVertices) +
                         " vertices (got " + std::to_string(n) + ")");
  }
  if (core::Status valid = check_vertices(vertices); !valid) return valid.error();
  auto corners = fillet_corners(vertices);
  if (!corners) return corners.error();

  Polygon polygon;
  polygon.vertices_ = std::move(vertices);
  polygon.boundary_ = boundary_pieces(polygon.vertices_, *corners);
  std::vector<Point> flat;
  std::vector<int> flat_vertex;  // the drawn vertex of the flat segment starting at flat[i]
  polygon.trace_boundary(flat, flat_vertex);
  if (core::Status simple = check_simple(flat, flat_vertex); !simple) return simple.error();
  if (!(polygon.area() > 0.0)) return core::failure("the polygon encloses no area");
  return polygon;
}

void Polygon::trace_boundary(std::vector<Point>& flat, std::vector<int>& flat_vertex) {
  // y-monotone parts for the inside test, the bounding box, and a flattened copy (arcs as chords
  // of at most 2°) for the self-intersection check.
  constexpr double inf = std::numeric_limits<double>::infinity();
  Rectangle box{inf, inf, -inf, -inf};
  const auto grow = [&box](Point q) {
    box.x_min = std::min(box.x_min, q.x);
    box.y_min = std::min(box.y_min, q.y);
    box.x_max = std::max(box.x_max, q.x);
    box.y_max = std::max(box.y_max, q.y);
  };
  for (const BoundaryPiece& piece : boundary_) {
    grow(piece.from);
    flat.push_back(piece.from);
    flat_vertex.push_back(piece.vertex);
    if (!piece.arc) {
      monotone_.push_back({piece.from, piece.to, false, {}, 0.0, 1.0});
      continue;
    }
    Point a = piece.from;
    double angle_a = piece.start;
    for (const auto& [angle, j] : quarter_angles(piece)) {
      const Point q = quarter_point(piece, j);
      grow(q);
      if (j % 2 != 0) {  // top or bottom: a monotone part ends here
        const double mid = 0.5 * (angle_a + angle);
        monotone_.push_back(
            {a, q, true, piece.centre, piece.radius, std::cos(mid) >= 0 ? 1.0 : -1.0});
        a = q;
        angle_a = angle;
      }
    }
    const double end = piece.start + piece.sweep;
    const double mid = 0.5 * (angle_a + end);
    monotone_.push_back(
        {a, piece.to, true, piece.centre, piece.radius, std::cos(mid) >= 0 ? 1.0 : -1.0});
    const auto chords = static_cast<int>(std::ceil(std::abs(piece.sweep) / (2.0 * kPi / 180.0)));
    for (int c = 1; c < chords; ++c) {
      const double t = piece.start + piece.sweep * c / chords;
      flat.push_back({piece.centre.x + piece.radius * std::cos(t),
                      piece.centre.y + piece.radius * std::sin(t)});
      flat_vertex.push_back(piece.vertex);
    }
  }
  box_ = box;
}

bool Polygon::contains(Point p) const {
  if (!box_.contains(p)) return false;
  for (const BoundaryPiece& piece : boundary_) {
    if (!piece.arc && orientation(piece.from, piece.to, p) == 0.0 &&
        on_segment(piece.from, piece.to, p)) {
      return true;  // closed: a point on an edge is inside
    }
  }
  bool inside = false;
  for (const Monotone& part : monotone_) {
    if (part.arc) {
      if (p.y < std::min(part.a.y, part.b.y) || p.y > std::max(part.a.y, part.b.y)) continue;
      const double dy = p.y - part.centre.y;
      const double x =
          part.centre.x + part.side * std::sqrt(std::max(0.0, part.radius * part.radius - dy * dy));
      if (x == p.x) return true;  // on the arc
      if ((part.a.y > p.y) != (part.b.y > p.y) && p.x < x) inside = !inside;
    } else if ((part.a.y > p.y) != (part.b.y > p.y)) {
      const double x = part.a.x + (p.y - part.a.y) * (part.b.x - part.a.x) / (part.b.y - part.a.y);
      if (p.x < x) inside = !inside;
    }
  }
  return inside;
}

double Polygon::distance(Point p) const {
  double best = std::numeric_limits<double>::infinity();
  for (const BoundaryPiece& piece : boundary_) best = std::min(best, piece.distance(p));
  return best;
}

double Polygon::area() const {
  // Green's theorem: A = ½∮(x dy − y dx); over an arc x = cx + r cos t, y = cy + r sin t it is
  // ½(r²·sweep + cx·(y1 − y0) − cy·(x1 − x0)).
  double twice = 0.0;
  for (const BoundaryPiece& piece : boundary_) {
    if (piece.arc) {
      twice += piece.radius * piece.radius * piece.sweep +
               piece.centre.x * (piece.to.y - piece.from.y) -
               piece.centre.y * (piece.to.x - piece.from.x);
    } else {
      twice += piece.from.x * piece.to.y - piece.to.x * piece.from.y;
    }
  }
  return 0.5 * std::abs(twice);
}

double Polygon::perimeter() const {
  double sum = 0.0;
  for (const BoundaryPiece& piece : boundary_) sum += piece.length();
  return sum;
}

}  // namespace peritwin::mesh
