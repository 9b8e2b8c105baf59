#include "solver/model/pd_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>

namespace peritwin::model {

namespace {
constexpr double pi = std::numbers::pi;

/// Strain energy density per squared isotropic strain, W_ccm/ε², of the plane model.
double isotropic_energy_coefficient(double e, double nu, PlaneCondition plane) {
  return plane == PlaneCondition::plane_stress ? e / (1.0 - nu)
                                               : e / ((1.0 + nu) * (1.0 - 2.0 * nu));
}

}  // namespace

core::Status validate(const Material& material, const ModelOptions& options) {
  if (!(material.youngs_modulus > 0)) return core::failure("material.youngs_modulus must be > 0");
  if (options.kind == ModelKind::state_based) {
    if (!(material.poisson_ratio > -1.0 && material.poisson_ratio < 0.5)) {
      return core::failure("material.poisson_ratio must lie in (-1, 0.5)");
    }
    if (options.kernel != Kernel::constant) {
      return core::failure(
          "model.kernel: the state-based constants of 000 Eq. (4) assume the constant kernel");
    }
  }
  if (material.fracture_toughness < 0)
    return core::failure("material.fracture_toughness must be >= 0");
  // Material scatter: σ_E < E/5 so that the clamped draw E − 4σ_E stays above E/5 > 0 (a node
  // with E_k <= 0 would make the stiffness indefinite).
  const double sd = material.youngs_modulus_std;
  if (!std::isfinite(sd) || sd < 0) {
    return core::failure("material.youngs_modulus_std must be finite and >= 0");
  }
  if (sd >= material.youngs_modulus / 5.0) {
    return core::failure(
        "material.youngs_modulus_std must be < E/5 (a draw clamped at E − 4σ stays > 0)");
  }
  return {};
}

std::vector<double> node_youngs_moduli(const Material& material, std::size_t num_nodes) {
  const double e = material.youngs_modulus;
  const double sd = material.youngs_modulus_std;
  if (!(sd > 0.0)) return {};
  // Decision: clamp (truncate) each draw to [E − 4σ, E + 4σ] rather than refuse it. validate()
  // refuses σ >= E/5, so E − 4σ > E/5 > 0 and no node can make the stiffness indefinite. A draw
  // below E − 5σ (the first non-positive E at σ = E/5) has probability 2.9e-7 per node, about once
  // in three builds of a million-node model; refusing a random draw would make a valid config
  // fail by chance. Beyond 4σ lie 6.3e-5 of the draws: the clamp leaves the mean (symmetric) and
  // lowers the standard deviation by 6e-5 relative (2∫_4^∞ (z² − 16)φ dz = 1.2e-4 of the variance).
  const double lo = e - 4.0 * sd;
  const double hi = e + 4.0 * sd;
  std::mt19937_64 gen(material.youngs_modulus_seed);
  constexpr double two_to_minus_53 = 0x1.0p-53;
  std::vector<double> moduli(num_nodes);
  for (std::size_t k = 0; k < num_nodes; ++k) {
    // Two uniforms from the top 53 bits: u1 in (0, 1] (log finite), u2 in [0, 1).
    const double u1 = static_cast<double>((gen() >> 11) + 1) * two_to_minus_53;
    const double u2 = static_cast<double>(gen() >> 11) * two_to_minus_53;
    const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * pi * u2);  // Box-Muller
    moduli[k] = std::clamp(e + sd * z, lo, hi);
  }
  return moduli;
}

double effective_poisson_ratio(const Material& material, const ModelOptions& options) {
  if (options.kind == ModelKind::state_based) return material.poisson_ratio;
  return options.plane == PlaneCondition::plane_stress ? 1.0 / 3.0 : 0.25;
}

double kernel_shape(Kernel kernel, double xi_over_delta) {
  switch (kernel) {
    case Kernel::constant:
      return 1.0;
    case Kernel::conical:  // 002 Eq. (4)
      return std::max(0.0, 1.0 - xi_over_delta);
    case Kernel::gaussian:  // 001 Eq. (31), p = 2
      return std::exp(-4.0 * xi_over_delta * xi_over_delta);
  }
  return 1.0;
}

double kernel_second_moment(Kernel kernel, double horizon) {
  const double d3 = horizon * horizon * horizon;
  switch (kernel) {
    case Kernel::constant:
      return d3 / 3.0;
    case Kernel::conical:
      return d3 / 12.0;
    case Kernel::gaussian: {
      // ∫_0^δ r² e^{-(pr/δ)²} dr = (δ/p)³ (√π erf(p)/4 − p e^{-p²}/2), p = 2.
      constexpr double p = 2.0;
      return d3 / (p * p * p) * (std::sqrt(pi) * std::erf(p) / 4.0 - p * std::exp(-p * p) / 2.0);
    }
  }
  return d3 / 3.0;
}

double bond_micromodulus(const Material& material, const ModelOptions& options, double horizon,
                         double thickness) {
  const double nu = effective_poisson_ratio(material, options);
  const double w = isotropic_energy_coefficient(material.youngs_modulus, nu, options.plane);
  return 2.0 * w / (pi * thickness * kernel_second_moment(options.kernel, horizon));
}

StateBasedConstants state_based_constants(const Material& material, PlaneCondition plane,
                                          double horizon, double thickness) {
  double e = material.youngs_modulus;
  double nu = material.poisson_ratio;
  if (plane == PlaneCondition::plane_strain) {
    e = e / (1.0 - nu * nu);
    nu = nu / (1.0 - nu);
  }
  StateBasedConstants c;
  c.a = e * thickness * (3.0 * nu - 1.0) / (4.0 * (1.0 - nu * nu));  // 000 Eq. (4a)
  c.b = 3.0 * e / ((1.0 + nu) * pi * horizon * horizon * horizon);   // 000 Eq. (4b)
  c.d = 2.0 / (pi * thickness * horizon * horizon);                  // 000 Eq. (4c)
  return c;
}

double stiff_rigid_index(const Material& material, const ModelOptions& options,
                         double rigid_factor) {
  double nu = material.poisson_ratio;
  if (options.plane == PlaneCondition::plane_strain) nu = nu / (1.0 - nu);
  return rigid_factor * (3.0 * nu - 1.0) / (1.0 - nu);
}

core::Status check_stiff_rigid_material(const Material& material, const ModelOptions& options,
                                        double rigid_factor) {
  if (options.kind != ModelKind::state_based) return {};
  const double index = stiff_rigid_index(material, options, rigid_factor);
  if (index >= kStiffRigidIndexLimit) return {};
  // The smallest ν this rigid_factor allows: rf·(3ν' − 1)/(1 − ν') = limit, ν' = ν/(1 − ν) in
  // plane strain.
  const double q = kStiffRigidIndexLimit / rigid_factor;
  double nu_min = (1.0 + q) / (3.0 + q);
  if (options.plane == PlaneCondition::plane_strain) nu_min = nu_min / (1.0 + nu_min);
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "rigid regions of stiff material (rigid_model = \"stiff_material\", E_rigid = "
                "%g·E) make the state-based stiffness indefinite at nu = %g (%s): "
                "rigid_factor·(3nu−1)/(1−nu) = %.3g is below %g, which needs nu >= %.4f; use "
                "rigid_model = \"constraint\" (the default), which holds for every nu",
                rigid_factor, material.poisson_ratio,
                options.plane == PlaneCondition::plane_strain ? "plane strain" : "plane stress",
                index, kStiffRigidIndexLimit, nu_min);
  return core::failure(buf);
}

PdModel build_model(const mesh::Discretization& disc, const Material& material,
                    const ModelOptions& options, double rigid_factor) {
  PdModel m;
  m.material = material;
  m.options = options;
  const bool osb = options.kind == ModelKind::state_based;
  const Kernel kernel = osb ? Kernel::constant : options.kernel;
  const double delta = disc.horizon;
  const double h = disc.thickness;
  const auto nb = static_cast<std::size_t>(disc.num_bonds());
  const auto nn = static_cast<std::size_t>(disc.num_nodes());

  // Surface (and lattice) correction, generalizing Madenci-Oterkus: every node k gets a
  // direction-dependent factor G_k(n) = A c⁴ + B s⁴ + 2C c²s² (n = (c, s)) chosen so that its
  // discrete family moments Σ w·G·c⁴, Σ w·G·s⁴, Σ w·G·c²s² equal the continuum ones over a full
  // horizon; these three moments are all the strain energy sees (uniaxial x, uniaxial y, shear),
  // so the interior reproduces E and ν exactly, which the x/y-only correction cannot on a square
  // lattice (3·Σc²s²/Σc⁴ = 1.007 for the families within δ = 3.015Δx, 0.949 if they reached
  // δ + Δx/2). The dilatation gets
  // G_k(n) = A' c² + B' s² matching Σ c² and Σ s². A bond takes the mean of its two nodes.
  std::vector<Eigen::Matrix3d> energy_moments(nn, Eigen::Matrix3d::Zero());
  std::vector<Eigen::Matrix2d> dil_moments(nn, Eigen::Matrix2d::Zero());
  for (std::size_t b = 0; b < nb; ++b) {
    const double xi = disc.bond_length[b];
    const double beta = disc.bond_volume_factor[b];
    const double c2 = disc.bond_cos[b] * disc.bond_cos[b];
    const double s2 = disc.bond_sin[b] * disc.bond_sin[b];
    const double w = beta * kernel_shape(kernel, xi / delta) * xi;
    // Row: moment (c⁴, s⁴, c²s²); column: the basis function (c⁴, s⁴, 2c²s²) of G.
    const Eigen::Vector3d modes(c2 * c2, s2 * s2, c2 * s2);
    const Eigen::Vector3d basis(c2 * c2, s2 * s2, 2.0 * c2 * s2);
    const Eigen::Vector2d dil(c2, s2);
    for (const auto k :
         {static_cast<std::size_t>(disc.bond_i[b]), static_cast<std::size_t>(disc.bond_j[b])}) {
      const double v = disc.volume[static_cast<std::size_t>(
          disc.other_end(static_cast<mesh::BondIndex>(b), static_cast<mesh::NodeIndex>(k)))];
      energy_moments[k] += w * v * modes * basis.transpose();
      dil_moments[k] += beta * v * dil * dil.transpose();
    }
  }
  const double energy_continuum = h * 0.75 * pi * kernel_second_moment(kernel, delta);
  const Eigen::Vector3d energy_target(energy_continuum, energy_continuum, energy_continuum / 3.0);
  const double dil_continuum = h * 0.5 * pi * delta * delta;
  std::vector<Eigen::Vector3d> energy_coef(nn, Eigen::Vector3d(1.0, 1.0, 1.0));
  std::vector<Eigen::Vector2d> dil_coef(nn, Eigen::Vector2d(1.0, 1.0));
  if (options.surface_correction) {
    for (std::size_t k = 0; k < nn; ++k) {
      const Eigen::Vector3d e = energy_moments[k].fullPivLu().solve(energy_target);
      // A corner node's moments can make the 3×3 fit meaningless; keep G positive in every
      // direction (checked on a fan of directions) or fall back to the x/y-only factors.
      bool positive = e.allFinite();
      for (int t = 0; positive && t <= 8; ++t) {
        const double ang = 0.5 * pi * t / 8.0;
        const double c2 = std::cos(ang) * std::cos(ang);
        const double s2 = 1.0 - c2;
        positive = e[0] * c2 * c2 + e[1] * s2 * s2 + 2.0 * e[2] * c2 * s2 > 0.05;
      }
      if (positive) {
        energy_coef[k] = e;
      } else {
        const double gx = energy_continuum / energy_moments[k](0, 0);
        const double gy = energy_continuum / energy_moments[k](1, 1);
        energy_coef[k] = Eigen::Vector3d(gx, gy, 0.5 * (gx + gy));
      }
      const Eigen::Vector2d dcoef =
          dil_moments[k].fullPivLu().solve(Eigen::Vector2d(dil_continuum, dil_continuum));
      if (dcoef.allFinite() && dcoef.minCoeff() > 0.05) dil_coef[k] = dcoef;
    }
  }
  auto energy_factor = [&](std::size_t k, double c2, double s2) {
    const auto& e = energy_coef[k];
    return e[0] * c2 * c2 + e[1] * s2 * s2 + 2.0 * e[2] * c2 * s2;
  };
  auto dilatation_factor = [&](std::size_t k, double c2, double s2) {
    return dil_coef[k][0] * c2 + dil_coef[k][1] * s2;
  };

  m.bond_stiffness.resize(nb);
  if (osb) {
    m.constants = state_based_constants(material, options.plane, delta, h);
    m.dilatation_weight.resize(nb);
  } else {
    m.micromodulus = bond_micromodulus(material, options, delta, h);
  }
  for (std::size_t b = 0; b < nb; ++b) {
    const auto i = static_cast<std::size_t>(disc.bond_i[b]);
    const auto j = static_cast<std::size_t>(disc.bond_j[b]);
    const double xi = disc.bond_length[b];
    const double beta = disc.bond_volume_factor[b];
    const double c = disc.bond_cos[b];
    const double s = disc.bond_sin[b];
    const double c2 = c * c;
    const double s2 = s * s;
    const double g_energy = 0.5 * (energy_factor(i, c2, s2) + energy_factor(j, c2, s2));
    const double rigid = disc.rigid[i] && disc.rigid[j] ? rigid_factor : 1.0;
    const double vv = disc.volume[i] * disc.volume[j];
    if (osb) {
      m.bond_stiffness[b] = rigid * 4.0 * m.constants.b * g_energy * beta * vv / (h * xi);
      const double g_dil = 0.5 * (dilatation_factor(i, c2, s2) + dilatation_factor(j, c2, s2));
      m.dilatation_weight[b] = m.constants.d * g_dil * beta * disc.volume[j];
    } else {
      const double micromodulus = m.micromodulus * kernel_shape(kernel, xi / delta);
      m.bond_stiffness[b] = rigid * micromodulus * g_energy * beta * vv / xi;
    }
  }
  if (osb) {
    m.dilatation_stiffness.resize(nn);
    for (std::size_t k = 0; k < nn; ++k) {
      const double rigid = disc.rigid[k] ? rigid_factor : 1.0;
      m.dilatation_stiffness[k] = rigid * 2.0 * m.constants.a * disc.volume[k] / h;
    }
  }
  // Material scatter (004): every coefficient above is linear in E (c ∝ E; a, b ∝ E through κ
  // and μ at fixed ν), so the local modulus enters as a factor on the uniform model, applied
  // after the surface correction, which is geometric. Without scatter nothing is touched: the
  // model is bit for bit the uniform one.
  m.node_youngs_modulus = node_youngs_moduli(material, nn);
  if (!m.node_youngs_modulus.empty()) {
    const double e = material.youngs_modulus;
    // Decision: a bond takes the arithmetic mean (E_i + E_j)/(2E). The strain energy is a sum
    // of point energies, each with its own point's constants (004 Eq. 5: W = ¼∫c s² ξ dV at
    // x), and a bond enters the energy of both its ends: the pair coefficient is then the mean
    // of the two points' coefficients, as the surface correction also averages its two
    // nodes' factors. The harmonic mean would treat the bond as two half-bars in series, which
    // is not how the PD energy is written; 004 does not say. The two differ by
    // (E_i − E_j)²/(2(E_i + E_j)), a relative 2.4e-4 on average at 193 ± 3 GPa.
    for (std::size_t b = 0; b < nb; ++b) {
      const auto i = static_cast<std::size_t>(disc.bond_i[b]);
      const auto j = static_cast<std::size_t>(disc.bond_j[b]);
      m.bond_stiffness[b] *= 0.5 * (m.node_youngs_modulus[i] + m.node_youngs_modulus[j]) / e;
    }
    // The dilatation term is a point's own energy a_k·θ_k²: E_k/E (000 Eq. 4a).
    for (std::size_t k = 0; k < m.dilatation_stiffness.size(); ++k) {
      m.dilatation_stiffness[k] *= m.node_youngs_modulus[k] / e;
    }
  }
  return m;
}

void bond_stretches(const mesh::Discretization& disc, const std::vector<double>& u,
                    std::vector<double>& stretch) {
  const auto nb = static_cast<std::size_t>(disc.num_bonds());
  stretch.resize(nb);
  for (std::size_t b = 0; b < nb; ++b) {
    const auto i = 2 * static_cast<std::size_t>(disc.bond_i[b]);
    const auto j = 2 * static_cast<std::size_t>(disc.bond_j[b]);
    stretch[b] = ((u[j] - u[i]) * disc.bond_cos[b] + (u[j + 1] - u[i + 1]) * disc.bond_sin[b]) /
                 disc.bond_length[b];  // 000 Eq. (3d)
  }
}

void dilatations(const mesh::Discretization& disc, const PdModel& model,
                 const std::vector<std::uint8_t>& intact, const std::vector<double>& stretch,
                 std::vector<double>& dilatation) {
  dilatation.assign(static_cast<std::size_t>(disc.num_nodes()), 0.0);
  if (model.options.kind != ModelKind::state_based) return;
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    if (!intact[b]) continue;
    const double q = model.dilatation_weight[b] * stretch[b];  // 000 Eq. (3c)
    dilatation[static_cast<std::size_t>(disc.bond_i[b])] += q;
    dilatation[static_cast<std::size_t>(disc.bond_j[b])] += q;
  }
}

void bond_energy_release_rates(const mesh::Discretization& disc, const PdModel& model,
                               const std::vector<double>& stretch,
                               const std::vector<double>& dilatation, std::vector<double>& g) {
  const auto nb = static_cast<std::size_t>(disc.num_bonds());
  g.resize(nb);
  const double h = disc.thickness;
  const bool osb = model.options.kind == ModelKind::state_based;
  const bool scatter = !model.node_youngs_modulus.empty();
  for (std::size_t b = 0; b < nb; ++b) {
    const auto i = static_cast<std::size_t>(disc.bond_i[b]);
    const auto j = static_cast<std::size_t>(disc.bond_j[b]);
    const double xi = disc.bond_length[b];
    const double vv = disc.volume[i] * disc.volume[j];
    // Force density per unit area as in 000 Eq. (3a): the pair term k_b·ξ·s·h/(V_i·V_j) ...
    double force = model.bond_stiffness[b] * xi * h * stretch[b] / vv;
    if (osb) {  // ... plus the dilatation term 2ad/ξ·(θ_i + θ_j) with the bond's weights.
      const double theta_sum = scatter
                                   ? (model.node_youngs_modulus[i] * dilatation[i] +
                                      model.node_youngs_modulus[j] * dilatation[j]) /
                                         model.material.youngs_modulus  // each node's a_k = a·E_k/E
                                   : dilatation[i] + dilatation[j];
      force +=
          2.0 * model.constants.a * model.dilatation_weight[b] / (disc.volume[j] * xi) * theta_sum;
    }
    g[b] = 0.5 * force * xi * stretch[b] * vv / (2.0 * disc.dx * h * h);  // 000 Eq. (31)
  }
}

void damage_index(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                  std::vector<double>& damage) {
  const auto nn = static_cast<std::size_t>(disc.num_nodes());
  damage.assign(nn, 0.0);
  for (std::size_t k = 0; k < nn; ++k) damage[k] = node_damage_index(disc, intact, k);
}

double node_damage_index(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                         std::size_t k) {
  double total = 0.0;
  double alive = 0.0;
  for (auto f = disc.family_offset[k]; f < disc.family_offset[k + 1]; ++f) {
    const auto b = static_cast<std::size_t>(disc.family_bonds[static_cast<std::size_t>(f)]);
    const double w = disc.bond_volume_factor[b] *
                     disc.volume[static_cast<std::size_t>(disc.other_end(
                         static_cast<mesh::BondIndex>(b), static_cast<mesh::NodeIndex>(k)))];
    total += w;
    if (intact[b]) alive += w;
  }
  return total > 0 ? 1.0 - alive / total : 0.0;  // 000 Eq. (13)
}

double straight_crack_face_damage(double horizon_ratio) {
  if (!(horizon_ratio >= 1.0) || !std::isfinite(horizon_ratio)) {
    throw std::invalid_argument("straight_crack_face_damage: horizon_ratio must be >= 1");
  }
  // A square of unit cells wide enough that the middle node's family lies inside, cut along
  // y = 0 (between two rows) from edge to edge.
  const double half = std::ceil(horizon_ratio) + 2.0;
  mesh::DetailGeometry plate;
  plate.outline.push_back(mesh::Rectangle{-half, -half, half, half});
  plate.notches.push_back({"split", {{-half - 1.0, 0.0}, {half + 1.0, 0.0}}});
  const mesh::Discretization disc = discretize(plate, 1.0, horizon_ratio);
  std::vector<std::uint8_t> intact(disc.bond_precut.size());
  for (std::size_t b = 0; b < intact.size(); ++b) intact[b] = disc.bond_precut[b] ? 0 : 1;
  std::vector<double> damage;
  damage_index(disc, intact, damage);
  return damage[static_cast<std::size_t>(disc.nearest_node({0.5, 0.5}))];
}

}  // namespace peritwin::model
