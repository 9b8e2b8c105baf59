// Strain (displacement) control in the static solver (issue 35 item 1): prescribed displacements
// leave the unknowns like supports, the right-hand side becomes F − K_fp·ū, and the reaction is
// the internal force at the prescribed DOFs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "solver/statics/static_solver.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

const model::Material steel_like{200e9, 1.0 / 3.0, 0.0};

/// The tension plate with its right edge layer moved by ū in x instead of pulled by a traction.
statics::Specimen strain_controlled_plate(model::ModelKind kind, double length, double height,
                                          double dx) {
  model::ModelOptions o;
  o.kind = kind;
  statics::Specimen p = testing::make_tension_plate(steel_like, o, length, height, dx, 1.0);
  statics::PrescribedDisplacement grip;
  grip.nodes = p.loads.front().nodes;
  grip.component = 0;
  grip.constant = 1.0;  // 1 m per unit of P: P is the grip's displacement
  p.prescribed.push_back(grip);
  p.loads.clear();
  return p;
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

class StrainControl : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(StrainControl, TheGripsReactionsAsLoadsGiveTheSameDisplacements) {
  // Independent check of F − K_fp·ū: apply each grip node's reaction (the bond-by-bond internal
  // force there) as a load on a free node; the force-controlled solve must move the grip nodes
  // by ū exactly and every other node as the strain-controlled solve did.
  const double dx = 0.0005;
  const auto p = strain_controlled_plate(GetParam(), 0.02, 0.008, dx);
  statics::StaticSolver strain(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(strain.solve().ok());
  const double ubar = 1e-5;  // 0.05 % strain over 20 mm
  std::vector<double> u;
  strain.displacement(ubar, 0.0, u);
  for (mesh::NodeIndex k : p.prescribed.front().nodes) {
    EXPECT_EQ(u[2 * static_cast<std::size_t>(k)], ubar);
  }
  const std::vector<double> f = strain.internal_force(u);
  std::vector<statics::LoadTerm> loads;
  double sum = 0.0;
  for (mesh::NodeIndex k : p.prescribed.front().nodes) {
    const auto i = 2 * static_cast<std::size_t>(k);
    loads.push_back({{k}, {f[i] / ubar, f[i + 1] / ubar}, {}, {}});
    sum += f[i];
  }
  statics::StaticSolver force(p.disc, p.model, p.supports, loads);
  ASSERT_TRUE(force.solve().ok());
  std::vector<double> v;
  force.displacement(ubar, 0.0, v);
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    EXPECT_NEAR(v[dof], u[dof], 1e-9 * ubar) << "dof " << dof;
  }
  // reaction() is that sum, linear in P.
  EXPECT_NEAR(strain.reaction(0, ubar, 0.0), sum, 1e-12 * std::abs(sum));
  EXPECT_NEAR(strain.reaction(0, 2 * ubar, 0.3), 2 * sum, 1e-12 * std::abs(sum));
  EXPECT_GT(sum, 0.0);  // the grips pull the bar: positive in +x
}

TEST_P(StrainControl, AUniaxialBarsReactionIsEAEpsilon) {
  // A bar on rollers stretched by ū: uniaxial stress, reaction = E·ε·A (ν-free sides). The
  // peridynamic surface layer is softer (surface correction restores most of it): 2 % stated.
  const double length = 0.02, height = 0.008, dx = 0.0005;
  const auto p = strain_controlled_plate(GetParam(), length, height, dx);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(solver.solve().ok());
  // The grip layer's centre is at length − dx/2, the roller layer's at dx/2.
  const double strain = 1.0 / (length - dx);
  const double expected = steel_like.youngs_modulus * strain * height * p.geometry.thickness;
  EXPECT_NEAR(solver.reaction(0, 1.0, 0.0) / expected, 1.0, 0.02);
}

TEST_P(StrainControl, BreakingBondsByRankUpdatesEqualsRefactorizing) {
  const auto p = strain_controlled_plate(GetParam(), 0.01, 0.006, 0.0005);
  statics::StaticSolver inc(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  statics::StaticSolver ref(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  inc.set_incremental(true);
  ASSERT_TRUE(inc.solve().ok());
  ASSERT_TRUE(ref.solve().ok());
  // Cut the bonds that cross x = 7 mm near the middle of the height, touching the grips' reach.
  std::vector<mesh::BondIndex> cut;
  for (mesh::BondIndex b = 0; b < p.disc.num_bonds(); ++b) {
    const auto& xi = p.disc.position[static_cast<std::size_t>(p.disc.bond_i[b])];
    const auto& xj = p.disc.position[static_cast<std::size_t>(p.disc.bond_j[b])];
    if ((xi.x - 0.007) * (xj.x - 0.007) < 0 && std::abs(xi.y) < 0.0015) cut.push_back(b);
  }
  ASSERT_FALSE(cut.empty());
  const double before = ref.reaction(0, 1.0, 0.0);
  ASSERT_TRUE(inc.break_bonds(cut).ok());
  ASSERT_TRUE(ref.break_bonds(cut).ok());
  std::vector<double> a, b;
  inc.displacement(1.0, 0.0, a);
  ref.displacement(1.0, 0.0, b);
  for (std::size_t dof = 0; dof < a.size(); ++dof) EXPECT_NEAR(a[dof], b[dof], 1e-10 * max_abs(b));
  EXPECT_NEAR(inc.reaction(0, 1.0, 0.0), ref.reaction(0, 1.0, 0.0), 1e-10 * before);
  EXPECT_LT(ref.reaction(0, 1.0, 0.0), before);  // a cut bar is softer
}

INSTANTIATE_TEST_SUITE_P(BothModels, StrainControl,
                         ::testing::Values(model::ModelKind::bond_based,
                                           model::ModelKind::state_based),
                         testing::model_kind_param_name);

}  // namespace
}  // namespace peritwin
