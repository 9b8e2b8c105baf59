// StaticSolver's bond state changes: breaking bonds and setting their stiffness factors, as
// low-rank update/downdate columns of the factor (incremental) or by refactorizing, with ground
// springs for the nodes left isolated.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "solver/statics/static_solver.h"

namespace peritwin::statics {

linalg::SparseCholesky::Column StaticSolver::dilatation_row(mesh::NodeIndex k) const {
  linalg::SparseCholesky::Column row;
  auto add = [&](int f, double v) {
    if (f < 0) return;
    for (std::size_t e = 0; e < row.rows.size(); ++e) {
      if (row.rows[e] == f) {
        row.values[e] += v;
        return;
      }
    }
    row.rows.push_back(f);
    row.values.push_back(v);
  };
  for (auto fam = disc_.family_offset[static_cast<std::size_t>(k)];
       fam < disc_.family_offset[static_cast<std::size_t>(k) + 1]; ++fam) {
    const auto b = static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(fam)]);
    if (!intact_[b]) continue;
    for (const auto& [f, v] :
         bond_gradient(b, model_.dilatation_weight[b] / disc_.bond_length[b])) {
      add(f, v);
    }
  }
  return row;
}

void StaticSolver::ground_isolated(const std::vector<mesh::NodeIndex>& nodes,
                                   std::vector<linalg::SparseCholesky::Column>& added) {
  for (mesh::NodeIndex k : nodes) {
    if (grounded_[static_cast<std::size_t>(k)] || !isolated(k)) continue;
    grounded_[static_cast<std::size_t>(k)] = 1;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(k) + c];
      // A pinned DOF has its spring already (the assembly adds one, not two).
      if (f >= 0 && !pinned_[static_cast<std::size_t>(f)]) {
        added.push_back({{f}, {std::sqrt(ground_stiffness_)}});
      }
    }
  }
}

core::Status StaticSolver::break_bonds(std::span<const mesh::BondIndex> bonds) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!incremental_ || !cholesky_.analyzed()) {
    group_nodes_.clear();
    for (mesh::BondIndex b : bonds) {
      if (intact_[static_cast<std::size_t>(b)]) {
        group_nodes_.push_back(disc_.bond_i[static_cast<std::size_t>(b)]);
        group_nodes_.push_back(disc_.bond_j[static_cast<std::size_t>(b)]);
      }
      intact_[static_cast<std::size_t>(b)] = 0;
      factor_[static_cast<std::size_t>(b)] = 0.0;
    }
    std::sort(group_nodes_.begin(), group_nodes_.end());
    group_nodes_.erase(std::unique(group_nodes_.begin(), group_nodes_.end()), group_nodes_.end());
    return refactor_resolve();
  }
  // K_new = K − Σ_b f_b·k_b·g_b·g_bᵀ + Σ_k α_k·(b'_k·b'_kᵀ − b_k·b_kᵀ) (+ ground springs), applied
  // as one rank-k update (the added terms) followed by one downdate (the removed ones).
  std::vector<linalg::SparseCholesky::Column> added, removed;
  const bool osb = model_.options.kind == model::ModelKind::state_based && !mixed_;
  std::vector<mesh::NodeIndex> nodes;
  for (mesh::BondIndex bond : bonds) {
    const auto b = static_cast<std::size_t>(bond);
    if (!intact_[b]) continue;
    linalg::SparseCholesky::Column g;
    const double w = std::sqrt(model_.bond_stiffness[b] * factor_[b]);
    for (const auto& [f, v] : bond_gradient(b, w)) {
      if (f >= 0) {
        g.rows.push_back(f);
        g.values.push_back(v);
      }
    }
    if (mixed_) {
      // The bond's entries c·g (c = q/ξ) in the (u, w_i) and (u, w_j) blocks go too. With the
      // pair term, the change is [g y]·S·[g y]ᵀ, g the unit bond gradient, y = e_wi + e_wj,
      // S = [[−k, −c], [−c, 0]]: one eigenvalue λ₊ = 2c²/(k + √(k² + 4c²)) > 0 with eigenvector
      // (c, −(k + λ₊)), one λ₋ = −(k + λ₊) < 0 with eigenvector (c, λ₊). So the bond is one
      // update column √λ₊·v₊ and one downdate column √−λ₋·v₋ (instead of three columns).
      const double k = model_.bond_stiffness[b] * factor_[b];
      const double c = model_.dilatation_weight[b] / disc_.bond_length[b];
      if (c > 0.0) {
        const double lambda = 2.0 * c * c / (k + std::sqrt(k * k + 4.0 * c * c));
        const double norm_plus = std::hypot(c, k + lambda);
        const double norm_minus = std::hypot(c, lambda);
        const double sp = std::sqrt(lambda) / norm_plus;  // update: √λ₊ · (c, −(k + λ₊))/‖·‖
        const double sm = std::sqrt(k + lambda) / norm_minus;  // downdate: √−λ₋ · (c, λ₊)/‖·‖
        linalg::SparseCholesky::Column up, down;
        for (const auto& [f, v] : bond_gradient(b, 1.0)) {
          if (f >= 0) {
            up.rows.push_back(f);
            up.values.push_back(sp * c * v);
            down.rows.push_back(f);
            down.values.push_back(sm * c * v);
          }
        }
        for (const mesh::NodeIndex node :
             {disc_.bond_i[b], disc_.bond_j[b]}) {  // y in w' = w/s: s·y
          up.rows.push_back(num_free_ + node);
          up.values.push_back(-sp * (k + lambda) * w_scale_);
          down.rows.push_back(num_free_ + node);
          down.values.push_back(sm * lambda * w_scale_);
        }
        added.push_back(std::move(up));
        removed.push_back(std::move(down));
        g.rows.clear();  // the pair term is in the two columns
      }
    }
    if (!g.rows.empty() && w > 0.0) removed.push_back(std::move(g));
    nodes.push_back(disc_.bond_i[b]);
    nodes.push_back(disc_.bond_j[b]);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  group_nodes_ = nodes;
  std::vector<linalg::SparseCholesky::Column> old_rows;
  if (osb) {
    for (mesh::NodeIndex k : nodes) old_rows.push_back(dilatation_row(k));
  }
  for (mesh::BondIndex b : bonds) {
    intact_[static_cast<std::size_t>(b)] = 0;
    factor_[static_cast<std::size_t>(b)] = 0.0;
  }
  for (std::size_t n = 0; osb && n < nodes.size(); ++n) {
    const double alpha = model_.dilatation_stiffness[static_cast<std::size_t>(nodes[n])];
    auto new_row = dilatation_row(nodes[n]);
    auto old_row = old_rows[n];
    const double w = std::sqrt(std::abs(alpha));
    for (auto& v : new_row.values) v *= w;
    for (auto& v : old_row.values) v *= w;
    // α > 0 adds α·b'b'ᵀ and removes α·bbᵀ; α < 0 (ν < 1/3) the other way round.
    auto& gain = alpha > 0 ? added : removed;
    auto& loss = alpha > 0 ? removed : added;
    if (!new_row.rows.empty()) gain.push_back(std::move(new_row));
    if (!old_row.rows.empty()) loss.push_back(std::move(old_row));
  }
  ground_isolated(nodes, added);
  return update_resolve(added, removed, t0);
}

core::Status StaticSolver::set_bond_factors(std::span<const mesh::BondIndex> bonds,
                                            std::span<const double> factors) {
  if (model_.options.kind != model::ModelKind::bond_based) {
    throw std::logic_error("StaticSolver::set_bond_factors: bond-based models only");
  }
  if (bonds.size() != factors.size()) {
    throw std::invalid_argument("StaticSolver::set_bond_factors: as many factors as bonds");
  }
  for (std::size_t n = 0; n < bonds.size(); ++n) {
    const auto b = static_cast<std::size_t>(bonds[n]);
    if (b >= factor_.size()) {
      throw std::invalid_argument("StaticSolver::set_bond_factors: bond index out of range");
    }
    if (!(factors[n] >= 0.0 && factors[n] <= 1.0)) {
      throw std::invalid_argument("StaticSolver::set_bond_factors: factor " +
                                  std::to_string(factors[n]) + " outside [0, 1]");
    }
    if (!intact_[b] && factors[n] > 0.0) {
      throw std::invalid_argument("StaticSolver::set_bond_factors: bond " +
                                  std::to_string(bonds[n]) + " is broken");
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  if (!incremental_ || !cholesky_.analyzed()) {
    bool broke = false;
    for (std::size_t n = 0; n < bonds.size(); ++n) {
      const auto b = static_cast<std::size_t>(bonds[n]);
      factor_[b] = factors[n];
      if (factors[n] == 0.0) {
        broke = broke || intact_[b] != 0;
        intact_[b] = 0;
      }
    }
    if (preconditioned_ && cholesky_.analyzed()) return preconditioned_resolve(broke);
    return refactor_resolve();
  }
  // K_new = K + Σ_b (f_new − f_old)·k_b·g_b·g_bᵀ: stiffer bonds in one update, softer ones in one
  // downdate, each column g_b scaled by sqrt(|f_new − f_old|·k_b).
  std::vector<linalg::SparseCholesky::Column> added, removed;
  std::vector<mesh::NodeIndex> nodes;
  for (std::size_t n = 0; n < bonds.size(); ++n) {
    const auto b = static_cast<std::size_t>(bonds[n]);
    const double change = factors[n] - factor_[b];
    factor_[b] = factors[n];
    if (factors[n] == 0.0 && intact_[b]) {
      intact_[b] = 0;
      nodes.push_back(disc_.bond_i[b]);
      nodes.push_back(disc_.bond_j[b]);
    }
    if (change == 0.0) continue;
    const double w = std::sqrt(std::abs(change) * model_.bond_stiffness[b]);
    linalg::SparseCholesky::Column g;
    for (const auto& [f, v] : bond_gradient(b, w)) {
      if (f >= 0) {
        g.rows.push_back(f);
        g.values.push_back(v);
      }
    }
    if (!g.rows.empty() && w > 0.0) (change > 0.0 ? added : removed).push_back(std::move(g));
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  ground_isolated(nodes, added);
  return update_resolve(added, removed, t0);
}

}  // namespace peritwin::statics
