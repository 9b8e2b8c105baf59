// Plane shapes as engineers draw them: a closed boundary of straight edges and circular arcs, with
// optional fillets (a corner rounded by a tangent arc). Used for outline entries, holes and regions
// (solver/mesh/geometry.h). Units: SI (m, rad).
#pragma once

#include <cstddef>
#include <vector>

#include "core/expected.h"

namespace peritwin::mesh {

struct Point {
  double x = 0.0;
  double y = 0.0;
};

/// Axis-aligned box; closed (a point on an edge is inside).
struct Rectangle {
  double x_min = 0.0;
  double y_min = 0.0;
  double x_max = 0.0;
  double y_max = 0.0;
  [[nodiscard]] bool contains(Point p) const {
    return p.x >= x_min && p.x <= x_max && p.y >= y_min && p.y <= y_max;
  }
};

/// True when the closed segments p1-p2 and q1-q2 intersect (touching at an end point counts, so a
/// bond ending on a crack line is cut; collinear overlap counts as a cut).
bool segments_cross(Point p1, Point p2, Point q1, Point q2);

/// Distance from p to the segment a-b (m).
double distance_to_segment(Point p, Point a, Point b);

/// One vertex of a polygon as drawn, with the edge that arrives at it from the previous vertex
/// (the first vertex's edge comes from the last one: the boundary is closed).
struct PolygonVertex {
  enum class Edge {
    straight,  ///< a straight edge
    arc_ccw,   ///< a circular arc about arc_centre, turning counterclockwise
    arc_cw,    ///< a circular arc about arc_centre, turning clockwise
  };
  Point at;
  Edge edge = Edge::straight;
  Point arc_centre;  ///< arcs only; |at − centre| must equal |previous − centre| (1e-6 relative)
  /// > 0: the corner at `at` is rounded by an arc of this radius tangent to both edges at it
  /// (both must be straight, and the arc must fit on them beside the neighbours' fillets).
  double fillet = 0.0;
};

/// A piece of the resolved boundary: a straight segment or a circular arc from `from` to `to`.
struct BoundaryPiece {
  Point from;
  Point to;
  bool arc = false;
  Point centre;       ///< arcs only
  double radius = 0;  ///< arcs only
  double start = 0;   ///< arcs only: angle of `from` about the centre (rad)
  double sweep = 0;   ///< arcs only: signed angle from `from` to `to` (rad, CCW > 0), 0 < |.| < 2π
  int vertex = 0;     ///< the drawn vertex this piece arrives at or rounds (its fillet)
  [[nodiscard]] double length() const;
  /// Distance from p to the piece (m).
  [[nodiscard]] double distance(Point p) const;
};

/// A simple closed shape bounded by straight edges and circular arcs. Built only by make(), which
/// validates it and resolves the fillets into arcs; the boundary is then fixed.
///
/// Inside test (contains): closed — a point on an edge or arc belongs to the polygon, like
/// Rectangle and Circle. Straight edges are tested exactly (orientation = 0 in double precision);
/// arcs to the rounding of √(r² − Δy²). Otherwise the crossing number of a ray towards +x with the
/// boundary cut into y-monotone pieces (arcs are split at their top and bottom points), each
/// counted by the half-open rule (one end strictly above the ray, the other at or below), so a
/// vertex on the ray is counted once. Deterministic: a pure function of the doubles given.
class Polygon {
 public:
  static constexpr std::size_t kMaxVertices = 4096;
  /// Validates and resolves: at least 3 vertices, consecutive vertices distinct, arc radii
  /// consistent, fillets on corners between straight edges that fit beside their neighbours', no
  /// self-intersection (arcs checked as chords of at most 2°), non-zero area. The error's field is
  /// "[k]" naming the vertex (0-based) when one is to blame.
  static core::Expected<Polygon> make(std::vector<PolygonVertex> vertices);

  [[nodiscard]] const std::vector<PolygonVertex>& vertices() const { return vertices_; }
  [[nodiscard]] const std::vector<BoundaryPiece>& boundary() const { return boundary_; }
  [[nodiscard]] bool contains(Point p) const;
  /// Distance from p to the boundary (m).
  [[nodiscard]] double distance(Point p) const;
  /// Smallest box holding the boundary (arcs included).
  [[nodiscard]] Rectangle bounding_box() const { return box_; }
  /// Enclosed area (m²), by Green's theorem over the pieces.
  [[nodiscard]] double area() const;
  [[nodiscard]] double perimeter() const;

 private:
  /// From boundary_: the y-monotone parts (monotone_), the bounding box (box_), and a flattened
  /// copy for the self-intersection check (arcs as chords of at most 2°; flat_vertex[i] is the
  /// drawn vertex of the segment starting at flat[i]).
  void trace_boundary(std::vector<Point>& flat, std::vector<int>& flat_vertex);
  /// A y-monotone part of a piece: a segment, or an arc on one side (±1) of its centre.
  struct Monotone {
    Point a;
    Point b;
    bool arc = false;
    Point centre;
    double radius = 0;
    double side = 1;  ///< arcs: +1 right of the centre, −1 left
  };
  std::vector<PolygonVertex> vertices_;
  std::vector<BoundaryPiece> boundary_;
  std::vector<Monotone> monotone_;
  Rectangle box_;
};

}  // namespace peritwin::mesh
