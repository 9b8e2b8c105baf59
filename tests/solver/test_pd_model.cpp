#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <string>
#include <vector>

#include "solver/model/pd_model.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

constexpr double pi = std::numbers::pi;

TEST(Micromodulus, ConstantKernelPlaneStressIs9EOverPiHDelta3) {
  // Classical 2D bond-based constant: c = 9E/(πhδ³) for plane stress (ν = 1/3).
  const model::Material m{70e9, 0.0, 0.0};
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  const double delta = 0.003, h = 0.01;
  EXPECT_NEAR(model::bond_micromodulus(m, o, delta, h) /
                  (9 * m.youngs_modulus / (pi * h * delta * delta * delta)),
              1.0, 1e-14);
  o.plane = model::PlaneCondition::plane_strain;  // 48E/(5πhδ³) for ν = 1/4
  EXPECT_NEAR(model::bond_micromodulus(m, o, delta, h) /
                  (48 * m.youngs_modulus / (5 * pi * h * delta * delta * delta)),
              1.0, 1e-14);
}

TEST(Micromodulus, GaussianKernelMatchesBouaraquiaEq30) {
  const model::Material m{73.5e9, 0.0, 0.0};
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  o.kernel = model::Kernel::gaussian;
  const double delta = 0.00078, h = 0.001;
  const double e4 = std::exp(4.0);
  // 001 Eq. (30): c0 = 96 e⁴ E / ((e⁴ √π erf(2) − 4) h π δ³)
  const double expected = 96 * e4 * m.youngs_modulus /
                          ((e4 * std::sqrt(pi) * std::erf(2.0) - 4) * h * pi * std::pow(delta, 3));
  EXPECT_NEAR(model::bond_micromodulus(m, o, delta, h) / expected, 1.0, 1e-13);
}

TEST(Micromodulus, ConicalKernelPlaneStrainMatchesZhangBobaruEq4) {
  const model::Material m{205e9, 0.0, 0.0};
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;
  o.kernel = model::Kernel::conical;
  o.plane = model::PlaneCondition::plane_strain;
  const double delta = 0.001, h = 1.0, nu = 0.25;
  // 002 Eq. (4): c(ξ) = 24E/((1 − ν − 2ν²)πδ³)·(1 − ξ/δ), per unit thickness.
  const double expected =
      24 * m.youngs_modulus / ((1 - nu - 2 * nu * nu) * pi * std::pow(delta, 3));
  EXPECT_NEAR(model::bond_micromodulus(m, o, delta, h) / expected, 1.0, 1e-13);
  EXPECT_DOUBLE_EQ(model::kernel_shape(model::Kernel::conical, 0.25), 0.75);
}

TEST(StateBased, ConstantsAreNguyenEq4) {
  const model::Material m{68e9, 0.33, 0.0};
  const double delta = 0.0015, h = 0.01;
  const auto c = model::state_based_constants(m, model::PlaneCondition::plane_stress, delta, h);
  EXPECT_DOUBLE_EQ(c.a, 68e9 * h * (3 * 0.33 - 1) / (4 * (1 - 0.33 * 0.33)));   // 000 Eq. (4a)
  EXPECT_DOUBLE_EQ(c.b, 3 * 68e9 / ((1 + 0.33) * pi * delta * delta * delta));  // 000 Eq. (4b)
  EXPECT_DOUBLE_EQ(c.d, 2 / (pi * h * delta * delta));                          // 000 Eq. (4c)
  // Plane strain maps E → E/(1−ν²), ν → ν/(1−ν).
  const auto s = model::state_based_constants(m, model::PlaneCondition::plane_strain, delta, h);
  const double e = 68e9 / (1 - 0.33 * 0.33), nu = 0.33 / 0.67;
  EXPECT_NEAR(s.b / (3 * e / ((1 + nu) * pi * delta * delta * delta)), 1.0, 1e-14);
}

TEST(ModelValidation, RejectsImpossibleValues) {
  model::ModelOptions o;
  EXPECT_NE(core::message_of(validate(model::Material{0.0, 0.3, 0.0}, o)).find("youngs_modulus"),
            std::string::npos);
  EXPECT_NE(core::message_of(validate(model::Material{1e9, 0.5, 0.0}, o)).find("poisson_ratio"),
            std::string::npos);
  o.kernel = model::Kernel::gaussian;
  EXPECT_NE(core::message_of(validate(model::Material{1e9, 0.3, 0.0}, o)).find("kernel"),
            std::string::npos);
  o.kind = model::ModelKind::bond_based;
  EXPECT_EQ(core::message_of(validate(model::Material{1e9, 0.3, 0.0}, o)), "");
}

struct TensionCase {
  model::ModelKind kind;
  model::Kernel kernel;
  double nu;
  double grid_perturbation = 0.0;  ///< irregular node arrangement, fraction of Δx
};

/// e.g. "state_based_constant_nu330", "bond_based_constant_nu333_perturbed" (ν in thousandths).
std::string tension_case_name(const TensionCase& c) {
  return model_kind_name(c.kind) + "_" + kernel_name(c.kernel) + "_nu" +
         std::to_string(std::lround(1000 * c.nu)) + (c.grid_perturbation > 0 ? "_perturbed" : "");
}
void PrintTo(const TensionCase& c, std::ostream* os) { *os << tension_case_name(c); }

class UniformTension : public ::testing::TestWithParam<TensionCase> {};

TEST_P(UniformTension, InteriorStrainIsSigmaOverEAndContractionIsNu) {
  // B4: uniaxial stress σ in a plane-stress plate; interior strain (displacement gradient, more
  // than 2δ from every edge) within 1 % of σ/E, lateral contraction within 3 % of ν. On a
  // perturbed grid the moment correction makes each family's energy exact for an affine field,
  // yet the plate comes out 1.4 % softer at amplitude 0.2Δx (measured; presumably the irregular
  // nodes relaxing off the affine field): the tolerance on σ/E is 2 % there.
  const auto param = GetParam();
  const model::Material m{68e9, param.nu, 0.0};
  model::ModelOptions o;
  o.kind = param.kind;
  o.kernel = param.kernel;
  const double sigma = 50e6, dx = 0.0005;
  auto plate =
      testing::make_tension_plate(m, o, 0.04, 0.02, dx, sigma, {param.grid_perturbation, 7});
  statics::StaticSolver solver(plate.disc, plate.model, plate.supports, plate.loads);
  ASSERT_TRUE(solver.solve().ok());
  const auto [exx, eyy] = testing::interior_strains(
      plate.disc, solver.basis_displacement(statics::basis_constant), 2 * plate.disc.horizon + dx);
  const double nu = model::effective_poisson_ratio(m, o);
  EXPECT_NEAR(exx / (sigma / m.youngs_modulus), 1.0, param.grid_perturbation > 0 ? 0.02 : 0.01);
  EXPECT_NEAR(-eyy / exx / nu, 1.0, 0.03);
}

INSTANTIATE_TEST_SUITE_P(
    Models, UniformTension,
    ::testing::Values(
        TensionCase{model::ModelKind::state_based, model::Kernel::constant, 0.33},
        TensionCase{model::ModelKind::state_based, model::Kernel::constant, 0.25},
        TensionCase{model::ModelKind::bond_based, model::Kernel::constant, 1.0 / 3.0},
        TensionCase{model::ModelKind::bond_based, model::Kernel::conical, 1.0 / 3.0},
        TensionCase{model::ModelKind::bond_based, model::Kernel::gaussian, 1.0 / 3.0},
        // The per-node moment correction also holds E and ν on a perturbed grid.
        TensionCase{model::ModelKind::state_based, model::Kernel::constant, 0.33, 0.2},
        TensionCase{model::ModelKind::bond_based, model::Kernel::constant, 1.0 / 3.0, 0.2}),
    [](const ::testing::TestParamInfo<TensionCase>& p) { return tension_case_name(p.param); });

// Material scatter (004, "KTF symmetric cyclic loading model": E = 193 ± 3 GPa for 316L).
constexpr double kE316 = 193e9;
constexpr double kStd316 = 3e9;

model::Material scattered_316l(std::uint64_t seed, double std = kStd316) {
  model::Material m{kE316, 0.3, 0.0};
  m.youngs_modulus_std = std;
  m.youngs_modulus_seed = seed;
  return m;
}

TEST(MaterialScatter, SameSeedSameModuliOtherSeedOthers) {
  const auto a = model::node_youngs_moduli(scattered_316l(7), 1000);
  const auto b = model::node_youngs_moduli(scattered_316l(7), 1000);
  const auto c = model::node_youngs_moduli(scattered_316l(8), 1000);
  ASSERT_EQ(a.size(), 1000u);
  EXPECT_EQ(a, b);  // bit for bit
  std::size_t differ = 0;
  for (std::size_t k = 0; k < a.size(); ++k) differ += a[k] != c[k] ? 1 : 0;
  EXPECT_EQ(differ, a.size());  // independent draws: equal doubles have probability ~0
  // The draw depends on the node's place only: a longer model starts with the same moduli.
  const auto longer = model::node_youngs_moduli(scattered_316l(7), 1500);
  EXPECT_TRUE(std::equal(a.begin(), a.end(), longer.begin()));
  // No scatter, no moduli.
  EXPECT_TRUE(model::node_youngs_moduli(scattered_316l(7, 0.0), 1000).empty());
}

TEST(MaterialScatter, FirstDrawsArePinned) {
  // The draw is portable by construction (mt19937_64 is fixed by the standard, Box-Muller is
  // written out); pinning its first values catches a change of the algorithm. Regenerate only on
  // purpose: a change moves every scattered model and its checkpoints' signatures.
  const auto e = model::node_youngs_moduli(scattered_316l(0), 3);
  ASSERT_EQ(e.size(), 3u);
  // 1 Pa (5e-12 relative): libm's log and cos may differ in the last bits between platforms.
  const double expected[] = {198738413587.85297, 186761776281.28183, 196107180835.12204};
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(e[k], expected[k], 1.0) << "node " << k;
}

TEST(MaterialScatter, SampleMeanAndStandardDeviationAreTheConfiguredOnes) {
  // 40 000 nodes (a 200 × 200 grid through build_model): the sample mean of n independent
  // N(E, σ²) draws has standard error σ/√n, so |mean − E| < 4σ/√n fails with probability 6e-5;
  // the sample standard deviation has relative standard error 1/√(2n) = 0.35 %, so 2 % is > 5
  // of them; the 4σ clamp lowers it by 6e-5 relative (pd_model.cpp).
  mesh::DetailGeometry g;
  g.thickness = 0.001;
  g.outline = {mesh::Rectangle{0.0, 0.0, 0.2, 0.2}};
  const auto disc = discretize(g, 0.001, 3.015 * 0.001);
  ASSERT_EQ(disc.num_nodes(), 40000);
  model::ModelOptions o;
  const auto m = model::build_model(disc, scattered_316l(2024), o, 200.0);
  const auto& e = m.node_youngs_modulus;
  ASSERT_EQ(e.size(), 40000u);
  const double n = static_cast<double>(e.size());
  double sum = 0.0;
  for (double v : e) sum += v;
  const double mean = sum / n;
  double ss = 0.0;
  for (double v : e) ss += (v - mean) * (v - mean);
  const double sd = std::sqrt(ss / (n - 1.0));
  EXPECT_LT(std::abs(mean - kE316), 4.0 * kStd316 / std::sqrt(n)) << mean;
  EXPECT_NEAR(sd / kStd316, 1.0, 0.02) << sd;
  // Clamped to E ± 4σ, so every E_k > 0.
  const auto [lo, hi] = std::minmax_element(e.begin(), e.end());
  EXPECT_GE(*lo, kE316 - 4.0 * kStd316);
  EXPECT_LE(*hi, kE316 + 4.0 * kStd316);
}

class ScatterModel : public ::testing::TestWithParam<model::ModelKind> {};

TEST_P(ScatterModel, ZeroStdIsTheUniformModelBitForBit) {
  // E_std = 0 with any seed builds exactly today's model.
  model::ModelOptions o;
  o.kind = GetParam();
  auto uniform =
      testing::make_tension_plate(model::Material{kE316, 0.3, 0.0}, o, 0.02, 0.01, 0.0005, 1e6);
  auto zero = testing::make_tension_plate(scattered_316l(99, 0.0), o, 0.02, 0.01, 0.0005, 1e6);
  EXPECT_TRUE(zero.model.node_youngs_modulus.empty());
  EXPECT_EQ(zero.model.bond_stiffness, uniform.model.bond_stiffness);
  EXPECT_EQ(zero.model.dilatation_weight, uniform.model.dilatation_weight);
  EXPECT_EQ(zero.model.dilatation_stiffness, uniform.model.dilatation_stiffness);
  EXPECT_EQ(zero.model.micromodulus, uniform.model.micromodulus);
}

TEST_P(ScatterModel, CoefficientsFollowTheLocalModulus) {
  // k_b × (E_i + E_j)/(2E), dilatation_stiffness[k] × E_k/E, dilatation_weight unchanged.
  model::ModelOptions o;
  o.kind = GetParam();
  auto uniform =
      testing::make_tension_plate(model::Material{kE316, 0.3, 0.0}, o, 0.02, 0.01, 0.0005, 1e6);
  auto scatter = testing::make_tension_plate(scattered_316l(5), o, 0.02, 0.01, 0.0005, 1e6);
  const auto& e = scatter.model.node_youngs_modulus;
  ASSERT_EQ(e.size(), static_cast<std::size_t>(scatter.disc.num_nodes()));
  for (std::size_t b = 0; b < uniform.model.bond_stiffness.size(); ++b) {
    const auto i = static_cast<std::size_t>(scatter.disc.bond_i[b]);
    const auto j = static_cast<std::size_t>(scatter.disc.bond_j[b]);
    EXPECT_NEAR(scatter.model.bond_stiffness[b] / uniform.model.bond_stiffness[b],
                0.5 * (e[i] + e[j]) / kE316, 1e-14)
        << "bond " << b;
  }
  EXPECT_EQ(scatter.model.dilatation_weight, uniform.model.dilatation_weight);
  ASSERT_EQ(scatter.model.dilatation_stiffness.size(), uniform.model.dilatation_stiffness.size());
  for (std::size_t k = 0; k < uniform.model.dilatation_stiffness.size(); ++k) {
    EXPECT_NEAR(scatter.model.dilatation_stiffness[k] / uniform.model.dilatation_stiffness[k],
                e[k] / kE316, 1e-14)
        << "node " << k;
  }
}

/// Largest stretch over bonds with both ends more than `margin` from every edge, and its bond.
std::pair<double, std::size_t> largest_interior_stretch(const mesh::Discretization& d,
                                                        const std::vector<double>& stretch,
                                                        double margin) {
  auto inside = [&](mesh::NodeIndex k) {
    const mesh::Point p = d.position[static_cast<std::size_t>(k)];
    return p.x > d.box.x_min + margin && p.x < d.box.x_max - margin && p.y > d.box.y_min + margin &&
           p.y < d.box.y_max - margin;
  };
  double largest = -std::numeric_limits<double>::infinity();
  std::size_t at = 0;
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    if (!inside(d.bond_i[b]) || !inside(d.bond_j[b])) continue;
    if (stretch[b] > largest) {
      largest = stretch[b];
      at = b;
    }
  }
  return {largest, at};
}

TEST_P(ScatterModel, TensionStripKeepsItsModulusAndLocalizesTheStretch) {
  // A 40 × 20 mm strip (81 × 41 nodes) of 316L, 193 ± 3 GPa (004), in uniaxial tension σ.
  // Far field: the interior strain gradient averages ~2000 independent node perturbations of
  // relative size σ_E/E = 1.6 %; the mean of E_k is E to 1.6 %/√2000 = 0.03 % and the effective
  // modulus of a random medium lies between the harmonic and arithmetic means of E_k, which
  // differ by (σ_E/E)² = 2.4e-4 relative: within 1 % of E (the uniform strip itself is within
  // 1 %, UniformTension).
  model::ModelOptions o;
  o.kind = GetParam();
  const model::Material uniform_material{kE316, 0.3, 0.0};
  const double sigma = 100e6, dx = 0.0005;
  const auto uniform = testing::make_tension_plate(uniform_material, o, 0.04, 0.02, dx, sigma);
  const auto scatter = testing::make_tension_plate(scattered_316l(11), o, 0.04, 0.02, dx, sigma);
  statics::StaticSolver su(uniform.disc, uniform.model, uniform.supports, uniform.loads);
  statics::StaticSolver ss(scatter.disc, scatter.model, scatter.supports, scatter.loads);
  ASSERT_TRUE(su.solve().ok());
  ASSERT_TRUE(ss.solve().ok());
  const auto& uu = su.basis_displacement(statics::basis_constant);
  const auto& us = ss.basis_displacement(statics::basis_constant);
  const double margin = 2 * uniform.disc.horizon + dx;
  const double exx_u = testing::interior_strains(uniform.disc, uu, margin).first;
  const double exx_s = testing::interior_strains(scatter.disc, us, margin).first;
  EXPECT_NEAR(sigma / exx_s / kE316, 1.0, 0.01);
  EXPECT_NEAR(exx_s / exx_u, 1.0, 0.01);

  // The scatter localizes: in the uniform strip's interior every bond of one direction has the
  // same stretch; with scatter the largest interior stretch is larger, at a soft spot.
  std::vector<double> stretch_u, stretch_s;
  model::bond_stretches(uniform.disc, uu, stretch_u);
  model::bond_stretches(scatter.disc, us, stretch_s);
  const double max_u = largest_interior_stretch(uniform.disc, stretch_u, margin).first;
  const auto [max_s, bond_s] = largest_interior_stretch(scatter.disc, stretch_s, margin);
  const auto& e = scatter.model.node_youngs_modulus;
  const double e_bond = 0.5 * (e[static_cast<std::size_t>(scatter.disc.bond_i[bond_s])] +
                               e[static_cast<std::size_t>(scatter.disc.bond_j[bond_s])]);
  // Measured (seed 11): 1.0113 × the uniform largest in both models, at a bond whose ends
  // average 0.984·E. Required: more than 0.5 % larger (a third of σ_E/E), at a softer-than-E bond.
  EXPECT_GT(max_s / max_u, 1.005) << max_s << " vs " << max_u;
  EXPECT_LT(e_bond, kE316);
}

TEST_P(ScatterModel, EnergyReleaseRateFollowsTheLocalModulus) {
  // Under a homogeneous strain every interior bond's stretch and both its ends' dilatations are
  // those of the uniform model, so its ḡ (000 Eq. 31, pair term and each end's a_k·θ_k) scales
  // by (E_i + E_j)/(2E) exactly as its stiffness does.
  model::ModelOptions o;
  o.kind = GetParam();
  const auto uniform =
      testing::make_tension_plate(model::Material{kE316, 0.3, 0.0}, o, 0.02, 0.01, 0.0005, 1e6);
  const auto scatter = testing::make_tension_plate(scattered_316l(3), o, 0.02, 0.01, 0.0005, 1e6);
  const auto& d = uniform.disc;
  std::vector<double> u(2 * static_cast<std::size_t>(d.num_nodes()));
  for (std::size_t k = 0; k < u.size() / 2; ++k) {
    u[2 * k] = 1e-3 * d.position[k].x;
    u[2 * k + 1] = -3e-4 * d.position[k].y;
  }
  const std::vector<std::uint8_t> intact(static_cast<std::size_t>(d.num_bonds()), 1);
  std::vector<double> stretch, theta_u, theta_s, g_u, g_s;
  model::bond_stretches(d, u, stretch);
  model::dilatations(d, uniform.model, intact, stretch, theta_u);
  model::dilatations(d, scatter.model, intact, stretch, theta_s);
  EXPECT_EQ(theta_u, theta_s);  // dilatation_weight is geometric
  model::bond_energy_release_rates(d, uniform.model, stretch, theta_u, g_u);
  model::bond_energy_release_rates(d, scatter.model, stretch, theta_s, g_s);
  const auto& e = scatter.model.node_youngs_modulus;
  const double margin = 2 * d.horizon + d.dx;
  double g_max = 0.0;
  for (double g : g_u) g_max = std::max(g_max, std::abs(g));
  std::size_t checked = 0;
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    const auto i = static_cast<std::size_t>(d.bond_i[b]);
    const auto j = static_cast<std::size_t>(d.bond_j[b]);
    const auto inside = [&](std::size_t k) {
      const mesh::Point p = d.position[k];
      return p.x > d.box.x_min + margin && p.x < d.box.x_max - margin &&
             p.y > d.box.y_min + margin && p.y < d.box.y_max - margin;
    };
    if (!inside(i) || !inside(j) || std::abs(g_u[b]) < 1e-6 * g_max) continue;  // ḡ ≈ 0
    ++checked;
    EXPECT_NEAR(g_s[b] / g_u[b], 0.5 * (e[i] + e[j]) / kE316, 1e-9) << "bond " << b;
  }
  EXPECT_GT(checked, 1000u);
}

INSTANTIATE_TEST_SUITE_P(Models, ScatterModel,
                         ::testing::Values(model::ModelKind::state_based,
                                           model::ModelKind::bond_based),
                         testing::model_kind_param_name);

TEST(MaterialScatter, ValidationNamesTheField) {
  const model::ModelOptions o;
  for (const double bad : {-1.0, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity(), kE316 / 5.0, kE316}) {
    const std::string why = core::message_of(validate(scattered_316l(1, bad), o));
    EXPECT_NE(why.find("youngs_modulus_std"), std::string::npos) << bad << ": " << why;
  }
  EXPECT_EQ(core::message_of(validate(scattered_316l(1, kE316 / 5.0 * 0.999), o)), "");
  EXPECT_EQ(core::message_of(validate(scattered_316l(1, 0.0), o)), "");
}

}  // namespace
}  // namespace peritwin
