#include "solver/static_solver.h"

#include <chrono>
#include <cmath>
#include <utility>

namespace peritwin {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

StaticSolver::StaticSolver(const Discretization& disc, const PdModel& model,
                           std::vector<Support> supports, std::vector<LoadTerm> loads)
    : disc_(disc), model_(model), supports_(std::move(supports)), loads_(std::move(loads)) {
  intact_.resize(static_cast<std::size_t>(disc.num_bonds()));
  for (std::size_t b = 0; b < intact_.size(); ++b) intact_[b] = disc.bond_precut[b] ? 0 : 1;
  const auto ndof = 2 * static_cast<std::size_t>(disc.num_nodes());
  free_index_.assign(ndof, 0);
  for (const auto& s : supports_) {
    for (NodeIndex k : s.nodes) {
      if (s.fix_x) free_index_[2 * static_cast<std::size_t>(k)] = -1;
      if (s.fix_y) free_index_[2 * static_cast<std::size_t>(k) + 1] = -1;
    }
  }
  for (auto& f : free_index_) f = f < 0 ? -1 : num_free_++;
}

void StaticSolver::assemble() {
  // Pattern from the bonds intact at construction; bonds broken since keep explicit zeros so
  // the pattern (and CHOLMOD's symbolic analysis) never changes.
  const auto nb = static_cast<std::size_t>(disc_.num_bonds());
  const bool osb = model_.options.kind == ModelKind::state_based;
  std::vector<Eigen::Triplet<double, int>> g_entries;
  g_entries.reserve(4 * nb);
  Eigen::VectorXd weight(static_cast<Eigen::Index>(nb));
  auto add_row = [&](std::vector<Eigen::Triplet<double, int>>& t, int row, std::size_t b,
                     double scale) {
    const auto i = 2 * static_cast<std::size_t>(disc_.bond_i[b]);
    const auto j = 2 * static_cast<std::size_t>(disc_.bond_j[b]);
    const double c = scale * disc_.bond_cos[b];
    const double s = scale * disc_.bond_sin[b];
    const std::array<std::pair<std::size_t, double>, 4> dofs{
        {{i, -c}, {i + 1, -s}, {j, c}, {j + 1, s}}};
    for (const auto& [dof, value] : dofs) {
      if (free_index_[dof] >= 0) t.emplace_back(row, free_index_[dof], value);
    }
  };
  for (std::size_t b = 0; b < nb; ++b) {
    add_row(g_entries, static_cast<int>(b), b, 1.0);  // row b: e·(u_j − u_i)
    weight[static_cast<Eigen::Index>(b)] =
        intact_[b] ? model_.bond_stiffness[b] : 0.0;
    if (disc_.bond_precut[b]) weight[static_cast<Eigen::Index>(b)] = 0.0;
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
    SparseMatrix bmat(disc_.num_nodes(), num_free_);
    bmat.setFromTriplets(b_entries.begin(), b_entries.end());
    b_entries = {};
    const Eigen::Map<const Eigen::VectorXd> alpha(model_.dilatation_stiffness.data(),
                                                  disc_.num_nodes());
    SparseMatrix bt = bmat.transpose();
    k += bt * (alpha.asDiagonal() * bmat);
  }
  upper_ = k.triangularView<Eigen::Upper>();
  upper_.makeCompressed();
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
  SparseMatrix incidence(nn, nn);
  incidence.setFromTriplets(links.begin(), links.end());
  SparseMatrix node_graph = incidence.selfadjointView<Eigen::Upper>();
  if (model_.options.kind == ModelKind::state_based) {
    node_graph = node_graph * node_graph;  // the dilatation couples nodes two bonds apart
  }
  SparseMatrix node_upper = node_graph.triangularView<Eigen::Upper>();
  node_upper.makeCompressed();
  const std::vector<int> node_order = SparseCholesky::fill_reducing_ordering(node_upper);
  std::vector<int> order;
  order.reserve(static_cast<std::size_t>(num_free_));
  for (int k : node_order) {
    for (int c = 0; c < 2; ++c) {
      const int f = free_index_[2 * static_cast<std::size_t>(k) + static_cast<std::size_t>(c)];
      if (f >= 0) order.push_back(f);
    }
  }
  return order;
}

FactorReport StaticSolver::solve() {
  auto t0 = std::chrono::steady_clock::now();
  assemble();
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
  timings_.factor_s = seconds_since(t0);
  if (!report.ok()) return report;

  t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(num_free_, 3);
  for (int basis = 0; basis < 3; ++basis) {
    const auto f = basis_force(static_cast<Basis>(basis));
    for (std::size_t dof = 0; dof < f.size(); ++dof) {
      if (free_index_[dof] >= 0) rhs(free_index_[dof], basis) = f[dof];
    }
  }
  cholesky_.solve(rhs);
  for (int basis = 0; basis < 3; ++basis) {
    auto& u = u_[static_cast<std::size_t>(basis)];
    u.assign(free_index_.size(), 0.0);
    for (std::size_t dof = 0; dof < u.size(); ++dof) {
      if (free_index_[dof] >= 0) u[dof] = rhs(free_index_[dof], basis);
    }
    bond_stretches(disc_, u, s_[static_cast<std::size_t>(basis)]);
  }
  timings_.solve_s = seconds_since(t0);
  return report;
}

FactorReport StaticSolver::break_bonds(std::span<const BondIndex> bonds) {
  for (BondIndex b : bonds) intact_[static_cast<std::size_t>(b)] = 0;
  return solve();
}

std::vector<double> StaticSolver::basis_force(Basis b) const {
  std::vector<double> f(2 * static_cast<std::size_t>(disc_.num_nodes()), 0.0);
  for (const auto& load : loads_) {
    if (load.nodes.empty()) continue;
    const Point part = b == basis_constant ? load.constant : b == basis_cos ? load.per_cos
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
    double magnitude = model_.bond_stiffness[b] * disc_.bond_length[b] * stretch_values[b];
    if (osb) {
      magnitude += model_.dilatation_weight[b] / disc_.bond_length[b] *
                   (model_.dilatation_stiffness[i] * theta[i] +
                    model_.dilatation_stiffness[j] * theta[j]);
    }
    // A stretched bond pulls i toward j: internal resisting force K·u is −(pull) on i.
    f[2 * i] -= magnitude * disc_.bond_cos[b];
    f[2 * i + 1] -= magnitude * disc_.bond_sin[b];
    f[2 * j] += magnitude * disc_.bond_cos[b];
    f[2 * j + 1] += magnitude * disc_.bond_sin[b];
  }
  return f;
}

}  // namespace peritwin
