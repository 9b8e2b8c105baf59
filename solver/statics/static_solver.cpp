// StaticSolver: the degrees of freedom, supports and ties (constructor), the bond and tie
// gradients the other parts build on, the basis load cases, and the results (displacement,
// stretch, internal force). Assembly: assembly.cpp; factorization and solves: direct_solve.cpp;
// breaking and softening bonds: bond_breaking.cpp; the preconditioned path: pcg.cpp.
#include "solver/statics/static_solver.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace peritwin::statics {

double tie_violation(const Tie& tie, const std::vector<double>& u) {
  double violation = 0.0;
  for (const TieTerm& term : tie.terms) {
    violation +=
        term.coefficient *
        u[2 * static_cast<std::size_t>(term.node) + static_cast<std::size_t>(term.component)];
  }
  return violation;
}

StaticSolver::StaticSolver(const mesh::Discretization& disc, const model::PdModel& model,
                           std::vector<Support> supports, std::vector<LoadTerm> loads,
                           std::vector<Tie> ties, std::vector<PrescribedDisplacement> prescribed)
    : disc_(disc),
      model_(model),
      supports_(std::move(supports)),
      loads_(std::move(loads)),
      ties_(std::move(ties)),
      prescribed_(std::move(prescribed)) {
  for (const Tie& tie : ties_) {
    const bool nodes_ok = std::all_of(tie.terms.begin(), tie.terms.end(), [&](const TieTerm& term) {
      return term.node >= 0 && term.node < disc.num_nodes() &&
             (term.component == 0 || term.component == 1) && std::isfinite(term.coefficient);
    });
    if (tie.terms.empty() || !nodes_ok || !(tie.stiffness > 0.0) || !std::isfinite(tie.stiffness)) {
      throw std::invalid_argument(
          "StaticSolver: a tie needs terms on nodes of the model (component 0 or 1, finite "
          "coefficient) and a finite stiffness > 0");
    }
  }
  for (const PrescribedDisplacement& p : prescribed_) {
    const bool nodes_ok = std::all_of(p.nodes.begin(), p.nodes.end(), [&](mesh::NodeIndex k) {
      return k >= 0 && k < disc.num_nodes();
    });
    if (p.nodes.empty() || !nodes_ok || (p.component != 0 && p.component != 1) ||
        !std::isfinite(p.constant) || !std::isfinite(p.per_cos) || !std::isfinite(p.per_sin)) {
      throw std::invalid_argument(
          "StaticSolver: a prescribed displacement needs nodes of the model, component 0 or 1 "
          "and finite coefficients");
    }
  }
  for (auto& r : reaction_) r.assign(prescribed_.size(), 0.0);
  intact_.resize(static_cast<std::size_t>(disc.num_bonds()));
  factor_.resize(intact_.size());
  for (std::size_t b = 0; b < intact_.size(); ++b) {
    intact_[b] = disc.bond_precut[b] ? 0 : 1;
    factor_[b] = intact_[b] ? 1.0 : 0.0;
  }
  const auto ndof = 2 * static_cast<std::size_t>(disc.num_nodes());
  free_index_.assign(ndof, 0);
  for (const auto& s : supports_) {
    for (mesh::NodeIndex k : s.nodes) {
      if (s.fix_x) free_index_[2 * static_cast<std::size_t>(k)] = -1;
      if (s.fix_y) free_index_[2 * static_cast<std::size_t>(k) + 1] = -1;
    }
  }
  for (const auto& p : prescribed_) {
    for (mesh::NodeIndex k : p.nodes) {
      free_index_[2 * static_cast<std::size_t>(k) + static_cast<std::size_t>(p.component)] = -1;
    }
  }
  for (auto& f : free_index_) f = f < 0 ? -1 : num_free_++;
  // Mixed form for the state-based model when every α_k = 2a·V_k/h < 0 (a < 0 ⇔ ν < 1/3):
  //   [K_bb  Bᵀ    ] [u]   [f]
  //   [B    −A⁻¹   ] [w] = [0],   A = diag(α_k),
  // whose Schur complement on w is K_bb + Bᵀ·A·B = K. −A⁻¹ is positive, and so is the Schur
  // complement, hence the whole matrix is SPD: Cholesky applies, the coupling reach is δ instead
  // of 2δ, and breaking a bond is a rank-3 change with 4-6 nonzeros per vector.
  mixed_ = model.options.kind == model::ModelKind::state_based &&
           !model.dilatation_stiffness.empty() &&
           std::all_of(model.dilatation_stiffness.begin(), model.dilatation_stiffness.end(),
                       [](double a) { return a < 0.0; });
  num_unknowns_ = num_free_ + (mixed_ ? disc.num_nodes() : 0);
  double sum = 0.0;
  for (double k : model.bond_stiffness) sum += k;
  ground_stiffness_ =
      model.bond_stiffness.empty() ? 1.0 : sum / static_cast<double>(model.bond_stiffness.size());
  grounded_.assign(static_cast<std::size_t>(disc.num_nodes()), 0);
  pinned_.assign(static_cast<std::size_t>(num_free_), 0);
  if (mixed_ && disc.num_nodes() > 0) {
    // −A⁻¹ is in m⁶-ish units per N, the stiffness in N/m: on B1 its diagonal is 1e-3..0.2 against
    // 3e8..1e11 for u, and min/max of the pivots fell below the 1e-14 singularity threshold
    // (cholmod_rcond) for a sound model (3,024 nodes; K's smallest eigenvalue was positive and
    // 2.4e9 times below its largest). Solving for w' = w/s, s² = (mean bond stiffness · mean
    // family size)/mean|1/α|, gives the w rows the stiffness's scale; u is unchanged.
    double inverse_alpha = 0.0;
    for (double a : model.dilatation_stiffness) inverse_alpha += 1.0 / std::abs(a);
    inverse_alpha /= static_cast<double>(disc.num_nodes());
    const double family = 2.0 * static_cast<double>(disc.num_bonds()) / disc.num_nodes();
    w_scale_ = std::sqrt(ground_stiffness_ * std::max(family, 1.0) / inverse_alpha);
  }
}

std::int32_t StaticSolver::pinned_dofs() const {
  return static_cast<std::int32_t>(std::count(pinned_.begin(), pinned_.end(), 1));
}

bool StaticSolver::isolated(mesh::NodeIndex k) const {
  for (auto f = disc_.family_offset[static_cast<std::size_t>(k)];
       f < disc_.family_offset[static_cast<std::size_t>(k) + 1]; ++f) {
    if (intact_[static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(f)])])
      return false;
  }
  return true;
}

std::array<std::pair<int, double>, 4> StaticSolver::bond_gradient(std::size_t b,
                                                                  double scale) const {
  const auto i = 2 * static_cast<std::size_t>(disc_.bond_i[b]);
  const auto j = 2 * static_cast<std::size_t>(disc_.bond_j[b]);
  const double c = scale * disc_.bond_cos[b];
  const double s = scale * disc_.bond_sin[b];
  return {{{free_index_[i], -c},
           {free_index_[i + 1], -s},
           {free_index_[j], c},
           {free_index_[j + 1], s}}};
}

std::vector<std::pair<int, double>> StaticSolver::tie_gradient(const Tie& tie) const {
  std::vector<std::pair<int, double>> g;
  g.reserve(tie.terms.size());
  for (const TieTerm& term : tie.terms) {
    g.emplace_back(free_index_[2 * static_cast<std::size_t>(term.node) +
                               static_cast<std::size_t>(term.component)],
                   term.coefficient);
  }
  return g;
}

std::vector<double> StaticSolver::basis_force(Basis b) const {
  std::vector<double> f(2 * static_cast<std::size_t>(disc_.num_nodes()), 0.0);
  for (const auto& load : loads_) {
    if (load.nodes.empty()) continue;
    const mesh::Point part = b == basis_constant ? load.constant
                             : b == basis_cos    ? load.per_cos
                                                 : load.per_sin;
    const double share = 1.0 / static_cast<double>(load.nodes.size());
    for (mesh::NodeIndex k : load.nodes) {
      f[2 * static_cast<std::size_t>(k)] += part.x * share;
      f[2 * static_cast<std::size_t>(k) + 1] += part.y * share;
    }
  }
  return f;
}

std::vector<double> StaticSolver::basis_prescribed(Basis b) const {
  std::vector<double> u(2 * static_cast<std::size_t>(disc_.num_nodes()), 0.0);
  for (const auto& p : prescribed_) {
    const double value = b == basis_constant ? p.constant : b == basis_cos ? p.per_cos : p.per_sin;
    for (mesh::NodeIndex k : p.nodes) {
      u[2 * static_cast<std::size_t>(k) + static_cast<std::size_t>(p.component)] = value;
    }
  }
  return u;
}

std::vector<double> StaticSolver::basis_rhs(Basis b, bool& loaded) const {
  std::vector<double> rhs = basis_force(b);
  loaded = std::any_of(rhs.begin(), rhs.end(), [](double v) { return v != 0.0; });
  if (prescribed_.empty()) return rhs;
  const std::vector<double> ubar = basis_prescribed(b);
  if (std::none_of(ubar.begin(), ubar.end(), [](double v) { return v != 0.0; })) return rhs;
  loaded = true;
  // F_f − K_fp·ū: K·ū bond by bond with the current bond factors; on the free rows it is K_fp·ū
  // (ū is zero there). In the mixed form the w rows get 0: the Schur complement of the mixed
  // matrix on u is K, so u_f solves K_ff·u_f = F_f − K_fp·ū all the same.
  const std::vector<double> k_ubar = internal_force(ubar);
  for (std::size_t dof = 0; dof < rhs.size(); ++dof) rhs[dof] -= k_ubar[dof];
  return rhs;
}

void StaticSolver::finish_basis(Basis b, std::vector<double>& u) {
  const auto bi = static_cast<std::size_t>(b);
  if (!prescribed_.empty()) {
    const std::vector<double> ubar = basis_prescribed(b);
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      if (free_index_[dof] < 0) u[dof] = ubar[dof];  // supports: 0
    }
    // The grips' force: K·u − F on the prescribed DOFs (the body's resistance to being moved).
    const std::vector<double> k_u = internal_force(u);
    const std::vector<double> f = basis_force(b);
    for (std::size_t t = 0; t < prescribed_.size(); ++t) {
      double sum = 0.0;
      for (mesh::NodeIndex k : prescribed_[t].nodes) {
        const auto dof =
            2 * static_cast<std::size_t>(k) + static_cast<std::size_t>(prescribed_[t].component);
        sum += k_u[dof] - f[dof];
      }
      reaction_[bi][t] = sum;
    }
  }
  model::bond_stretches(disc_, u, s_[bi]);
}

double StaticSolver::reaction(std::size_t term, double p, double alpha) const {
  return p * (reaction_[0][term] + std::cos(alpha) * reaction_[1][term] +
              std::sin(alpha) * reaction_[2][term]);
}

void StaticSolver::displacement(double p, double alpha, std::vector<double>& u) const {
  const double c = std::cos(alpha);
  const double s = std::sin(alpha);
  u.resize(u_[0].size());
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = p * (u_[0][i] + c * u_[1][i] + s * u_[2][i]);
}

void StaticSolver::stretch(double p, double alpha, std::vector<double>& s) const {
  const double c = std::cos(alpha);
  const double sn = std::sin(alpha);
  s.resize(s_[0].size());
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = p * (s_[0][i] + c * s_[1][i] + sn * s_[2][i]);
}

std::vector<double> StaticSolver::internal_force(const std::vector<double>& u) const {
  // Total force on each node from its bonds, written from 000 Eq. (3a) directly:
  // pair term k_b·ξ·s along e, plus the dilatation term (2a·V/h)·(θ_i + θ_j)·q_b/ξ along e.
  std::vector<double> stretch_values;
  model::bond_stretches(disc_, u, stretch_values);
  std::vector<double> theta;
  model::dilatations(disc_, model_, intact_, stretch_values, theta);
  std::vector<double> f(u.size(), 0.0);
  const bool osb = model_.options.kind == model::ModelKind::state_based;
  for (std::size_t b = 0; b < stretch_values.size(); ++b) {
    if (!intact_[b]) continue;
    const auto i = static_cast<std::size_t>(disc_.bond_i[b]);
    const auto j = static_cast<std::size_t>(disc_.bond_j[b]);
    double magnitude =
        model_.bond_stiffness[b] * factor_[b] * disc_.bond_length[b] * stretch_values[b];
    if (osb) {
      magnitude +=
          model_.dilatation_weight[b] / disc_.bond_length[b] *
          (model_.dilatation_stiffness[i] * theta[i] + model_.dilatation_stiffness[j] * theta[j]);
    }
    // A stretched bond pulls i toward j: internal resisting force K·u is −(pull) on i.
    f[2 * i] -= magnitude * disc_.bond_cos[b];
    f[2 * i + 1] -= magnitude * disc_.bond_sin[b];
    f[2 * j] += magnitude * disc_.bond_cos[b];
    f[2 * j + 1] += magnitude * disc_.bond_sin[b];
  }
  for (const Tie& tie : ties_) {  // K·u of the penalty: k·c_i·(gᵀu) on DOF i
    const double violation = tie_violation(tie, u);
    for (const TieTerm& term : tie.terms) {
      f[2 * static_cast<std::size_t>(term.node) + static_cast<std::size_t>(term.component)] +=
          tie.stiffness * term.coefficient * violation;
    }
  }
  return f;
}

}  // namespace peritwin::statics
