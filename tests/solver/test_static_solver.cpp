#include <gtest/gtest.h>

#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cmath>
#include <random>

#include "plates.h"
#include "solver/static_solver.h"

namespace peritwin {
namespace {

const Material aluminium{68e9, 0.33, 48.7e6};

ModelOptions options_for(ModelKind kind) {
  ModelOptions o;
  o.kind = kind;
  return o;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

class SolverModels : public ::testing::TestWithParam<ModelKind> {};

TEST_P(SolverModels, InternalForcesBalanceAppliedLoads) {
  // Equilibrium: at every free DOF the bond-by-bond internal force equals the applied load, and
  // the reactions at the supports balance the total applied load (to solver precision).
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.02, 0.01, 0.0005, 80e6);
  StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  const auto& u = solver.basis_displacement(basis_constant);
  const auto f_int = solver.internal_force(u);
  const auto f_ext = solver.basis_force(basis_constant);
  const double scale = max_abs(f_ext);
  double reaction_x = 0, reaction_y = 0;
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) {
      EXPECT_NEAR(f_int[dof], f_ext[dof], 1e-9 * scale) << "dof " << dof;
    } else {
      (dof % 2 == 0 ? reaction_x : reaction_y) += f_int[dof] - f_ext[dof];
    }
  }
  double applied_x = 0;
  for (std::size_t dof = 0; dof < u.size(); dof += 2) applied_x += f_ext[dof];
  EXPECT_NEAR(reaction_x, -applied_x, 1e-9 * std::abs(applied_x));  // supports push back
  EXPECT_NEAR(reaction_y, 0.0, 1e-9 * std::abs(applied_x));
}

TEST_P(SolverModels, StiffnessIsSymmetricAndRigidMotionIsForceFree) {
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> uni(-1e-6, 1e-6);
  std::vector<double> u1(2 * static_cast<std::size_t>(plate.disc.num_nodes()));
  std::vector<double> u2(u1.size());
  for (auto& x : u1) x = uni(rng);
  for (auto& x : u2) x = uni(rng);
  // Maxwell-Betti reciprocity u1·K·u2 = u2·K·u1, with K applied bond by bond.
  const auto f1 = solver.internal_force(u1);
  const auto f2 = solver.internal_force(u2);
  double a = 0, b = 0, norm = 0;
  for (std::size_t i = 0; i < u1.size(); ++i) {
    a += u1[i] * f2[i];
    b += u2[i] * f1[i];
    norm += std::abs(u1[i] * f2[i]);
  }
  EXPECT_NEAR(a, b, 1e-12 * norm);
  // Rigid translation plus a small (linearized) rotation: zero force everywhere.
  std::vector<double> rigid(u1.size());
  const double tx = 1e-4, ty = -2e-4, theta = 3e-4;
  for (NodeIndex k = 0; k < plate.disc.num_nodes(); ++k) {
    const Point p = plate.disc.position[k];
    rigid[2 * static_cast<std::size_t>(k)] = tx - theta * p.y;
    rigid[2 * static_cast<std::size_t>(k) + 1] = ty + theta * p.x;
  }
  // f1 comes from displacements of 1e-6 m; the rigid motion is up to ~1e-4 m, so a relative
  // 1e-12 of the force scale of such displacements is round-off.
  EXPECT_LT(max_abs(solver.internal_force(rigid)), 1e-12 * max_abs(f1) * 1e2);
}

TEST_P(SolverModels, CholmodAgreesWithUmfpackOracle) {
  // The same reduced system solved by an LU factorization (UMFPACK) of the full symmetric matrix
  // (for the state-based model with ν < 1/3 the mixed form: displacements then w = α·θ).
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  SparseMatrix full = solver.stiffness_upper().selfadjointView<Eigen::Upper>();
  Eigen::UmfPackLU<SparseMatrix> lu(full);
  ASSERT_EQ(lu.info(), Eigen::Success);
  if (GetParam() == ModelKind::state_based) {
    EXPECT_TRUE(solver.mixed_form());
  }
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(solver.num_unknowns());
  const auto f = solver.basis_force(basis_constant);
  for (std::size_t dof = 0; dof < f.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) rhs[solver.free_index()[dof]] = f[dof];
  }
  const Eigen::VectorXd x = lu.solve(rhs);
  const auto& u = solver.basis_displacement(basis_constant);
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) {
      EXPECT_NEAR(u[dof], x[solver.free_index()[dof]], 1e-9 * x.cwiseAbs().maxCoeff());
    }
  }
}

TEST_P(SolverModels, UnsupportedModelIsATypedFailure) {
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  StaticSolver solver(plate.disc, plate.model, {}, plate.loads);
  const FactorReport r = solver.solve();
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message.find("loose"), std::string::npos);
}

TEST_P(SolverModels, BreakingBondsEqualsBuildingWithoutThem) {
  // Oracle for the re-solve path: break a band of bonds through break_bonds(), compare with a
  // fresh solver whose discretization had those bonds cut from the start.
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  std::vector<BondIndex> cut;
  auto disc2 = plate.disc;
  for (BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    const Point a = plate.disc.position[plate.disc.bond_i[b]];
    const Point c = plate.disc.position[plate.disc.bond_j[b]];
    if (segments_cross(a, c, {0.005, -0.001}, {0.005, 0.0015})) {
      cut.push_back(b);
      disc2.bond_precut[b] = 1;
    }
  }
  ASSERT_GT(cut.size(), 10u);
  StaticSolver updated(plate.disc, plate.model, plate.supports, plate.loads);
  updated.set_incremental(true);
  ASSERT_TRUE(updated.solve().ok());
  // Incremental path: break in three groups by rank updates of the factor.
  const std::size_t third = cut.size() / 3;
  ASSERT_TRUE(updated.break_bonds(std::span(cut).first(third)).ok());
  ASSERT_TRUE(updated.break_bonds(std::span(cut).subspan(third, third)).ok());
  ASSERT_TRUE(updated.break_bonds(std::span(cut).subspan(2 * third)).ok());
  EXPECT_EQ(updated.factorizations(), 1);
  EXPECT_EQ(updated.updates(), 3);
  ASSERT_TRUE(solver.break_bonds(cut).ok());
  StaticSolver fresh(disc2, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(fresh.solve().ok());
  const auto& u1 = solver.basis_displacement(basis_constant);
  const auto& u2 = fresh.basis_displacement(basis_constant);
  const auto& u3 = updated.basis_displacement(basis_constant);
  for (std::size_t i = 0; i < u1.size(); ++i) {
    EXPECT_NEAR(u1[i], u2[i], 1e-10 * max_abs(u2));
    EXPECT_NEAR(u3[i], u2[i], 1e-9 * max_abs(u2));
  }
  EXPECT_EQ(solver.factorizations(), 2);
}

INSTANTIATE_TEST_SUITE_P(BothModels, SolverModels,
                         ::testing::Values(ModelKind::bond_based, ModelKind::state_based));

}  // namespace
}  // namespace peritwin
