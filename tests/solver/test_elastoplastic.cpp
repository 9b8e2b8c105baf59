// Elastoplastic bonds in the static solver (issue 35 item 2): Newton turning points of a bar of
// points on 004's curve with Masing hardening, against the elastic solve, the curve, and itself.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "solver/statics/elastoplastic.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

constexpr double kE = 193e9;  // 004: 316L

/// A bond-based bar [0, L]×[−H/2, H/2] on rollers at the left, its right layer moved in x by P
/// (metres): uniaxial stress.
statics::Specimen bar(double length, double height, double dx) {
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  statics::Specimen p =
      testing::make_tension_plate(model::Material{kE, 1.0 / 3.0, 0.0}, o, length, height, dx, 1.0);
  statics::PrescribedDisplacement grip;
  grip.nodes = p.loads.front().nodes;
  grip.component = 0;
  grip.constant = 1.0;
  p.prescribed.push_back(grip);
  p.loads.clear();
  return p;
}

constexpr double kLength = 0.01, kHeight = 0.004, kDx = 0.0005;
double grip_for(double strain) { return strain * (kLength - kDx); }
double bar_area(const statics::Specimen& p) { return kHeight * p.geometry.thickness; }

TEST(Elastoplastic, BelowYieldNewtonIsTheLinearSolve) {
  const auto p = bar(kLength, kHeight, kDx);
  statics::StaticSolver linear(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(linear.solve().ok());
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(solver.solve().ok());
  statics::ElastoplasticSolver plastic(solver, statics::BondPlasticity{});
  const double grip = grip_for(4e-4);  // below ε_y = 8.35e-4 in every bond
  const auto tp = plastic.solve_turning_point(grip, 0.0);
  ASSERT_TRUE(tp.ok()) << tp.error().reason;
  EXPECT_LE(tp->iterations, 2);
  std::vector<double> u;
  linear.displacement(grip, 0.0, u);
  double scale = 0.0;
  for (double v : u) scale = std::max(scale, std::abs(v));
  for (std::size_t dof = 0; dof < u.size(); ++dof) {
    EXPECT_NEAR(plastic.displacement()[dof], u[dof], 1e-12 * scale);
  }
  EXPECT_NEAR(plastic.reaction(0), linear.reaction(0, grip, 0.0),
              1e-10 * linear.reaction(0, grip, 0.0));
}

TEST(Elastoplastic, TheCommittedStateIsInEquilibrium) {
  // Independent check: the bond forces from the committed Masing stresses, summed bond by bond
  // here, balance at every free DOF to the Newton tolerance.
  const auto p = bar(kLength, kHeight, kDx);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(solver.solve().ok());
  statics::BondPlasticity law;
  statics::ElastoplasticSolver plastic(solver, law);
  for (double strain : {0.006, -0.006, 0.0018}) {
    const auto tp = plastic.solve_turning_point(grip_for(strain), 0.0);
    ASSERT_TRUE(tp.ok()) << tp.error().reason;
    std::vector<double> f(plastic.displacement().size(), 0.0);
    for (std::size_t b = 0; b < plastic.bond_states().size(); ++b) {
      if (!solver.intact()[b]) continue;
      const double m = p.model.bond_stiffness[b] * p.disc.bond_length[b] * law.stretch_per_strain *
                       plastic.bond_stress(b) / kE;
      const auto i = 2 * static_cast<std::size_t>(p.disc.bond_i[b]);
      const auto j = 2 * static_cast<std::size_t>(p.disc.bond_j[b]);
      f[i] -= m * p.disc.bond_cos[b];
      f[i + 1] -= m * p.disc.bond_sin[b];
      f[j] += m * p.disc.bond_cos[b];
      f[j + 1] += m * p.disc.bond_sin[b];
    }
    double worst = 0.0;
    for (std::size_t dof = 0; dof < f.size(); ++dof) {
      if (solver.free_index()[dof] >= 0) worst = std::max(worst, std::abs(f[dof]));
    }
    EXPECT_LT(worst, 1e-9 * std::abs(plastic.reaction(0))) << "strain " << strain;
    EXPECT_GT(tp->iterations, 1);  // plastic: more than the elastic predictor
  }
}

TEST(Elastoplastic, SymmetricStrainCyclesArePeriodicFromTheSecondCycle) {
  const auto p = bar(kLength, kHeight, kDx);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(solver.solve().ok());
  statics::ElastoplasticSolver plastic(solver, statics::BondPlasticity{});
  std::vector<std::vector<model::MasingState>> ends;
  std::vector<double> peaks;
  for (int cycle = 0; cycle < 3; ++cycle) {
    ASSERT_TRUE(plastic.solve_turning_point(grip_for(0.0018), 0.0).ok());
    peaks.push_back(plastic.reaction(0));
    ASSERT_TRUE(plastic.solve_turning_point(grip_for(-0.0018), 0.0).ok());
    ends.push_back(plastic.bond_states());
  }
  // Masing under strain control is stable at once: the reaction at the peak repeats to the
  // Newton tolerance (the states are a solve's output, not snapped: 1e-9).
  EXPECT_NEAR(peaks[2], peaks[1], 1e-9 * peaks[1]);
  for (std::size_t b = 0; b < ends[1].size(); ++b) {
    EXPECT_NEAR(ends[2][b].stress, ends[1][b].stress, 1e-6 * 295e6) << "bond " << b;
  }
}

TEST(Elastoplastic, TheBarsStressStrainFollowsTheBondCurveWithinItsOrientationSpread) {
  // Uniaxial bar: the axial bonds stretch by ε/κ·κ = ε, the others less (bond-based, ν = 1/3):
  // the bar's σ = R/A starts elastic at E and yields later and higher than a single bond. The
  // bar's stress at 0.18 % and 0.6 % lies between the curve's (every bond axial) and E·ε.
  const auto p = bar(kLength, kHeight, kDx);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads, p.ties, p.prescribed);
  ASSERT_TRUE(solver.solve().ok());
  statics::BondPlasticity law;
  statics::ElastoplasticSolver plastic(solver, law);
  for (double strain : {0.0018, 0.006}) {
    ASSERT_TRUE(plastic.solve_turning_point(grip_for(strain), 0.0).ok());
    const double sigma = plastic.reaction(0) / bar_area(p);
    const double curve = law.curve.stress(strain);
    RecordProperty("bar_stress_at_" + std::to_string(strain), std::to_string(sigma));
    EXPECT_GT(sigma, 0.97 * curve);
    EXPECT_LT(sigma, kE * strain);
  }
}

}  // namespace
}  // namespace peritwin
