#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

#include "solver/mesh/discretization.h"

namespace peritwin {
namespace {

/// The independent oracle for families: an O(N²) search over all node pairs within δ.
std::set<std::pair<int, int>> pairs_within_horizon(const mesh::Discretization& d) {
  std::set<std::pair<int, int>> pairs;
  for (int a = 0; a < d.num_nodes(); ++a) {
    for (int b = a + 1; b < d.num_nodes(); ++b) {
      const double r =
          std::hypot(d.position[b].x - d.position[a].x, d.position[b].y - d.position[a].y);
      if (r <= d.horizon) pairs.insert({a, b});
    }
  }
  return pairs;
}

TEST(PartialVolume, MatchesBouaraquiaEq36) {
  // 001 Eq. (36) with δ = 3, Δx = 1: full weight up to δ − Δx/2, linear to zero at δ + Δx/2.
  EXPECT_DOUBLE_EQ(mesh::partial_volume_factor(2.5, 3.0, 1.0), 1.0);
  EXPECT_DOUBLE_EQ(mesh::partial_volume_factor(3.0, 3.0, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(mesh::partial_volume_factor(3.25, 3.0, 1.0), 0.25);
  EXPECT_DOUBLE_EQ(mesh::partial_volume_factor(3.5, 3.0, 1.0), 0.0);
}

TEST(Discretization, BondsEqualBruteForcePairSearch) {
  // A plate with a hole: the cell-list families must equal an O(N²) search over all node pairs
  // within δ.
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.02, 0.01}, mesh::Rectangle{0.02, 0.0, 0.03, 0.004}};
  g.holes = {mesh::Circle{{0.01, 0.005}, 0.002}};
  const double dx = 0.0005;
  const mesh::Discretization d = discretize(g, dx, 3.015 * dx);
  const auto expected = pairs_within_horizon(d);
  std::set<std::pair<int, int>> found;
  for (int b = 0; b < d.num_bonds(); ++b) found.insert({d.bond_i[b], d.bond_j[b]});
  EXPECT_EQ(found.size(), static_cast<std::size_t>(d.num_bonds()));  // no duplicates
  EXPECT_EQ(found, expected);
  // An interior node has the 28 lattice neighbours with i² + j² ≤ 9 (|ξ| ≤ 3.015Δx).
  const mesh::NodeIndex centre = d.nearest_node({0.004, 0.005});
  EXPECT_EQ(d.family_offset[centre + 1] - d.family_offset[centre], 28);
  // Unit vectors point from bond_i to bond_j.
  for (int b = 0; b < d.num_bonds(); ++b) {
    const auto pi = d.position[d.bond_i[b]];
    const auto pj = d.position[d.bond_j[b]];
    EXPECT_NEAR(pi.x + d.bond_length[b] * d.bond_cos[b], pj.x, 1e-12);
    EXPECT_NEAR(pi.y + d.bond_length[b] * d.bond_sin[b], pj.y, 1e-12);
  }
}

TEST(Discretization, PerturbedGridKeepsTheBruteForceFamiliesAndIsReproducible) {
  // An irregular arrangement (amplitude 0.2Δx): every node within 0.2Δx (per coordinate) of a
  // grid point, the families equal the O(N²) search over the true distances, the weights are
  // 001 Eq. (36) of the true length, and the same seed gives the same nodes bit for bit.
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.02, 0.01}};
  g.holes = {mesh::Circle{{0.01, 0.005}, 0.002}};
  const double dx = 0.0005;
  const mesh::GridPerturbation grid{0.2, 42};
  const mesh::Discretization d = discretize(g, dx, 3.015 * dx, grid);
  const mesh::Discretization regular = discretize(g, dx, 3.015 * dx);
  double largest = 0.0;
  for (const mesh::Point p : d.position) {
    const double fx = p.x / dx - 0.5 - std::round(p.x / dx - 0.5);
    const double fy = p.y / dx - 0.5 - std::round(p.y / dx - 0.5);
    largest = std::max({largest, std::abs(fx), std::abs(fy)});
    EXPECT_FALSE(g.holes[0].contains(p));
  }
  EXPECT_LE(largest, 0.2);
  EXPECT_GT(largest, 0.19);  // the offsets do fill the range
  const auto expected = pairs_within_horizon(d);
  std::set<std::pair<int, int>> found;
  for (int b = 0; b < d.num_bonds(); ++b) {
    found.insert({d.bond_i[b], d.bond_j[b]});
    const auto pi = d.position[d.bond_i[b]];
    const auto pj = d.position[d.bond_j[b]];
    const double r = std::hypot(pj.x - pi.x, pj.y - pi.y);
    EXPECT_DOUBLE_EQ(d.bond_length[b], r);
    EXPECT_DOUBLE_EQ(d.bond_volume_factor[b], mesh::partial_volume_factor(r, d.horizon, dx));
  }
  EXPECT_EQ(found, expected);
  // Family sizes now vary around the regular grid's 28.
  EXPECT_NE(d.num_bonds(), regular.num_bonds());
  const mesh::Discretization again = discretize(g, dx, 3.015 * dx, grid);
  ASSERT_EQ(again.num_nodes(), d.num_nodes());
  for (int k = 0; k < d.num_nodes(); ++k) {
    EXPECT_EQ(again.position[k].x, d.position[k].x);
    EXPECT_EQ(again.position[k].y, d.position[k].y);
  }
  const mesh::Discretization other_seed = discretize(g, dx, 3.015 * dx, {0.2, 43});
  EXPECT_NE(other_seed.position[0].x, d.position[0].x);
  // Amplitude 0 is the regular grid exactly; an amplitude that could swap cells is refused.
  const mesh::Discretization zero = discretize(g, dx, 3.015 * dx, {0.0, 42});
  EXPECT_EQ(zero.bond_length, regular.bond_length);
  EXPECT_THROW((void)discretize(g, dx, 3.015 * dx, {0.25, 1}), std::invalid_argument);
  EXPECT_THROW((void)discretize(g, dx, 3.015 * dx, {-0.1, 1}), std::invalid_argument);
}

TEST(Discretization, PreCrackCutsExactlyTheCrossingBonds) {
  // 4 × 4 nodes at (i+½, j+½) on [0,4]×[−2,2], Δx = 1, δ = 1.5: families hold the distance-1
  // and distance-√2 neighbours. A crack along y = 0 from x = −1 to x = 2.2 cuts, counted by hand:
  // the vertical bonds at x = 0.5 and 1.5 (2), and the diagonals between rows y = ±0.5 crossing
  // y = 0 at x = 1.0 (two of them) and x = 2.0 (two of them): 6 bonds.
  mesh::DetailGeometry g;
  g.outline = {mesh::Rectangle{0.0, -2.0, 4.0, 2.0}};
  g.notches = {{"notch 0", {{-1.0, 0.0}, {2.2, 0.0}}}};
  const mesh::Discretization d = discretize(g, 1.0, 1.5);
  EXPECT_EQ(d.num_nodes(), 16);
  int cut = 0;
  for (int b = 0; b < d.num_bonds(); ++b) cut += d.bond_precut[b];
  EXPECT_EQ(cut, 6);
  // 16 nodes: 24 distance-1 bonds + 18 diagonal bonds.
  EXPECT_EQ(d.num_bonds(), 42);
}

TEST(Geometry, ValidationNamesTheProblem) {
  mesh::DetailGeometry g;
  EXPECT_NE(core::message_of(g.validate()).find("outline"), std::string::npos);
  g.outline = {mesh::Rectangle{0.0, 0.0, 1.0, 1.0}};
  g.holes = {mesh::Circle{{5.0, 5.0}, 0.1}};
  EXPECT_NE(core::message_of(g.validate()).find("outside"), std::string::npos);
  g.holes = {mesh::Circle{{0.5, 0.5}, 0.1}};
  EXPECT_EQ(core::message_of(g.validate()), "");
}

}  // namespace
}  // namespace peritwin
