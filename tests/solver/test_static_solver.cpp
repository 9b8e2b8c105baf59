#include <gtest/gtest.h>

#include <Eigen/UmfPackSupport>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "solver/statics/static_solver.h"
#include "tests/support/plates.h"
#include "validation/specimens.h"

namespace peritwin {
namespace {

using namespace peritwin::validation;  // the benchmark specimens

const model::Material aluminium{68e9, 0.33, 48.7e6};

model::ModelOptions options_for(model::ModelKind kind) {
  model::ModelOptions o;
  o.kind = kind;
  return o;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

class SolverModels : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(SolverModels, InternalForcesBalanceAppliedLoads) {
  // Equilibrium: at every free DOF the bond-by-bond internal force equals the applied load, and
  // the reactions at the supports balance the total applied load (to solver precision).
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.02, 0.01, 0.0005, 80e6);
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  const auto& u = solver.basis_displacement(statics::basis_constant);
  const auto f_int = solver.internal_force(u);
  const auto f_ext = solver.basis_force(statics::basis_constant);
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
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
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
  for (mesh::NodeIndex k = 0; k < plate.disc.num_nodes(); ++k) {
    const mesh::Point p = plate.disc.position[k];
    rigid[2 * static_cast<std::size_t>(k)] = tx - theta * p.y;
    rigid[2 * static_cast<std::size_t>(k) + 1] = ty + theta * p.x;
  }
  // f1 comes from displacements of 1e-6 m; the rigid motion is up to ~1e-4 m, so a relative
  // 1e-12 of the force scale of such displacements is round-off.
  EXPECT_LT(max_abs(solver.internal_force(rigid)), 1e-12 * max_abs(f1) * 1e2);
}

TEST_P(SolverModels, CholmodAgreesWithUmfpackOracle) {
  // The same reduced system solved by an LU factorization (UMFPACK) of the full symmetric matrix
  // (for the state-based model with ν < 1/3 the mixed form: displacements then w' = α·θ/s).
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  linalg::SparseMatrix full = solver.stiffness_upper().selfadjointView<Eigen::Upper>();
  Eigen::UmfPackLU<linalg::SparseMatrix> lu(full);
  ASSERT_EQ(lu.info(), Eigen::Success);
  if (GetParam() == model::ModelKind::state_based) {
    EXPECT_TRUE(solver.mixed_form());
  }
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(solver.num_unknowns());
  const auto f = solver.basis_force(statics::basis_constant);
  for (std::size_t dof = 0; dof < f.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) rhs[solver.free_index()[dof]] = f[dof];
  }
  const Eigen::VectorXd x = lu.solve(rhs);
  const auto& u = solver.basis_displacement(statics::basis_constant);
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) {
      EXPECT_NEAR(u[dof], x[solver.free_index()[dof]], 1e-9 * x.cwiseAbs().maxCoeff());
    }
  }
}

TEST(MixedForm, StiffPinsAtCoarseSpacingAreNotReportedSingular) {
  // B1 state-based at the spacing for 3,000 nodes (Δx = 1.11 mm): the w diagonal (−A⁻¹) used to be
  // 1e-3 against 1.2e11 for the rigid pins' u diagonal, min/max pivot 9e-15 < 1e-14, and the sound
  // model was refused as "singular". With w scaled it solves, and the condensed internal force
  // (bond by bond, not from the mixed matrix) balances the load within 1e-9 of its scale.
  const CompactTensionSpec spec;
  const statics::Specimen s =
      make_compact_tension(spec, model::ModelOptions{}, compact_tension_spacing(spec, 3000));
  statics::StaticSolver solver(s.disc, s.model, s.supports, s.loads);
  const auto report = solver.solve();
  ASSERT_TRUE(report.ok()) << core::message_of(report);
  EXPECT_TRUE(solver.mixed_form());
  const auto f = solver.basis_force(statics::basis_constant);
  const auto r = solver.internal_force(solver.basis_displacement(statics::basis_constant));
  double worst = 0.0;
  for (std::size_t dof = 0; dof < f.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) worst = std::max(worst, std::abs(r[dof] - f[dof]));
  }
  EXPECT_LT(worst, 1e-9 * max_abs(f));
}

TEST_P(SolverModels, UnsupportedModelIsATypedFailure) {
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  statics::StaticSolver solver(plate.disc, plate.model, {}, plate.loads);
  const core::Status r = solver.solve();
  EXPECT_FALSE(r.ok());
  EXPECT_NE(core::message_of(r).find("loose"), std::string::npos);
}

TEST_P(SolverModels, BreakingBondsEqualsBuildingWithoutThem) {
  // Oracle for the re-solve path: break a band of bonds through break_bonds(), compare with a
  // fresh solver whose discretization had those bonds cut from the start.
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  std::vector<mesh::BondIndex> cut;
  auto disc2 = plate.disc;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    const mesh::Point a = plate.disc.position[plate.disc.bond_i[b]];
    const mesh::Point c = plate.disc.position[plate.disc.bond_j[b]];
    if (mesh::segments_cross(a, c, {0.005, -0.001}, {0.005, 0.0015})) {
      cut.push_back(b);
      disc2.bond_precut[b] = 1;
    }
  }
  ASSERT_GT(cut.size(), 10u);
  statics::StaticSolver updated(plate.disc, plate.model, plate.supports, plate.loads);
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
  statics::StaticSolver fresh(disc2, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(fresh.solve().ok());
  const auto& u1 = solver.basis_displacement(statics::basis_constant);
  const auto& u2 = fresh.basis_displacement(statics::basis_constant);
  const auto& u3 = updated.basis_displacement(statics::basis_constant);
  for (std::size_t i = 0; i < u1.size(); ++i) {
    EXPECT_NEAR(u1[i], u2[i], 1e-10 * max_abs(u2));
    EXPECT_NEAR(u3[i], u2[i], 1e-9 * max_abs(u2));
  }
  EXPECT_EQ(solver.factorizations(), 2);
}

TEST_P(SolverModels, TiesHoldTheirConstraintInEquilibriumAndUnderUpdates) {
  // A tie u_y(top right) − u_y(bottom right) = 0 stops the plate's Poisson contraction at its
  // loaded end. Checked: the constraint holds to 1e-3 of the free contraction; bond-by-bond
  // internal forces plus the tie's penalty force balance the applied load at every free DOF;
  // breaking a band of bonds by rank updates equals refactorizing (the ties stay in the factor);
  // bond-based: multiply() (the PCG path's matrix-free product) equals the assembled matrix.
  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  const mesh::NodeIndex top = plate.disc.nearest_node({0.01, 0.003});
  const mesh::NodeIndex bottom = plate.disc.nearest_node({0.01, -0.003});
  const double k = 200.0 * aluminium.youngs_modulus * plate.geometry.thickness;
  const std::vector<statics::Tie> ties = {{{{top, 1, 1.0}, {bottom, 1, -1.0}}, k}};
  statics::StaticSolver free_plate(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(free_plate.solve().ok());
  statics::StaticSolver tied(plate.disc, plate.model, plate.supports, plate.loads, ties);
  tied.set_incremental(true);
  ASSERT_TRUE(tied.solve().ok());
  auto gap = [&](const std::vector<double>& u) {
    return u[2 * static_cast<std::size_t>(top) + 1] - u[2 * static_cast<std::size_t>(bottom) + 1];
  };
  const double contraction = gap(free_plate.basis_displacement(statics::basis_constant));
  ASSERT_LT(contraction, 0.0);  // the free plate narrows
  const auto& u = tied.basis_displacement(statics::basis_constant);
  EXPECT_LT(std::abs(gap(u)), 1e-3 * std::abs(contraction));
  const auto f_int = tied.internal_force(u);
  const auto f_ext = tied.basis_force(statics::basis_constant);
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (tied.free_index()[dof] >= 0) {
      EXPECT_NEAR(f_int[dof], f_ext[dof], 1e-9 * max_abs(f_ext)) << "dof " << dof;
    }
  }
  // The tie's force k·gap is what it takes to stop the contraction: not negligible.
  const double tie_force = k * gap(u);
  EXPECT_GT(std::abs(tie_force), 1e-3 * max_abs(f_ext));

  std::vector<mesh::BondIndex> cut;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    if (mesh::segments_cross(plate.disc.position[plate.disc.bond_i[b]],
                             plate.disc.position[plate.disc.bond_j[b]], {0.005, -0.001},
                             {0.005, 0.0015})) {
      cut.push_back(b);
    }
  }
  ASSERT_GT(cut.size(), 10u);
  statics::StaticSolver refactored(plate.disc, plate.model, plate.supports, plate.loads, ties);
  ASSERT_TRUE(refactored.solve().ok());
  ASSERT_TRUE(refactored.break_bonds(cut).ok());
  ASSERT_TRUE(tied.break_bonds(cut).ok());
  EXPECT_EQ(tied.factorizations(), 1);
  const auto& u_updated = tied.basis_displacement(statics::basis_constant);
  const auto& u_refactored = refactored.basis_displacement(statics::basis_constant);
  for (std::size_t i = 0; i < u_updated.size(); ++i) {
    EXPECT_NEAR(u_updated[i], u_refactored[i], 1e-9 * max_abs(u_refactored));
  }
  if (GetParam() == model::ModelKind::bond_based) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const auto n = static_cast<std::size_t>(refactored.num_unknowns());
    std::vector<double> x(n), y(n);
    for (auto& v : x) v = uni(rng);
    refactored.multiply(refactored.bond_factors(), x.data(), y.data());
    const Eigen::Map<const Eigen::VectorXd> xv(x.data(), static_cast<Eigen::Index>(n));
    const Eigen::VectorXd assembled =
        refactored.stiffness_upper().selfadjointView<Eigen::Upper>() * xv;
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(y[i], assembled[static_cast<Eigen::Index>(i)],
                  1e-9 * assembled.cwiseAbs().maxCoeff());
    }
  }
}

/// Pattern and values of two upper triangles, bit for bit (signed zeros included).
void expect_same_bits(const linalg::SparseMatrix& a, const linalg::SparseMatrix& b) {
  ASSERT_EQ(a.rows(), b.rows());
  ASSERT_EQ(a.cols(), b.cols());
  ASSERT_EQ(a.nonZeros(), b.nonZeros());
  ASSERT_TRUE(a.isCompressed() && b.isCompressed());
  EXPECT_TRUE(std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.cols() + 1, b.outerIndexPtr()));
  EXPECT_TRUE(std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr()));
  EXPECT_EQ(std::memcmp(a.valuePtr(), b.valuePtr(),
                        sizeof(double) * static_cast<std::size_t>(a.nonZeros())),
            0);
}

TEST_P(SolverModels, ScatterAssemblyIsBitForBitTheProductsAssembly) {
  // The direct scatter into the known pattern (the cold start's assembly, issue 18 item 4) must
  // give the very matrix of the Eigen products and triplets it replaced, so that the factor and
  // every hash stay the same: on the B1 specimen (precut bonds, rigid pins, supported DOFs), then
  // after breaking a node's whole family by refactorization (a ground spring) and a notch band;
  // and on a plate with a tie.
  const CompactTensionSpec spec;
  const statics::Specimen s =
      make_compact_tension(spec, options_for(GetParam()), compact_tension_spacing(spec, 900));
  statics::StaticSolver solver(s.disc, s.model, s.supports, s.loads);
  ASSERT_TRUE(solver.solve().ok());
  expect_same_bits(solver.stiffness_upper(), solver.stiffness_upper_by_products());
  const mesh::NodeIndex lone = s.disc.nearest_node({0.5 * spec.width, 0.3 * spec.width});
  std::vector<mesh::BondIndex> cut;
  for (auto f = s.disc.family_offset[static_cast<std::size_t>(lone)];
       f < s.disc.family_offset[static_cast<std::size_t>(lone) + 1]; ++f) {
    cut.push_back(s.disc.family_bonds[static_cast<std::size_t>(f)]);
  }
  for (mesh::BondIndex b = 0; b < s.disc.num_bonds(); b += 7) {
    if (mesh::segments_cross(s.disc.position[s.disc.bond_i[b]], s.disc.position[s.disc.bond_j[b]],
                             {0.5 * spec.width, -0.002}, {0.6 * spec.width, 0.002})) {
      cut.push_back(b);
    }
  }
  ASSERT_TRUE(solver.break_bonds(cut).ok());
  EXPECT_EQ(solver.factorizations(), 2);
  expect_same_bits(solver.stiffness_upper(), solver.stiffness_upper_by_products());

  auto plate =
      testing::make_tension_plate(aluminium, options_for(GetParam()), 0.01, 0.006, 0.0005, 1e6);
  const mesh::NodeIndex top = plate.disc.nearest_node({0.01, 0.003});
  const mesh::NodeIndex bottom = plate.disc.nearest_node({0.01, -0.003});
  const mesh::NodeIndex middle = plate.disc.nearest_node({0.005, 0.0});
  const double k = 200.0 * aluminium.youngs_modulus * plate.geometry.thickness;
  const std::vector<statics::Tie> ties = {
      {{{top, 1, 1.0}, {bottom, 1, -1.0}, {middle, 0, 0.5}}, k}};
  statics::StaticSolver tied(plate.disc, plate.model, plate.supports, plate.loads, ties);
  ASSERT_TRUE(tied.solve().ok());
  expect_same_bits(tied.stiffness_upper(), tied.stiffness_upper_by_products());
}

TEST(Ties, MalformedTiesAreRejected) {
  auto plate = testing::make_tension_plate(aluminium, options_for(model::ModelKind::bond_based),
                                           0.01, 0.006, 0.0005, 1e6);
  const mesh::NodeIndex outside = plate.disc.num_nodes();
  for (const statics::Tie& bad :
       {statics::Tie{{}, 1.0}, statics::Tie{{{0, 1, 1.0}}, 0.0},
        statics::Tie{{{outside, 0, 1.0}}, 1.0}, statics::Tie{{{0, 2, 1.0}}, 1.0},
        statics::Tie{{{0, 0, std::nan("")}}, 1.0}}) {
    EXPECT_THROW(statics::StaticSolver(plate.disc, plate.model, plate.supports, plate.loads, {bad}),
                 std::invalid_argument);
  }
}

/// Rank-one update columns shaped like bonds: every `stride`-th bond's free DOFs at both ends,
/// with random values of order 0.3·√K_ff (seeded), so that an update stays in the pattern.
std::vector<linalg::SparseCholesky::Column> random_bond_columns(const testing::TensionPlate& plate,
                                                                const statics::StaticSolver& solver,
                                                                mesh::BondIndex stride,
                                                                unsigned seed) {
  const linalg::SparseMatrix& upper = solver.stiffness_upper();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<linalg::SparseCholesky::Column> columns;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); b += stride) {
    linalg::SparseCholesky::Column col;
    for (const mesh::NodeIndex k : {plate.disc.bond_i[b], plate.disc.bond_j[b]}) {
      for (std::size_t c = 0; c < 2; ++c) {
        const int f = solver.free_index()[2 * static_cast<std::size_t>(k) + c];
        if (f < 0) continue;
        col.rows.push_back(f);
        col.values.push_back(0.3 * std::sqrt(upper.coeff(f, f)) * uni(rng));
      }
    }
    if (!col.rows.empty()) columns.push_back(std::move(col));
  }
  return columns;
}

TEST(SparseCholeskyOwnSolve, MatchesCholmodAfterUpdatesOnOneOrTwoThreads) {
  // The simplicial LDLᵀ solve after modify() is peritwin's own (two elimination subtrees on two
  // threads): equal to CHOLMOD's solve to round-off, and bit-identical on one or two threads.
  auto plate = testing::make_tension_plate(aluminium, options_for(model::ModelKind::state_based),
                                           0.02, 0.01, 0.0005, 1e6);
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  const linalg::SparseMatrix& upper = solver.stiffness_upper();
  linalg::SparseCholesky cholesky;
  ASSERT_TRUE(cholesky.factorize(upper).ok());
  // Columns within the matrix's pattern (no fill): scaled copies of some of its columns.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  std::vector<linalg::SparseCholesky::Column> columns;
  for (int c = 0; c < upper.cols(); c += 97) {
    linalg::SparseCholesky::Column col;
    const double d = std::sqrt(std::abs(upper.coeff(c, c)));
    for (linalg::SparseMatrix::InnerIterator it(upper, c); it; ++it) {
      col.rows.push_back(static_cast<int>(it.row()));
      col.values.push_back(0.3 * d * uni(rng));
    }
    columns.push_back(std::move(col));
  }
  ASSERT_GT(columns.size(), 9u);
  ASSERT_TRUE(cholesky.modify(columns, true).ok());
  columns.resize(columns.size() / 2);
  ASSERT_TRUE(cholesky.modify(columns, false).ok());
  for (int nrhs = 1; nrhs <= 3; ++nrhs) {
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(upper.rows(), nrhs);
    Eigen::MatrixXd reference = b, one = b, two = b;
    cholesky.solve_with_cholmod(reference);
    cholesky.set_solve_threads(1);
    cholesky.solve(one);
    cholesky.set_solve_threads(2);
    cholesky.solve(two);
    EXPECT_TRUE(one == two) << nrhs;
    EXPECT_LT((one - reference).cwiseAbs().maxCoeff(), 1e-10 * reference.cwiseAbs().maxCoeff());
  }
}

/// A state-based tension plate solved once, with random bond columns to update by (pairs in the
/// pattern: no fill): `added`, `removed` its first half, `first` its first three.
struct BondColumnsCase {
  explicit BondColumnsCase(unsigned seed)
      : plate(testing::make_tension_plate(aluminium, options_for(model::ModelKind::state_based),
                                          0.02, 0.01, 0.0005, 1e6)),
        solver(plate.disc, plate.model, plate.supports, plate.loads) {
    solved = solver.solve().ok();  // solver holds references into plate: never copied
    added = random_bond_columns(plate, solver, 37, seed);
    removed.assign(added.begin(), added.begin() + static_cast<std::ptrdiff_t>(added.size() / 2));
    first.assign(added.begin(), added.begin() + 3);
  }
  BondColumnsCase(const BondColumnsCase&) = delete;
  BondColumnsCase& operator=(const BondColumnsCase&) = delete;
  testing::TensionPlate plate;
  statics::StaticSolver solver;
  bool solved = false;
  std::vector<linalg::SparseCholesky::Column> added, removed, first;
};

TEST(SparseCholeskyFusedUpdate, MatchesCholmodUpdownOnOneOrTwoThreads) {
  // modify_fused(added, removed): peritwin's one-sweep multiple-rank update equals CHOLMOD's update
  // then downdate to round-off, and is bit-identical on one or two threads.
  const BondColumnsCase bonds(5);
  ASSERT_TRUE(bonds.solved);
  const linalg::SparseMatrix& upper = bonds.solver.stiffness_upper();
  const auto& added = bonds.added;
  const auto& removed = bonds.removed;
  const auto& first = bonds.first;
  ASSERT_GT(added.size(), 40u);  // more than one sweep of 16 ranks
  linalg::SparseCholesky reference, one, two;
  for (linalg::SparseCholesky* c : {&reference, &one, &two}) ASSERT_TRUE(c->factorize(upper).ok());
  // A first small update, then a solve: its forward half is kept up to date by the next update.
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(upper.rows(), 2);
  one.set_solve_threads(1);
  two.set_solve_threads(2);
  for (linalg::SparseCholesky* c : {&one, &two}) {
    ASSERT_TRUE(c->modify_fused(first, {}).ok());
    Eigen::MatrixXd x = b;
    c->solve(x);
  }
  ASSERT_TRUE(reference.modify(first, true).ok());
  ASSERT_TRUE(reference.modify(added, true).ok());
  ASSERT_TRUE(reference.modify(removed, false).ok());
  ASSERT_TRUE(one.modify_fused(added, removed).ok());
  ASSERT_TRUE(two.modify_fused(added, removed).ok());
  Eigen::MatrixXd x_ref = b, x_one = b, x_two = b;
  reference.solve_with_cholmod(x_ref);
  one.solve(x_one);
  two.solve(x_two);
  EXPECT_TRUE(x_one == x_two);
  EXPECT_LT((x_one - x_ref).cwiseAbs().maxCoeff(), 1e-10 * x_ref.cwiseAbs().maxCoeff());
  // Removing what is left returns to the original matrix.
  std::vector<linalg::SparseCholesky::Column> rest(added.begin() + added.size() / 2, added.end());
  rest.insert(rest.end(), first.begin(), first.end());  // `first` was added twice
  ASSERT_TRUE(two.modify_fused({}, rest).ok());
  linalg::SparseCholesky fresh;
  ASSERT_TRUE(fresh.factorize(upper).ok());
  Eigen::MatrixXd x_fresh = b, x_back = b;
  fresh.solve_with_cholmod(x_fresh);
  two.solve(x_back);
  EXPECT_LT((x_back - x_fresh).cwiseAbs().maxCoeff(), 1e-10 * x_fresh.cwiseAbs().maxCoeff());
}

TEST(SparseCholeskyFusedUpdate, FourEntriesSideBySideGiveTheOneAtATimeBits) {
  // The interleaved sweep (four entries of a column through the ranks side by side, issue 37)
  // does every entry's operations in the same order as the one-entry-at-a-time oracle: the same
  // factor and the same tracked forward solve, bit for bit, on one thread and on two.
  const BondColumnsCase bonds(11);
  ASSERT_TRUE(bonds.solved);
  const linalg::SparseMatrix& upper = bonds.solver.stiffness_upper();
  const auto& added = bonds.added;
  const auto& removed = bonds.removed;
  const auto& first = bonds.first;
  ASSERT_GT(added.size(), 40u);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(upper.rows(), 2);
  std::vector<Eigen::MatrixXd> solutions;
  std::vector<double> flops;
  for (const bool interleaved : {false, true}) {
    for (const int threads : {1, 2}) {
      linalg::SparseCholesky::set_interleaved_update(interleaved);
      linalg::SparseCholesky c;
      ASSERT_TRUE(c.factorize(upper).ok());
      c.set_solve_threads(threads);
      ASSERT_TRUE(c.modify_fused(first, {}).ok());
      Eigen::MatrixXd x = b;
      c.solve(x);  // tracked: the next update keeps its forward half
      const double predicted = c.update_flops(added, removed);
      ASSERT_TRUE(c.modify_fused(added, removed).ok());
      x = b;
      c.solve(x);
      solutions.push_back(x);
      // update_flops is what the updates did: the total is the sum of the two predictions.
      EXPECT_EQ(c.update_flops_total(), c.update_flops(first, {}) + predicted);
      flops.push_back(predicted);
    }
  }
  linalg::SparseCholesky::set_interleaved_update(true);
  for (std::size_t k = 1; k < solutions.size(); ++k) {
    EXPECT_TRUE(solutions[k] == solutions[0]) << k;
    EXPECT_EQ(flops[k], flops[0]);
  }
  // The count is additive over columns, and positive for a column below the root.
  linalg::SparseCholesky c;
  ASSERT_TRUE(c.factorize(upper).ok());
  const std::vector<linalg::SparseCholesky::Column> half(added.begin(),
                                                         added.begin() + added.size() / 2);
  const std::vector<linalg::SparseCholesky::Column> rest(added.begin() + added.size() / 2,
                                                         added.end());
  EXPECT_EQ(c.update_flops(added, {}), c.update_flops(half, {}) + c.update_flops(rest, {}));
  EXPECT_EQ(c.update_flops({}, {}), 0.0);
  EXPECT_GT(c.update_flops(first, {}), 0.0);
  EXPECT_GT(c.factorization_flops(), 0.0);
}

TEST(IncrementalResolve, AGroupDearerThanRefactorizingIsRefactorized) {
  // A group of breaks whose rank updates would cost more flops than kRefactorOverUpdate of a
  // factorization (the phase III cascade) is refactorized with the kept analysis: the same bits
  // as the refactorizing path, which analyzes afresh (dof_ordering depends only on the bonds not
  // precut: the same ordering). A small group is still a rank update.
  auto plate = testing::make_tension_plate(aluminium, options_for(model::ModelKind::state_based),
                                           0.02, 0.01, 0.0005, 1e6);
  std::vector<mesh::BondIndex> small, band;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    const mesh::Point a = plate.disc.position[plate.disc.bond_i[b]];
    const mesh::Point c = plate.disc.position[plate.disc.bond_j[b]];
    if (mesh::segments_cross(a, c, {0.004, -0.001}, {0.004, 0.0004}) && small.size() < 3) {
      small.push_back(b);
    }
    if (mesh::segments_cross(a, c, {0.012, -0.001}, {0.012, 0.008})) band.push_back(b);
  }
  ASSERT_EQ(small.size(), 3u);
  ASSERT_GT(band.size(), statics::StaticSolver::kRefactorMinimumRanks);
  statics::StaticSolver updated(plate.disc, plate.model, plate.supports, plate.loads);
  updated.set_incremental(true);
  updated.set_refactor_minimum_flops(0.0);  // a small plate: the rule as on a large model
  ASSERT_TRUE(updated.solve().ok());
  statics::StaticSolver refactored(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(refactored.solve().ok());
  ASSERT_TRUE(updated.break_bonds(small).ok());
  EXPECT_EQ(updated.updates(), 1);
  EXPECT_EQ(updated.refactorized_groups(), 0);
  ASSERT_TRUE(updated.break_bonds(band).ok());
  EXPECT_EQ(updated.updates(), 1);
  EXPECT_EQ(updated.refactorized_groups(), 1);
  EXPECT_EQ(updated.factorizations(), 2);
  ASSERT_TRUE(refactored.break_bonds(small).ok());
  ASSERT_TRUE(refactored.break_bonds(band).ok());
  const auto& u_updated = updated.basis_displacement(statics::basis_constant);
  const auto& u_refactored = refactored.basis_displacement(statics::basis_constant);
  EXPECT_TRUE(u_updated == u_refactored);
  // Updates go on from the new factor: one more small group equals the refactorizing path.
  std::vector<mesh::BondIndex> after;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    const mesh::Point a = plate.disc.position[plate.disc.bond_i[b]];
    const mesh::Point c = plate.disc.position[plate.disc.bond_j[b]];
    if (mesh::segments_cross(a, c, {0.016, -0.001}, {0.016, 0.0004}) && after.size() < 3) {
      after.push_back(b);
    }
  }
  ASSERT_TRUE(updated.break_bonds(after).ok());
  ASSERT_TRUE(refactored.break_bonds(after).ok());
  EXPECT_EQ(updated.updates(), 2);
  const auto& u1 = updated.basis_displacement(statics::basis_constant);
  const auto& u2 = refactored.basis_displacement(statics::basis_constant);
  for (std::size_t i = 0; i < u1.size(); ++i) EXPECT_NEAR(u1[i], u2[i], 1e-9 * max_abs(u2));
}

TEST(SparseCholeskyPackedLdlt, HoldsCholmodsSimplicialValuesInTheSupernodalStorage) {
  // modify_fused() turns the supernodal LLᵀ factor into LDLᵀ in place, in the supernodes' own
  // storage (cholesky_impl.h, PackedLdlt), instead of CHOLMOD's simplicial copy. The values must
  // be CHOLMOD's conversion bit for bit: a factor converted by CHOLMOD (cholmod_change_factor,
  // through modify() with a zero column on the last row, which changes no value) and one by
  // modify_fused(), then the same fused update on both, must solve to identical bits.
  auto plate = testing::make_tension_plate(aluminium, options_for(model::ModelKind::state_based),
                                           0.02, 0.01, 0.0005, 1e6);
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  const linalg::SparseMatrix& upper = solver.stiffness_upper();
  const int n = static_cast<int>(upper.rows());
  // Bond vectors: in the pattern, no fill.
  const std::vector<linalg::SparseCholesky::Column> bonds =
      random_bond_columns(plate, solver, 53, 7);
  ASSERT_GT(bonds.size(), 20u);
  linalg::SparseCholesky by_cholmod, packed;
  ASSERT_TRUE(by_cholmod.factorize(upper).ok());
  ASSERT_TRUE(packed.factorize(upper).ok());
  const double supernodal_entries = packed.factor_nonzeros();
  const linalg::SparseCholesky::Column zero{{n - 1}, {0.0}};
  ASSERT_TRUE(by_cholmod.modify({zero}, true).ok());
  const double simplicial_entries = by_cholmod.factor_nonzeros();
  ASSERT_TRUE(by_cholmod.modify_fused(bonds, {}).ok());
  ASSERT_TRUE(packed.modify_fused(bonds, {}).ok());
  // The packed factor keeps exactly the simplicial factor's entries (the supernodes' upper
  // triangles given back), fewer than the supernodal storage.
  EXPECT_EQ(packed.factor_nonzeros(), simplicial_entries);
  EXPECT_LT(packed.factor_nonzeros(), supernodal_entries);
  for (int nrhs = 1; nrhs <= 3; ++nrhs) {
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, nrhs);
    Eigen::MatrixXd x_cholmod = b, x_packed = b;
    by_cholmod.solve(x_cholmod);
    packed.solve(x_packed);
    EXPECT_TRUE(x_cholmod == x_packed) << nrhs;
  }
  {  // more than three columns: three at a time with the packed factor (CHOLMOD's solve before)
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 4);
    Eigen::MatrixXd x_cholmod = b, x_packed = b;
    by_cholmod.solve(x_cholmod);
    packed.solve(x_packed);
    EXPECT_LT((x_packed - x_cholmod).cwiseAbs().maxCoeff(),
              1e-10 * x_cholmod.cwiseAbs().maxCoeff());
  }
  // factorize() after an update refactorizes with the kept supernodal analysis: the factor of
  // a fresh analysis and factorization, bit for bit.
  {
    linalg::SparseCholesky again, fresh;
    ASSERT_TRUE(again.factorize(upper).ok());
    ASSERT_TRUE(again.modify_fused(bonds, {}).ok());
    ASSERT_TRUE(again.factorize(upper).ok());
    EXPECT_EQ(again.factor_nonzeros(), supernodal_entries);
    ASSERT_TRUE(fresh.factorize(upper).ok());
    const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 2);
    Eigen::MatrixXd x_again = b, x_fresh = b;
    again.solve(x_again);
    fresh.solve(x_fresh);
    EXPECT_TRUE(x_again == x_fresh);
  }
  // CHOLMOD's own solve cannot read the packed factor: refused, not wrong.
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(n, 1);
  EXPECT_THROW(packed.solve_with_cholmod(x), std::logic_error);
  // An update that needs fill (a column coupling the first and last rows, not in the pattern)
  // falls back to CHOLMOD's updown: the packed factor becomes CHOLMOD's simplicial one with the
  // same values, so both factors take the same path to the same bits; the result is the
  // matrix with the column added, checked against a fresh factorization of it.
  const linalg::SparseCholesky::Column fill{
      {0, n - 1}, {0.5 * std::sqrt(upper.coeff(0, 0)), 0.5 * std::sqrt(upper.coeff(n - 1, n - 1))}};
  ASSERT_TRUE(by_cholmod.modify_fused({fill}, {}).ok());
  ASSERT_TRUE(packed.modify_fused({fill}, {}).ok());
  ASSERT_TRUE(packed.modify_fused({}, bonds).ok());
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 2);
  Eigen::MatrixXd x_packed = b, x_fresh = b;
  packed.solve_with_cholmod(x_packed);  // CHOLMOD's factor again: its solve works
  Eigen::MatrixXd x_cholmod = b;
  ASSERT_TRUE(by_cholmod.modify_fused({}, bonds).ok());
  by_cholmod.solve_with_cholmod(x_cholmod);
  EXPECT_TRUE(x_cholmod == x_packed);
  linalg::SparseMatrix with_fill = upper;
  with_fill.coeffRef(0, 0) += fill.values[0] * fill.values[0];
  with_fill.coeffRef(n - 1, n - 1) += fill.values[1] * fill.values[1];
  with_fill.coeffRef(0, n - 1) += fill.values[0] * fill.values[1];
  with_fill.makeCompressed();
  linalg::SparseCholesky fresh;
  ASSERT_TRUE(fresh.factorize(with_fill).ok());
  fresh.solve_with_cholmod(x_fresh);
  EXPECT_LT((x_packed - x_fresh).cwiseAbs().maxCoeff(), 1e-10 * x_fresh.cwiseAbs().maxCoeff());
}

// Bond stiffness factors (bilinear softening, 003): bond-based model only.
class BondFactors : public ::testing::Test {
 protected:
  testing::TensionPlate plate = testing::make_tension_plate(
      aluminium, options_for(model::ModelKind::bond_based), 0.01, 0.006, 0.0005, 1e6);
  /// Bonds crossing a vertical line at x (a band across the plate's middle).
  std::vector<mesh::BondIndex> band(double x) const {
    std::vector<mesh::BondIndex> out;
    for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
      const mesh::Point a = plate.disc.position[plate.disc.bond_i[b]];
      const mesh::Point c = plate.disc.position[plate.disc.bond_j[b]];
      if (mesh::segments_cross(a, c, {x, -0.001}, {x, 0.0015})) out.push_back(b);
    }
    return out;
  }
  static void expect_same(const std::vector<double>& u, const std::vector<double>& oracle,
                          double rel) {
    ASSERT_EQ(u.size(), oracle.size());
    const double scale = max_abs(oracle);
    for (std::size_t i = 0; i < u.size(); ++i) EXPECT_NEAR(u[i], oracle[i], rel * scale) << i;
  }
};

TEST_F(BondFactors, IncrementalSofteningEqualsRefactorization) {
  // Random factors on two overlapping sets of bonds, in two steps (the second one softens some
  // bonds further, stiffens none, and breaks a few via factor 0): rank updates vs refactoring.
  statics::StaticSolver incremental(plate.disc, plate.model, plate.supports, plate.loads);
  incremental.set_incremental(true);
  statics::StaticSolver refactor(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(incremental.solve().ok());
  ASSERT_TRUE(refactor.solve().ok());
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> uni(0.05, 1.0);
  std::vector<mesh::BondIndex> first = band(0.004);
  std::vector<double> f1(first.size());
  for (auto& f : f1) f = uni(rng);
  ASSERT_GT(first.size(), 10u);
  ASSERT_TRUE(incremental.set_bond_factors(first, f1).ok());
  ASSERT_TRUE(refactor.set_bond_factors(first, f1).ok());
  expect_same(incremental.basis_displacement(statics::basis_constant),
              refactor.basis_displacement(statics::basis_constant), 1e-9);
  std::vector<mesh::BondIndex> second = band(0.006);
  second.insert(second.end(), first.begin(), first.begin() + 5);
  std::vector<double> f2(second.size());
  for (std::size_t n = 0; n < second.size(); ++n) {
    const double old = incremental.bond_factor(second[n]);
    f2[n] = n % 7 == 0 ? 0.0 : old * uni(rng);
  }
  ASSERT_TRUE(incremental.set_bond_factors(second, f2).ok());
  ASSERT_TRUE(refactor.set_bond_factors(second, f2).ok());
  EXPECT_EQ(incremental.factorizations(), 1);
  EXPECT_EQ(incremental.updates(), 2);
  EXPECT_EQ(refactor.factorizations(), 3);
  EXPECT_EQ(incremental.intact(), refactor.intact());
  EXPECT_EQ(incremental.bond_factors(), refactor.bond_factors());
  EXPECT_EQ(incremental.bond_factor(second[0]), 0.0);
  EXPECT_FALSE(incremental.intact()[static_cast<std::size_t>(second[0])]);
  for (int basis = 0; basis < 3; ++basis) {
    expect_same(incremental.basis_displacement(static_cast<statics::Basis>(basis)),
                refactor.basis_displacement(static_cast<statics::Basis>(basis)), 1e-9);
  }
  // Breaking a softened bond removes only its remaining stiffness.
  const std::vector<mesh::BondIndex> broken(second.begin() + 1, second.begin() + 4);
  ASSERT_TRUE(incremental.break_bonds(broken).ok());
  ASSERT_TRUE(refactor.break_bonds(broken).ok());
  expect_same(incremental.basis_displacement(statics::basis_constant),
              refactor.basis_displacement(statics::basis_constant), 1e-9);
  for (mesh::BondIndex b : broken) EXPECT_EQ(incremental.bond_factor(b), 0.0);
}

TEST_F(BondFactors, SofteningToZeroEqualsBreaking) {
  const std::vector<mesh::BondIndex> cut = band(0.005);
  const std::vector<double> zeros(cut.size(), 0.0);
  for (bool incremental : {true, false}) {
    statics::StaticSolver softened(plate.disc, plate.model, plate.supports, plate.loads);
    statics::StaticSolver broken(plate.disc, plate.model, plate.supports, plate.loads);
    softened.set_incremental(incremental);
    broken.set_incremental(incremental);
    ASSERT_TRUE(softened.solve().ok());
    ASSERT_TRUE(broken.solve().ok());
    ASSERT_TRUE(softened.set_bond_factors(cut, zeros).ok());
    ASSERT_TRUE(broken.break_bonds(cut).ok());
    EXPECT_EQ(softened.intact(), broken.intact());
    EXPECT_EQ(softened.bond_factors(), broken.bond_factors());
    expect_same(softened.basis_displacement(statics::basis_constant),
                broken.basis_displacement(statics::basis_constant), 1e-12);
  }
}

TEST_F(BondFactors, SoftenedModelIsInEquilibrium) {
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  solver.set_incremental(true);
  ASSERT_TRUE(solver.solve().ok());
  const std::vector<mesh::BondIndex> bonds = band(0.005);
  std::vector<double> factors(bonds.size());
  for (std::size_t n = 0; n < bonds.size(); ++n)
    factors[n] = 0.1 + 0.2 * static_cast<double>(n % 5);
  ASSERT_TRUE(solver.set_bond_factors(bonds, factors).ok());
  const auto& u = solver.basis_displacement(statics::basis_constant);
  const auto f_int = solver.internal_force(u);
  const auto f_ext = solver.basis_force(statics::basis_constant);
  const double scale = max_abs(f_ext);
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    if (solver.free_index()[dof] >= 0) {
      EXPECT_NEAR(f_int[dof], f_ext[dof], 1e-9 * scale) << dof;
    }
  }
}

TEST_F(BondFactors, UniformFactorScalesDisplacementByItsInverse) {
  // Every bond at factor f: K becomes f·K, so u = u_intact / f (uniform tension).
  statics::StaticSolver intact(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(intact.solve().ok());
  std::vector<mesh::BondIndex> all;
  for (mesh::BondIndex b = 0; b < plate.disc.num_bonds(); ++b) {
    if (intact.intact()[static_cast<std::size_t>(b)]) all.push_back(b);
  }
  const double f = 0.37;
  const std::vector<double> factors(all.size(), f);
  for (bool incremental : {false, true}) {
    statics::StaticSolver soft(plate.disc, plate.model, plate.supports, plate.loads);
    soft.set_incremental(incremental);
    ASSERT_TRUE(soft.solve().ok());
    ASSERT_TRUE(soft.set_bond_factors(all, factors).ok());
    std::vector<double> expected = intact.basis_displacement(statics::basis_constant);
    for (auto& x : expected) x /= f;
    expect_same(soft.basis_displacement(statics::basis_constant), expected, 1e-9);
  }
}

TEST(BondFactorsErrors, StateBasedAndInvalidFactorsAreRejected) {
  auto osb = testing::make_tension_plate(aluminium, options_for(model::ModelKind::state_based),
                                         0.004, 0.003, 0.0005, 1e6);
  statics::StaticSolver s(osb.disc, osb.model, osb.supports, osb.loads);
  ASSERT_TRUE(s.solve().ok());
  const std::vector<mesh::BondIndex> one{0};
  const std::vector<double> half{0.5};
  EXPECT_THROW((void)s.set_bond_factors(one, half), std::logic_error);
  auto bb = testing::make_tension_plate(aluminium, options_for(model::ModelKind::bond_based), 0.004,
                                        0.003, 0.0005, 1e6);
  statics::StaticSolver b(bb.disc, bb.model, bb.supports, bb.loads);
  ASSERT_TRUE(b.solve().ok());
  EXPECT_EQ(b.bond_factor(0), 1.0);
  const std::vector<double> bad{1.5};
  EXPECT_THROW((void)b.set_bond_factors(one, bad), std::invalid_argument);
  const std::vector<double> two{0.5, 0.5};
  EXPECT_THROW((void)b.set_bond_factors(one, two), std::invalid_argument);
  ASSERT_TRUE(b.break_bonds(one).ok());
  EXPECT_THROW((void)b.set_bond_factors(one, half), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(BothModels, SolverModels,
                         ::testing::Values(model::ModelKind::bond_based,
                                           model::ModelKind::state_based),
                         testing::model_kind_param_name);

}  // namespace
}  // namespace peritwin
