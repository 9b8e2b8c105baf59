// ElastoplasticSolver: Newton–Raphson turning points of bonds on 004's power-law curve with
// Masing hardening; contracts in elastoplastic.h.
#include "solver/statics/elastoplastic.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/param_reader.h"

namespace peritwin::statics {

namespace {

double free_norm(const std::vector<double>& v, const std::vector<std::int32_t>& free_index) {
  double sum = 0.0;
  for (std::size_t dof = 0; dof < v.size(); ++dof) {
    if (free_index[dof] >= 0) sum += v[dof] * v[dof];
  }
  return std::sqrt(sum);
}

const model::PowerLawCurve& checked(const model::PowerLawCurve& curve) {
  if (const core::Status valid = model::validate(curve); !valid.ok()) {
    throw std::invalid_argument("ElastoplasticSolver: " + core::message_of(valid));
  }
  return curve;
}

}  // namespace

ElastoplasticSolver::ElastoplasticSolver(StaticSolver& solver, BondPlasticity law)
    : solver_(solver),
      law_(std::move(law)),
      skeleton_(checked(law_.curve)),
      commit_skeleton_(law_.curve, law_.snap_tolerance) {
  if (solver.model().options.kind != model::ModelKind::bond_based || solver.mixed_form()) {
    throw std::invalid_argument("ElastoplasticSolver: bond-based models only");
  }
  if (!(law_.stretch_per_strain > 0.0) || !(law_.tolerance > 0.0) || law_.max_iterations < 1) {
    throw std::invalid_argument("ElastoplasticSolver: κ > 0, tolerance > 0, iterations >= 1");
  }
  const auto nb = static_cast<std::size_t>(solver.discretization().num_bonds());
  state_.assign(nb, model::MasingState{});
  work_.assign(nb, 0.0);
  u_.assign(2 * static_cast<std::size_t>(solver.discretization().num_nodes()), 0.0);
  reaction_.assign(solver.prescribed().size(), 0.0);
}

ElastoplasticSolver::ElastoplasticSolver(const ElastoplasticSolver& other, StaticSolver& solver)
    : solver_(solver),
      law_(other.law_),
      skeleton_(other.skeleton_),
      commit_skeleton_(other.commit_skeleton_),
      state_(other.state_),
      work_(other.work_),
      u_(other.u_),
      reaction_(other.reaction_),
      p_(other.p_),
      iterations_(other.iterations_),
      stalled_(other.stalled_),
      substepped_(other.substepped_) {}

double ElastoplasticSolver::bond_force(std::size_t b, double stress) const {
  const double kappa = law_.stretch_per_strain;
  return solver_.model().bond_stiffness[b] * solver_.discretization().bond_length[b] * kappa *
         stress / law_.curve.youngs_modulus;
}

double ElastoplasticSolver::bond_work(std::size_t b, double work) const {
  const double xi = solver_.discretization().bond_length[b];
  const double kappa = law_.stretch_per_strain;
  return solver_.model().bond_stiffness[b] * xi * xi * kappa * kappa / law_.curve.youngs_modulus *
         work;
}

double ElastoplasticSolver::evaluate(const std::vector<double>& u, std::vector<double>& force,
                                     std::vector<double>& tangent_factor,
                                     std::vector<double>* work) const {
  const mesh::Discretization& disc = solver_.discretization();
  std::vector<double> stretch;
  model::bond_stretches(disc, u, stretch);
  force.assign(u.size(), 0.0);
  tangent_factor.assign(stretch.size(), 0.0);
  const double kappa = law_.stretch_per_strain;
  const double e = law_.curve.youngs_modulus;
  double energy = 0.0;
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    if (!solver_.intact()[b]) continue;
    const model::MasingResponse r =
        model::masing_evaluate(skeleton_, state_[b], stretch[b] / kappa);
    // F_b = k_b·ξ·κ·σ(ε)/E: the elastic k_b·ξ·s below yield.
    const double magnitude = bond_force(b, r.stress);
    tangent_factor[b] = std::clamp(r.tangent / e, 1e-9, 1.0);
    if (work != nullptr) (*work)[b] = r.work;
    // The bond's work along the ramp (J): k_b·ξ²·κ²/E·∫σ dε, whose derivative is its force.
    energy += bond_work(b, r.work);
    const auto i = 2 * static_cast<std::size_t>(disc.bond_i[b]);
    const auto j = 2 * static_cast<std::size_t>(disc.bond_j[b]);
    force[i] -= magnitude * disc.bond_cos[b];
    force[i + 1] -= magnitude * disc.bond_sin[b];
    force[j] += magnitude * disc.bond_cos[b];
    force[j + 1] += magnitude * disc.bond_sin[b];
  }
  return energy;
}

core::Expected<TurningPoint> ElastoplasticSolver::solve_turning_point(double p, double alpha) {
  auto direct = ramp(p, alpha);
  if (direct.ok()) return direct;
  // Substeps: the same monotone ramp in 2, 4, … 64 parts, each committed (a bond whose strain
  // turns within the ramp then keeps that reversal, which the single step could not see).
  const std::vector<model::MasingState> state = state_;
  const std::vector<double> u = u_, reaction = reaction_, work0 = work_;
  const double from = p_;
  for (int parts = 2; parts <= 64; parts *= 2) {
    std::vector<double> work(work_.size(), 0.0);
    TurningPoint total;
    bool ok = true;
    for (int k = 1; k <= parts && ok; ++k) {
      const double at = k == parts ? p : from + (p - from) * k / parts;
      auto part = ramp(at, alpha);
      ok = part.ok();
      if (!ok) break;
      total.iterations += part->iterations;
      total.residual = part->residual;
      for (std::size_t b = 0; b < work.size(); ++b) work[b] += work_[b];
    }
    if (ok) {
      work_ = std::move(work);
      total.control = p;
      total.substeps = parts;
      ++substepped_;
      return total;
    }
    state_ = state;
    u_ = u;
    reaction_ = reaction;
    work_ = work0;
    p_ = from;
  }
  return direct;
}

core::Expected<TurningPoint> ElastoplasticSolver::ramp(double p, double alpha) {
  const std::vector<std::int32_t>& free_index = solver_.free_index();
  const double c = std::cos(alpha);
  const double s = std::sin(alpha);
  // The grips' and loads' values at (p, α).
  std::vector<double> grips(u_.size(), 0.0);
  std::vector<double> external(u_.size(), 0.0);
  {
    const std::array<std::vector<double>, 3> ubar = {solver_.basis_prescribed(basis_constant),
                                                     solver_.basis_prescribed(basis_cos),
                                                     solver_.basis_prescribed(basis_sin)};
    const std::array<std::vector<double>, 3> f = {solver_.basis_force(basis_constant),
                                                  solver_.basis_force(basis_cos),
                                                  solver_.basis_force(basis_sin)};
    for (std::size_t dof = 0; dof < u_.size(); ++dof) {
      if (free_index[dof] < 0)
        grips[dof] = p * (ubar[0][dof] + c * ubar[1][dof] + s * ubar[2][dof]);
      external[dof] = p * (f[0][dof] + c * f[1][dof] + s * f[2][dof]);
    }
  }
  std::vector<mesh::BondIndex> bonds;
  for (std::size_t b = 0; b < solver_.intact().size(); ++b) {
    if (solver_.intact()[b]) bonds.push_back(static_cast<mesh::BondIndex>(b));
  }
  std::vector<double> force, tangent, residual(u_.size()), step;
  TurningPoint out;
  out.control = p;
  double energy = 0.0;  // Π(u) of the ramp at the last evaluation
  const auto residual_at = [&](const std::vector<double>& at) {
    energy = evaluate(at, force, tangent, nullptr);
    for (std::size_t dof = 0; dof < at.size(); ++dof) {
      residual[dof] = free_index[dof] >= 0 ? external[dof] - force[dof] : 0.0;
      if (free_index[dof] >= 0) energy -= external[dof] * at[dof];
    }
    // The scale: the grips' force (or the applied load) now.
    double scale = 0.0;
    for (std::size_t dof = 0; dof < at.size(); ++dof) {
      const double v = free_index[dof] < 0 ? force[dof] : external[dof];
      scale += v * v;
    }
    return free_norm(residual, free_index) / std::max(std::sqrt(scale), 1e-300);
  };
  // The elastic predictor (every branch leaves a reversal with the slope E): from the committed
  // state, the grips move by Δū and the free DOFs by K⁻¹·(r(u_c) − K_fp·Δū), K the elastic
  // stiffness the solver holds (its factors are 1 for intact bonds, 0 for broken ones).
  std::vector<double> u = u_;
  {
    std::vector<double> moved(u_.size(), 0.0);
    for (std::size_t dof = 0; dof < u_.size(); ++dof) {
      if (free_index[dof] < 0) moved[dof] = grips[dof] - u_[dof];
    }
    const std::vector<double> k_moved = solver_.internal_force(moved);
    residual_at(u_);
    for (std::size_t dof = 0; dof < u_.size(); ++dof) {
      if (free_index[dof] >= 0) residual[dof] -= k_moved[dof];
    }
    solver_.solve_free(residual, step);
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      u[dof] = free_index[dof] >= 0 ? u_[dof] + step[dof] : grips[dof];
    }
  }
  std::vector<double> trial;
  out.residual = residual_at(u);
  int elastic_steps = 0;
  bool elastic_tried = false;
  for (int it = 0; out.residual > law_.tolerance; ++it) {
    if (it == law_.max_iterations) {
      if (out.residual <= law_.stall_tolerance) {  // see BondPlasticity::stall_tolerance
        ++stalled_;
        break;
      }
      return core::failure("elastoplastic turning point at P = " + core::format_number(p) +
                           ": Newton did not converge in " + std::to_string(law_.max_iterations) +
                           " iterations (residual " + core::format_number(out.residual) +
                           " of the grips' force)");
    }
    // Newton: K_t·Δu = r by conjugate gradients preconditioned with the elastic factor (the
    // spectrum of K_e⁻¹K_t lies in (min σ'/E, 1]: no refactorization per iteration).
    // After a Newton step that could not decrease Π, a few steps with the elastic stiffness
    // (the initial-stiffness method: K_e ≥ K_t, so it decreases Π whatever the kinks; linear
    // convergence), then Newton again.
    if (elastic_steps > 0) {
      solver_.solve_free(residual, step);
      --elastic_steps;
    } else {
      tangent_step(tangent, residual, step);
    }
    // Backtracking (Armijo) on the ramp's potential Π(u) = Σ_b W_b(ε_b) − F·u: each bond's
    // stress along a monotone ramp from its committed state increases with its strain (tangent
    // > 0), so Π is convex and its gradient is −r. Any SPD K_t makes Δu a descent direction of
    // Π, even where the tangent is inconsistent: a bond whose strain barely moves switches
    // between the slope E (reversing) and its branch's tangent, where ‖r‖ is not smooth.
    double slope = 0.0;  // dΠ/dλ at λ = 0: −rᵀΔu
    for (std::size_t dof = 0; dof < u.size(); ++dof) slope -= residual[dof] * step[dof];
    const double energy0 = energy;
    const double residual0 = out.residual;
    double length = 1.0;
    bool decreased = false;
    for (int halving = 0; halving <= 40 && slope < 0.0; ++halving) {
      trial = u;
      for (std::size_t dof = 0; dof < u.size(); ++dof) trial[dof] += length * step[dof];
      const double r = residual_at(trial);
      // Near the solution Π's decrease (∝ ‖r‖²) drowns in its round-off: ‖r‖ decides there.
      if (r < residual0 || energy <= energy0 + 1e-4 * length * slope) {
        out.residual = r;
        decreased = true;
        u.swap(trial);
        break;
      }
      length *= 0.5;
    }
    if (!decreased) out.residual = residual0;
    ++out.iterations;
    ++iterations_;
    if (!decreased) {
      residual_at(u);  // the state of u again (force, tangents, residual)
      if (elastic_steps == 0 && !elastic_tried) {
        elastic_steps = 10;
        elastic_tried = true;
        continue;
      }
      if (out.residual <= law_.stall_tolerance) {
        ++stalled_;
        break;
      }
      return core::failure("elastoplastic turning point at P = " + core::format_number(p) +
                           ": no Newton step decreases the potential (residual " +
                           core::format_number(out.residual) + " of the grips' force)");
    }
    if (elastic_steps == 0) elastic_tried = false;
  }
  evaluate(u, force, tangent, &work_);
  const double kappa = law_.stretch_per_strain;
  std::vector<double> stretch;
  model::bond_stretches(solver_.discretization(), u, stretch);
  for (mesh::BondIndex b : bonds) {
    const auto bi = static_cast<std::size_t>(b);
    state_[bi] = model::masing_commit(commit_skeleton_, state_[bi], stretch[bi] / kappa);
  }
  for (std::size_t t = 0; t < solver_.prescribed().size(); ++t) {
    double sum = 0.0;
    for (mesh::NodeIndex k : solver_.prescribed()[t].nodes) {
      const auto dof = 2 * static_cast<std::size_t>(k) +
                       static_cast<std::size_t>(solver_.prescribed()[t].component);
      sum += force[dof] - external[dof];
    }
    reaction_[t] = sum;
  }
  u_ = std::move(u);
  p_ = p;
  return out;
}

void ElastoplasticSolver::tangent_step(const std::vector<double>& tangent,
                                       const std::vector<double>& residual,
                                       std::vector<double>& step) const {
  const std::vector<std::int32_t>& free_index = solver_.free_index();
  const auto n = static_cast<std::size_t>(solver_.num_unknowns());
  std::vector<double> r(n, 0.0), x(n, 0.0), z, q(n, 0.0), d;
  for (std::size_t dof = 0; dof < residual.size(); ++dof) {
    if (free_index[dof] >= 0) r[static_cast<std::size_t>(free_index[dof])] = residual[dof];
  }
  const auto dot = [](const std::vector<double>& a, const std::vector<double>& b) {
    double sum = 0.0;  // sequential: the same bits every run
    for (std::size_t i = 0; i < a.size(); ++i) sum += a[i] * b[i];
    return sum;
  };
  const double norm0 = std::sqrt(dot(r, r));
  z = r;
  solver_.solve_unknowns(z);
  d = z;
  double rz = dot(r, z);
  for (int k = 0; k < law_.max_linear_iterations && norm0 > 0.0; ++k) {
    solver_.multiply(tangent, d.data(), q.data());
    const double alpha = rz / dot(d, q);
    for (std::size_t i = 0; i < n; ++i) {
      x[i] += alpha * d[i];
      r[i] -= alpha * q[i];
    }
    if (std::sqrt(dot(r, r)) <= law_.linear_tolerance * norm0) break;
    z = r;
    solver_.solve_unknowns(z);
    const double rz_next = dot(r, z);
    const double beta = rz_next / rz;
    rz = rz_next;
    for (std::size_t i = 0; i < n; ++i) d[i] = z[i] + beta * d[i];
  }
  step.assign(residual.size(), 0.0);
  for (std::size_t dof = 0; dof < step.size(); ++dof) {
    if (free_index[dof] >= 0) step[dof] = x[static_cast<std::size_t>(free_index[dof])];
  }
}

core::Status ElastoplasticSolver::break_bonds(std::span<const mesh::BondIndex> bonds) {
  for (mesh::BondIndex b : bonds) {
    state_[static_cast<std::size_t>(b)] = model::MasingState{};
    work_[static_cast<std::size_t>(b)] = 0.0;
  }
  return solver_.break_bonds(bonds);
}

std::vector<std::array<double, 3>> ElastoplasticSolver::node_stress() const {
  const mesh::Discretization& disc = solver_.discretization();
  std::vector<std::array<double, 3>> sigma(static_cast<std::size_t>(disc.num_nodes()),
                                           std::array<double, 3>{0.0, 0.0, 0.0});
  for (std::size_t b = 0; b < state_.size(); ++b) {
    if (!solver_.intact()[b]) continue;
    const double force = bond_force(b, state_[b].stress);
    const double c = disc.bond_cos[b];
    const double s = disc.bond_sin[b];
    const double half = 0.5 * force * disc.bond_length[b];
    for (const auto k : {disc.bond_i[b], disc.bond_j[b]}) {
      auto& t = sigma[static_cast<std::size_t>(k)];
      t[0] += half * c * c;
      t[1] += half * s * s;
      t[2] += half * c * s;
    }
  }
  for (std::size_t k = 0; k < sigma.size(); ++k) {
    for (double& v : sigma[k]) v /= disc.volume[k];
  }
  return sigma;
}

std::vector<double> ElastoplasticSolver::node_loop_area(
    const std::vector<double>& bond_loop) const {
  const mesh::Discretization& disc = solver_.discretization();
  std::vector<double> area(static_cast<std::size_t>(disc.num_nodes()), 0.0);
  for (std::size_t b = 0; b < bond_loop.size(); ++b) {
    if (!solver_.intact()[b]) continue;
    const double w = bond_work(b, bond_loop[b]);  // half to each end
    area[static_cast<std::size_t>(disc.bond_i[b])] += 0.5 * w;
    area[static_cast<std::size_t>(disc.bond_j[b])] += 0.5 * w;
  }
  for (std::size_t k = 0; k < area.size(); ++k) area[k] /= disc.volume[k];
  return area;
}

}  // namespace peritwin::statics
