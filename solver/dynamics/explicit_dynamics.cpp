#include "solver/dynamics/explicit_dynamics.h"

#include <algorithm>
#include <barrier>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <thread>

namespace peritwin::dynamics {

namespace {
constexpr double pi = std::numbers::pi;
}  // namespace

std::string KernelChoice::name() const {
  if (shape == Shape::constant) return "constant";
  char text[32];
  std::snprintf(text, sizeof text, "gaussian p=%g", p);
  return text;
}

double kernel_weight(const KernelChoice& kernel, double xi_over_delta) {
  if (xi_over_delta > 1.0) return 0.0;
  if (kernel.shape == KernelChoice::Shape::constant) return 1.0;  // 001 Eq. (9)
  const double a = kernel.p * xi_over_delta;
  return std::exp(-a * a);  // 001 Eq. (10)
}

double micromodulus(Dimension dimension, model::PlaneCondition plane, const KernelChoice& kernel,
                    double youngs_modulus, double horizon, double measure) {
  const double e = youngs_modulus;
  const double d = horizon;
  const bool gaussian = kernel.shape == KernelChoice::Shape::gaussian;
  const double p = kernel.p;
  if (dimension == Dimension::one) {
    const double c0 = 2.0 * e / (measure * d * d);                 // 001 Eq. (26)
    return gaussian ? c0 * p * p / (1.0 - std::exp(-p * p)) : c0;  // 001 Eq. (33)
  }
  double c0 = 0.0;
  if (gaussian) {
    // 001 Eq. (29)
    c0 = 12.0 * e / (measure * pi * d * d * d) * p * p * p /
         (std::sqrt(pi) * std::erf(p) - 2.0 * p * std::exp(-p * p));
  } else {
    c0 = 9.0 * e / (measure * pi * d * d * d);  // 001 Eq. (24)
  }
  // Plane strain: Eq. (25) = Eq. (24)·16/15; the same ratio for the Gaussian (see header).
  return plane == model::PlaneCondition::plane_strain ? c0 * 16.0 / 15.0 : c0;
}

mesh::Discretization bar_discretization(double x_first, int count, double dx, double horizon,
                                        double area) {
  assert(count > 0 && dx > 0 && horizon >= dx);
  mesh::Discretization d;
  d.dx = dx;
  d.horizon = horizon;
  d.thickness = area;
  d.box = mesh::Rectangle{x_first - 0.5 * dx, -0.5 * dx, x_first + (count - 0.5) * dx, 0.5 * dx};
  const auto n = static_cast<std::size_t>(count);
  d.position.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    d.position[i] = mesh::Point{x_first + static_cast<double>(i) * dx, 0.0};
  }
  d.volume.assign(n, area * dx);
  d.rigid.assign(n, 0);
  d.no_fail.assign(n, 0);
  // Pairs j − i = 1..m with m·Δx <= δ (up to rounding of δ/Δx).
  const int m = static_cast<int>(std::floor(horizon / dx + 1e-9));
  for (int i = 0; i < count; ++i) {
    for (int k = 1; k <= m && i + k < count; ++k) {
      const double length = k * dx;
      d.bond_i.push_back(i);
      d.bond_j.push_back(i + k);
      d.bond_length.push_back(length);
      d.bond_cos.push_back(1.0);
      d.bond_sin.push_back(0.0);
      // 001 Eq. (36); the outermost bond (ξ = δ) gets ½ when δ is a multiple of Δx.
      d.bond_volume_factor.push_back(
          mesh::partial_volume_factor(std::min(length, horizon), horizon, dx));
      d.bond_precut.push_back(0);
    }
  }
  d.family_offset.assign(n + 1, 0);
  for (mesh::BondIndex b = 0; b < d.num_bonds(); ++b) {
    ++d.family_offset[static_cast<std::size_t>(d.bond_i[static_cast<std::size_t>(b)]) + 1];
    ++d.family_offset[static_cast<std::size_t>(d.bond_j[static_cast<std::size_t>(b)]) + 1];
  }
  for (std::size_t k = 0; k < n; ++k) d.family_offset[k + 1] += d.family_offset[k];
  d.family_bonds.resize(static_cast<std::size_t>(d.family_offset[n]));
  std::vector<std::int32_t> cursor(d.family_offset.begin(), d.family_offset.end() - 1);
  for (mesh::BondIndex b = 0; b < d.num_bonds(); ++b) {
    const auto bi = static_cast<std::size_t>(b);
    d.family_bonds[static_cast<std::size_t>(cursor[static_cast<std::size_t>(d.bond_i[bi])]++)] = b;
    d.family_bonds[static_cast<std::size_t>(cursor[static_cast<std::size_t>(d.bond_j[bi])]++)] = b;
  }
  return d;
}

double LoadHistory::at(double t) const {
  switch (kind) {
    case Kind::constant:
      return 1.0;
    case Kind::step:
      return t >= 0.0 ? 1.0 : 0.0;
    case Kind::ramp:  // 001 Eq. (64)
      if (t <= 0.0) return 0.0;
      return t >= rise_time ? 1.0 : t / rise_time;
  }
  return 1.0;
}

double lattice_calibration_factor(Dimension dimension, const KernelChoice& kernel, double dx,
                                  double horizon) {
  // Isotropic strain ε: every bond has s = ε, the node's energy density is ¼ Σ_j c β V_j ξ ε² with
  // c = c0 W̄ (001 Eq. 15 discretized as Eq. 35), V_j = Δx^dim per unit measure. The continuum
  // value is the same expression with the sum replaced by the integral that defined c0, i.e.
  // ¼ c0 ∫ W̄ ξ dV: compare the two sums directly (c0 cancels).
  const int reach = static_cast<int>(std::ceil(horizon / dx)) + 1;
  double discrete = 0.0;
  const int rows = dimension == Dimension::one ? 0 : reach;
  for (int dj = -rows; dj <= rows; ++dj) {
    for (int di = -reach; di <= reach; ++di) {
      if (di == 0 && dj == 0) continue;
      const double xi = dx * std::hypot(static_cast<double>(di), static_cast<double>(dj));
      if (xi > horizon * (1.0 + 1e-12)) continue;  // the families of discretize()
      const double volume = dimension == Dimension::one ? dx : dx * dx;
      discrete += kernel_weight(kernel, std::min(1.0, xi / horizon)) *
                  mesh::partial_volume_factor(std::min(xi, horizon), horizon, dx) * volume * xi;
    }
  }
  // ∫ W̄(ξ) ξ dV over the horizon: 1D 2∫_0^δ W̄ ξ dξ, 2D 2π∫_0^δ W̄ ξ² dξ (numerically, fine
  // Simpson: the kernels are smooth on [0, δ]).
  const int n = 20000;
  double integral = 0.0;
  for (int k = 0; k <= n; ++k) {
    const double xi = horizon * k / n;
    const double w = (k == 0 || k == n) ? 1.0 : (k % 2 ? 4.0 : 2.0);
    const double f = dimension == Dimension::one
                         ? 2.0 * kernel_weight(kernel, xi / horizon) * xi
                         : 2.0 * pi * kernel_weight(kernel, xi / horizon) * xi * xi;
    integral += w * f;
  }
  integral *= horizon / n / 3.0;
  return integral / discrete;
}

ExplicitDynamics::~ExplicitDynamics() = default;

core::Expected<std::unique_ptr<ExplicitDynamics>> ExplicitDynamics::create(
    const mesh::Discretization& disc, const DynamicsSetup& setup) {
  if (!(setup.youngs_modulus > 0)) return core::Error{"youngs_modulus", "must be > 0"};
  if (!(setup.density > 0)) return core::Error{"density", "must be > 0"};
  if (!(setup.time_step > 0)) return core::Error{"time_step", "must be > 0"};
  if (setup.threads < 1) return core::Error{"threads", "must be >= 1"};
  if (setup.kernel.shape == KernelChoice::Shape::gaussian && !(setup.kernel.p > 0)) {
    return core::Error{"kernel.p", "must be > 0"};
  }
  if (setup.critical_stretch < 0)
    return core::Error{"critical_stretch", "must be >= 0 (0: no breaking)"};
  std::unique_ptr<ExplicitDynamics> d(new ExplicitDynamics());
  d->disc_ = &disc;
  d->setup_ = setup;
  d->nodes_ = disc.num_nodes();
  d->dt_ = setup.time_step;
  d->c0_ = micromodulus(setup.dimension, setup.plane, setup.kernel, setup.youngs_modulus,
                        disc.horizon, disc.thickness);
  if (setup.lattice_calibrated) {
    d->c0_ *= lattice_calibration_factor(setup.dimension, setup.kernel, disc.dx, disc.horizon);
  }
  const auto n = static_cast<std::size_t>(d->nodes_);
  d->offset_.assign(disc.family_offset.begin(), disc.family_offset.end());
  const auto ne = static_cast<std::size_t>(disc.family_offset[n]);
  d->neighbour_.resize(ne);
  d->xi_x_.resize(ne);
  d->xi_y_.resize(ne);
  d->xi_.resize(ne);
  d->coef_.resize(ne);
  d->bond_of_.resize(ne);
  d->mass_.resize(n);
  double min_step = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    d->mass_[i] = setup.density * disc.volume[i];
    double sum = 0.0;  // Σ_j V_j β c(ξ)/(ρ ξ) over the family (Eq. 42-43 divided by ρ)
    for (auto e = static_cast<std::size_t>(disc.family_offset[i]);
         e < static_cast<std::size_t>(disc.family_offset[i + 1]); ++e) {
      const mesh::BondIndex b = disc.family_bonds[e];
      const auto bi = static_cast<std::size_t>(b);
      const mesh::NodeIndex j = disc.other_end(b, static_cast<mesh::NodeIndex>(i));
      const auto ju = static_cast<std::size_t>(j);
      const double xi = disc.bond_length[bi];
      d->neighbour_[e] = j;
      d->bond_of_[e] = b;
      d->xi_x_[e] = disc.position[ju].x - disc.position[i].x;
      d->xi_y_[e] = disc.position[ju].y - disc.position[i].y;
      d->xi_[e] = xi;
      const double c = d->c0_ * kernel_weight(setup.kernel, xi / disc.horizon);  // Eq. (8)
      const double coef = c * disc.bond_volume_factor[bi] * disc.volume[ju] / (setup.density * xi);
      d->coef_[e] = disc.bond_precut[bi] ? 0.0 : coef;
      sum += d->coef_[e];
    }
    // 001 Eq. (42) as printed: Δt_cr = √(ρ / Σ V_j C_ij), the smallest over the nodes. The von
    // Neumann analysis it cites (Silling & Askari 2005, its ref. [24]) gives √(2ρ / Σ V_j C_ij):
    // the highest lattice frequency is ω² = max_k Σ (V_j C_ij/ρ)(1 − cos kξ) <= 2 Σ V_j C_ij/ρ
    // and central differences are stable for ωΔt <= 2. We refuse above the printed (√2 smaller,
    // more conservative) value, as the brief and the paper say; the paper's own steps respect it
    // (D1: 1e-8 s against 4.2e-7 s constant, 2.8e-7 s Gaussian; D3 Gaussian: 5e-6 s against
    // 5.64e-6 s).
    // von_neumann_time_step() reports the larger bound.
    if (sum > 0) min_step = std::min(min_step, std::sqrt(1.0 / sum));
  }
  d->stable_time_step_ = min_step;
  if (setup.critical_stretch > 0) {
    // Breaking compares the elongation l − ξ with s_c·ξ; a bond touching a no-fail node (the
    // geometry's no-fail zones, 002 Sec. 7: load rows) gets an infinite limit.
    d->elongation_limit_.resize(ne);
    for (std::size_t e = 0; e < ne; ++e) {
      const auto b = static_cast<std::size_t>(d->bond_of_[e]);
      const bool no_fail = disc.no_fail[static_cast<std::size_t>(disc.bond_i[b])] ||
                           disc.no_fail[static_cast<std::size_t>(disc.bond_j[b])];
      d->elongation_limit_[e] =
          no_fail ? std::numeric_limits<double>::infinity() : setup.critical_stretch * d->xi_[e];
    }
  }
  if (setup.time_step > min_step) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "%.6g s exceeds the stable time step %.6g s of 001 Eq. (42)-(43) "
                  "(sqrt(rho / sum V_j C_ij), the smallest over the nodes)",
                  setup.time_step, min_step);
    return core::Error{"time_step", text};
  }
  d->body_.assign(2 * n, 0.0);
  d->fixed_.assign(n, 0);
  d->fixed_u_.assign(2 * n, 0.0);
  for (auto& b : d->buffer_) b.assign(2 * n, 0.0);
  // Threads own contiguous node ranges with about equal numbers of entries.
  const int threads = std::max(1, std::min(setup.threads, d->nodes_));
  d->partition_.assign(static_cast<std::size_t>(threads) + 1, d->nodes_);
  d->partition_[0] = 0;
  int node = 0;
  for (int t = 1; t < threads; ++t) {
    const double target = static_cast<double>(ne) * t / threads;
    while (node < d->nodes_ && d->offset_[static_cast<std::size_t>(node)] < target) ++node;
    d->partition_[static_cast<std::size_t>(t)] = node;
  }
  return d;
}

double ExplicitDynamics::von_neumann_time_step() const {
  return stable_time_step_ * std::sqrt(2.0);
}

template <bool Breaking>
void ExplicitDynamics::accelerate(int lo, int hi, const double* u, double load, double* a) {
  const std::int32_t* nb = neighbour_.data();
  const double* xx = xi_x_.data();
  const double* xy = xi_y_.data();
  const double* xl = xi_.data();
  double* coef = coef_.data();
  const double* limit = elongation_limit_.data();
  for (int i = lo; i < hi; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    const double uxi = u[2 * iu];
    const double uyi = u[2 * iu + 1];
    double ax = 0.0;
    double ay = 0.0;
    const auto end = static_cast<std::size_t>(offset_[iu + 1]);
    for (auto e = static_cast<std::size_t>(offset_[iu]); e < end; ++e) {
      const auto j = static_cast<std::size_t>(nb[e]);
      // ξ + η (001 Eq. 38), its length and the stretch of Eq. (39).
      const double dx = xx[e] + (u[2 * j] - uxi);
      const double dy = xy[e] + (u[2 * j + 1] - uyi);
      const double l = std::sqrt(dx * dx + dy * dy);
      if constexpr (Breaking) {
        // Both ends compute the same bits of l (ξ_ji + η_ji = −(ξ_ij + η_ij) exactly), so they
        // break the bond at the same step.
        coef[e] = (l - xl[e]) > limit[e] ? 0.0 : coef[e];
      }
      // c s (ξ+η)/|ξ+η| · β V_j / ρ with s = (l − ξ)/ξ: coef·ξ·s/l = coef·(1 − ξ/l).
      const double t = coef[e] * (1.0 - xl[e] / l);
      ax += t * dx;
      ay += t * dy;
    }
    a[2 * iu] = ax + body_[2 * iu] * load;
    a[2 * iu + 1] = ay + body_[2 * iu + 1] * load;
  }
}

void ExplicitDynamics::set_initial_state(std::span<const double> u0, std::span<const double> v0) {
  const auto n2 = static_cast<std::size_t>(2 * nodes_);
  assert(u0.size() == n2 && v0.size() == n2);
  step_ = 0;
  current_ = 1;
  std::vector<double>& u = buffer_[1];
  std::vector<double>& up = buffer_[0];
  std::copy(u0.begin(), u0.end(), u.begin());
  for (const auto& im : images_) {
    const auto g = static_cast<std::size_t>(im.image), s = static_cast<std::size_t>(im.source);
    u[2 * g] = im.sx * u[2 * s];
    u[2 * g + 1] = im.sy * u[2 * s + 1];
  }
  std::vector<double> a(n2, 0.0);
  if (setup_.critical_stretch > 0) {
    accelerate<true>(0, nodes_, u.data(), history_.at(0.0), a.data());
  } else {
    accelerate<false>(0, nodes_, u.data(), history_.at(0.0), a.data());
  }
  const double dt = dt_;
  for (std::size_t k = 0; k < n2; ++k) up[k] = u[k] - dt * v0[k] + 0.5 * dt * dt * a[k];
  for (std::size_t i = 0; i < static_cast<std::size_t>(nodes_); ++i) {
    if (!fixed_[i]) continue;
    for (std::size_t c = 0; c < 2; ++c) {
      fixed_u_[2 * i + c] = u[2 * i + c];
      up[2 * i + c] = u[2 * i + c];
    }
  }
  for (const auto& im : images_) {
    const auto g = static_cast<std::size_t>(im.image), s = static_cast<std::size_t>(im.source);
    up[2 * g] = im.sx * up[2 * s];
    up[2 * g + 1] = im.sy * up[2 * s + 1];
  }
}

void ExplicitDynamics::fix_nodes(std::span<const mesh::NodeIndex> nodes) {
  for (const mesh::NodeIndex k : nodes) fixed_[static_cast<std::size_t>(k)] = 1;
}

void ExplicitDynamics::add_image_node(mesh::NodeIndex image, mesh::NodeIndex source, double sx,
                                      double sy) {
  images_.push_back({image, source, sx, sy});
}

void ExplicitDynamics::add_body_force(mesh::NodeIndex node, double bx, double by) {
  const auto k = static_cast<std::size_t>(node);
  body_[2 * k] += bx / setup_.density;
  body_[2 * k + 1] += by / setup_.density;
}

void ExplicitDynamics::advance_range(int /*thread*/, int lo, int hi) {
  const double* u = buffer_[current_].data();
  const double* up = buffer_[(current_ + 2) % 3].data();
  double* un = buffer_[(current_ + 1) % 3].data();
  const double load = history_.at(time());
  // The accelerations land in u_{n+1}'s slots first, then Eq. (41) turns them into u_{n+1}.
  if (setup_.critical_stretch > 0) {
    accelerate<true>(lo, hi, u, load, un);
  } else {
    accelerate<false>(lo, hi, u, load, un);
  }
  const double dt2 = dt_ * dt_;
  for (auto k = static_cast<std::size_t>(2 * lo); k < static_cast<std::size_t>(2 * hi); ++k) {
    un[k] = dt2 * un[k] + (2.0 * u[k] - up[k]);  // 001 Eq. (41)
  }
  for (auto i = static_cast<std::size_t>(lo); i < static_cast<std::size_t>(hi); ++i) {
    if (!fixed_[i]) continue;
    un[2 * i] = fixed_u_[2 * i];
    un[2 * i + 1] = fixed_u_[2 * i + 1];
  }
}

void ExplicitDynamics::step(int steps) {
  if (steps <= 0) return;
  const int threads = static_cast<int>(partition_.size()) - 1;
  auto finish_step = [this]() noexcept {
    const int next = (current_ + 1) % 3;
    double* un = buffer_[next].data();
    for (const auto& im : images_) {
      const auto g = static_cast<std::size_t>(im.image), s = static_cast<std::size_t>(im.source);
      un[2 * g] = im.sx * un[2 * s];
      un[2 * g + 1] = im.sy * un[2 * s + 1];
    }
    current_ = next;
    ++step_;
  };
  if (threads == 1) {
    for (int s = 0; s < steps; ++s) {
      advance_range(0, 0, nodes_);
      finish_step();
    }
    return;
  }
  std::barrier sync(threads, finish_step);
  auto work = [&](int t) {
    const int lo = partition_[static_cast<std::size_t>(t)];
    const int hi = partition_[static_cast<std::size_t>(t) + 1];
    for (int s = 0; s < steps; ++s) {
      advance_range(t, lo, hi);
      sync.arrive_and_wait();
    }
  };
  std::vector<std::jthread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
}

std::span<const double> ExplicitDynamics::displacement() const {
  return {buffer_[current_].data(), buffer_[current_].size()};
}

void ExplicitDynamics::half_step_velocity(std::vector<double>& out) const {
  const auto& u = buffer_[current_];
  const auto& up = buffer_[(current_ + 2) % 3];
  out.resize(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) out[k] = (u[k] - up[k]) / dt_;
}

Energy ExplicitDynamics::energy() const {
  const auto n = static_cast<std::size_t>(nodes_);
  const auto& u = buffer_[current_];
  const auto& up = buffer_[(current_ + 2) % 3];
  const double load = history_.at(time());
  Energy en;
  for (std::size_t i = 0; i < n; ++i) {
    double ax = 0.0, ay = 0.0, strain = 0.0;
    for (auto e = static_cast<std::size_t>(offset_[i]);
         e < static_cast<std::size_t>(offset_[i + 1]); ++e) {
      const auto j = static_cast<std::size_t>(neighbour_[e]);
      const double dx = xi_x_[e] + (u[2 * j] - u[2 * i]);
      const double dy = xi_y_[e] + (u[2 * j + 1] - u[2 * i + 1]);
      const double l = std::sqrt(dx * dx + dy * dy);
      const double t = coef_[e] * (1.0 - xi_[e] / l);
      ax += t * dx;
      ay += t * dy;
      const double s = (l - xi_[e]) / xi_[e];
      strain += coef_[e] * xi_[e] * xi_[e] * s * s;  // = c β V_j ξ s²/ρ
    }
    ax += body_[2 * i] * load;
    ay += body_[2 * i + 1] * load;
    en.strain += 0.25 * mass_[i] * strain;  // each bond seen from both ends: ½·½
    en.external -= mass_[i] * load * (body_[2 * i] * u[2 * i] + body_[2 * i + 1] * u[2 * i + 1]);
    // v_{n−½} and v_{n+½} = v_{n−½} + Δt a_n (Eq. 41 divided by Δt).
    const double vmx = (u[2 * i] - up[2 * i]) / dt_;
    const double vmy = (u[2 * i + 1] - up[2 * i + 1]) / dt_;
    double vpx = vmx + dt_ * ax;
    double vpy = vmy + dt_ * ay;
    if (fixed_[i]) vpx = vpy = 0.0;
    en.kinetic += 0.5 * mass_[i] * (vmx * vpx + vmy * vpy);
  }
  return en;
}

double ExplicitDynamics::lattice_omega_squared(mesh::NodeIndex i, double k) const {
  const auto iu = static_cast<std::size_t>(i);
  double sum = 0.0;
  for (auto e = static_cast<std::size_t>(offset_[iu]);
       e < static_cast<std::size_t>(offset_[iu + 1]); ++e) {
    const double c = xi_x_[e] / xi_[e];
    sum += coef_[e] * c * c * (1.0 - std::cos(k * xi_x_[e]));
  }
  return sum;
}

std::vector<std::uint8_t> ExplicitDynamics::intact_bonds() const {
  std::vector<std::uint8_t> intact(static_cast<std::size_t>(disc_->num_bonds()), 1);
  for (std::size_t e = 0; e < coef_.size(); ++e) {
    if (coef_[e] == 0.0) intact[static_cast<std::size_t>(bond_of_[e])] = 0;
  }
  return intact;
}

std::int64_t ExplicitDynamics::broken_bonds() const {
  const auto intact = intact_bonds();
  return static_cast<std::int64_t>(std::count(intact.begin(), intact.end(), 0));
}

}  // namespace peritwin::dynamics
