// Peridynamic material models in 2D: bond-based (constant, conical, Gaussian kernels; plane stress
// or plane strain) and linear ordinary state-based (000 Eq. 3-4). The model turns a discretization
// into per-bond and per-node stiffness coefficients; the static solver assembles them.
// Units: SI (Pa, m, N). Forces are total nodal forces (N): the force densities of 000 Eq. (3),
// which are per unit area of the plate, times the node's area Δx² (= V/h).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/expected.h"
#include "solver/mesh/discretization.h"

namespace peritwin::model {

enum class ModelKind { bond_based, state_based };
enum class Kernel { constant, conical, gaussian };
enum class PlaneCondition { plane_stress, plane_strain };

struct Material {
  double youngs_modulus = 0.0;      ///< E (Pa)
  double poisson_ratio = 0.0;       ///< ν (state-based only; bond-based fixes ν, see below)
  double fracture_toughness = 0.0;  ///< K_c (Pa·√m), 0 = not given
  /// G_c = K_c²/E (docs/benchmarks.md B1); 0 when K_c is not given.
  [[nodiscard]] double critical_energy_release_rate() const {
    return fracture_toughness * fracture_toughness / youngs_modulus;
  }
  /// Material scatter (004, "KTF symmetric cyclic loading model": E = 193 ± 3 GPa): the standard
  /// deviation σ_E (Pa) of a Young's modulus drawn per node from N(E, σ_E²), 0 = uniform E;
  /// build_model draws it (node_youngs_moduli). 0 <= σ_E < E/5 (validate).
  double youngs_modulus_std = 0.0;
  /// Seed of that draw: the same seed gives the same moduli, bit for bit.
  std::uint64_t youngs_modulus_seed = 0;
};

struct ModelOptions {
  ModelKind kind = ModelKind::state_based;
  Kernel kernel = Kernel::constant;  ///< bond-based only; state-based uses the constant kernel
  PlaneCondition plane = PlaneCondition::plane_stress;
  /// Madenci-Oterkus surface correction: scale every bond so that a node's discrete strain energy
  /// (and dilatation) under uniform uniaxial strain equals the continuum value, in x and in y.
  bool surface_correction = true;
};

/// OK, or a message naming the offending field.
core::Status validate(const Material& material, const ModelOptions& options);

/// The per-node Young's moduli E_k ~ N(E, σ_E²) of the material scatter (004), one per
/// node in node order; empty when σ_E = 0. Portable and deterministic per seed: std::mt19937_64
/// (fixed by the standard) seeded with youngs_modulus_seed, two uniforms per node from the 53-bit
/// mantissa, Box-Muller written out (z = √(−2 ln u1)·cos(2π u2)), never std::normal_distribution
/// (its algorithm differs between standard libraries). Each E_k is clamped to [E − 4σ_E,
/// E + 4σ_E], which with σ_E < E/5 keeps it above E/5 > 0 (docs/solver.md "Material scatter").
std::vector<double> node_youngs_moduli(const Material& material, std::size_t num_nodes);

/// Rigid regions of stiff material (000 Sec. 6.1, E_rigid = rigid_factor·E) in the state-based
/// model: the index rigid_factor·(κ − 2μ)/μ = rigid_factor·(3ν − 1)/(1 − ν) (2D κ = E/(2(1 − ν)),
/// μ = E/(2(1 + ν)); plane strain through E/(1 − ν²), ν/(1 − ν) as 000 Eq. 4). Below 0 the rigid
/// nodes' dilatation term (000 Eq. 4a's a < 0, times rigid_factor) also weighs the bonds into the
/// plate, whose pair terms are not stiffened: the stiffness turns indefinite. Measured on B1
/// (Δx = 1 mm, docs/solver.md "Rigid regions"): sound at −9.6, spurious bond breaks at −11.8, no
/// virgin solve at −14.9. The config refuses below kStiffRigidIndexLimit.
double stiff_rigid_index(const Material& material, const ModelOptions& options,
                         double rigid_factor);
inline constexpr double kStiffRigidIndexLimit = -6.0;
/// OK when stiff-material rigid regions are valid for this material and model (always for the
/// bond-based model, whose pair terms are all positive), else why not and what to use instead.
core::Status check_stiff_rigid_material(const Material& material, const ModelOptions& options,
                                        double rigid_factor);

/// Poisson's ratio the model actually represents: bond-based 2D fixes ν = 1/3 in plane stress and
/// ν = 1/4 in plane strain; state-based represents the material's ν.
double effective_poisson_ratio(const Material& material, const ModelOptions& options);

/// Kernel shape ω(ξ/δ) of the bond-based micromodulus c(ξ) = c0·ω.
double kernel_shape(Kernel kernel, double xi_over_delta);

/// ∫_0^δ ω(r/δ) r² dr, closed form per kernel.
double kernel_second_moment(Kernel kernel, double horizon);

/// Bond-based micromodulus c0 (N/m^6) from matching the strain energy density under isotropic
/// strain: (1/4)·c0·h·2π·∫ω r² dr = W_ccm/ε². Reproduces 001 Eq. (29)-(30) (Gaussian, p = 2),
/// 002 Eq. (4) (conical, plane strain) and c = 9E/(πhδ³) (constant, plane stress).
double bond_micromodulus(const Material& material, const ModelOptions& options, double horizon,
                         double thickness);

/// The a, b, d constants of 000 Eq. (4a)-(4c), with E and ν mapped to E/(1-ν²), ν/(1-ν) in plane
/// strain.
struct StateBasedConstants {
  double a = 0.0;
  double b = 0.0;
  double d = 0.0;
};
StateBasedConstants state_based_constants(const Material& material, PlaneCondition plane,
                                          double horizon, double thickness);

/// The model of one detail, ready for assembly. For every bond b between nodes i and j:
///   bond_stiffness[b]  k_b such that the pair force is k_b·ξ·s along the bond (N), i.e. the
///                      stiffness block k_b·e⊗e (BB: c·β·V_i·V_j/ξ; OSB b-term: 4b·β·V_i·V_j/(hξ))
///   dilatation_weight  q_b: θ_k = Σ_b q_b·s_b over k's family (000 Eq. 3c), OSB only
/// and for every node k (OSB only): dilatation_stiffness[k] = 2a·V_k/h, the coefficient of θ_k² in
/// the node's strain energy; the dilatation part of K is Bᵀ·diag(2a·V/h)·B with θ = B·u (000 App.
/// B). Broken bonds keep their coefficients here; the bond state lives with the solver.
/// With material scatter (Material::youngs_modulus_std > 0) every coefficient, being linear in E,
/// follows the local modulus: k_b times (E_i + E_j)/(2E), dilatation_stiffness[k] times E_k/E;
/// dilatation_weight is geometric and stays (docs/solver.md "Material scatter (004)").
struct PdModel {
  Material material;
  ModelOptions options;
  StateBasedConstants constants;  ///< OSB only
  double micromodulus = 0.0;      ///< BB only: c0
  std::vector<double> bond_stiffness;
  std::vector<double> dilatation_weight;
  std::vector<double> dilatation_stiffness;
  /// E_k (Pa) per node with material scatter, empty without (node_youngs_moduli).
  std::vector<double> node_youngs_modulus;
};

PdModel build_model(const mesh::Discretization& disc, const Material& material,
                    const ModelOptions& options, double rigid_factor);

/// Linearized bond stretch s = e·(u_j − u_i)/ξ (000 Eq. 3d); u interleaved [u0, v0, u1, v1, ...].
void bond_stretches(const mesh::Discretization& disc, const std::vector<double>& u,
                    std::vector<double>& stretch);

/// Node dilatation θ_k = Σ q_b ψ_b s_b (000 Eq. 3c); zero for the bond-based model.
void dilatations(const mesh::Discretization& disc, const PdModel& model,
                 const std::vector<std::uint8_t>& intact, const std::vector<double>& stretch,
                 std::vector<double>& dilatation);

/// Bond energy release rate ḡ (J/m²) of 000 Eq. (31), with the bond's force density written
/// with the same (corrected) coefficients the stiffness uses; for the bond-based model a = 0 and
/// 4b is the micromodulus c (000 Eq. 32 and the remark after it).
void bond_energy_release_rates(const mesh::Discretization& disc, const PdModel& model,
                               const std::vector<double>& stretch,
                               const std::vector<double>& dilatation, std::vector<double>& g);

/// Damage index (000 Eq. 13, weighted as damage_index does) of a node next to a long straight
/// crack between two rows of the regular grid, for δ = horizon_ratio·Δx: the value along a split,
/// which 000 Sec. 4.4 (Fig. 2) reads as 0.398 at δ = 3Δx. horizon_ratio >= 1.
double straight_crack_face_damage(double horizon_ratio);

/// Damage index φ_k = 1 − Σ ψ·β·V / Σ β·V over the family (000 Eq. 13).
void damage_index(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                  std::vector<double>& damage);
/// The same for one node k (damage_index computes every node with it: equal bits).
double node_damage_index(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                         std::size_t k);

}  // namespace peritwin::model
