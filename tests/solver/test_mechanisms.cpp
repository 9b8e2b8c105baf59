// What a singular stiffness means (docs/solver.md, "Mechanisms are pinned"): a part still attached
// that moves without straining any intact bond is pinned and solved, unloaded debris smaller than
// a family is grounded like an isolated node, and only a piece that came loose with load on it or
// as large as a family is final failure, named. Both re-solve paths (rank updates and
// refactorization) agree.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "solver/statics/static_solver.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

const model::Material aluminium{68e9, 0.33, 48.7e6};

/// A 20 × 10 mm plate at Δx = 0.5 mm (40 × 20 nodes) under uniaxial tension.
testing::TensionPlate plate(model::ModelKind kind) {
  model::ModelOptions o;
  o.kind = kind;
  return testing::make_tension_plate(aluminium, o, 0.02, 0.01, 0.0005, 80e6);
}

bool horizontal(const mesh::Discretization& d, mesh::BondIndex b) {
  return std::abs(d.bond_sin[static_cast<std::size_t>(b)]) < 1e-12;
}

/// Every bond of the given nodes except those between two of them and (if `keep_rows`) those
/// along the x axis: with keep_rows the nodes hang from their rows by collinear bonds only.
std::vector<mesh::BondIndex> bonds_cutting_off(const mesh::Discretization& d,
                                               const std::vector<mesh::NodeIndex>& nodes,
                                               bool keep_rows) {
  std::vector<mesh::BondIndex> cut;
  for (mesh::BondIndex b = 0; b < d.num_bonds(); ++b) {
    const bool i_in = std::count(nodes.begin(), nodes.end(), d.bond_i[b]) > 0;
    const bool j_in = std::count(nodes.begin(), nodes.end(), d.bond_j[b]) > 0;
    if (i_in == j_in || (keep_rows && horizontal(d, b))) continue;
    cut.push_back(b);
  }
  return cut;
}

/// At every free DOF the bond-by-bond internal force equals the applied load: a pinned DOF's
/// spring carries nothing.
void expect_equilibrium(const statics::StaticSolver& s) {
  const auto& u = s.basis_displacement(statics::basis_constant);
  const auto f_int = s.internal_force(u);
  const auto f_ext = s.basis_force(statics::basis_constant);
  double scale = 0.0;
  for (double f : f_ext) scale = std::max(scale, std::abs(f));
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (s.free_index()[dof] >= 0) {
      EXPECT_NEAR(f_int[dof], f_ext[dof], 1e-9 * scale) << dof;
    }
  }
}

/// The two solvers' stretches of the intact bonds agree (relative to the largest).
void expect_same_stretches(const statics::StaticSolver& a, const statics::StaticSolver& b) {
  const auto& sa = a.basis_stretch(statics::basis_constant);
  const auto& sb = b.basis_stretch(statics::basis_constant);
  double scale = 0.0;
  for (double s : sa) scale = std::max(scale, std::abs(s));
  for (std::size_t k = 0; k < sa.size(); ++k) {
    if (a.intact()[k]) {
      EXPECT_NEAR(sa[k], sb[k], 1e-9 * scale) << "bond " << k;
    }
  }
}

class Mechanisms : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(Mechanisms, SliverHeldByCollinearBondsIsPinnedNotFinalFailure) {
  // The middle-crack tension panel's false final failure (docs/solver.md): two nodes, one above
  // the other, bonded to each other and otherwise only along their rows. Their common y motion
  // strains no bond (000 Eq. 3d is linear in e·Δu), so K has a null vector — in the mixed form
  // as in the condensed one, the dilatation term being a function of the stretches too.
  const auto p = plate(GetParam());
  const mesh::NodeIndex a = p.disc.nearest_node({0.01025, -0.00025});
  const mesh::NodeIndex b = p.disc.nearest_node({0.01025, 0.00025});
  const auto cut = bonds_cutting_off(p.disc, {a, b}, true);
  ASSERT_EQ(cut.size(), 42U);  // of each node's 28: all but the 6 along its row and a–b
  statics::StaticSolver incremental(p.disc, p.model, p.supports, p.loads);
  statics::StaticSolver oracle(p.disc, p.model, p.supports, p.loads);
  incremental.set_incremental(true);
  ASSERT_TRUE(incremental.solve().ok());
  ASSERT_TRUE(oracle.solve().ok());
  const core::Status ri = incremental.break_bonds(cut);
  const core::Status ro = oracle.break_bonds(cut);
  ASSERT_TRUE(ri.ok()) << core::message_of(ri);
  ASSERT_TRUE(ro.ok()) << core::message_of(ro);
  for (const auto* s : {&incremental, &oracle}) {
    ASSERT_EQ(s->pinned_dofs(), 1);
    // The pin is a y DOF of a or b.
    const auto at = std::find(s->pinned().begin(), s->pinned().end(), 1) - s->pinned().begin();
    const auto dof =
        std::find(s->free_index().begin(), s->free_index().end(), at) - s->free_index().begin();
    EXPECT_EQ(dof % 2, 1);
    EXPECT_TRUE(dof / 2 == a || dof / 2 == b);
    expect_equilibrium(*s);
  }
  expect_same_stretches(incremental, oracle);
  // The incremental path pinned it from the failed update's first bad pivot: one factorization
  // at the start, one after the update.
  EXPECT_EQ(incremental.factorizations(), 2);
}

TEST_P(Mechanisms, UnloadedDebrisIsGroundedAndALargerPieceIsFinalFailure) {
  // Two nodes bonded only to each other: fewer nodes than a family and no load, so grounded like
  // an isolated node (no strain under any load, no stretch changed). A 6 × 6 block (36 nodes, more
  // than a family of 28) cut out of the plate's middle is a piece that came loose.
  const auto p = plate(GetParam());
  const mesh::NodeIndex a = p.disc.nearest_node({0.01025, -0.00025});
  const mesh::NodeIndex b = p.disc.nearest_node({0.01025, 0.00025});
  for (const bool incremental : {true, false}) {
    statics::StaticSolver s(p.disc, p.model, p.supports, p.loads);
    s.set_incremental(incremental);
    ASSERT_TRUE(s.solve().ok());
    const core::Status r = s.break_bonds(bonds_cutting_off(p.disc, {a, b}, false));
    ASSERT_TRUE(r.ok()) << core::message_of(r);
    EXPECT_EQ(s.pinned_dofs(), 0);
    expect_equilibrium(s);
    std::vector<mesh::NodeIndex> block;
    for (mesh::NodeIndex k = 0; k < p.disc.num_nodes(); ++k) {
      const mesh::Point q = p.disc.position[static_cast<std::size_t>(k)];
      if (q.x > 0.004 && q.x < 0.007 && q.y > -0.0015 && q.y < 0.0015) block.push_back(k);
    }
    ASSERT_EQ(block.size(), 36U);
    const core::Status loose = s.break_bonds(bonds_cutting_off(p.disc, block, false));
    ASSERT_FALSE(loose.ok());
    EXPECT_EQ(core::message_of(loose),
              "a piece of 36 nodes came loose (x from 4.25 to 6.75 mm, y from -1.25 to 1.25 mm)")
        << "incremental " << incremental;
  }
}

TEST_P(Mechanisms, LoadedPartThatComesLooseIsNamedOnBothPaths) {
  // Cutting the plate across at x = 15 mm: the right part carries the load and nothing holds
  // it. Final failure, saying so, on the update path as on the refactorizing one.
  const auto p = plate(GetParam());
  std::vector<mesh::BondIndex> across;
  for (mesh::BondIndex b = 0; b < p.disc.num_bonds(); ++b) {
    const double xi = p.disc.position[static_cast<std::size_t>(p.disc.bond_i[b])].x;
    const double xj = p.disc.position[static_cast<std::size_t>(p.disc.bond_j[b])].x;
    if ((xi - 0.015) * (xj - 0.015) < 0) across.push_back(b);
  }
  for (const bool incremental : {true, false}) {
    statics::StaticSolver s(p.disc, p.model, p.supports, p.loads);
    s.set_incremental(incremental);
    ASSERT_TRUE(s.solve().ok());
    const core::Status r = s.break_bonds(across);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(core::message_of(r),
              "a piece of 200 nodes with load on it came loose (x from 15.25 to 19.75 mm, y "
              "from -4.75 to 4.75 mm)")
        << "incremental " << incremental;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, Mechanisms,
                         ::testing::Values(model::ModelKind::state_based,
                                           model::ModelKind::bond_based),
                         testing::model_kind_param_name);

}  // namespace
}  // namespace peritwin
