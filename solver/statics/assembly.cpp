// StaticSolver's stiffness assembly (000 App. B): K = Bᵀ·diag(2aV/h)·B + Σ_b k_b·(e⊗e) (+ ground
// springs and ties), by scatter into a fixed pattern (bond-based and the mixed form) or by
// Eigen products and triplets (the condensed state-based form, and the scatter's oracle).
#include <algorithm>
#include <cstdint>
#include <vector>

#include "solver/statics/static_solver.h"

namespace peritwin::statics {

void StaticSolver::append_ties(std::vector<Eigen::Triplet<double, int>>& entries) const {
  for (const Tie& tie : ties_) {
    const auto g = tie_gradient(tie);
    for (const auto& [row, g_row] : g) {
      for (const auto& [col, g_col] : g) {
        if (row >= 0 && col >= 0 && row <= col) {
          entries.emplace_back(row, col, tie.stiffness * g_row * g_col);
        }
      }
    }
  }
}

void StaticSolver::append_ground(std::vector<Eigen::Triplet<double, int>>& entries) const {
  for (mesh::NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    const bool ground = grounded_[static_cast<std::size_t>(node)] != 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0) {  // a pinned DOF has the same spring (one, if its node is grounded too)
        const bool spring = ground || pinned_[static_cast<std::size_t>(f)] != 0;
        entries.emplace_back(f, f, spring ? ground_stiffness_ : 0.0);
      }
    }
  }
}

void StaticSolver::assemble(const std::vector<double>& factors) {
  const bool condensed = model_.options.kind == model::ModelKind::state_based && !mixed_;
  if (condensed) {
    assemble_by_products(factors, upper_);
  } else {
    assemble_by_scatter(factors);
  }
}

linalg::SparseMatrix StaticSolver::stiffness_upper_by_products() const {
  linalg::SparseMatrix out;
  assemble_by_products(factor_, out);
  return out;
}

void StaticSolver::build_pattern() {
  // Node adjacency over the bonds not precut (K_bb and the Bᵀ block of the mixed form). A precut
  // bond is never in the stiffness: its entries would be explicit zeros that the fill-reducing
  // ordering (dof_ordering, which leaves them out) does not see, 16 % more factor entries at 60k
  // nodes (64.9M against 55.9M, docs/benchmarks.md "Solver cold start").
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  auto adjacency = [&](std::vector<int>& offset, std::vector<int>& nodes) {
    offset.assign(nn + 1, 0);
    for (std::size_t b = 0; b < nb; ++b) {
      if (disc_.bond_precut[b]) continue;
      ++offset[static_cast<std::size_t>(disc_.bond_i[b]) + 1];
      ++offset[static_cast<std::size_t>(disc_.bond_j[b]) + 1];
    }
    for (std::size_t k = 0; k < nn; ++k) offset[k + 1] += offset[k];
    nodes.assign(static_cast<std::size_t>(offset[nn]), 0);
    std::vector<int> next(offset.begin(), offset.end() - 1);
    for (std::size_t b = 0; b < nb; ++b) {
      if (disc_.bond_precut[b]) continue;
      const auto i = static_cast<std::size_t>(disc_.bond_i[b]);
      const auto j = static_cast<std::size_t>(disc_.bond_j[b]);
      nodes[static_cast<std::size_t>(next[i]++)] = static_cast<int>(j);
      nodes[static_cast<std::size_t>(next[j]++)] = static_cast<int>(i);
    }
    for (std::size_t k = 0; k < nn; ++k) {
      std::sort(nodes.begin() + offset[k], nodes.begin() + offset[k + 1]);
    }
  };
  std::vector<int> all_offset, all_nodes;
  adjacency(all_offset, all_nodes);
  // Tie entries (row ≤ col) per column.
  std::vector<std::vector<int>> tie_rows(static_cast<std::size_t>(num_free_));
  for (const Tie& tie : ties_) {
    const auto g = tie_gradient(tie);
    for (const auto& [row, g_row] : g) {
      for (const auto& [col, g_col] : g) {
        if (row >= 0 && col >= 0 && row <= col)
          tie_rows[static_cast<std::size_t>(col)].push_back(row);
      }
    }
  }
  std::vector<int> outer(static_cast<std::size_t>(num_unknowns_) + 1, 0);
  std::vector<int> inner;
  inner.reserve(all_nodes.size() * 4 + 4 * nn);
  std::vector<int> rows;
  auto add_node_rows = [&](std::size_t r, int limit) {
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * r + c];
      if (f >= 0 && f <= limit) rows.push_back(f);
    }
  };
  for (std::size_t k = 0; k < nn; ++k) {
    for (std::size_t comp = 0; comp < 2; ++comp) {
      const int col = free_index_[2 * k + comp];
      if (col < 0) continue;
      rows.clear();
      for (int a = all_offset[k]; a < all_offset[k + 1]; ++a) {
        const auto r = static_cast<std::size_t>(all_nodes[static_cast<std::size_t>(a)]);
        if (r < k) add_node_rows(r, col);
      }
      if (all_offset[k + 1] > all_offset[k]) add_node_rows(k, col);
      rows.push_back(col);
      const auto& extra = tie_rows[static_cast<std::size_t>(col)];
      rows.insert(rows.end(), extra.begin(), extra.end());
      std::sort(rows.begin(), rows.end());
      rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
      inner.insert(inner.end(), rows.begin(), rows.end());
      outer[static_cast<std::size_t>(col) + 1] = static_cast<int>(inner.size());
    }
  }
  if (mixed_) {
    for (std::size_t k = 0; k < nn; ++k) {
      rows.clear();
      for (int a = all_offset[k]; a < all_offset[k + 1]; ++a) {
        add_node_rows(static_cast<std::size_t>(all_nodes[static_cast<std::size_t>(a)]), num_free_);
      }
      if (all_offset[k + 1] > all_offset[k]) add_node_rows(k, num_free_);
      std::sort(rows.begin(), rows.end());
      rows.push_back(num_free_ + static_cast<int>(k));
      inner.insert(inner.end(), rows.begin(), rows.end());
      outer[static_cast<std::size_t>(num_free_) + k + 1] = static_cast<int>(inner.size());
    }
  }
  upper_.resize(num_unknowns_, num_unknowns_);
  upper_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), upper_.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), upper_.innerIndexPtr());
  pattern_ready_ = true;
}

std::size_t StaticSolver::entry(int row, int col) const {
  const int* begin = upper_.innerIndexPtr() + upper_.outerIndexPtr()[col];
  const int* end = upper_.innerIndexPtr() + upper_.outerIndexPtr()[col + 1];
  const int* at = std::lower_bound(begin, end, row);
  return static_cast<std::size_t>(at - upper_.innerIndexPtr());
}

void StaticSolver::assemble_by_scatter(const std::vector<double>& factors) {
  // The products' order per entry (assemble_by_products): K_bb(i, j) is Σ_b g_bi·(w_b·g_bj) over
  // the bonds in increasing order, the first term assigned (−0 + x = x reproduces that, signed
  // zeros included); then, bond-based, K_bb + (ground + ties) as Eigen's sparse sum (an entry in
  // one operand only is x + 0 or 0 + x); mixed, setFromTriplets' sums in triplet order: K_bb,
  // then Bᵀ, the w diagonal, the ground springs, the ties.
  if (!pattern_ready_) build_pattern();
  const auto nnz = static_cast<std::size_t>(upper_.nonZeros());
  double* value = upper_.valuePtr();
  std::fill(value, value + nnz, -0.0);
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  std::vector<std::uint8_t> has_bond(mixed_ ? 0 : nnz, 0);
  for (std::size_t b = 0; b < nb; ++b) {
    if (disc_.bond_precut[b]) continue;  // not in the stiffness (build_pattern)
    const double w = intact_[b] ? model_.bond_stiffness[b] * factors[b] : 0.0;
    const auto g = bond_gradient(b, 1.0);
    for (const auto& [row, g_row] : g) {
      if (row < 0) continue;
      for (const auto& [col, g_col] : g) {
        if (col < row) continue;  // col ≥ 0 too
        const std::size_t e = entry(row, col);
        value[e] += g_row * (w * g_col);
        if (!mixed_) has_bond[e] = 1;
      }
    }
  }
  if (mixed_) {
    for (std::size_t b = 0; b < nb; ++b) {
      if (disc_.bond_precut[b]) continue;
      const double q = intact_[b] ? model_.dilatation_weight[b] / disc_.bond_length[b] : 0.0;
      for (const mesh::NodeIndex node : {disc_.bond_i[b], disc_.bond_j[b]}) {
        for (const auto& [f, v] : bond_gradient(b, q)) {
          if (f >= 0) value[entry(f, num_free_ + node)] += w_scale_ * v;
        }
      }
    }
    for (mesh::NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
      const int w_row = num_free_ + node;
      value[entry(w_row, w_row)] +=
          -w_scale_ * w_scale_ / model_.dilatation_stiffness[static_cast<std::size_t>(node)];
    }
  }
  // Ground springs and ties: added in place (mixed) or summed apart and added as a matrix.
  std::vector<double> extra(mixed_ ? 0 : nnz, -0.0);
  std::vector<std::uint8_t> has_extra(mixed_ ? 0 : nnz, 0);
  auto add_extra = [&](int row, int col, double v) {
    const std::size_t e = entry(row, col);
    if (mixed_) {
      value[e] += v;
    } else {
      extra[e] += v;
      has_extra[e] = 1;
    }
  };
  for (mesh::NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    const bool ground = grounded_[static_cast<std::size_t>(node)] != 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0) {  // as append_ground: pins are the same springs
        const bool spring = ground || pinned_[static_cast<std::size_t>(f)] != 0;
        add_extra(f, f, spring ? ground_stiffness_ : 0.0);
      }
    }
  }
  for (const Tie& tie : ties_) {
    const auto g = tie_gradient(tie);
    for (const auto& [row, g_row] : g) {
      for (const auto& [col, g_col] : g) {
        if (row >= 0 && col >= 0 && row <= col) add_extra(row, col, tie.stiffness * g_row * g_col);
      }
    }
  }
  if (!mixed_) {
    for (std::size_t e = 0; e < nnz; ++e) {
      if (has_bond[e] && has_extra[e]) {
        value[e] = value[e] + extra[e];
      } else if (has_bond[e]) {
        value[e] = value[e] + 0.0;
      } else {
        value[e] = 0.0 + extra[e];
      }
    }
  }
}

void StaticSolver::assemble_by_products(const std::vector<double>& factors,
                                        linalg::SparseMatrix& out) const {
  // Pattern from the bonds not precut (their rows of G are empty); bonds broken since keep
  // explicit zeros so the pattern (and CHOLMOD's symbolic analysis) never changes.
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  const bool osb = model_.options.kind == model::ModelKind::state_based;
  std::vector<Eigen::Triplet<double, int>> g_entries;
  g_entries.reserve(4 * nb);
  Eigen::VectorXd weight(static_cast<Eigen::Index>(nb));
  auto add_row = [&](std::vector<Eigen::Triplet<double, int>>& t, int row, std::size_t b,
                     double scale) {
    for (const auto& [f, value] : bond_gradient(b, scale)) {
      if (f >= 0) t.emplace_back(row, f, value);
    }
  };
  for (std::size_t b = 0; b < nb; ++b) {
    weight[static_cast<Eigen::Index>(b)] = 0.0;
    if (disc_.bond_precut[b]) continue;
    add_row(g_entries, static_cast<int>(b), b, 1.0);  // row b: e·(u_j − u_i)
    weight[static_cast<Eigen::Index>(b)] = intact_[b] ? model_.bond_stiffness[b] * factors[b] : 0.0;
  }
  linalg::SparseMatrix g(static_cast<Eigen::Index>(nb), num_free_);
  g.setFromTriplets(g_entries.begin(), g_entries.end());
  g_entries = {};
  linalg::SparseMatrix gt = g.transpose();
  linalg::SparseMatrix k = gt * (weight.asDiagonal() * g);

  if (osb) {
    // θ = B·u, row k: Σ_b q_b·ψ_b·e·(u_j − u_i)/ξ over k's family (000 Eq. B4).
    std::vector<Eigen::Triplet<double, int>> b_entries;
    b_entries.reserve(8 * nb);
    for (std::size_t b = 0; b < nb; ++b) {
      if (disc_.bond_precut[b]) continue;
      const double q = intact_[b] ? model_.dilatation_weight[b] / disc_.bond_length[b] : 0.0;
      add_row(b_entries, disc_.bond_i[b], b, q);
      add_row(b_entries, disc_.bond_j[b], b, q);
    }
    if (mixed_) {
      // Upper triangle of the mixed matrix: K_bb, then Bᵀ in the (u, w) block, then −A⁻¹.
      std::vector<Eigen::Triplet<double, int>> m;
      m.reserve(static_cast<std::size_t>(k.nonZeros()) / 2 + b_entries.size() +
                2 * static_cast<std::size_t>(num_unknowns_));
      for (int c = 0; c < k.outerSize(); ++c) {
        for (linalg::SparseMatrix::InnerIterator it(k, c); it; ++it) {
          if (it.row() <= it.col()) m.emplace_back(it.row(), it.col(), it.value());
        }
      }
      // In w' = w/s: the Bᵀ block times s, −A⁻¹ times s².
      for (const auto& t : b_entries) {
        m.emplace_back(t.col(), num_free_ + t.row(), w_scale_ * t.value());
      }
      for (mesh::NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
        m.emplace_back(
            num_free_ + node, num_free_ + node,
            -w_scale_ * w_scale_ / model_.dilatation_stiffness[static_cast<std::size_t>(node)]);
      }
      append_ground(m);
      append_ties(m);
      out.resize(num_unknowns_, num_unknowns_);
      out.setFromTriplets(m.begin(), m.end());
      out.makeCompressed();
      return;
    }
    linalg::SparseMatrix bmat(disc_.num_nodes(), num_free_);
    bmat.setFromTriplets(b_entries.begin(), b_entries.end());
    b_entries = {};
    const Eigen::Map<const Eigen::VectorXd> alpha(model_.dilatation_stiffness.data(),
                                                  disc_.num_nodes());
    linalg::SparseMatrix bt = bmat.transpose();
    k += bt * (alpha.asDiagonal() * bmat);
  }
  // Ground springs on isolated nodes; every free DOF is in the diagonal's pattern (zeros elsewhere)
  // so the pattern does not change when a node becomes isolated.
  // The ties' upper triangle goes in with them (k is full; its upper part is kept below).
  std::vector<Eigen::Triplet<double, int>> diag;
  append_ground(diag);
  append_ties(diag);
  linalg::SparseMatrix ground(num_free_, num_free_);
  ground.setFromTriplets(diag.begin(), diag.end());
  k += ground;
  out = k.triangularView<Eigen::Upper>();
  out.makeCompressed();
}

}  // namespace peritwin::statics
