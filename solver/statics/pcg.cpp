// StaticSolver's preconditioned path (set_preconditioned; 003's bilinear increments, see
// docs/solver.md): conjugate gradients on K(f)·u = F with the factor of a reference stiffness
// K(f_ref) as the preconditioner, refactorized only when some bond's reference changes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "solver/statics/solve_clock.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

using static_solver_detail::seconds_since;

void StaticSolver::set_preconditioned(bool on, double tolerance, int step, int max_iterations) {
  if (!(tolerance > 0.0) || step < 1 || step > 64 || max_iterations < 1) {
    throw std::invalid_argument(
        "StaticSolver::set_preconditioned: tolerance > 0, step in [1, 64], max_iterations >= 1");
  }
  preconditioned_ = on;
  pcg_tolerance_ = tolerance;
  pcg_step_ = step;
  pcg_max_iterations_ = max_iterations;
}

double StaticSolver::reference_factor(double f, int step) {
  if (f >= 1.0) return 1.0;
  if (!(f > 0.0)) return 0.0;
  int e = 0;
  const double m = std::frexp(f, &e);          // f = m·2^e, m ∈ [0.5, 1)
  const int ceil_log2 = m == 0.5 ? e - 1 : e;  // ≤ 0
  return std::ldexp(1.0, -step * (-ceil_log2 / step));
}

void StaticSolver::multiply(const std::vector<double>& factors, const double* x, double* y) const {
  // K(f)·x = Σ_b f_b·k_b·g_b·(g_bᵀ·x) + ground springs, g_b = e·(u_j − u_i) over the free DOFs:
  // the same matrix as assemble(factors), in a fixed order (deterministic).
  const auto n = static_cast<std::size_t>(num_unknowns_);
  std::fill(y, y + n, 0.0);
  const auto nb = factors.size();
  for (std::size_t b = 0; b < nb; ++b) {
    if (!intact_[b] || factors[b] == 0.0) continue;
    const auto i = 2 * static_cast<std::size_t>(disc_.bond_i[b]);
    const auto j = 2 * static_cast<std::size_t>(disc_.bond_j[b]);
    const int f[4] = {free_index_[i], free_index_[i + 1], free_index_[j], free_index_[j + 1]};
    const double c = disc_.bond_cos[b];
    const double s = disc_.bond_sin[b];
    const double g[4] = {-c, -s, c, s};
    double t = 0.0;
    for (int e = 0; e < 4; ++e) {
      if (f[e] >= 0) t += g[e] * x[f[e]];
    }
    const double w = factors[b] * model_.bond_stiffness[b] * t;
    for (int e = 0; e < 4; ++e) {
      if (f[e] >= 0) y[f[e]] += g[e] * w;
    }
  }
  for (mesh::NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    const bool ground = grounded_[static_cast<std::size_t>(node)] != 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0 && (ground || pinned_[static_cast<std::size_t>(f)])) {
        y[f] += ground_stiffness_ * x[f];
      }
    }
  }
  for (const Tie& tie : ties_) {
    const auto g = tie_gradient(tie);
    double t = 0.0;
    for (const auto& [f, v] : g) {
      if (f >= 0) t += v * x[f];
    }
    for (const auto& [f, v] : g) {
      if (f >= 0) y[f] += v * tie.stiffness * t;
    }
  }
}

namespace {
double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double sum = 0.0;  // sequential: the same bits every run
  for (std::size_t i = 0; i < a.size(); ++i) sum += a[i] * b[i];
  return sum;
}
}  // namespace

bool StaticSolver::pcg_solve_bases() {
  const auto t0 = std::chrono::steady_clock::now();
  const auto n = static_cast<std::size_t>(num_unknowns_);
  std::vector<int> loaded;
  std::vector<std::vector<double>> x, r, z, p;
  for (int basis = 0; basis < 3; ++basis) {
    bool any = false;
    const auto force = basis_rhs(static_cast<Basis>(basis), any);
    if (!any) continue;
    std::vector<double> rhs(n, 0.0);
    for (std::size_t dof = 0; dof < force.size(); ++dof) {
      if (free_index_[dof] >= 0) rhs[static_cast<std::size_t>(free_index_[dof])] = force[dof];
    }
    loaded.push_back(basis);
    x.emplace_back(n, 0.0);
    r.push_back(std::move(rhs));
  }
  const std::size_t nc = loaded.size();
  // z = M⁻¹·r for the listed columns, one block solve with the reference factor.
  auto precondition = [&](const std::vector<std::size_t>& columns) {
    Eigen::MatrixXd block(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t k = 0; k < columns.size(); ++k) {
      std::copy(r[columns[k]].begin(), r[columns[k]].end(),
                block.col(static_cast<Eigen::Index>(k)).data());
    }
    cholesky_.solve(block);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const double* col = block.col(static_cast<Eigen::Index>(k)).data();
      z[columns[k]].assign(col, col + n);
    }
  };
  std::vector<std::size_t> active;
  for (std::size_t c = 0; c < nc; ++c) active.push_back(c);
  z.assign(nc, {});
  if (nc > 0) precondition(active);
  p = z;
  std::vector<double> rho(nc), rho0(nc), q(n);
  for (std::size_t c = 0; c < nc; ++c) rho[c] = rho0[c] = dot(r[c], z[c]);
  const double tol2 = pcg_tolerance_ * pcg_tolerance_;
  int it = 0;
  bool ok = true;
  while (!active.empty()) {
    if (it == pcg_max_iterations_) {
      ok = false;
      break;
    }
    ++it;
    for (std::size_t c : active) {  // x += α·p, r −= α·K(f)·p, α = rᵀz / pᵀKp
      multiply(factor_, p[c].data(), q.data());
      const double pq = dot(p[c], q);
      if (!(pq > 0.0) || !std::isfinite(pq)) {
        ok = false;
        break;
      }
      const double alpha = rho[c] / pq;
      for (std::size_t i = 0; i < n; ++i) {
        x[c][i] += alpha * p[c][i];
        r[c][i] -= alpha * q[i];
      }
    }
    if (!ok) break;
    precondition(active);
    std::vector<std::size_t> still;
    for (std::size_t c : active) {
      const double rho_new = dot(r[c], z[c]);
      if (rho_new <= tol2 * rho0[c]) continue;  // sqrt(rᵀM⁻¹r / bᵀM⁻¹b) ≤ tolerance
      const double beta = rho_new / rho[c];
      rho[c] = rho_new;
      for (std::size_t i = 0; i < n; ++i) p[c][i] = z[c][i] + beta * p[c][i];
      still.push_back(c);
    }
    active = std::move(still);
  }
  ++pcg_.solves;
  pcg_.iterations += it;
  pcg_.max_iterations = std::max(pcg_.max_iterations, it);
  if (ok) {
    for (int basis = 0; basis < 3; ++basis) {
      auto& u = u_[static_cast<std::size_t>(basis)];
      u.assign(free_index_.size(), 0.0);
      const auto at = std::find(loaded.begin(), loaded.end(), basis);
      if (at != loaded.end()) {
        const auto& sol = x[static_cast<std::size_t>(at - loaded.begin())];
        for (std::size_t dof = 0; dof < u.size(); ++dof) {
          if (free_index_[dof] >= 0) u[dof] = sol[static_cast<std::size_t>(free_index_[dof])];
        }
        finish_basis(static_cast<Basis>(basis), u);
      } else {
        s_[static_cast<std::size_t>(basis)].assign(static_cast<std::size_t>(disc_.num_bonds()),
                                                   0.0);
        for (double& value : reaction_[static_cast<std::size_t>(basis)]) value = 0.0;
      }
    }
  }
  pcg_.seconds += seconds_since(t0);
  return ok;
}

core::Status StaticSolver::preconditioned_resolve(bool broke) {
  if (broke) {  // the same ground springs as refactor_resolve
    for (mesh::NodeIndex k = 0; k < disc_.num_nodes(); ++k) {
      if (isolated(k)) grounded_[static_cast<std::size_t>(k)] = 1;
    }
  }
  if (modified_) {  // an updated factor is not the factor of any reference: start afresh
    cholesky_ = linalg::SparseCholesky();
    modified_ = false;
  }
  std::vector<double> reference(factor_.size());
  for (std::size_t b = 0; b < factor_.size(); ++b) {
    reference[b] = reference_factor(factor_[b], pcg_step_);
  }
  // A new reference exactly when some bond's f_ref changed (a bond broke: its f_ref is 0 now, so
  // the ground springs, which change only then, are always current in the factor).
  if (!cholesky_.analyzed() || reference != reference_) {
    const int before = factorizations_;
    core::Status report = factorize_pinning(reference);
    pcg_.reference_factorizations += factorizations_ - before;
    if (!report.ok()) {
      reference_.clear();
      return report;
    }
    reference_ = std::move(reference);
  }
  if (pcg_solve_bases()) return {};
  ++pcg_.fallbacks;  // not converged: the refactorizing path (K(f) exactly)
  return refactor_resolve();
}

}  // namespace peritwin::statics
