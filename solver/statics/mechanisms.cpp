// StaticSolver's mechanisms: what a factorization that fails has found. Either a piece of the model
// came loose (no intact bond or tie connects it to a support): final failure, named, unless it is
// unloaded debris smaller than a family, which is grounded like an isolated node; or a part still
// attached can move without straining any intact bond — a mechanism of the linearized bond
// stretch (000 Eq. 3d), e.g. nodes left with bonds along one line only — which is pinned by a
// ground spring on one of its DOFs. Either way it is factorized again (docs/solver.md,
// "Mechanisms are pinned"). The state-based model has the same mechanisms as its pair terms: the
// dilatation θ_k (000 Eq. 3c) is a sum of the intact bonds' stretches, and its negative
// coefficient for ν < 1/3 (000 Eq. 4a) is outweighed by the pair terms (at ν = 0.33 and
// δ = 3.015Δx under 1 % of them by Cauchy–Schwarz on a full family, less as bonds break); a patch
// where it were not would be reported as indefinite.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/statics/static_solver.h"

namespace peritwin::statics {

namespace {

/// A patch eigenvalue at most this fraction of the patch's largest is a mechanism: an exact one
/// is round-off (5e-18 in the middle-crack tension panel, docs/solver.md, whose next eigenvalue,
/// a weak real stiffness next to the crack, was 6e-3), and the factorization's own verdict,
/// min/max of the pivots, is 1e-14.
constexpr double kMechanismRelative = 1e-10;
/// A mechanism carries load when its work with a basis load exceeds this fraction of the load's
/// norm (the loads act on whole regions, away from the patch, or on it).
constexpr double kLoadRelative = 1e-9;

}  // namespace

core::Status StaticSolver::ground_loose_debris(bool& grounded_any) {
  grounded_any = false;
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  // Ties join their nodes like bonds do.
  std::vector<std::vector<mesh::NodeIndex>> tied(nn);
  for (const Tie& tie : ties_) {
    for (const TieTerm& a : tie.terms) {
      for (const TieTerm& b : tie.terms) {
        if (a.node != b.node) tied[static_cast<std::size_t>(a.node)].push_back(b.node);
      }
    }
  }
  std::vector<std::uint8_t> reached(nn, 0);
  std::vector<mesh::NodeIndex> stack;
  std::vector<mesh::NodeIndex> piece;
  auto flood = [&](std::size_t start) {  // the nodes connected to `start`, into `piece`
    piece.clear();
    reached[start] = 1;
    stack.push_back(static_cast<mesh::NodeIndex>(start));
    while (!stack.empty()) {
      const mesh::NodeIndex k = stack.back();
      stack.pop_back();
      piece.push_back(k);
      auto visit = [&](mesh::NodeIndex o) {
        if (!reached[static_cast<std::size_t>(o)]) {
          reached[static_cast<std::size_t>(o)] = 1;
          stack.push_back(o);
        }
      };
      for (auto f = disc_.family_offset[static_cast<std::size_t>(k)];
           f < disc_.family_offset[static_cast<std::size_t>(k) + 1]; ++f) {
        const mesh::BondIndex b = disc_.family_bonds[static_cast<std::size_t>(f)];
        if (intact_[static_cast<std::size_t>(b)]) visit(disc_.other_end(b, k));
      }
      for (mesh::NodeIndex o : tied[static_cast<std::size_t>(k)]) visit(o);
    }
  };
  for (std::size_t k = 0; k < nn; ++k) {  // everything connected to a support
    if (!reached[k] && (free_index_[2 * k] < 0 || free_index_[2 * k + 1] < 0)) flood(k);
  }
  std::vector<std::uint8_t> loaded(nn, 0);
  for (const LoadTerm& load : loads_) {
    const bool any = load.constant.x != 0.0 || load.constant.y != 0.0 || load.per_cos.x != 0.0 ||
                     load.per_cos.y != 0.0 || load.per_sin.x != 0.0 || load.per_sin.y != 0.0;
    for (mesh::NodeIndex k : load.nodes) loaded[static_cast<std::size_t>(k)] |= any ? 1 : 0;
  }
  std::int32_t family = 0;
  for (std::size_t k = 0; k < nn; ++k) {
    family = std::max(family, disc_.family_offset[k + 1] - disc_.family_offset[k]);
  }
  // Debris: a loose piece without load and with fewer nodes than a full family, smaller than
  // the model's length scale δ (a single isolated node is the smallest). The rest is final.
  std::vector<mesh::NodeIndex> debris;
  std::int64_t finals = 0;
  std::size_t largest = 0;
  bool largest_loaded = false;
  double box[4] = {0.0, 0.0, 0.0, 0.0};
  for (std::size_t k = 0; k < nn; ++k) {
    if (reached[k]) continue;
    flood(k);
    bool carries = false;
    bool held = true;  // every node grounded already (isolated nodes, earlier debris)
    for (mesh::NodeIndex n : piece) {
      carries = carries || loaded[static_cast<std::size_t>(n)] != 0;
      held = held && grounded_[static_cast<std::size_t>(n)] != 0;
    }
    if (held && !carries) continue;
    if (!carries && piece.size() < static_cast<std::size_t>(family)) {
      debris.insert(debris.end(), piece.begin(), piece.end());
      continue;
    }
    ++finals;
    if (piece.size() <= largest) continue;
    largest = piece.size();
    largest_loaded = carries;
    const mesh::Point first = disc_.position[static_cast<std::size_t>(piece.front())];
    box[0] = box[1] = first.x;
    box[2] = box[3] = first.y;
    for (mesh::NodeIndex n : piece) {
      const mesh::Point p = disc_.position[static_cast<std::size_t>(n)];
      box[0] = std::min(box[0], p.x);
      box[1] = std::max(box[1], p.x);
      box[2] = std::min(box[2], p.y);
      box[3] = std::max(box[3], p.y);
    }
  }
  if (finals > 0) {
    char text[200];
    std::snprintf(text, sizeof text,
                  "a piece of %zu nodes%s came loose (x from %g to %g mm, y from %g to "
                  "%g mm)",
                  largest, largest_loaded ? " with load on it" : "", box[0] * 1e3, box[1] * 1e3,
                  box[2] * 1e3, box[3] * 1e3);
    std::string out = text;
    if (finals > 1) {
      std::snprintf(text, sizeof text, " and %lld more pieces", static_cast<long long>(finals - 1));
      out += text;
    }
    return core::failure(out);
  }
  // Unloaded and held by nothing, debris has no strain under any load: a ground spring on each
  // of its nodes (as on an isolated node) fixes its free motion and changes no stretch.
  for (mesh::NodeIndex n : debris) grounded_[static_cast<std::size_t>(n)] = 1;
  grounded_any = !debris.empty();
  return {};
}

core::Status StaticSolver::pin_group_mechanisms(const std::vector<double>& factors) {
  std::vector<mesh::NodeIndex> centres;
  const double spacing2 = disc_.horizon * disc_.horizon;
  for (const mesh::NodeIndex k : group_nodes_) {
    const mesh::Point p = disc_.position[static_cast<std::size_t>(k)];
    const bool covered = std::any_of(centres.begin(), centres.end(), [&](mesh::NodeIndex c) {
      const mesh::Point q = disc_.position[static_cast<std::size_t>(c)];
      return (p.x - q.x) * (p.x - q.x) + (p.y - q.y) * (p.y - q.y) < spacing2;
    });
    if (!covered) centres.push_back(k);
  }
  for (const mesh::NodeIndex c : centres) {
    if (auto r = pin_mechanisms(c, factors, false, false); !r.ok()) return r;
  }
  return {};
}

core::Status StaticSolver::pin_mechanisms(mesh::NodeIndex centre,
                                          const std::vector<double>& factors, bool wide,
                                          bool none_is_failure) {
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  const mesh::Point c = disc_.position[static_cast<std::size_t>(centre)];
  char where_text[64];
  std::snprintf(where_text, sizeof where_text, "(%g, %g) mm", c.x * 1e3, c.y * 1e3);
  const std::string where = where_text;
  std::array<std::vector<double>, 3> loads;
  for (int basis = 0; basis < 3; ++basis) {
    loads[static_cast<std::size_t>(basis)] = basis_force(static_cast<Basis>(basis));
  }
  for (const double radius : {2.0 * disc_.horizon, 4.0 * disc_.horizon}) {
    if (radius > 2.0 * disc_.horizon && !wide) break;
    // The patch: the free DOFs of the nodes within `radius` of the centre. Its principal
    // submatrix of K is the energy of the displacements that vanish outside it, so a null
    // vector there (K_SS·m = 0) is one of K (mᵀKm = 0 and K ≥ 0 give K·m = 0).
    std::vector<std::size_t> nodes;
    std::vector<std::int32_t> local(static_cast<std::size_t>(num_free_), -1);
    std::vector<std::int32_t> dofs;     // local -> free index
    std::vector<std::size_t> dof_node;  // local -> node
    for (std::size_t k = 0; k < nn; ++k) {
      const double dx = disc_.position[k].x - c.x;
      const double dy = disc_.position[k].y - c.y;
      if (dx * dx + dy * dy > radius * radius) continue;
      nodes.push_back(k);
      for (std::size_t comp = 0; comp < 2; ++comp) {
        const int f = free_index_[2 * k + comp];
        if (f < 0) continue;
        local[static_cast<std::size_t>(f)] = static_cast<std::int32_t>(dofs.size());
        dofs.push_back(f);
        dof_node.push_back(k);
      }
    }
    const auto n = static_cast<Eigen::Index>(dofs.size());
    if (n == 0) continue;
    Eigen::MatrixXd k_ss = Eigen::MatrixXd::Zero(n, n);
    std::vector<std::pair<Eigen::Index, double>> g;
    auto restrict = [&](const std::array<std::pair<int, double>, 4>& full) {
      g.clear();
      for (const auto& [f, v] : full) {
        if (f >= 0 && local[static_cast<std::size_t>(f)] >= 0) {
          g.emplace_back(local[static_cast<std::size_t>(f)], v);
        }
      }
    };
    auto add_outer = [&](const std::vector<std::pair<Eigen::Index, double>>& v, double w) {
      for (const auto& [r, a] : v) {
        for (const auto& [s, b] : v) k_ss(r, s) += w * a * b;
      }
    };
    // Pair terms of the intact bonds with an end in the patch, once each; the nodes whose
    // dilatation sees the patch are those bonds' ends.
    std::vector<std::uint8_t> seen(nb, 0);
    std::vector<std::uint8_t> dilating(nn, 0);
    std::vector<std::size_t> dilating_nodes;
    for (const std::size_t k : nodes) {
      for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
        const auto b = static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(f)]);
        if (seen[b] || !intact_[b]) continue;
        seen[b] = 1;
        const double w = model_.bond_stiffness[b] * factors[b];
        restrict(bond_gradient(b, 1.0));
        add_outer(g, w);
        for (const auto e : {static_cast<std::size_t>(disc_.bond_i[b]),
                             static_cast<std::size_t>(disc_.bond_j[b])}) {
          if (!dilating[e]) dilating_nodes.push_back(e);
          dilating[e] = 1;
        }
      }
    }
    // Dilatation terms α_k·b_k·b_kᵀ, b_k the patch part of θ_k = B_k·u (000 Eq. B4).
    if (!model_.dilatation_stiffness.empty()) {
      std::sort(dilating_nodes.begin(), dilating_nodes.end());
      Eigen::VectorXd row(n);
      for (const std::size_t k : dilating_nodes) {
        row.setZero();
        for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
          const auto b = static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(f)]);
          if (!intact_[b]) continue;
          restrict(bond_gradient(b, model_.dilatation_weight[b] / disc_.bond_length[b]));
          for (const auto& [r, v] : g) row[r] += v;
        }
        k_ss.noalias() += model_.dilatation_stiffness[k] * row * row.transpose();
      }
    }
    // Ground springs, pins and ties, as assembled.
    for (Eigen::Index r = 0; r < n; ++r) {
      const auto f = static_cast<std::size_t>(dofs[static_cast<std::size_t>(r)]);
      if (grounded_[dof_node[static_cast<std::size_t>(r)]] || pinned_[f]) {
        k_ss(r, r) += ground_stiffness_;
      }
    }
    for (const Tie& tie : ties_) {
      g.clear();
      for (const auto& [f, v] : tie_gradient(tie)) {
        if (f >= 0 && local[static_cast<std::size_t>(f)] >= 0) {
          g.emplace_back(local[static_cast<std::size_t>(f)], v);
        }
      }
      add_outer(g, tie.stiffness);
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(k_ss);
    if (eig.info() != Eigen::Success) break;
    const Eigen::VectorXd& lambda = eig.eigenvalues();  // ascending
    const double largest = std::max(std::abs(lambda[0]), std::abs(lambda[n - 1]));
    if (lambda[0] < -kMechanismRelative * largest) {
      char text[64];
      std::snprintf(text, sizeof text, "%.3g", lambda[0] / largest);
      return core::failure("the stiffness is indefinite at " + where +
                           " (the smallest eigenvalue within " +
                           (radius > 2.0 * disc_.horizon ? "4δ" : "2δ") + " is " + text +
                           " of the largest): the model's energy is not positive there");
    }
    Eigen::Index rank = 0;  // null vectors: the first `rank` eigenvectors
    while (rank < n && lambda[rank] <= kMechanismRelative * largest) ++rank;
    if (rank == 0) continue;  // none here: look wider
    const Eigen::MatrixXd null = eig.eigenvectors().leftCols(rank);
    for (const auto& f : loads) {
      double norm = 0.0;
      for (std::size_t dof = 0; dof < f.size(); ++dof) {
        if (free_index_[dof] >= 0) norm += f[dof] * f[dof];
      }
      norm = std::sqrt(norm);
      Eigen::VectorXd f_s = Eigen::VectorXd::Zero(n);
      for (std::size_t dof = 0; dof < f.size(); ++dof) {
        const int fi = free_index_[dof];
        if (fi >= 0 && local[static_cast<std::size_t>(fi)] >= 0) {
          f_s[local[static_cast<std::size_t>(fi)]] = f[dof];
        }
      }
      if (norm > 0.0 && (null.transpose() * f_s).cwiseAbs().maxCoeff() > kLoadRelative * norm) {
        return core::failure("a part of the model with load on it moves at " + where +
                             " without straining any bond");
      }
    }
    // One DOF per null vector, by elimination with complete pivoting on the null basis: the
    // pinned DOFs' rows of it are then independent, so the springs hold every mechanism (the
    // patch matrix with them is nonsingular), and a pin at a DOF where the mechanism moves
    // most keeps the factorization's pivots large.
    Eigen::MatrixXd a = null;
    std::vector<std::uint8_t> taken(static_cast<std::size_t>(n), 0);
    for (Eigen::Index col = 0; col < rank; ++col) {
      Eigen::Index best_row = -1;
      Eigen::Index best_col = col;
      double best = 0.0;
      for (Eigen::Index j = col; j < rank; ++j) {
        for (Eigen::Index r = 0; r < n; ++r) {
          if (!taken[static_cast<std::size_t>(r)] && std::abs(a(r, j)) > best) {
            best = std::abs(a(r, j));
            best_row = r;
            best_col = j;
          }
        }
      }
      if (best_row < 0) break;
      a.col(col).swap(a.col(best_col));
      taken[static_cast<std::size_t>(best_row)] = 1;
      pinned_[static_cast<std::size_t>(dofs[static_cast<std::size_t>(best_row)])] = 1;
      for (Eigen::Index j = col + 1; j < rank; ++j) {
        a.col(j) -= a(best_row, j) / a(best_row, col) * a.col(col);
      }
    }
    return {};
  }
  if (!none_is_failure) return {};
  return core::failure("the stiffness is singular at " + where +
                       ": no piece came loose, but a part wider than " + (wide ? "4δ" : "2δ") +
                       " moves there without straining any bond");
}

}  // namespace peritwin::statics
