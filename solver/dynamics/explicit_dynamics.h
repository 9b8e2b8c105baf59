// Explicit dynamics of bond-based peridynamics, paper 001: the discretized equation of motion
// (Eq. 35-39) integrated by the central difference scheme (Eq. 40-41) under the stable time step of
// Eq. (42)-(43), with the constant and the p-dependent Gaussian kernel (Eq. 9-10) and their
// micromoduli (Eq. 24-26, 29, 33), partial volumes (Eq. 36), a mass density, fixed nodes, image
// nodes (a mirrored boundary layer), body-force patterns under a time history (ramp of Eq. 64,
// step) and optional critical-stretch bond breaking.
//
// The same code runs 1D bars (nodes on the x axis, V = A·Δx, bar_discretization) and 2D plates
// (solver/mesh/discretize, V = Δx²·h): a "node" is a point of a Discretization either way.
//
// Determinism: a node's acceleration is the sum over its own family in the Discretization's
// family order (each bond evaluated once from each end), so the result of a step does not depend
// on how the nodes are split among threads: 1 and N threads give the same bits (no atomics, no
// reductions across threads).
//
// Units: SI (m, s, kg/m³, Pa, N). Body forces are force densities (N/m³).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/expected.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"

namespace peritwin::dynamics {

/// The kernel W̄(ξ, δ) of 001 Eq. (9) (constant) or Eq. (10) (Gaussian e^{-(pξ/δ)²}).
struct KernelChoice {
  enum class Shape { constant, gaussian } shape = Shape::gaussian;
  double p = 2.0;  ///< Gaussian only; the paper uses p = 1 and p = 2 (integers, Eq. 10)
  [[nodiscard]] std::string name() const;
};

/// W̄(ξ, δ) for ξ/δ <= 1 (001 Eq. 9-10); 0 beyond.
double kernel_weight(const KernelChoice& kernel, double xi_over_delta);

enum class Dimension { one, two };

/// Bond stiffness c0(δ) of 001: 1D Eq. (26) constant, Eq. (33) Gaussian (measure = A, the bar's
/// cross-section); 2D plane stress Eq. (24) constant, Eq. (29) Gaussian (measure = h, thickness).
/// 2D plane strain: Eq. (25) for the constant kernel; the paper gives no Gaussian plane-strain
/// formula, so we scale Eq. (29) by the same 16/15 that turns Eq. (24) into Eq. (25) (the
/// isotropic energy E/((1+ν)(1-2ν)) at ν = 1/4 over E/(1-ν) at ν = 1/3, kernel-independent).
double micromodulus(Dimension dimension, model::PlaneCondition plane, const KernelChoice& kernel,
                    double youngs_modulus, double horizon, double measure);

/// A 1D bar on the x axis as a Discretization: `count` nodes at x = x_first + i·Δx (y = 0),
/// volume A·Δx, every pair within δ bonded with its partial volume (001 Eq. 36), families in
/// increasing bond order. `thickness` holds the area A.
mesh::Discretization bar_discretization(double x_first, int count, double dx, double horizon,
                                        double area);

/// A load's time history g(t), multiplying a body-force pattern.
struct LoadHistory {
  enum class Kind { constant, step, ramp } kind = Kind::step;
  double rise_time = 0.0;  ///< t_d of the ramp (001 Eq. 64)
  /// step: 1 for t >= 0 (σ0·H(t)); ramp: t/t_d up to t_d, then 1 (Eq. 64); constant: 1.
  [[nodiscard]] double at(double t) const;
};

struct DynamicsSetup {
  Dimension dimension = Dimension::two;
  model::PlaneCondition plane = model::PlaneCondition::plane_stress;
  KernelChoice kernel;
  double youngs_modulus = 0.0;  ///< E (Pa)
  double density = 0.0;         ///< ρ (kg/m³)
  double time_step = 0.0;       ///< Δt (s); refused above the stable step of Eq. (42)
  int threads = 1;              ///< bond-force evaluation threads (>= 1)
  /// s_c: a bond whose stretch exceeds it breaks; 0 = never. Bonds touching a node of the
  /// Discretization's no-fail zones never break.
  double critical_stretch = 0.0;
  /// false: c0 of the paper (Eq. 24-33, from the continuum integral over the horizon). true: c0
  /// scaled so that an interior node's discrete family (the lattice sum with the partial volumes
  /// of Eq. 36) has the continuum's strain energy under isotropic strain, the same idea as the
  /// static model's surface correction. With δ = mΔx the sum and the integral differ by a few
  /// per cent for the Gaussian kernel (1D, m = 5, p = 2: 3.1 %), which shows as a wave speed
  /// 1.6 % low (docs/validation.md, D1). Not part of paper 001: off by default.
  bool lattice_calibrated = false;
};

/// The factor lattice_calibrated applies to c0: continuum energy over the discrete one of a full
/// interior family (integer offsets within δ on the grid of spacing Δx).
double lattice_calibration_factor(Dimension dimension, const KernelChoice& kernel, double dx,
                                  double horizon);

/// Energy of the central-difference state at step n (J).
///   kinetic  = ½ Σ m_i v_{n-½}·v_{n+½}, v_{n±½} the half-step velocities (u_{n+1} − u_n)/Δt and
///              (u_n − u_{n−1})/Δt: for a linear force this averaged kinetic energy plus the strain
///              energy at u_n is conserved exactly by Eq. (41) (the scheme's discrete energy; the
///              mean of the two half-step kinetic energies is not: it oscillates by O((ωΔt)²)).
///   strain   = Σ_bonds ½ c β V_i V_j ξ s² (001 Eq. 5, 15), s from Eq. (39).
///   external = −Σ_i V_i b_i(t_n)·u_i: the potential of the body forces at their current value.
struct Energy {
  double kinetic = 0.0;
  double strain = 0.0;
  double external = 0.0;
  [[nodiscard]] double total() const { return kinetic + strain + external; }
};

class ExplicitDynamics {
 public:
  /// Builds the per-entry coefficients (each bond stored from both ends) and checks Δt against
  /// stable_time_step(); an error names the limit. `disc` must outlive the integrator.
  static core::Expected<std::unique_ptr<ExplicitDynamics>> create(const mesh::Discretization& disc,
                                                                  const DynamicsSetup& setup);
  ~ExplicitDynamics();
  ExplicitDynamics(const ExplicitDynamics&) = delete;
  ExplicitDynamics& operator=(const ExplicitDynamics&) = delete;

  /// 001 Eq. (42)-(43) as printed: min over nodes of √(ρ / Σ_j V_j β_j c(ξ)/ξ); Δt above it is
  /// refused.
  [[nodiscard]] double stable_time_step() const { return stable_time_step_; }
  /// √2 × stable_time_step(): the von Neumann bound √(2ρ / Σ V_j C_ij) of the paper's source
  /// (Silling & Askari 2005), sufficient for stability (see the .cpp); informational.
  [[nodiscard]] double von_neumann_time_step() const;

  /// u0, v0 interleaved [x0, y0, x1, y1, ...] (size 2·nodes). Sets step 0; u_{−1} from the Taylor
  /// start u_{−1} = u0 − Δt v0 + ½Δt² a0, which makes Eq. (41)'s first step u1 = u0 + Δt v0 + ½Δt²
  /// a0.
  void set_initial_state(std::span<const double> u0, std::span<const double> v0);
  /// Configuration (fix_nodes, add_image_node, add_body_force, set_load_history) comes first,
  /// set_initial_state last: it computes a0 with them.
  /// These nodes keep the displacement set_initial_state gives them (zero velocity).
  void fix_nodes(std::span<const mesh::NodeIndex> nodes);
  /// After every step node `image` takes (sx·u_x, sy·u_y) of node `source` (a mirrored boundary
  /// layer: sx = −1 on a bar's fixed end gives the odd image of u(0, t) = 0).
  void add_image_node(mesh::NodeIndex image, mesh::NodeIndex source, double sx, double sy);
  /// Adds a body-force density pattern (N/m³ per node, interleaved) times history.at(t).
  /// All patterns share one history (set_load_history).
  void add_body_force(mesh::NodeIndex node, double bx, double by);
  void set_load_history(const LoadHistory& history) { history_ = history; }

  /// Advances `steps` steps of Eq. (41).
  void step(int steps = 1);

  [[nodiscard]] std::int64_t step_count() const { return step_; }
  [[nodiscard]] double time() const { return static_cast<double>(step_) * dt_; }
  /// Displacement at the current step (interleaved).
  [[nodiscard]] std::span<const double> displacement() const;
  /// (u_n − u_{n−1})/Δt, the velocity at t_{n−½} (interleaved, into `out`).
  void half_step_velocity(std::vector<double>& out) const;
  [[nodiscard]] Energy energy() const;
  /// Intact flag per bond of the Discretization (both ends agree: the stretch is the same bits).
  [[nodiscard]] std::vector<std::uint8_t> intact_bonds() const;
  [[nodiscard]] std::int64_t broken_bonds() const;
  /// Directed bond evaluations per step (2 × intact-or-not bonds): the benchmark's unit.
  [[nodiscard]] std::int64_t entries() const {
    return static_cast<std::int64_t>(neighbour_.size());
  }
  [[nodiscard]] int num_nodes() const { return nodes_; }
  /// ω² of a longitudinal plane wave e^{i(kx − ωt)} along x seen by node i's actual family in the
  /// linearized model: Σ_e coef_e (ξx/ξ)² (1 − cos kξx), coef_e = c β V_j/(ρ ξ) (001 Eq. 46-48
  /// summed over the entries the integrator uses).
  [[nodiscard]] double lattice_omega_squared(mesh::NodeIndex i, double k) const;

 private:
  ExplicitDynamics() = default;
  template <bool Breaking>
  void accelerate(int lo, int hi, const double* u, double load, double* a);
  void advance_range(int thread, int lo, int hi);

  const mesh::Discretization* disc_ = nullptr;
  DynamicsSetup setup_;
  int nodes_ = 0;
  double dt_ = 0.0;
  double c0_ = 0.0;
  double stable_time_step_ = 0.0;
  std::int64_t step_ = 0;

  // Per directed entry e of node i's family (CSR by node, in the Discretization's family order).
  std::vector<std::int32_t> offset_;
  std::vector<std::int32_t> neighbour_;
  std::vector<double> xi_x_, xi_y_, xi_;  ///< ξ = x_j − x_i and |ξ|
  std::vector<double> coef_;  ///< c(ξ)·β·V_j/(ρ ξ) (1/s² per unit stretch·m), 0 = broken
  std::vector<mesh::BondIndex> bond_of_;  ///< the Discretization bond of the entry
  std::vector<double> elongation_limit_;  ///< s_c·ξ, +inf near no-fail nodes (breaking only)
  std::vector<double> mass_;              ///< ρ V_i
  std::vector<double> body_;              ///< b/ρ per node (interleaved), m/s²
  std::vector<std::uint8_t> fixed_;
  std::vector<double> fixed_u_;
  struct Image {
    mesh::NodeIndex image, source;
    double sx, sy;
  };
  std::vector<Image> images_;
  LoadHistory history_{LoadHistory::Kind::constant, 0.0};

  // u_{n−1}, u_n, u_{n+1} rotate through three buffers.
  std::vector<double> buffer_[3];
  int current_ = 1;             ///< buffer of u_n; u_{n−1} is (current_ + 2) % 3
  std::vector<int> partition_;  ///< thread t owns nodes [partition_[t], partition_[t+1])
};

}  // namespace peritwin::dynamics
