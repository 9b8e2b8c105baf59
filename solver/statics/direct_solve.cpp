// StaticSolver's direct path: the fill-reducing ordering, the factorization and the basis
// solves, the refactorizing re-solve (the oracle) and the re-solve after a rank update of the
// factor, and releasing an idle factor's values.
#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/statics/solve_clock.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

using static_solver_detail::seconds_since;

std::vector<int> StaticSolver::dof_ordering() const {
  // Order the node graph (the 2x2 blocks of K) and expand it to the free DOFs: 2-4x smaller to
  // order than the DOF graph, and it keeps each node's DOFs together in the supernodes.
  const auto nn = disc_.num_nodes();
  std::vector<Eigen::Triplet<double, int>> links;
  links.reserve(static_cast<std::size_t>(disc_.num_bonds()) + static_cast<std::size_t>(nn));
  for (mesh::NodeIndex k = 0; k < nn; ++k) links.emplace_back(k, k, 1.0);
  for (mesh::BondIndex b = 0; b < disc_.num_bonds(); ++b) {
    if (!disc_.bond_precut[b]) links.emplace_back(disc_.bond_i[b], disc_.bond_j[b], 1.0);
  }
  for (const Tie& tie : ties_) {  // a tie couples every pair of its nodes
    std::vector<mesh::NodeIndex> nodes;
    for (const TieTerm& term : tie.terms) nodes.push_back(term.node);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (std::size_t p = 0; p < nodes.size(); ++p) {
      for (std::size_t q = p + 1; q < nodes.size(); ++q)
        links.emplace_back(nodes[p], nodes[q], 1.0);
    }
  }
  linalg::SparseMatrix incidence(nn, nn);
  incidence.setFromTriplets(links.begin(), links.end());
  linalg::SparseMatrix node_graph = incidence.selfadjointView<Eigen::Upper>();
  if (model_.options.kind == model::ModelKind::state_based && !mixed_) {
    node_graph = node_graph * node_graph;  // the dilatation couples nodes two bonds apart
  }
  linalg::SparseMatrix node_upper = node_graph.triangularView<Eigen::Upper>();
  node_upper.makeCompressed();
  const std::vector<int> node_order =
      linalg::SparseCholesky::fill_reducing_ordering(node_upper, ordering_);
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(num_unknowns_));
  for (int k : node_order) {
    for (int c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(k) + static_cast<std::size_t>(c)];
      if (f >= 0) order.push_back(f);
    }
    if (mixed_) order.push_back(num_free_ + k);
  }
  return order;
}

core::Status StaticSolver::factorize_pinning(const std::vector<double>& factors) {
  // Each round grounds or pins at least one DOF, so this ends; the bound only caps the work (a
  // round is a factorization) on a model riddled with mechanisms.
  constexpr int kMaxPinRounds = 256;
  timings_.factor_s = 0.0;
  for (int round = 0;; ++round) {
    auto t0 = std::chrono::steady_clock::now();
    assemble(factors);
    timings_.assemble_s = seconds_since(t0);
    if (!cholesky_.analyzed()) {
      t0 = std::chrono::steady_clock::now();
      const std::vector<int> permutation = dof_ordering();
      if (auto r = cholesky_.analyze(upper_, &permutation); !r.ok()) return r;
      timings_.analyze_s = seconds_since(t0);
    }
    t0 = std::chrono::steady_clock::now();
    core::Status report = cholesky_.factorize(upper_);
    ++factorizations_;
    timings_.factor_s += seconds_since(t0);
    if (report.ok()) {
      group_nodes_.clear();
      return report;
    }
    if (round == kMaxPinRounds) {
      return core::failure(core::message_of(report) + "; more than " +
                           std::to_string(kMaxPinRounds) + " rounds of pinning mechanisms");
    }
    // A piece that came loose is final failure (named), unless it is debris (grounded, and
    // factorized again); then a mechanism at the weakest pivot is pinned. Their failures say what
    // the factorization's cannot: what came loose, or why nothing can be pinned.
    bool grounded = false;
    if (auto loose = ground_loose_debris(grounded); !loose.ok()) return loose;
    if (grounded) continue;
    const int row = cholesky_.weakest_pivot_row();
    if (row < 0) return report;
    if (auto pinned = pin_mechanisms(node_of_unknown(row), factors, true); !pinned.ok()) {
      return pinned;
    }
    // The phase III cascade's groups leave mechanisms all along the new crack faces, and each
    // factorization names one (B1 at 60k nodes: 18 rounds at 4.8 s each in the last cycle, issue
    // 37): the group's other mechanisms are looked for around its bonds' ends now, once.
    if (!group_nodes_.empty()) {
      const core::Status screened = pin_group_mechanisms(factors);
      group_nodes_.clear();
      if (!screened.ok()) return screened;
    }
  }
}

mesh::NodeIndex StaticSolver::node_of_unknown(int row) const {
  if (row >= num_free_) return static_cast<mesh::NodeIndex>(row - num_free_);  // w_k: node k
  const auto dof = std::find(free_index_.begin(), free_index_.end(), row) - free_index_.begin();
  return static_cast<mesh::NodeIndex>(dof / 2);
}

core::Status StaticSolver::solve() {
  auto report = factorize_pinning(factor_);
  updated_ = false;
  released_ = false;
  if (!report.ok()) return report;
  reference_ = factor_;

  auto t0 = std::chrono::steady_clock::now();
  solve_bases();
  timings_.solve_s = seconds_since(t0);
  // Incremental: the factor is read again only after a rank update, which turns it into LDLᵀ:
  // do it now (the same values as at the first update, bit for bit) so that a detail that
  // breaks no bond for a while holds the packed factor, not the supernodal one with its
  // diagonal blocks' upper triangles (issue 18: memory of a fleet of details).
  if (incremental_ && cholesky_.convert_to_ldlt().ok()) modified_ = true;
  return report;
}

void StaticSolver::solve_bases() {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<int> loaded;
  std::array<std::vector<double>, 3> forces;
  for (int basis = 0; basis < 3; ++basis) {
    bool any = false;
    forces[static_cast<std::size_t>(basis)] = basis_rhs(static_cast<Basis>(basis), any);
    if (any) loaded.push_back(basis);
  }
  Eigen::MatrixXd rhs =
      Eigen::MatrixXd::Zero(num_unknowns_, static_cast<Eigen::Index>(loaded.size()));
  for (std::size_t c = 0; c < loaded.size(); ++c) {
    const auto& f = forces[static_cast<std::size_t>(loaded[c])];
    for (std::size_t dof = 0; dof < f.size(); ++dof) {
      if (free_index_[dof] >= 0) rhs(free_index_[dof], static_cast<Eigen::Index>(c)) = f[dof];
    }
  }
  if (!loaded.empty()) cholesky_.solve(rhs);
  for (int basis = 0; basis < 3; ++basis) {
    auto& u = u_[static_cast<std::size_t>(basis)];
    u.assign(free_index_.size(), 0.0);
    const auto it = std::find(loaded.begin(), loaded.end(), basis);
    if (it != loaded.end()) {
      const auto c = static_cast<Eigen::Index>(it - loaded.begin());
      for (std::size_t dof = 0; dof < u.size(); ++dof) {
        if (free_index_[dof] >= 0) u[dof] = rhs(free_index_[dof], c);
      }
      finish_basis(static_cast<Basis>(basis), u);
    } else {
      s_[static_cast<std::size_t>(basis)].assign(static_cast<std::size_t>(disc_.num_bonds()), 0.0);
      for (double& r : reaction_[static_cast<std::size_t>(basis)]) r = 0.0;
    }
  }
  basis_solve_s_ += seconds_since(t0);
}

void StaticSolver::solve_free(const std::vector<double>& rhs, std::vector<double>& x) const {
  if (mixed_) throw std::logic_error("StaticSolver::solve_free: not in the mixed form");
  Eigen::MatrixXd column = Eigen::MatrixXd::Zero(num_unknowns_, 1);
  for (std::size_t dof = 0; dof < rhs.size(); ++dof) {
    if (free_index_[dof] >= 0) column(free_index_[dof], 0) = rhs[dof];
  }
  cholesky_.solve(column);
  x.assign(free_index_.size(), 0.0);
  for (std::size_t dof = 0; dof < x.size(); ++dof) {
    if (free_index_[dof] >= 0) x[dof] = column(free_index_[dof], 0);
  }
}

void StaticSolver::solve_unknowns(std::vector<double>& x) const {
  Eigen::MatrixXd column = Eigen::Map<const Eigen::VectorXd>(x.data(), num_unknowns_);
  cholesky_.solve(column);
  std::copy(column.data(), column.data() + num_unknowns_, x.begin());
}

core::Status StaticSolver::refactor_resolve() {
  for (mesh::NodeIndex k = 0; k < disc_.num_nodes(); ++k) {
    if (isolated(k)) grounded_[static_cast<std::size_t>(k)] = 1;
  }
  // A piece that came loose makes the factorization fail, and then factorize_pinning asks
  // ground_loose_debris why: asked first (a flood fill over the bonds, no factorization), a
  // loose loaded piece is final failure at once and debris is grounded before the first
  // factorization instead of after a failed one (the phase III cascade at the end of a life
  // cut the body in its last groups: a refactorization each, issue 37).
  bool grounded = false;
  if (auto loose = ground_loose_debris(grounded); !loose.ok()) return loose;
  if (modified_) {
    // The packed LDLᵀ of the rank updates lives in the supernodal analysis, which factorize()
    // reuses: the ordering (dof_ordering) depends only on the bonds not precut and the ties, so a
    // new analysis would be the same one, at the cost of METIS and CHOLMOD's symbolic
    // factorization again (issue 37). Only CHOLMOD's simplicial factor (after modify()'s
    // fallback) needs analyzing again for a supernodal one.
    if (!cholesky_.supernodal_analysis()) cholesky_ = linalg::SparseCholesky();
    modified_ = false;
  }
  return solve();
}

bool StaticSolver::release_factor() {
  if (!incremental_ || preconditioned_ || updated_ || released_ || !cholesky_.has_values()) {
    return false;
  }
  released_ = cholesky_.release_values();
  return released_;
}

core::Status StaticSolver::update_resolve(
    const std::vector<linalg::SparseCholesky::Column>& added,
    const std::vector<linalg::SparseCholesky::Column>& removed,
    std::chrono::steady_clock::time_point t0) {
  if (released_) {  // upper_ is still the released factor's matrix: the same factor again
    core::Status f = cholesky_.factorize(upper_);
    ++factorizations_;
    released_ = false;
    if (f.ok()) f = cholesky_.convert_to_ldlt();
    if (!f.ok()) {
      update_s_ += seconds_since(t0);
      return f;
    }
  }
  // A group whose rank updates would cost more than refactorizing — the phase III cascade at the
  // end of a life, hundreds of bonds a group — is refactorized instead (issue 37). The choice is
  // by flop counts, which depend only on the factor's pattern and the group, never on timing
  // (determinism); kRefactorOverUpdate is the ratio of the two paths' measured rates (docs/
  // solver.md, "Incremental re-solve").
  const double update_flops = cholesky_.update_flops(added, removed);
  const double factorization_flops = cholesky_.factorization_flops();
  if (added.size() + removed.size() >= kRefactorMinimumRanks &&
      factorization_flops >= refactor_minimum_flops_ &&
      update_flops > kRefactorOverUpdate * factorization_flops) {
    ++refactorized_groups_;
    update_s_ += seconds_since(t0);
    return refactor_resolve();
  }
  updated_ = true;
  modified_ = true;
  update_flops_ += update_flops;
  const auto sweep_t0 = std::chrono::steady_clock::now();
  core::Status r = cholesky_.modify_fused(added, removed);
  sweep_s_ += seconds_since(sweep_t0);
  ++updates_;
  if (!r.ok()) {
    // A downdate that leaves a pivot ≤ 0 or min(D)/max(D) < 1e-14 leaves a factor that is no
    // use (the pivots after the bad one are noise): the verdict is the refactorization's, which
    // grounds debris or pins a mechanism and goes on, or says what came loose (docs/solver.md,
    // "Mechanisms are pinned"). Round-off carried by the updates alone no longer ends a life
    // either. Debris and a mechanism at the first bad pivot are dealt with first, which spares
    // the refactorization that would find them; what this misses, it finds.
    update_s_ += seconds_since(t0);
    bool grounded = false;
    const int row = cholesky_.weakest_pivot_row();
    if (ground_loose_debris(grounded).ok() && !grounded && row >= 0) {
      (void)pin_mechanisms(node_of_unknown(row), factor_, false);
      // And the group's other mechanisms (see factorize_pinning); what they cannot pin, or a
      // mechanism with load on it, the refactorization finds and decides on.
      (void)pin_group_mechanisms(factor_);
      group_nodes_.clear();
    }
    return refactor_resolve();
  }
  group_nodes_.clear();  // the update held: no mechanism to look for
  solve_bases();
  update_s_ += seconds_since(t0);
  return r;
}

}  // namespace peritwin::statics
