// Geometry of a detail: the nearest surface to a point (the outline union's boundary, holes,
// notches). Every expected distance is worked out by hand in the comment next to it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "solver/mesh/geometry.h"

namespace peritwin {
namespace {

using Kind = mesh::SurfacePlace::Kind;

TEST(GeometryNearestSurface, RectangleEdgeHoleAndNotch) {
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.1, 0.04}};
  g.holes = {mesh::Circle{{0.05, 0.02}, 0.005}};
  g.notches = {{"notch 0", {{0.0, 0.01}, {0.02, 0.01}}}};
  // 1 cm above the bottom edge, far from the rest.
  mesh::SurfacePlace s = g.nearest_surface({0.08, 0.01});
  EXPECT_EQ(s.kind, Kind::outline);
  EXPECT_EQ(s.index, 0);
  EXPECT_DOUBLE_EQ(s.distance, 0.01);
  // 8 mm above the hole's centre: 3 mm from its rim (radius 5 mm).
  s = g.nearest_surface({0.05, 0.028});
  EXPECT_EQ(s.kind, Kind::hole);
  EXPECT_EQ(s.index, 0);
  EXPECT_NEAR(s.distance, 0.003, 1e-15);
  // Inside the hole, 1 mm from the centre: 4 mm from the rim.
  EXPECT_NEAR(g.nearest_surface({0.051, 0.02}).distance, 0.004, 1e-15);
  // Beyond the notch tip (0.02, 0.01) by (5, 3) mm: hypot = 5.831 mm, nearer than any edge.
  s = g.nearest_surface({0.025, 0.013});
  EXPECT_EQ(s.kind, Kind::notch);
  EXPECT_EQ(s.index, 0);
  EXPECT_NEAR(s.distance, std::hypot(0.005, 0.003), 1e-15);
}

TEST(GeometryNearestSurface, SharedEdgeOfTwoRectanglesIsNotSurface) {
  // Two rectangles side by side make one 200 x 40 mm strip: the edge x = 0.1 they share is inside.
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.1, 0.04}, mesh::Rectangle{0.1, 0.0, 0.2, 0.04}};
  // 1 mm from the shared edge, 20 mm from the top and bottom.
  const mesh::SurfacePlace s = g.nearest_surface({0.099, 0.02});
  EXPECT_EQ(s.kind, Kind::outline);
  EXPECT_DOUBLE_EQ(s.distance, 0.02);
  // On the shared edge itself: still 20 mm.
  EXPECT_DOUBLE_EQ(g.nearest_surface({0.1, 0.02}).distance, 0.02);
}

TEST(GeometryNearestSurface, ReEntrantCornerOfAnLShape) {
  // L-shape: a 100 x 20 mm foot and a 20 x 100 mm leg overlapping in [0, 0.02]². The point
  // (15, 15) mm lies in the overlap; the foot's top edge is covered above it for x < 20 mm and the
  // leg's right edge for y < 20 mm, so the nearest surface is the re-entrant corner (20, 20) mm at
  // hypot(5, 5) = 7.071 mm (the covered edges, 5 mm away, are not surface).
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.1, 0.02}, mesh::Rectangle{0.0, 0.0, 0.02, 0.1}};
  const mesh::SurfacePlace s = g.nearest_surface({0.015, 0.015});
  EXPECT_EQ(s.kind, Kind::outline);
  EXPECT_EQ(s.index, 0);  // the foot's top edge and the leg's right edge tie: the lower index
  EXPECT_NEAR(s.distance, std::hypot(0.005, 0.005), 1e-15);
}

TEST(GeometryNearestSurface, NoSurfaceGivesInfinity) {
  const mesh::SurfacePlace s = mesh::DetailGeometry{}.nearest_surface({0.0, 0.0});
  EXPECT_EQ(s.index, -1);
  EXPECT_TRUE(std::isinf(s.distance));
}

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

using Edge = mesh::PolygonVertex::Edge;

mesh::PolygonVertex corner(double x, double y, double fillet = 0.0) {
  return {{x, y}, Edge::straight, {}, fillet};
}
mesh::PolygonVertex arc_to(double x, double y, mesh::Point centre, Edge edge) {
  return {{x, y}, edge, centre, 0.0};
}

mesh::Polygon make(std::vector<mesh::PolygonVertex> v) {
  auto p = mesh::Polygon::make(std::move(v));
  EXPECT_TRUE(p.ok()) << (p ? "" : p.error().message());
  return p ? std::move(p).value() : mesh::Polygon{};
}

TEST(GeometryPolygon, InsideTestOfAConcaveLShapeIsClosed) {
  // L of three unit squares; the re-entrant corner at (1, 1).
  const mesh::Polygon l =
      make({corner(0, 0), corner(2, 0), corner(2, 1), corner(1, 1), corner(1, 2), corner(0, 2)});
  EXPECT_TRUE(l.contains({0.5, 0.5}));
  EXPECT_TRUE(l.contains({1.5, 0.5}));
  EXPECT_TRUE(l.contains({0.5, 1.5}));
  EXPECT_FALSE(l.contains({1.5, 1.5}));  // the missing square
  // On the boundary: inside (closed), at edges, vertices and the ray through a vertex.
  EXPECT_TRUE(l.contains({1.0, 1.5}));
  EXPECT_TRUE(l.contains({1.5, 1.0}));
  EXPECT_TRUE(l.contains({2.0, 1.0}));
  EXPECT_TRUE(l.contains({1.0, 1.0}));
  EXPECT_TRUE(l.contains({0.0, 0.0}));
  EXPECT_FALSE(l.contains({2.5, 1.0}));  // the ray from here passes through the vertex (2, 1)
  EXPECT_FALSE(l.contains({-0.5, 1.0}));
  EXPECT_FALSE(l.contains({-1e-12, 0.5}));
  EXPECT_DOUBLE_EQ(l.area(), 3.0);
  EXPECT_DOUBLE_EQ(l.perimeter(), 8.0);
  EXPECT_DOUBLE_EQ(l.distance({1.5, 1.5}), 0.5);
}

TEST(GeometryPolygon, SemicircularHeadBulgesOutCounterclockwiseAndInClockwise) {
  // A 2 x 2 shank with a semicircular end of radius 1 about (2, 0).
  const mesh::Polygon lug =
      make({corner(0, -1), corner(2, -1), arc_to(2, 1, {2, 0}, Edge::arc_ccw), corner(0, 1)});
  EXPECT_TRUE(lug.contains({2.9, 0.0}));
  EXPECT_TRUE(lug.contains({3.0, 0.0}));  // on the arc: x = 2 + √(1 − 0) exactly
  EXPECT_FALSE(lug.contains({3.0001, 0.0}));
  EXPECT_TRUE(lug.contains({2.7, 0.7}));     // 0.990 from the centre
  EXPECT_FALSE(lug.contains({2.75, 0.75}));  // 1.061 from the centre
  EXPECT_TRUE(lug.contains({2.0, 1.0}));     // the arc's end
  EXPECT_NEAR(lug.area(), 4.0 + std::numbers::pi / 2, 1e-15);
  EXPECT_NEAR(lug.perimeter(), 6.0 + std::numbers::pi, 1e-15);
  const mesh::Rectangle box = lug.bounding_box();
  EXPECT_DOUBLE_EQ(box.x_max, 3.0);
  EXPECT_DOUBLE_EQ(box.y_max, 1.0);
  EXPECT_NEAR(lug.distance({3.5, 0.0}), 0.5, 1e-15);
  // The same arc clockwise bites into the square instead.
  const mesh::Polygon bitten =
      make({corner(0, -1), corner(2, -1), arc_to(2, 1, {2, 0}, Edge::arc_cw), corner(0, 1)});
  EXPECT_TRUE(bitten.contains({0.5, 0.0}));
  EXPECT_FALSE(bitten.contains({1.5, 0.0}));
  EXPECT_FALSE(bitten.contains({2.5, 0.0}));
  EXPECT_NEAR(bitten.area(), 4.0 - std::numbers::pi / 2, 1e-15);
}

TEST(GeometryPolygon, FilletRoundsACorner) {
  // Unit square, corner (1, 1) rounded with r = 0.2: the arc about (0.8, 0.8) from (1, 0.8) to
  // (0.8, 1) removes (1 − π/4)·r² = 0.008584 of area.
  const mesh::Polygon p = make({corner(0, 0), corner(1, 0), corner(1, 1, 0.2), corner(0, 1)});
  EXPECT_NEAR(p.area(), 1.0 - (1.0 - std::numbers::pi / 4) * 0.04, 1e-15);
  EXPECT_NEAR(p.perimeter(), 4.0 - 0.4 + std::numbers::pi * 0.1, 1e-15);
  EXPECT_FALSE(p.contains({0.99, 0.99}));
  EXPECT_TRUE(p.contains({0.9, 0.9}));  // 0.141 from the fillet's centre
  EXPECT_TRUE(p.contains({1.0, 0.5}));
  EXPECT_NEAR(p.distance({1.0, 1.0}), std::sqrt(2.0) * 0.2 - 0.2, 1e-15);
}

TEST(GeometryPolygon, GridNodeCountGivesTheAnalyticArea) {
  // A 40 x 20 mm plate with four 5 mm fillets and a semicircular-ended slot of radius 3 mm as a
  // polygon hole; 0.1 mm grid. Area = 800 − 4·(1 − π/4)·25 − (8·6 + π·9) = 723.27 mm². The lattice
  // count differs from it only through the cells cut by the boundary (perimeter 160 mm ≈ 1600
  // cells of which the misses largely cancel); tolerance 0.1 % = 7 cells·10.
  mesh::DetailGeometry g;
  g.outline = {make({corner(0, 0, 0.005), corner(0.04, 0, 0.005), corner(0.04, 0.02, 0.005),
                     corner(0, 0.02, 0.005)})};
  g.holes = {make({arc_to(0.016, 0.007, {0.016, 0.010}, Edge::arc_ccw), corner(0.024, 0.007),
                   arc_to(0.024, 0.013, {0.024, 0.010}, Edge::arc_ccw), corner(0.016, 0.013)})};
  ASSERT_TRUE(g.validate().ok()) << core::message_of(g.validate());
  const double dx = 1e-4;
  long nodes = 0;
  for (int j = 0; j < 200; ++j) {
    for (int i = 0; i < 400; ++i) nodes += g.is_material({(i + 0.5) * dx, (j + 0.5) * dx}) ? 1 : 0;
  }
  const double area =
      800e-6 - 4 * (1 - std::numbers::pi / 4) * 25e-6 - (48e-6 + std::numbers::pi * 9e-6);
  EXPECT_NEAR(g.outline[0].area() - g.holes[0].area(), area, 1e-18);
  EXPECT_NEAR(static_cast<double>(nodes) * dx * dx, area, 1e-3 * area);
  // Nearest surface: 1 mm right of the slot's right end (27 mm, 10 mm) -> the hole at 1 mm.
  const mesh::SurfacePlace s = g.nearest_surface({0.028, 0.010});
  EXPECT_EQ(s.kind, mesh::SurfacePlace::Kind::hole);
  EXPECT_NEAR(s.distance, 0.001, 1e-15);
  // The filleted corner: from (0, 0) to the arc about (5, 5) mm is 5√2 − 5 mm = 2.071 mm.
  EXPECT_NEAR(g.nearest_surface({0.0, 0.0}).distance, 0.005 * std::sqrt(2.0) - 0.005, 1e-15);
}

TEST(GeometryPolygon, InvalidPolygonsNameTheVertex) {
  const auto error = [](std::vector<mesh::PolygonVertex> v) {
    const auto p = mesh::Polygon::make(std::move(v));
    return p ? std::string("ok") : p.error().message();
  };
  EXPECT_EQ(error({corner(0, 0), corner(1, 0)}), "a polygon needs at least 3 vertices (got 2)");
  // Bow tie: the edge to [3] crosses the edge to [1].
  EXPECT_EQ(error({corner(0, 0), corner(1, 1), corner(1, 0), corner(0, 1)}),
            "[3]: the boundary crosses itself (the edge to this vertex meets the edge to vertex "
            "[1])");
  EXPECT_EQ(error({corner(0, 0), corner(1, 0), corner(1, 0), corner(0, 1)}),
            "[2]: coincides with the previous vertex [1]");
  EXPECT_NE(
      error({corner(0, -1), corner(2, -1), arc_to(2, 1.1, {2, 0}, Edge::arc_ccw), corner(0, 1)})
          .find("[2]: the arc ends 1.1 m from its centre"),
      std::string::npos);
  // A 0.6 fillet needs 0.6 of each unit edge: two of them on one edge do not fit.
  EXPECT_EQ(error({corner(0, 0), corner(1, 0, 0.6), corner(1, 1, 0.6), corner(0, 1)}),
            "[2]: the fillets need 1.2 m of the edge from vertex [1], which is 1 m long");
  EXPECT_EQ(
      error({corner(0, -1), corner(2, -1, 0.1), arc_to(2, 1, {2, 0}, Edge::arc_ccw), corner(0, 1)}),
      "[1]: a fillet needs straight edges on both sides of its vertex");
  EXPECT_EQ(error({corner(0, 0), corner(1, 0), corner(2, 0)}),
            "[0]: the boundary turns back on itself");
}

}  // namespace
}  // namespace peritwin
