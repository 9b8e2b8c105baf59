#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>

#include "solver/crack/crack_tracker.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"
#include "solver/statics/static_solver.h"
#include "validation/specimens.h"

namespace peritwin {
namespace {

using namespace peritwin::validation;  // the benchmark specimens

constexpr double pi = std::numbers::pi;

/// Center-cracked plate of width W and height 2W, crack 2a along y = 0 (between two node rows),
/// uniform tension σ on the top and bottom edge layers; bond-based plane stress (ν = 1/3).
using CenterCrack = statics::Specimen;  // geometry, discretization, model, supports, loads

CenterCrack make_center_crack(double width, double a, double dx, double horizon,
                              model::Kernel kernel) {
  CenterCrack p;
  p.geometry.thickness = 0.001;
  p.geometry.outline = {mesh::Rectangle{-0.5 * width, -width, 0.5 * width, width}};
  p.geometry.notches = {{"crack", {{-a, 0.0}, {a, 0.0}}}};
  p.disc = discretize(p.geometry, dx, horizon);
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  o.kernel = kernel;
  p.model = model::build_model(p.disc, model::Material{70e9, 1.0 / 3.0, 0.0}, o, 200.0);
  const double force = 1.0 * width * p.geometry.thickness;  // σ = 1 Pa per unit P
  p.loads.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-width, width - dx, width, 2 * width})),
       {0, force},
       {},
       {}});
  p.loads.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-width, -2 * width, width, -width + dx})),
       {0, -force},
       {},
       {}});
  // Minimal supports away from the crack: the left-edge node at y = +Δx/2 pinned, the right-edge
  // node at y = +Δx/2 fixed in y (the loads are self-balanced).
  p.supports.push_back({{p.disc.nearest_node({-0.5 * width, 0.5 * dx})}, true, true});
  p.supports.push_back({{p.disc.nearest_node({0.5 * width, 0.5 * dx})}, false, true});
  return p;
}

/// K_I by displacement extrapolation, 001 Eq. (62), from the upper crack face at two distances
/// r1 < r2 behind the right tip; u2 is half the face opening (upper minus lower node over 2).
double k_i_by_extrapolation(const CenterCrack& p, const std::vector<double>& u, double a, double r1,
                            double r2) {
  const double e = p.model.material.youngs_modulus;
  const double nu = 1.0 / 3.0;
  const double mu = e / (2 * (1 + nu));
  const double kappa = (3 - nu) / (1 + nu);  // 001 Eq. (59), plane stress
  const double dx = p.disc.dx;
  auto half_opening = [&](double r) {
    const auto up = static_cast<std::size_t>(p.disc.nearest_node({a - r, 0.5 * dx}));
    const auto low = static_cast<std::size_t>(p.disc.nearest_node({a - r, -0.5 * dx}));
    return 0.5 * (u[2 * up + 1] - u[2 * low + 1]);
  };
  const double xb = a - p.disc.position[p.disc.nearest_node({a - r1, 0.5 * dx})].x;
  const double xd = a - p.disc.position[p.disc.nearest_node({a - r2, 0.5 * dx})].x;
  return 2 * mu * std::sqrt(2 * pi) / (kappa + 1) *
         (half_opening(r1) * xd / std::sqrt(xb) - half_opening(r2) * xb / std::sqrt(xd)) /
         (xd - xb);
}

TEST(CenterCrackedPlate, StressIntensityByExtrapolationMatchesFeddersen) {
  // B4: K_I within 5 % of σ√(πa)·√(sec(πa/W)) at a/W = 0.2 (Feddersen's finite-width correction).
  const double width = 0.03, a = 0.006, dx = 0.00025;
  for (const model::Kernel kernel : {model::Kernel::constant, model::Kernel::gaussian}) {
    const auto p = make_center_crack(width, a, dx, 3.015 * dx, kernel);
    statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads);
    ASSERT_TRUE(solver.solve().ok());
    const double k = k_i_by_extrapolation(p, solver.basis_displacement(statics::basis_constant), a,
                                          3 * p.disc.horizon, 6 * p.disc.horizon);
    const double expected = std::sqrt(pi * a) * std::sqrt(1 / std::cos(pi * a / width));
    EXPECT_NEAR(k / expected, 1.0, 0.05)
        << (kernel == model::Kernel::constant ? "constant" : "gaussian");
  }
}

/// Crack-mouth opening (at the crack centre) per unit σ of the center-cracked plate.
double crack_centre_opening(double dx, double horizon) {
  const double width = 0.024, a = 0.0048;
  const auto p = make_center_crack(width, a, dx, horizon, model::Kernel::constant);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads);
  EXPECT_TRUE(solver.solve().ok());
  const auto& u = solver.basis_displacement(statics::basis_constant);
  const auto up = static_cast<std::size_t>(p.disc.nearest_node({0.5 * dx, 0.5 * dx}));
  const auto low = static_cast<std::size_t>(p.disc.nearest_node({0.5 * dx, -0.5 * dx}));
  return u[2 * up + 1] - u[2 * low + 1];
}

/// Elastic reference: opening at the centre of a crack 2a in a strip of width W = 2b,
/// 2v = (4σa/E)·V1(a/b), V1 from Tada, Paris & Irwin (plane stress).
double tada_centre_opening() {
  const double e = 70e9, a = 0.0048, b = 0.012, t = a / b;
  const double v1 =
      -0.071 - 0.535 * t + 0.169 * t * t + 0.020 * t * t * t - 1.071 / t * std::log(1 - t);
  return 4 * a / e * v1;
}

TEST(KFieldPlate, ExtrapolationAndWilliamsFitRecoverTheAppliedKIKIIAndT) {
  // The plate's edges carry the Williams tractions of K_I = 1 and T = 3·K_I (cos basis) or of
  // K_II = −1 (sin basis); state-based, Δx = 0.5 mm, L = 30 mm. Independent check of the edge
  // loading and of the extraction at 3δ-6δ behind the tip (001 Eq. 62-63): K_I within 5 %, K_II
  // within 10 % (measured +8.6 %), the crack-face T within 0.3/√m of the applied 3/√m and of 0.
  // The K_II excess is the plate's rigid turn ω, which the supports allow: the face rows sit Δx
  // apart, so ω·Δx enters the tangential jump at every r and the two-point formula reads it as
  // K_II. A least-squares fit of c + A√r + Br^(3/2) to the jumps (tried, not kept) gave −0.984. On
  // the CTS that fit swung from 0.40 to 0.53 in K_II/K_I with the range of r (higher-order terms),
  // while the two-point ratio stayed within 0.458-0.475 over r from 2-9 to 9-24 mm: B2 keeps it.
  KFieldPlateSpec spec;
  spec.t_over_ki = 3.0;
  model::ModelOptions o;
  o.kind = model::ModelKind::state_based;
  const statics::Specimen p = make_k_field_plate(spec, o, 0.0005);
  statics::StaticSolver solver(p.disc, p.model, p.supports, p.loads);
  ASSERT_TRUE(solver.solve().ok());
  const double nu = p.material.poisson_ratio;
  const double mu = p.material.youngs_modulus / (2 * (1 + nu));
  const double kappa = crack::kolosov_kappa(nu, model::PlaneCondition::plane_stress);
  const double r1 = 3 * p.disc.horizon, r2 = 6 * p.disc.horizon;
  const auto& u_i = solver.basis_displacement(statics::basis_cos);
  const auto k_i = crack::stress_intensity_by_extrapolation(p.disc, u_i, p.initial_crack_tip,
                                                            {1, 0}, r1, r2, mu, kappa);
  EXPECT_NEAR(k_i.k_i, 1.0, 0.05);
  EXPECT_NEAR(k_i.k_ii, 0.0, 0.05);
  EXPECT_NEAR(crack::t_stress_from_crack_faces(p.disc, u_i, p.initial_crack_tip, r1, r2,
                                               p.material.youngs_modulus),
              3.0, 0.3);
  const auto& u_ii = solver.basis_displacement(statics::basis_sin);
  const auto k_ii = crack::stress_intensity_by_extrapolation(p.disc, u_ii, p.initial_crack_tip,
                                                             {1, 0}, r1, r2, mu, kappa);
  EXPECT_NEAR(k_ii.k_ii, -1.0, 0.10);
  EXPECT_NEAR(k_ii.k_i, 0.0, 0.05);
  EXPECT_NEAR(crack::t_stress_from_crack_faces(p.disc, u_ii, p.initial_crack_tip, r1, r2,
                                               p.material.youngs_modulus),
              0.0, 0.3);

  // The second method: a least-squares fit of the Williams series (7 terms per mode) to every
  // node 3δ-12δ from the tip. Measured: K_I 1.027, K_II −1.052, T 3.02 and 0.01; over annuli from
  // 2δ-8δ to 4δ-16δ with 4-10 terms K_I 1.025-1.032, K_II −1.046 to −1.063, T 2.99-3.04 (the PD
  // plate is a few per cent more compliant than the elastic field its edges carry; the fit takes
  // the rigid turn as the mode II r¹ term). Tolerances: K_I 5 %, K_II 8 %, T 0.1/√m.
  const auto mode_i = crack::williams_series_fit(p.disc, u_i, p.initial_crack_tip, {1, 0}, r1,
                                                 4 * r1, 7, mu, kappa);
  EXPECT_GT(mode_i.nodes, 1000);
  EXPECT_TRUE(mode_i.fitted);
  EXPECT_NEAR(mode_i.k_i, 1.0, 0.05);
  EXPECT_NEAR(mode_i.k_ii, 0.0, 0.05);
  EXPECT_NEAR(mode_i.t_stress, 3.0, 0.1);
  const auto mode_ii = crack::williams_series_fit(p.disc, u_ii, p.initial_crack_tip, {1, 0}, r1,
                                                  4 * r1, 7, mu, kappa);
  EXPECT_NEAR(mode_ii.k_ii, -1.0, 0.08);
  EXPECT_NEAR(mode_ii.k_i, 0.0, 0.05);
  EXPECT_NEAR(mode_ii.t_stress, 0.0, 0.1);
}

TEST(CompactTensionShear, RigidFixturesGiveRichardsStressIntensity) {
  // B2's CTS (Δx = 1 mm, state-based, loaded lower holes) in Richard's loading device: the three
  // pins of each half held to a rigid-body motion by stiff ties (Specimen::ties). Two independent
  // computations of the same device agree: the tied fixture (one solve) and the oracle, the pin
  // split from the specimen's flexibility (12 unit solves, compatibility and the fixture's
  // equilibrium). The pin forces the ties pass to the specimen match the oracle's split within
  // 0.2 % of P (measured 0.05 %), and K at the initial tip (Williams fit, 3δ–15 mm) within 0.1 %
  // (measured 0.01 %). K matches Richard's formulas, an independent calibration of the specimen in
  // its device: measured K_I +0.3 % (α = 0) and −0.3 % (α = 45°), K_II −6.6 %; asserted within 3 %
  // and 10 %. With each pin carrying its own Eq. (51) force the same specimen is 18 % above
  // Richard in K_I (asserted > 10 %).
  CompactTensionShearSpec spec;
  spec.lower_holes_fixed = false;
  model::ModelOptions o;
  o.kind = model::ModelKind::state_based;
  const double dx = 0.001;
  const double nu = spec.material.poisson_ratio;
  const double mu = spec.material.youngs_modulus / (2 * (1 + nu));
  const double kappa = crack::kolosov_kappa(nu, model::PlaneCondition::plane_stress);
  auto solved = [](const statics::Specimen& s) {
    auto solver =
        std::make_unique<statics::StaticSolver>(s.disc, s.model, s.supports, s.loads, s.ties);
    EXPECT_TRUE(solver->solve().ok());
    return solver;
  };
  auto fitted_k = [&](const statics::Specimen& s, const statics::StaticSolver& solver,
                      double alpha) {
    std::vector<double> u;
    solver.displacement(1.0, alpha, u);
    return crack::williams_series_fit(s.disc, u, s.initial_crack_tip, {1, 0}, 3 * s.disc.horizon,
                                      0.015, 7, mu, kappa);
  };
  const statics::Specimen pins = make_compact_tension_shear(spec, o, dx);
  statics::Specimen oracle = pins;
  oracle.loads = rigid_fixture_loads_by_flexibility(pins);
  // The oracle's upper pins carry Eq. (51)'s resultant (0, P) for cos α and (−P, 0) for sin α,
  // with no moment about the crack tip (45 mm, 0): the load line of the device runs through it.
  mesh::Point sum_cos, sum_sin;
  double moment_cos = 0.0, moment_sin = 0.0;
  for (std::size_t h = 0; h < 3; ++h) {
    const auto& load = oracle.loads[h];
    const mesh::Point centre = oracle.disc.centroid(load.nodes);
    sum_cos = {sum_cos.x + load.per_cos.x, sum_cos.y + load.per_cos.y};
    sum_sin = {sum_sin.x + load.per_sin.x, sum_sin.y + load.per_sin.y};
    const mesh::Point arm{centre.x - spec.crack_length, centre.y};
    moment_cos += arm.x * load.per_cos.y - arm.y * load.per_cos.x;
    moment_sin += arm.x * load.per_sin.y - arm.y * load.per_sin.x;
  }
  EXPECT_NEAR(sum_cos.x, 0.0, 1e-9);
  EXPECT_NEAR(sum_cos.y, 1.0, 1e-9);
  EXPECT_NEAR(sum_sin.x, -1.0, 1e-9);
  EXPECT_NEAR(sum_sin.y, 0.0, 1e-9);
  EXPECT_NEAR(moment_cos, 0.0, 1e-4);  // N·m per N; the disc centroids sit within Δx of the centres
  EXPECT_NEAR(moment_sin, 0.0, 1e-4);

  spec.rigid_fixtures = true;
  const statics::Specimen fixture = make_compact_tension_shear(spec, o, dx);
  ASSERT_EQ(fixture.ties.size(), 2u * 3u);  // 2·3 − 3 per fixture
  const auto fixture_solver = solved(fixture);
  const auto oracle_solver = solved(oracle);
  // Force each pin passes to the specimen: its applied load minus what the ties take, −k·c_i·(gᵀu)
  // on each DOF i of the pin's nodes.
  for (const statics::Basis basis : {statics::basis_cos, statics::basis_sin}) {
    const auto& u = fixture_solver->basis_displacement(basis);
    for (std::size_t h = 0; h < fixture.loads.size(); ++h) {
      const auto& nodes = fixture.loads[h].nodes;
      mesh::Point f =
          basis == statics::basis_cos ? fixture.loads[h].per_cos : fixture.loads[h].per_sin;
      for (const statics::Tie& tie : fixture.ties) {
        const double violation = statics::tie_violation(tie, u);
        for (const statics::TieTerm& term : tie.terms) {
          if (std::find(nodes.begin(), nodes.end(), term.node) == nodes.end()) continue;
          (term.component == 0 ? f.x : f.y) -= tie.stiffness * term.coefficient * violation;
        }
      }
      const mesh::Point want =
          basis == statics::basis_cos ? oracle.loads[h].per_cos : oracle.loads[h].per_sin;
      EXPECT_NEAR(f.x, want.x, 0.002) << "pin " << h << " basis " << basis;
      EXPECT_NEAR(f.y, want.y, 0.002) << "pin " << h << " basis " << basis;
    }
  }
  for (const double alpha_deg : {0.0, 45.0}) {
    const double alpha = alpha_deg * pi / 180;
    const auto k = fitted_k(fixture, *fixture_solver, alpha);
    const auto k_oracle = fitted_k(oracle, *oracle_solver, alpha);
    const auto richard = richard_cts_stress_intensity(spec, 1.0, alpha);
    EXPECT_NEAR(k.k_i / k_oracle.k_i, 1.0, 0.001) << "alpha " << alpha_deg;
    EXPECT_NEAR(k.k_i / richard.k_i, 1.0, 0.03) << "alpha " << alpha_deg;
    if (alpha_deg > 0) {
      EXPECT_NEAR(k.k_ii / k_oracle.k_ii, 1.0, 0.001);
      EXPECT_NEAR(std::abs(k.k_ii) / richard.k_ii, 1.0, 0.10);
    }
  }
  const auto eq51 = fitted_k(pins, *solved(pins), 0.0);
  EXPECT_GT(eq51.k_i / richard_cts_stress_intensity(spec, 1.0, 0.0).k_i, 1.10);
}

TEST(CompactTensionShear, GridSpacingKeepsNodeRowsOffTheCrackLine) {
  // At Δx = 2 mm the 90 mm height holds 45 rows and one lies on the crack line y = 0: the notch
  // cuts every bond of its nodes there (each touches the line), which leaves them out of the
  // model. The stiffness was singular; now (docs/solver.md, "Mechanisms are pinned") they are
  // grounded as unloaded debris, as nodes isolated by breaking always were, and it solves — but
  // the material on the line is lost all the same. The spacing is moved to the nearest even row
  // count (46 rows, 1.957 mm); spacings without a row on the line are kept.
  const CompactTensionShearSpec spec;
  EXPECT_EQ(compact_tension_shear_grid_spacing(spec, 0.001), 0.001);
  EXPECT_EQ(compact_tension_shear_grid_spacing(spec, 0.0006), 0.0006);
  EXPECT_EQ(compact_tension_shear_grid_spacing(spec, 0.00025), 0.00025);
  const double dx = compact_tension_shear_grid_spacing(spec, 0.002);
  EXPECT_DOUBLE_EQ(dx, 0.090 / 46);
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  for (const double spacing : {0.002, dx}) {
    const statics::Specimen s = make_compact_tension_shear(spec, o, spacing);
    int cut_off = 0;  // nodes whose every bond the notch cut
    for (mesh::NodeIndex k = 0; k < s.disc.num_nodes(); ++k) {
      bool all = true;
      for (auto f = s.disc.family_offset[static_cast<std::size_t>(k)];
           f < s.disc.family_offset[static_cast<std::size_t>(k) + 1]; ++f) {
        all = all && s.disc.bond_precut[static_cast<std::size_t>(
                         s.disc.family_bonds[static_cast<std::size_t>(f)])] != 0;
      }
      cut_off += all ? 1 : 0;
    }
    EXPECT_EQ(cut_off > 0, spacing == 0.002) << "dx " << spacing << ": " << cut_off;
    statics::StaticSolver solver(s.disc, s.model, s.supports, s.loads);
    EXPECT_TRUE(solver.solve().ok()) << "dx " << spacing;
    EXPECT_EQ(solver.pinned_dofs(), 0);
  }
}

TEST(Convergence, HorizonRatioAtFixedHorizon) {
  // m-convergence: δ fixed at 1.2 mm, Δx = δ/m for m = 2, 3, 4: the opening approaches the
  // elastic solution and the last step changes it less than the first.
  const double delta = 0.0012, ref = tada_centre_opening();
  const double c2 = crack_centre_opening(delta / 2, delta);
  const double c3 = crack_centre_opening(delta / 3, delta);
  const double c4 = crack_centre_opening(delta / 4, delta);
  EXPECT_LT(std::abs(c4 - c3), std::abs(c3 - c2));
  EXPECT_LT(std::abs(c4 / ref - 1), std::abs(c2 / ref - 1));
  EXPECT_NEAR(c4 / ref, 1.0, 0.05);
}

TEST(Convergence, HorizonAtFixedRatio) {
  // δ-convergence: δ = 3.015Δx with Δx = 0.4, 0.3, 0.2 mm: the error against the elastic opening
  // shrinks monotonically.
  const double ref = tada_centre_opening();
  const double e1 = std::abs(crack_centre_opening(0.0004, 3.015 * 0.0004) / ref - 1);
  const double e2 = std::abs(crack_centre_opening(0.0003, 3.015 * 0.0003) / ref - 1);
  const double e3 = std::abs(crack_centre_opening(0.0002, 3.015 * 0.0002) / ref - 1);
  EXPECT_LT(e2, e1);
  EXPECT_LT(e3, e2);
  EXPECT_LT(e3, 0.05);
}

}  // namespace
}  // namespace peritwin
