// Geometry of a detail: the nearest surface to a point (the outline union's boundary, holes,
// notches). Every expected distance is worked out by hand in the comment next to it.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/mesh/geometry.h"

namespace peritwin {
namespace {

using Kind = SurfacePlace::Kind;

TEST(GeometryNearestSurface, RectangleEdgeHoleAndNotch) {
  DetailGeometry g;
  g.outline = {{0.0, 0.0, 0.1, 0.04}};
  g.holes = {{{0.05, 0.02}, 0.005}};
  g.notches = {{{0.0, 0.01}, {0.02, 0.01}}};
  // 1 cm above the bottom edge, far from the rest.
  SurfacePlace s = g.nearest_surface({0.08, 0.01});
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
  DetailGeometry g;
  g.outline = {{0.0, 0.0, 0.1, 0.04}, {0.1, 0.0, 0.2, 0.04}};
  // 1 mm from the shared edge, 20 mm from the top and bottom.
  const SurfacePlace s = g.nearest_surface({0.099, 0.02});
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
  DetailGeometry g;
  g.outline = {{0.0, 0.0, 0.1, 0.02}, {0.0, 0.0, 0.02, 0.1}};
  const SurfacePlace s = g.nearest_surface({0.015, 0.015});
  EXPECT_EQ(s.kind, Kind::outline);
  EXPECT_EQ(s.index, 0);  // the foot's top edge and the leg's right edge tie: the lower index
  EXPECT_NEAR(s.distance, std::hypot(0.005, 0.005), 1e-15);
}

TEST(GeometryNearestSurface, NoSurfaceGivesInfinity) {
  const SurfacePlace s = DetailGeometry{}.nearest_surface({0.0, 0.0});
  EXPECT_EQ(s.index, -1);
  EXPECT_TRUE(std::isinf(s.distance));
}

}  // namespace
}  // namespace peritwin
