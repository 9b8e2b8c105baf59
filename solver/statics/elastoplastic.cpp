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
    : solver_(solver), law_(std::move(law)), skeleton_(checked(law_.curve)) {
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
  solver_.set_incremental(false);
}

void ElastoplasticSolver::evaluate(const std::vector<double>& u, std::vector<double>& force,
                                   std::vector<double>& tangent_factor,
                                   std::vector<double>* work) const {
  const mesh::Discretization& disc = solver_.discretization();
  const model::PdModel& model = solver_.model();
  std::vector<double> stretch;
  model::bond_stretches(disc, u, stretch);
  force.assign(u.size(), 0.0);
  tangent_factor.assign(stretch.size(), 0.0);
  const double kappa = law_.stretch_per_strain;
  const double e = law_.curve.youngs_modulus;
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    if (!solver_.intact()[b]) continue;
    const model::MasingResponse r =
        model::masing_evaluate(skeleton_, state_[b], stretch[b] / kappa);
    // F_b = k_b·ξ·κ·σ(ε)/E: the elastic k_b·ξ·s below yield.
    const double magnitude = model.bond_stiffness[b] * disc.bond_length[b] * kappa * r.stress / e;
    tangent_factor[b] = std::clamp(r.tangent / e, 1e-9, 1.0);
    if (work != nullptr) (*work)[b] = r.work;
    const auto i = 2 * static_cast<std::size_t>(disc.bond_i[b]);
    const auto j = 2 * static_cast<std::size_t>(disc.bond_j[b]);
    force[i] -= magnitude * disc.bond_cos[b];
    force[i + 1] -= magnitude * disc.bond_sin[b];
    force[j] += magnitude * disc.bond_cos[b];
    force[j + 1] += magnitude * disc.bond_sin[b];
  }
}

core::Expected<TurningPoint> ElastoplasticSolver::solve_turning_point(double p, double alpha) {
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
  std::vector<double> force, tangent, factors(bonds.size(), 1.0), residual(u_.size()), step;
  TurningPoint out;
  out.control = p;
  // The elastic predictor (every branch leaves a reversal with the slope E): from the committed
  // state, the grips move by Δū and the free DOFs by K⁻¹·(r(u_c) − K_fp·Δū), K elastic.
  if (auto f = solver_.set_bond_factors(bonds, factors); !f.ok()) {
    return core::failure(core::message_of(f));
  }
  std::vector<double> u = u_;
  {
    std::vector<double> moved(u_.size(), 0.0);
    for (std::size_t dof = 0; dof < u_.size(); ++dof) {
      if (free_index[dof] < 0) moved[dof] = grips[dof] - u_[dof];
    }
    const std::vector<double> k_moved = solver_.internal_force(moved);
    evaluate(u_, force, tangent, nullptr);
    for (std::size_t dof = 0; dof < u_.size(); ++dof) {
      residual[dof] = free_index[dof] >= 0 ? external[dof] - force[dof] - k_moved[dof] : 0.0;
    }
    solver_.solve_free(residual, step);
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      u[dof] = free_index[dof] >= 0 ? u_[dof] + step[dof] : grips[dof];
    }
  }
  for (int it = 0;; ++it) {
    evaluate(u, force, tangent, nullptr);
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      residual[dof] = free_index[dof] >= 0 ? external[dof] - force[dof] : 0.0;
    }
    // The scale: the grips' force (or the applied load) now.
    double scale = 0.0;
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      const double v = free_index[dof] < 0 ? force[dof] : external[dof];
      scale += v * v;
    }
    out.residual = free_norm(residual, free_index) / std::max(std::sqrt(scale), 1e-300);
    if (out.residual <= law_.tolerance) break;
    if (it == law_.max_iterations) {
      return core::failure("elastoplastic turning point at P = " + core::format_number(p) +
                           ": Newton did not converge in " + std::to_string(law_.max_iterations) +
                           " iterations (residual " + core::format_number(out.residual) +
                           " of the grips' force)");
    }
    // The tangent of each bond's branch at its current strain.
    for (std::size_t n = 0; n < bonds.size(); ++n) {
      factors[n] = tangent[static_cast<std::size_t>(bonds[n])];
    }
    if (auto f = solver_.set_bond_factors(bonds, factors); !f.ok()) {
      return core::failure(core::message_of(f));
    }
    solver_.solve_free(residual, step);
    for (std::size_t dof = 0; dof < u.size(); ++dof) u[dof] += step[dof];
    ++out.iterations;
    ++iterations_;
  }
  evaluate(u, force, tangent, &work_);
  const double kappa = law_.stretch_per_strain;
  std::vector<double> stretch;
  model::bond_stretches(solver_.discretization(), u, stretch);
  for (mesh::BondIndex b : bonds) {
    const auto bi = static_cast<std::size_t>(b);
    state_[bi] = model::masing_commit(skeleton_, state_[bi], stretch[bi] / kappa);
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

core::Status ElastoplasticSolver::break_bonds(std::span<const mesh::BondIndex> bonds) {
  for (mesh::BondIndex b : bonds) {
    state_[static_cast<std::size_t>(b)] = model::MasingState{};
    work_[static_cast<std::size_t>(b)] = 0.0;
  }
  return solver_.break_bonds(bonds);
}

std::vector<double> ElastoplasticSolver::node_loop_area(
    const std::vector<double>& bond_loop) const {
  const mesh::Discretization& disc = solver_.discretization();
  const model::PdModel& model = solver_.model();
  const double kappa = law_.stretch_per_strain;
  std::vector<double> area(static_cast<std::size_t>(disc.num_nodes()), 0.0);
  for (std::size_t b = 0; b < bond_loop.size(); ++b) {
    if (!solver_.intact()[b]) continue;
    // W_b = k_b·ξ²·κ²/E·∮σ dε (J), half to each end.
    const double w = model.bond_stiffness[b] * disc.bond_length[b] * disc.bond_length[b] * kappa *
                     kappa / law_.curve.youngs_modulus * bond_loop[b];
    area[static_cast<std::size_t>(disc.bond_i[b])] += 0.5 * w;
    area[static_cast<std::size_t>(disc.bond_j[b])] += 0.5 * w;
  }
  for (std::size_t k = 0; k < area.size(); ++k) area[k] /= disc.volume[k];
  return area;
}

}  // namespace peritwin::statics
