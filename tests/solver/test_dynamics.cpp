// Explicit bond-based PD dynamics of paper 001 (solver/dynamics) and coarse versions of the
// D1-D3 validation cases (validation/dynamics_cases.h; the full ones: peritwin-validate --case D*).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "solver/dynamics/dispersion.h"
#include "solver/dynamics/dynamic_crack.h"
#include "solver/dynamics/explicit_dynamics.h"
#include "validation/dynamics_cases.h"

namespace peritwin {
namespace {

using dynamics::KernelChoice;
constexpr double pi = std::numbers::pi;

dynamics::KernelChoice constant_kernel() { return {dynamics::KernelChoice::Shape::constant, 0.0}; }
dynamics::KernelChoice gaussian_kernel(double p = 2.0) {
  return {dynamics::KernelChoice::Shape::gaussian, p};
}

mesh::Discretization plate(double width, double height, double dx, double ratio,
                           const std::vector<mesh::Notch>& notches = {}, double no_fail_rows = 0) {
  mesh::DetailGeometry g;
  g.thickness = 1.0;
  g.outline.push_back(mesh::Region(mesh::Rectangle{0.0, 0.0, width, height}));
  g.notches = notches;
  if (no_fail_rows > 0) {  // the loaded edges
    g.no_fail_zones.push_back(mesh::Region(mesh::Rectangle{0.0, 0.0, width, no_fail_rows * dx}));
    g.no_fail_zones.push_back(
        mesh::Region(mesh::Rectangle{0.0, height - no_fail_rows * dx, width, height}));
  }
  return discretize(g, dx, ratio * dx);
}

// 001 Eq. (24), (29)-(30), (26), (33) against closed forms written independently: the project's
// static micromodulus (energy matching with the kernel's second moment, p = 2) and Eq. (30).
TEST(Dynamics, MicromodulusMatchesThePapersClosedForms) {
  const double e = 210e9, delta = 0.15, h = 1.0;
  const double gauss =
      dynamics::micromodulus(dynamics::Dimension::two, model::PlaneCondition::plane_stress,
                             gaussian_kernel(2.0), e, delta, h);
  model::ModelOptions options;
  options.kind = model::ModelKind::bond_based;
  options.kernel = model::Kernel::gaussian;
  model::Material mat;
  mat.youngs_modulus = e;
  EXPECT_NEAR(gauss / model::bond_micromodulus(mat, options, delta, h), 1.0, 1e-12);
  const double e4 = std::exp(4.0);  // Eq. (30)
  EXPECT_NEAR(gauss / (96 * e4 * e /
                       ((e4 * std::sqrt(pi) * std::erf(2.0) - 4) * h * pi * delta * delta * delta)),
              1.0, 1e-12);
  EXPECT_NEAR(dynamics::micromodulus(dynamics::Dimension::two, model::PlaneCondition::plane_stress,
                                     constant_kernel(), e, delta, h) /
                  (9 * e / (h * pi * delta * delta * delta)),
              1.0, 1e-14);
  EXPECT_NEAR(dynamics::micromodulus(dynamics::Dimension::two, model::PlaneCondition::plane_strain,
                                     constant_kernel(), e, delta, h) /
                  (48 * e / (5 * h * pi * delta * delta * delta)),
              1.0, 1e-14);
  const double area = 1e-6, d1 = 6.25e-3;
  EXPECT_NEAR(dynamics::micromodulus(dynamics::Dimension::one, model::PlaneCondition::plane_stress,
                                     gaussian_kernel(2.0), e, d1, area) /
                  (2 * e / (area * d1 * d1) * 4 / (1 - std::exp(-4.0))),
              1.0, 1e-14);
}

// The central difference scheme conserves, for a linear force, E_n = ½ Σ m v_{n−½}·v_{n+½} + U(u_n)
// exactly (multiply Eq. 41 by (u_{n+1} − u_{n−1})/(2Δt)); the bond force of Eq. (38) is nonlinear
// only through the rotation of the bond, of relative size ~ the strain (1e-6 here), so the drift
// of E over 10⁴ steps must stay below 1e-6 of it.
TEST(Dynamics, FreePlateConservesTheSchemesDiscreteEnergy) {
  const mesh::Discretization disc = plate(0.02, 0.02, 1e-3, 3.0);
  dynamics::DynamicsSetup setup;
  setup.kernel = gaussian_kernel(2.0);
  setup.youngs_modulus = 210e9;
  setup.density = 8000;
  setup.time_step = 1e-30;
  auto probe = dynamics::ExplicitDynamics::create(disc, setup);
  ASSERT_TRUE(probe) << probe.error().message();
  setup.time_step = 0.5 * probe.value()->stable_time_step();
  auto made = dynamics::ExplicitDynamics::create(disc, setup);
  ASSERT_TRUE(made);
  auto& dyn = *made.value();
  const auto n = static_cast<std::size_t>(disc.num_nodes());
  std::vector<double> u0(2 * n), v0(2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = disc.position[i].x / 0.02, y = disc.position[i].y / 0.02;
    u0[2 * i] = 2e-8 * std::sin(2 * pi * x) * std::cos(pi * y);  // strain ~ 6e-6
    u0[2 * i + 1] = 1e-8 * std::cos(3 * pi * x * y);
    v0[2 * i] = 1e-3 * std::cos(pi * y);
    v0[2 * i + 1] = 2e-3 * std::sin(2 * pi * x);
  }
  dyn.set_initial_state(u0, v0);
  const double e0 = dyn.energy().total();
  ASSERT_GT(dyn.energy().strain, 0.05 * e0);  // both forms of energy take part
  double worst = 0.0, worst_naive = 0.0;
  std::vector<double> vm;
  for (int block = 0; block < 100; ++block) {
    dyn.step(100);
    const auto en = dyn.energy();
    worst = std::max(worst, std::abs(en.total() - e0) / e0);
    // The half-step kinetic energy alone (not conserved: shown for contrast, not asserted).
    dyn.half_step_velocity(vm);
    double k_half = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      k_half +=
          0.5 * 8000 * disc.volume[i] * (vm[2 * i] * vm[2 * i] + vm[2 * i + 1] * vm[2 * i + 1]);
    }
    worst_naive = std::max(worst_naive, std::abs(k_half + en.strain - e0) / e0);
  }
  EXPECT_EQ(dyn.step_count(), 10000);
  EXPECT_LE(worst, 1e-6) << "naive (half-step kinetic) drift " << worst_naive;
  RecordProperty("relative_drift", std::to_string(worst));
  std::printf("energy drift over 1e4 steps: %.3g (half-step kinetic energy instead: %.3g)\n", worst,
              worst_naive);
}

// Eq. (42)-(43): the limit is computed as printed, a larger Δt refused naming it, the limit itself
// accepted; and it is a sufficient one: 2/ω_max of the actual lattice (max over k of the lattice
// sum at the bar's middle node) is not below it, nor below the √2-larger von Neumann bound.
TEST(Dynamics, RefusesATimeStepAboveTheStableOne) {
  const mesh::Discretization disc = dynamics::bar_discretization(0.0, 200, 1.25e-3, 6.25e-3, 1e-6);
  dynamics::DynamicsSetup setup;
  setup.dimension = dynamics::Dimension::one;
  setup.kernel = constant_kernel();
  setup.youngs_modulus = 200e9;
  setup.density = 7850;
  setup.time_step = 1e-8;
  auto ok = dynamics::ExplicitDynamics::create(disc, setup);
  ASSERT_TRUE(ok);
  const double limit = ok.value()->stable_time_step();
  // Independent: Σ_j V_j C_ij over an interior node, j = ±1..5, β = ½ at j = ±5 (Eq. 36).
  const double c0 = 2 * 200e9 / (1e-6 * 6.25e-3 * 6.25e-3);
  double sum = 0.0;
  for (int j = 1; j <= 5; ++j)
    sum += 2 * c0 * (j == 5 ? 0.5 : 1.0) * 1e-6 * 1.25e-3 / (j * 1.25e-3);
  // The end nodes have half a family: the interior one is the smallest limit.
  EXPECT_NEAR(limit, std::sqrt(7850 / sum), 1e-12 * limit);
  double omega_max = 0.0;
  for (int s = 0; s <= 2000; ++s) {
    const double k = pi / 1.25e-3 * s / 2000.0;
    omega_max = std::max(omega_max, std::sqrt(ok.value()->lattice_omega_squared(100, k)));
  }
  // The printed limit and even the √2-larger von Neumann bound are within 2/ω_max.
  EXPECT_GE(2.0 / omega_max, ok.value()->von_neumann_time_step());
  EXPECT_NEAR(ok.value()->von_neumann_time_step(), std::sqrt(2.0) * limit, 1e-12 * limit);
  setup.time_step = limit;
  EXPECT_TRUE(dynamics::ExplicitDynamics::create(disc, setup));
  setup.time_step = 1.001 * limit;
  auto refused = dynamics::ExplicitDynamics::create(disc, setup);
  ASSERT_FALSE(refused);
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", limit);
  EXPECT_NE(refused.error().message().find(text), std::string::npos) << refused.error().message();
  EXPECT_NE(refused.error().message().find("stable time step"), std::string::npos);
}

// Two threads give the same bits as one: a notched plate pulled by a step traction hard enough to
// break bonds at the notch tip (critical stretch), every displacement compared bit for bit.
TEST(Dynamics, TwoThreadsEqualOneThreadBitForBit) {
  mesh::Notch notch;
  notch.path = {mesh::Point{-0.001, 0.01}, mesh::Point{0.008, 0.01}};
  const mesh::Discretization disc = plate(0.03, 0.02, 0.5e-3, 3.0, {notch});
  std::vector<std::vector<double>> results;
  std::vector<std::int64_t> broken;
  for (const int threads : {1, 2}) {
    dynamics::DynamicsSetup setup;
    setup.kernel = gaussian_kernel(2.0);
    setup.youngs_modulus = 210e9;
    setup.density = 8000;
    setup.time_step = 2e-8;
    setup.threads = threads;
    setup.critical_stretch = 1e-3;
    auto made = dynamics::ExplicitDynamics::create(disc, setup);
    ASSERT_TRUE(made) << made.error().message();
    auto& dyn = *made.value();
    for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
      const double y = disc.position[static_cast<std::size_t>(k)].y;
      if (y > 0.02 - 0.5e-3) dyn.add_body_force(k, 0.0, 1.5e9 / 0.5e-3);
      if (y < 0.5e-3) dyn.add_body_force(k, 0.0, -1.5e9 / 0.5e-3);
    }
    dyn.set_load_history({dynamics::LoadHistory::Kind::step, 0.0});
    const auto n2 = static_cast<std::size_t>(2 * disc.num_nodes());
    dyn.set_initial_state(std::vector<double>(n2, 0.0), std::vector<double>(n2, 0.0));
    dyn.step(300);
    results.emplace_back(dyn.displacement().begin(), dyn.displacement().end());
    broken.push_back(dyn.broken_bonds());
  }
  const auto precut =
      static_cast<std::int64_t>(std::count(disc.bond_precut.begin(), disc.bond_precut.end(), 1));
  EXPECT_GT(broken[0], precut) << "no bond broke: the test would not exercise breaking";
  EXPECT_EQ(broken[0], broken[1]);
  ASSERT_EQ(results[0].size(), results[1].size());
  EXPECT_EQ(std::memcmp(results[0].data(), results[1].data(), results[0].size() * sizeof(double)),
            0);
}

// 001 Eq. (48)-(50) with the partial volumes of Eq. (36) is the sum the integrator's coefficients
// make at an interior node of the bar: equal to round-off for both kernels and many k. And the
// constant kernel with the partial volumes has the exact long-wave speed: (2/m²)Σ j β_j = 1.
TEST(Dynamics, LatticeDispersionEqualsThePapersFormula) {
  for (const auto& kernel : {constant_kernel(), gaussian_kernel(1.0), gaussian_kernel(2.0)}) {
    const double dx = 1.25e-3, e = 200e9, rho = 7850;
    const mesh::Discretization disc = dynamics::bar_discretization(0.0, 41, dx, 5 * dx, 1.0);
    dynamics::DynamicsSetup setup;
    setup.dimension = dynamics::Dimension::one;
    setup.kernel = kernel;
    setup.youngs_modulus = e;
    setup.density = rho;
    setup.time_step = 1e-9;
    auto made = dynamics::ExplicitDynamics::create(disc, setup);
    ASSERT_TRUE(made);
    const double v = std::sqrt(e / rho);
    double worst = 0.0;
    for (int s = 1; s <= 200; ++s) {
      const double k = 2 * pi / dx * s / 200.0;
      const double lattice = std::sqrt(made.value()->lattice_omega_squared(20, k));
      const double formula = dynamics::dispersion_omega(kernel, v, 5, dx, k, true);
      worst = std::max(worst, std::abs(lattice - formula) / formula);
    }
    EXPECT_LE(worst, 1e-12) << kernel.name();
    if (kernel.shape == dynamics::KernelChoice::Shape::constant) {
      const double k = 1e-2;
      EXPECT_NEAR(dynamics::dispersion_omega(kernel, v, 5, dx, k, true) / (k * v), 1.0, 1e-6);
    }
  }
}

// Eq. (56) in closed form against the series itself away from the jumps (the series converges as
// 1/(N·distance to a jump): 20000 terms, 0.05 m away, error < 1e-3 of F0/EA).
TEST(Dynamics, BarExactStrainClosedFormIsTheSeries) {
  const double c = std::sqrt(200e9 / 7850), l = 1.0;
  for (const double tc : {0.1, 0.3, 0.7, 1.1, 1.3, 1.7}) {
    for (const double x : {0.2, 0.5, 0.9}) {
      if (std::abs(std::abs(x - tc) - 0.0) < 0.05 || std::abs(x + tc - 2.0) < 0.05) continue;
      const double t = tc * l / c;
      EXPECT_NEAR(validation::bar_exact_strain(x, t, l, c, 1e-3),
                  validation::bar_exact_strain_series(x, t, l, c, 1e-3, 20000), 1e-6)
          << "x " << x << " ct/L " << tc;
    }
  }
}

// Coarse D1: Δx = 5 mm (200 nodes), δ = 5Δx, Δt = 1e-7 s. The L2 error of a square wave is set by
// the width of the jumps' ringing, which grows like Δx, so the error like √Δx: the full case
// (Δx = 1.25 mm) measures 0.092 with the lattice-calibrated c0 (docs/validation.md), hence about
// 0.18 here; we allow 0.22. The paper's c0 (Eq. 33) makes the Gaussian lattice's wave 1.6 % slow
// (m = 5), which only adds error: it must be worse than the calibrated one.
TEST(Dynamics, CoarseBarFollowsTheExactStrain) {
  validation::BarSpec spec;
  spec.dx = 5e-3;
  spec.time_step = 1e-7;
  spec.sample_every = 10;
  spec.kernel = gaussian_kernel(2.0);
  const auto paper = validation::run_bar(spec);
  spec.lattice_calibrated = true;
  const auto calibrated = validation::run_bar(spec);
  spec.kernel = constant_kernel();
  const auto constant = validation::run_bar(spec);
  std::printf("coarse D1 rel_l2: gaussian %.4f (paper c0 %.4f), constant %.4f\n",
              calibrated.rel_l2_error, paper.rel_l2_error, constant.rel_l2_error);
  EXPECT_LE(calibrated.rel_l2_error, 0.22);
  EXPECT_LE(constant.rel_l2_error, 0.22);
  EXPECT_GT(paper.rel_l2_error, calibrated.rel_l2_error);
}

// D2: a packet's measured speed is the lattice's group speed dω/dk (not the classical c), within 1
// %.
TEST(Dynamics, WavePacketTravelsAtTheGroupSpeed) {
  validation::PacketSpec spec;
  spec.kernel = gaussian_kernel(2.0);
  const auto r = validation::run_packet(spec);
  std::printf("packet: measured %.2f group %.2f phase %.2f classical %.2f m/s\n", r.measured_speed,
              r.group_speed, r.phase_speed, r.classical_speed);
  EXPECT_NEAR(r.measured_speed / r.group_speed, 1.0, 0.01);
  EXPECT_GT(std::abs(r.group_speed / r.classical_speed - 1.0),
            0.05);  // the test can tell them apart
}

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

// Coarse D3: the semi-infinite crack at Δ = 0.1 m (100 × 40 nodes, δ = 3Δ, Δt = 1e-5 s), Gaussian
// p = 2, ramp (Eq. 64-65) against Freund over 1.2 t_c <= t <= 3 t_c. The full case (Δ = 0.05 m)
// measures a mean error of 0.054; at twice the spacing the extrapolation points sit twice as far
// from the tip (δ + Δ/2 and 2δ + Δ/2) and the near-tip field is coarser: a mean error within 0.15.
// Loading both edges doubles K exactly in this window (the two waves superpose on the crack line).
TEST(Dynamics, CoarseSemiInfiniteCrackFollowsFreund) {
  validation::CrackSpec spec;
  spec.dx = 0.1;
  spec.time_step = 1e-5;
  spec.end_over_tc = 3.0;
  spec.kernel = {dynamics::KernelChoice::Shape::gaussian, 2.0};
  const auto top = validation::run_semi_infinite_crack(spec);
  std::printf("coarse D3 ramp gaussian: mean %.4f max %.4f\n", top.mean_rel_error,
              top.max_rel_error);
  EXPECT_LE(top.mean_rel_error, 0.15);
  spec.both_edges = true;
  const auto both = validation::run_semi_infinite_crack(spec);
  ASSERT_EQ(both.k_pd.size(), top.k_pd.size());
  for (std::size_t i = 0; i < top.k_pd.size(); ++i) {
    if (top.time[i] > top.first_reflection) break;
    // Exact superposition up to the geometric nonlinearity of Eq. (38) (strains ~5e-6): 2e-5.
    EXPECT_NEAR(both.k_pd[i], 2.0 * top.k_pd[i], 2e-5 * std::abs(both.k_pd[i]) + 1e-3)
        << "t = " << top.time[i];
  }
}

}  // namespace
}  // namespace peritwin

namespace peritwin {
namespace {

// Critical-stretch breaking with the crack tracker: a notched plate (30 × 20 mm, Δx = 0.5 mm,
// notch 8 mm at mid-height, s_c = 2e-3) with its bottom row fixed and a suddenly applied tension
// of 0.15 GPa on its top edge runs a crack from the notch (strain 7e-4 in the plane wave, below
// s_c even where it doubles on reflection from the fixed edge: only the notch's concentration
// breaks bonds). The tracker follows the tip; its mean speed from initiation must be positive and
// below the Rayleigh speed of the model's material (E, ν = 1/3 plane stress: c_s = √(3E/(8ρ)),
// c_R ≈ 0.918 c_s by Viktorov's (0.862 + 1.14ν')/(1 + ν') with the plane-strain-equivalent
// ν' = 1/4): no elastic crack outruns the surface wave that carries its energy (Freund 1990,
// Ch. 5). Initiation is known to the sampling interval (0.5 µs), late rather than early, so the
// measured mean speed errs high: the bound stays a fair test.
TEST(Dynamics, CrackRunsUnderTheRayleighSpeed) {
  mesh::Notch notch;
  notch.name = "notch";
  notch.path = {mesh::Point{-0.001, 0.01}, mesh::Point{0.008, 0.01}};
  // Bonds of the loaded (and fixed) rows and the four next to them never break (002 Sec. 7's
  // no-fail zones): the load row's own bonds stretch far more than the bulk as the wave starts.
  const mesh::Discretization disc = plate(0.03, 0.02, 0.5e-3, 3.0, {notch}, 5);
  std::vector<mesh::NodeIndex> bottom;
  dynamics::DynamicsSetup setup;
  setup.kernel = gaussian_kernel(2.0);
  setup.youngs_modulus = 210e9;
  setup.density = 8000;
  setup.time_step = 2e-8;
  setup.critical_stretch = 2e-3;
  auto made = dynamics::ExplicitDynamics::create(disc, setup);
  ASSERT_TRUE(made) << made.error().message();
  auto& dyn = *made.value();
  for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
    const double y = disc.position[static_cast<std::size_t>(k)].y;
    if (y > 0.02 - 0.5e-3) dyn.add_body_force(k, 0.0, 0.15e9 / 0.5e-3);
    if (y < 0.5e-3) bottom.push_back(k);
  }
  dyn.fix_nodes(bottom);
  dyn.set_load_history({dynamics::LoadHistory::Kind::step, 0.0});
  const auto n2 = static_cast<std::size_t>(2 * disc.num_nodes());
  dyn.set_initial_state(std::vector<double>(n2, 0.0), std::vector<double>(n2, 0.0));
  dynamics::DynamicCrackMonitor monitor(disc, {notch});
  double t_start = -1.0;
  for (int s = 0; s < 80; ++s) {
    dyn.step(25);
    const auto& tip = monitor.sample(dyn);
    if (t_start < 0 && tip.length > 0) t_start = tip.time;
    if (tip.tip.x > 0.025) break;
  }
  const auto& last = monitor.history().back();
  ASSERT_GT(t_start, 0.0) << "no crack grew; broken bonds " << dyn.broken_bonds();
  ASSERT_GT(last.length, 0.003) << "the crack did not run";
  EXPECT_GT(last.tip.x, 0.025);
  EXPECT_NEAR(last.tip.y, 0.01, 4e-3);  // mostly along the notch line (it wavers, as PD cracks do)
  const double c_s = std::sqrt(3.0 * 210e9 / 8.0 / 8000);
  const double nu = 0.25;
  const double c_r = (0.862 + 1.14 * nu) / (1 + nu) * c_s;  // 0.918 c_s
  const double mean_speed = last.length / (last.time - t_start);
  std::printf("crack: %.2f mm in %.2f us, mean %.0f m/s, c_R %.0f m/s\n", 1e3 * last.length,
              1e6 * (last.time - t_start), mean_speed, c_r);
  EXPECT_GT(mean_speed, 0.0);
  EXPECT_LT(mean_speed, c_r);
}

}  // namespace
}  // namespace peritwin
