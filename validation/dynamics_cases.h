// The dynamics benchmarks of paper 001 (peritwin-validate --case D1..D4, docs/validation.md) as
// functions the validation tool runs at the paper's resolution and the tests run coarse.
// D1: 1D bar released from a uniform stretch (001 Sec. 4.2, Eq. 53-56).
// D2: dispersion (Sec. 4.1, Eq. 44-51): lattice vs formula, and a wave packet's speed.
// D3: stationary semi-infinite crack under a ramp (Eq. 64-65) or step (Eq. 67) (Sec. 5.2.1).
// D4: mode II plate (Sec. 5.2.2).
// Units: SI.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "solver/dynamics/explicit_dynamics.h"

namespace peritwin::validation {

// ---- D1 ----------------------------------------------------------------------------------------

struct BarSpec {
  double length = 1.0;      ///< L (m)
  double density = 7850.0;  ///< ρ
  double youngs_modulus = 200e9;
  double area = 1e-6;    ///< A = 1 mm²
  double force = 200.0;  ///< F0 (N): u(x, 0) = F0 x/(EA) (Eq. 54)
  double dx = 1.25e-3;
  int m = 5;  ///< δ = mΔx = 6.25 mm
  double time_step = 1e-8;
  double transits = 2.0;  ///< simulate t in [0, transits·L/c]
  double probe_x = 0.5;   ///< where ε(t) is recorded (m)
  int sample_every = 100;
  dynamics::KernelChoice kernel;
  int threads = 1;
  bool lattice_calibrated = false;  ///< DynamicsSetup::lattice_calibrated
};

struct BarResult {
  std::vector<double> time, strain, exact;
  double rel_l2_error = 0.0;  ///< ‖ε − ε_exact‖₂ / ‖ε_exact‖₂ over the samples
  double max_abs_error_over_strain = 0.0;  ///< max |ε − ε_exact| / (F0/EA)
  /// The oscillation behind each jump, over the 50 µs after the exact arrival, per F0/EA: how far
  /// ε dips below 0 after the first (1 -> 0) and below −1 after the second (0 -> −1).
  double undershoot_first_jump = 0.0;
  double overshoot_second_jump = 0.0;
  double stable_time_step = 0.0;
  int nodes = 0;
  double wall_s = 0.0;
};

/// 001 Eq. (56) summed in closed form: the Fourier series is the d'Alembert square wave
/// ε = (F0/EA)·½[S(x − ct) + S(x + ct)], S the extension of 1 on (0, L) even about 0 (fixed end)
/// and odd about L (free end), period 4L. At a jump it returns the series' mean value.
double bar_exact_strain(double x, double t, double length, double wave_speed, double strain0);
/// 001 Eq. (56) literally, with `terms` terms (for checking the closed form).
double bar_exact_strain_series(double x, double t, double length, double wave_speed, double strain0,
                               int terms);

/// Fixed end: a layer of m image nodes at x < 0 holding u(−x) = −u(x) (the odd image of
/// u(0, t) = 0, Eq. 53); free end: the bar's PD surface (no nodes beyond L).
BarResult run_bar(const BarSpec& spec);

// ---- D2 ----------------------------------------------------------------------------------------

struct PacketSpec {
  double length = 2.0;
  double density = 7850.0;
  double youngs_modulus = 200e9;
  double area = 1e-6;
  double dx = 1.25e-3;
  int m = 5;
  double wave_number = 400.0;  ///< k0 (1/m) of the carrier
  double envelope = 0.04;      ///< Gaussian envelope σ (m)
  double start = 0.6;          ///< centre at t = 0 (m)
  double travel_time = 1.2e-4;
  double time_step = 2e-8;
  dynamics::KernelChoice kernel;
};

struct PacketResult {
  double measured_speed = 0.0;   ///< centroid of u² + (v/ω)² over the right-going packet
  double group_speed = 0.0;      ///< dω/dk of the formula (with the partial volumes) at k0
  double phase_speed = 0.0;      ///< ω/k
  double classical_speed = 0.0;  ///< √(E/ρ)
};
PacketResult run_packet(const PacketSpec& spec);

// ---- D3 ----------------------------------------------------------------------------------------

struct CrackSpec {
  double length = 10.0;      ///< L
  double half_height = 2.0;  ///< H (2H = 4 m)
  double crack = 5.0;        ///< a
  double youngs_modulus = 210e9;
  double density = 8000.0;
  double dx = 0.05;  ///< Δ
  double horizon_ratio = 3.0;
  double time_step = 5e-6;
  double stress = 1e6;  ///< σ0 (Pa): linear problem, the normalized K does not depend on it
  dynamics::LoadHistory loading{dynamics::LoadHistory::Kind::ramp, 3.36e-4};
  dynamics::KernelChoice kernel;
  int threads = 1;
  bool lattice_calibrated = false;
  /// false: σ(t) on the top edge only, one plane wave of amplitude σ0 meeting the crack: Freund's
  /// problem (the crack faces see the pressure σ0). true: on both edges, the two waves add at the
  /// crack line (pressure 2σ0) and K_I is twice Eq. (65)/(67) — compared with that doubled value.
  bool both_edges = false;
  /// Face-node distances behind the tip for Eq. (62) (m); NaN: δ + Δ/2 and 2δ + Δ/2 (the node
  /// columns at δ and 2δ behind the tip, the static solver's convention).
  double r1 = std::numeric_limits<double>::quiet_NaN();
  double r2 = std::numeric_limits<double>::quiet_NaN();
  double end_over_tc = 3.5;  ///< simulate to this many t_c
};

struct CrackResult {
  std::vector<double> time, k_pd, k_exact;  ///< K_I (Pa√m)
  double t_c = 0.0;                         ///< H/C_d
  double first_reflection = 0.0;            ///< 3 t_c: the tip's own wave back from the loaded edge
  double wave_speed = 0.0;                  ///< C_d of the model (plane stress, ν = 1/3)
  double mean_rel_error = 0.0;              ///< over 1.2 t_c <= t <= first_reflection
  double max_rel_error = 0.0;
  double r1 = 0.0, r2 = 0.0;
  int nodes = 0;
  double wall_s = 0.0;
};

/// Freund's K_I of a semi-infinite crack under a suddenly applied (Eq. 67) or ramped (Eq. 65)
/// traction, t the time since the start of loading, t_c the arrival at the tip; ν the
/// plane-strain Poisson ratio of the formula (for a plane stress body with ν_ps use ν_ps/(1+ν_ps)).
double freund_k_step(double stress, double wave_speed, double nu, double t, double t_c);
double freund_k_ramp(double stress, double wave_speed, double nu, double t, double t_c,
                     double rise_time);

CrackResult run_semi_infinite_crack(const CrackSpec& spec);

// ---- D4 ----------------------------------------------------------------------------------------

struct ShearPlateSpec {
  double length = 0.104;      ///< L
  double height = 0.040;      ///< H, the full height (see the .cpp)
  double half_crack = 0.012;  ///< a (2a = 24 mm)
  double youngs_modulus = 73.5e9;
  double density = 2450.0;
  double dx = 0.26e-3;
  double horizon_ratio = 3.0;
  double stress = 1e6;  ///< τ (Pa)
  double end_time = 30e-6;
  double time_step = 0.0;  ///< 0: 0.9 × the stable step
  int sample_every = 10;
  dynamics::KernelChoice kernel;
  int threads = 2;
};

struct ShearPlateResult {
  std::vector<double> time, k_ii_normalized;  ///< K_II/(τ√(πa)) at the right tip
  double peak = 0.0, peak_time = 0.0;
  double time_step = 0.0;
  int nodes = 0;
  double wall_s = 0.0;
};
ShearPlateResult run_shear_plate(const ShearPlateSpec& spec);

}  // namespace peritwin::validation
