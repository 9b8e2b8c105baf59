#include "solver/static/static_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace peritwin {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

double tie_violation(const Tie& tie, const std::vector<double>& u) {
  double violation = 0.0;
  for (const TieTerm& term : tie.terms) {
    violation +=
        term.coefficient *
        u[2 * static_cast<std::size_t>(term.node) + static_cast<std::size_t>(term.component)];
  }
  return violation;
}

StaticSolver::StaticSolver(const Discretization& disc, const PdModel& model,
                           std::vector<Support> supports, std::vector<LoadTerm> loads,
                           std::vector<Tie> ties)
    : disc_(disc),
      model_(model),
      supports_(std::move(supports)),
      loads_(std::move(loads)),
      ties_(std::move(ties)) {
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
  intact_.resize(static_cast<std::size_t>(disc.num_bonds()));
  factor_.resize(intact_.size());
  for (std::size_t b = 0; b < intact_.size(); ++b) {
    intact_[b] = disc.bond_precut[b] ? 0 : 1;
    factor_[b] = intact_[b] ? 1.0 : 0.0;
  }
  const auto ndof = 2 * static_cast<std::size_t>(disc.num_nodes());
  free_index_.assign(ndof, 0);
  for (const auto& s : supports_) {
    for (NodeIndex k : s.nodes) {
      if (s.fix_x) free_index_[2 * static_cast<std::size_t>(k)] = -1;
      if (s.fix_y) free_index_[2 * static_cast<std::size_t>(k) + 1] = -1;
    }
  }
  for (auto& f : free_index_) f = f < 0 ? -1 : num_free_++;
  // Mixed form for the state-based model when every α_k = 2a·V_k/h < 0 (a < 0 ⇔ ν < 1/3):
  //   [K_bb  Bᵀ    ] [u]   [f]
  //   [B    −A⁻¹   ] [w] = [0],   A = diag(α_k),
  // whose Schur complement on w is K_bb + Bᵀ·A·B = K. −A⁻¹ is positive, and so is the Schur
  // complement, hence the whole matrix is SPD: Cholesky applies, the coupling reach is δ instead
  // of 2δ, and breaking a bond is a rank-3 change with 4-6 nonzeros per vector.
  mixed_ = model.options.kind == ModelKind::state_based && !model.dilatation_stiffness.empty() &&
           std::all_of(model.dilatation_stiffness.begin(), model.dilatation_stiffness.end(),
                       [](double a) { return a < 0.0; });
  num_unknowns_ = num_free_ + (mixed_ ? disc.num_nodes() : 0);
  double sum = 0.0;
  for (double k : model.bond_stiffness) sum += k;
  ground_stiffness_ =
      model.bond_stiffness.empty() ? 1.0 : sum / static_cast<double>(model.bond_stiffness.size());
  grounded_.assign(static_cast<std::size_t>(disc.num_nodes()), 0);
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

bool StaticSolver::isolated(NodeIndex k) const {
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

SparseCholesky::Column StaticSolver::dilatation_row(NodeIndex k) const {
  SparseCholesky::Column row;
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

void StaticSolver::append_ground(std::vector<Eigen::Triplet<double, int>>& entries) const {
  for (NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    const bool ground = grounded_[static_cast<std::size_t>(node)] != 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0) entries.emplace_back(f, f, ground ? ground_stiffness_ : 0.0);
    }
  }
}

void StaticSolver::assemble(const std::vector<double>& factors) {
  const bool condensed = model_.options.kind == ModelKind::state_based && !mixed_;
  if (condensed) {
    assemble_by_products(factors, upper_);
  } else {
    assemble_by_scatter(factors);
  }
}

SparseMatrix StaticSolver::stiffness_upper_by_products() const {
  SparseMatrix out;
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
      for (const NodeIndex node : {disc_.bond_i[b], disc_.bond_j[b]}) {
        for (const auto& [f, v] : bond_gradient(b, q)) {
          if (f >= 0) value[entry(f, num_free_ + node)] += w_scale_ * v;
        }
      }
    }
    for (NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
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
  for (NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    const bool ground = grounded_[static_cast<std::size_t>(node)] != 0;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0) add_extra(f, f, ground ? ground_stiffness_ : 0.0);
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
                                        SparseMatrix& out) const {
  // Pattern from the bonds not precut (their rows of G are empty); bonds broken since keep
  // explicit zeros so the pattern (and CHOLMOD's symbolic analysis) never changes.
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  const bool osb = model_.options.kind == ModelKind::state_based;
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
  SparseMatrix g(static_cast<Eigen::Index>(nb), num_free_);
  g.setFromTriplets(g_entries.begin(), g_entries.end());
  g_entries = {};
  SparseMatrix gt = g.transpose();
  SparseMatrix k = gt * (weight.asDiagonal() * g);

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
        for (SparseMatrix::InnerIterator it(k, c); it; ++it) {
          if (it.row() <= it.col()) m.emplace_back(it.row(), it.col(), it.value());
        }
      }
      // In w' = w/s: the Bᵀ block times s, −A⁻¹ times s².
      for (const auto& t : b_entries) {
        m.emplace_back(t.col(), num_free_ + t.row(), w_scale_ * t.value());
      }
      for (NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
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
    SparseMatrix bmat(disc_.num_nodes(), num_free_);
    bmat.setFromTriplets(b_entries.begin(), b_entries.end());
    b_entries = {};
    const Eigen::Map<const Eigen::VectorXd> alpha(model_.dilatation_stiffness.data(),
                                                  disc_.num_nodes());
    SparseMatrix bt = bmat.transpose();
    k += bt * (alpha.asDiagonal() * bmat);
  }
  // Ground springs on isolated nodes; every free DOF is in the diagonal's pattern (zeros elsewhere)
  // so the pattern does not change when a node becomes isolated.
  // The ties' upper triangle goes in with them (k is full; its upper part is kept below).
  std::vector<Eigen::Triplet<double, int>> diag;
  append_ground(diag);
  append_ties(diag);
  SparseMatrix ground(num_free_, num_free_);
  ground.setFromTriplets(diag.begin(), diag.end());
  k += ground;
  out = k.triangularView<Eigen::Upper>();
  out.makeCompressed();
}

std::vector<int> StaticSolver::dof_ordering() const {
  // Order the node graph (the 2x2 blocks of K) and expand it to the free DOFs: 2-4x smaller to
  // order than the DOF graph, and it keeps each node's DOFs together in the supernodes.
  const auto nn = disc_.num_nodes();
  std::vector<Eigen::Triplet<double, int>> links;
  links.reserve(static_cast<std::size_t>(disc_.num_bonds()) + static_cast<std::size_t>(nn));
  for (NodeIndex k = 0; k < nn; ++k) links.emplace_back(k, k, 1.0);
  for (BondIndex b = 0; b < disc_.num_bonds(); ++b) {
    if (!disc_.bond_precut[b]) links.emplace_back(disc_.bond_i[b], disc_.bond_j[b], 1.0);
  }
  for (const Tie& tie : ties_) {  // a tie couples every pair of its nodes
    std::vector<NodeIndex> nodes;
    for (const TieTerm& term : tie.terms) nodes.push_back(term.node);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    for (std::size_t p = 0; p < nodes.size(); ++p) {
      for (std::size_t q = p + 1; q < nodes.size(); ++q)
        links.emplace_back(nodes[p], nodes[q], 1.0);
    }
  }
  SparseMatrix incidence(nn, nn);
  incidence.setFromTriplets(links.begin(), links.end());
  SparseMatrix node_graph = incidence.selfadjointView<Eigen::Upper>();
  if (model_.options.kind == ModelKind::state_based && !mixed_) {
    node_graph = node_graph * node_graph;  // the dilatation couples nodes two bonds apart
  }
  SparseMatrix node_upper = node_graph.triangularView<Eigen::Upper>();
  node_upper.makeCompressed();
  const std::vector<int> node_order = SparseCholesky::fill_reducing_ordering(node_upper, ordering_);
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

Status StaticSolver::solve() {
  auto t0 = std::chrono::steady_clock::now();
  assemble(factor_);
  timings_.assemble_s = seconds_since(t0);
  if (!cholesky_.analyzed()) {
    t0 = std::chrono::steady_clock::now();
    const std::vector<int> permutation = dof_ordering();
    if (auto r = cholesky_.analyze(upper_, &permutation); !r.ok()) return r;
    timings_.analyze_s = seconds_since(t0);
  }
  t0 = std::chrono::steady_clock::now();
  auto report = cholesky_.factorize(upper_);
  ++factorizations_;
  updated_ = false;
  released_ = false;
  timings_.factor_s = seconds_since(t0);
  if (!report.ok()) return report;
  reference_ = factor_;

  t0 = std::chrono::steady_clock::now();
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
    forces[static_cast<std::size_t>(basis)] = basis_force(static_cast<Basis>(basis));
    bool any = false;
    for (double v : forces[static_cast<std::size_t>(basis)]) any = any || v != 0.0;
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
      bond_stretches(disc_, u, s_[static_cast<std::size_t>(basis)]);
    } else {
      s_[static_cast<std::size_t>(basis)].assign(static_cast<std::size_t>(disc_.num_bonds()), 0.0);
    }
  }
  basis_solve_s_ += seconds_since(t0);
}

Status StaticSolver::refactor_resolve() {
  for (NodeIndex k = 0; k < disc_.num_nodes(); ++k) {
    if (isolated(k)) grounded_[static_cast<std::size_t>(k)] = 1;
  }
  if (modified_) {  // the factor is simplicial LDLᵀ now: analyze again for a supernodal one
    cholesky_ = SparseCholesky();
    modified_ = false;
  }
  return solve();
}

void StaticSolver::ground_isolated(const std::vector<NodeIndex>& nodes,
                                   std::vector<SparseCholesky::Column>& added) {
  for (NodeIndex k : nodes) {
    if (grounded_[static_cast<std::size_t>(k)] || !isolated(k)) continue;
    grounded_[static_cast<std::size_t>(k)] = 1;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(k) + c];
      if (f >= 0) added.push_back({{f}, {std::sqrt(ground_stiffness_)}});
    }
  }
}

bool StaticSolver::release_factor() {
  if (!incremental_ || preconditioned_ || updated_ || released_ || !cholesky_.has_values()) {
    return false;
  }
  released_ = cholesky_.release_values();
  return released_;
}

Status StaticSolver::update_resolve(const std::vector<SparseCholesky::Column>& added,
                                    const std::vector<SparseCholesky::Column>& removed,
                                    std::chrono::steady_clock::time_point t0) {
  if (released_) {  // upper_ is still the released factor's matrix: the same factor again
    Status f = cholesky_.factorize(upper_);
    ++factorizations_;
    released_ = false;
    if (f.ok()) f = cholesky_.convert_to_ldlt();
    if (!f.ok()) {
      update_s_ += seconds_since(t0);
      return f;
    }
  }
  updated_ = true;
  modified_ = true;
  Status r = cholesky_.modify_fused(added, removed);
  ++updates_;
  if (!r.ok()) {
    update_s_ += seconds_since(t0);
    return r;
  }
  solve_bases();
  update_s_ += seconds_since(t0);
  return r;
}

Status StaticSolver::break_bonds(std::span<const BondIndex> bonds) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!incremental_ || !cholesky_.analyzed()) {
    for (BondIndex b : bonds) {
      intact_[static_cast<std::size_t>(b)] = 0;
      factor_[static_cast<std::size_t>(b)] = 0.0;
    }
    return refactor_resolve();
  }
  // K_new = K − Σ_b f_b·k_b·g_b·g_bᵀ + Σ_k α_k·(b'_k·b'_kᵀ − b_k·b_kᵀ) (+ ground springs), applied
  // as one rank-k update (the added terms) followed by one downdate (the removed ones).
  std::vector<SparseCholesky::Column> added, removed;
  const bool osb = model_.options.kind == ModelKind::state_based && !mixed_;
  std::vector<NodeIndex> nodes;
  for (BondIndex bond : bonds) {
    const auto b = static_cast<std::size_t>(bond);
    if (!intact_[b]) continue;
    SparseCholesky::Column g;
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
        SparseCholesky::Column up, down;
        for (const auto& [f, v] : bond_gradient(b, 1.0)) {
          if (f >= 0) {
            up.rows.push_back(f);
            up.values.push_back(sp * c * v);
            down.rows.push_back(f);
            down.values.push_back(sm * c * v);
          }
        }
        for (const NodeIndex node : {disc_.bond_i[b], disc_.bond_j[b]}) {  // y in w' = w/s: s·y
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
  std::vector<SparseCholesky::Column> old_rows;
  if (osb) {
    for (NodeIndex k : nodes) old_rows.push_back(dilatation_row(k));
  }
  for (BondIndex b : bonds) {
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

Status StaticSolver::set_bond_factors(std::span<const BondIndex> bonds,
                                      std::span<const double> factors) {
  if (model_.options.kind != ModelKind::bond_based) {
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
  std::vector<SparseCholesky::Column> added, removed;
  std::vector<NodeIndex> nodes;
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
    SparseCholesky::Column g;
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
  for (NodeIndex node = 0; node < disc_.num_nodes(); ++node) {
    if (!grounded_[static_cast<std::size_t>(node)]) continue;
    for (std::size_t c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(node) + c];
      if (f >= 0) y[f] += ground_stiffness_ * x[f];
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
    const auto force = basis_force(static_cast<Basis>(basis));
    std::vector<double> rhs(n, 0.0);
    bool any = false;
    for (std::size_t dof = 0; dof < force.size(); ++dof) {
      if (free_index_[dof] >= 0) rhs[static_cast<std::size_t>(free_index_[dof])] = force[dof];
      any = any || force[dof] != 0.0;
    }
    if (!any) continue;
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
        bond_stretches(disc_, u, s_[static_cast<std::size_t>(basis)]);
      } else {
        s_[static_cast<std::size_t>(basis)].assign(static_cast<std::size_t>(disc_.num_bonds()),
                                                   0.0);
      }
    }
  }
  pcg_.seconds += seconds_since(t0);
  return ok;
}

Status StaticSolver::preconditioned_resolve(bool broke) {
  if (broke) {  // the same ground springs as refactor_resolve
    for (NodeIndex k = 0; k < disc_.num_nodes(); ++k) {
      if (isolated(k)) grounded_[static_cast<std::size_t>(k)] = 1;
    }
  }
  if (modified_) {  // an updated factor is not the factor of any reference: start afresh
    cholesky_ = SparseCholesky();
    modified_ = false;
  }
  std::vector<double> reference(factor_.size());
  for (std::size_t b = 0; b < factor_.size(); ++b) {
    reference[b] = reference_factor(factor_[b], pcg_step_);
  }
  // A new reference exactly when some bond's f_ref changed (a bond broke: its f_ref is 0 now, so
  // the ground springs, which change only then, are always current in the factor).
  if (!cholesky_.analyzed() || reference != reference_) {
    auto t = std::chrono::steady_clock::now();
    assemble(reference);
    timings_.assemble_s = seconds_since(t);
    if (!cholesky_.analyzed()) {
      const std::vector<int> permutation = dof_ordering();
      if (auto r = cholesky_.analyze(upper_, &permutation); !r.ok()) return r;
    }
    t = std::chrono::steady_clock::now();
    Status report = cholesky_.factorize(upper_);
    ++factorizations_;
    ++pcg_.reference_factorizations;
    timings_.factor_s = seconds_since(t);
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

std::vector<double> StaticSolver::basis_force(Basis b) const {
  std::vector<double> f(2 * static_cast<std::size_t>(disc_.num_nodes()), 0.0);
  for (const auto& load : loads_) {
    if (load.nodes.empty()) continue;
    const Point part = b == basis_constant ? load.constant
                       : b == basis_cos    ? load.per_cos
                                           : load.per_sin;
    const double share = 1.0 / static_cast<double>(load.nodes.size());
    for (NodeIndex k : load.nodes) {
      f[2 * static_cast<std::size_t>(k)] += part.x * share;
      f[2 * static_cast<std::size_t>(k) + 1] += part.y * share;
    }
  }
  return f;
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
  bond_stretches(disc_, u, stretch_values);
  std::vector<double> theta;
  dilatations(disc_, model_, intact_, stretch_values, theta);
  std::vector<double> f(u.size(), 0.0);
  const bool osb = model_.options.kind == ModelKind::state_based;
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

}  // namespace peritwin
