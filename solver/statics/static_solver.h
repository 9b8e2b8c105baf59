// Static peridynamic solve (000 App. B): assemble K = Bᵀ·diag(2aV/h)·B + Σ_b k_b·(e⊗e) over the
// intact bonds, remove supported degrees of freedom, factorize once per stiffness state with
// CHOLMOD, and solve the three basis load cases of an affine load pattern.
// Units: SI (N, m). Degrees of freedom are interleaved [u0, v0, u1, v1, ...].
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "solver/linalg/sparse_cholesky.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"

namespace peritwin::statics {

/// Fixed displacement components (zero) of a set of nodes.
struct Support {
  std::vector<mesh::NodeIndex> nodes;
  bool fix_x = true;
  bool fix_y = true;
};

/// A force shared equally by a set of nodes (a point load is one node, a load spread over a
/// region or an edge layer is many). The total force is affine in the cycle's load (P, α):
///   F = P·(constant + cos α·per_cos + sin α·per_sin)   (N, per N of P)
/// which covers the CTS loading F1, F2, F3 of 000 Eq. (51) exactly.
struct LoadTerm {
  std::vector<mesh::NodeIndex> nodes;
  mesh::Point constant;
  mesh::Point per_cos;
  mesh::Point per_sin;
};

/// Strain (displacement) control: one displacement component imposed on a set of nodes (a
/// specimen's grip layer, a bolted joint's imposed slip, a constrained thermal expansion), affine
/// in the cycle's load like LoadTerm, with P in the detail's control unit:
///   ū = P·(constant + cos α·per_cos + sin α·per_sin)   (m per unit of P)
/// The DOFs leave the unknowns as supports do (a support is the case ū = 0): the factor is K_ff,
/// and each basis is solved with the right-hand side F − K_fp·ū, K_fp·ū computed bond by bond
/// (internal_force), so a break's rank update is unchanged. The reaction at the prescribed DOFs
/// is the internal force there (reaction()).
struct PrescribedDisplacement {
  std::vector<mesh::NodeIndex> nodes;
  int component = 1;  ///< 0: x, 1: y
  double constant = 0.0;
  double per_cos = 0.0;
  double per_sin = 0.0;
};

/// One displacement component of a node, with its coefficient in a Tie.
struct TieTerm {
  mesh::NodeIndex node = 0;
  int component = 0;  ///< 0: x, 1: y
  double coefficient = 0.0;
};

/// A linear constraint between displacements outside the peridynamic bond families, held by a
/// stiff penalty: Σ c_i·u_i = 0 with energy ½·k·(Σ c_i·u_i)², which adds k·g·gᵀ to the stiffness
/// (g: the coefficients over the DOFs) and acts on DOF i with the force −k·c_i·(gᵀu). A loading
/// fixture that ties pins together (B2's rigid CTS fixture) is three of them. Ties never break
/// and carry no fatigue.
struct Tie {
  std::vector<TieTerm> terms;
  double stiffness = 0.0;  ///< k (N/m when the coefficients are dimensionless)
};

/// gᵀu of a tie for a full DOF vector u ([u0, v0, u1, v1, ...]): 0 when the constraint holds; the
/// tie then acts on DOF i with the force −k·c_i·gᵀu.
double tie_violation(const Tie& tie, const std::vector<double>& u);

/// Which basis solution: the load pattern's constant part, its cos α part, its sin α part.
enum Basis : int { basis_constant = 0, basis_cos = 1, basis_sin = 2 };

struct SolveTimings {
  double assemble_s = 0.0;
  double analyze_s = 0.0;
  double factor_s = 0.0;
  double solve_s = 0.0;
};

class StaticSolver {
 public:
  StaticSolver(const mesh::Discretization& disc, const model::PdModel& model,
               std::vector<Support> supports, std::vector<LoadTerm> loads,
               std::vector<Tie> ties = {}, std::vector<PrescribedDisplacement> prescribed = {});
  /// A deep copy (the factor too) that continues bit for bit as this solver would
  /// (FatigueEngine::fork); the copy refers to the same discretization and model.
  StaticSolver(const StaticSolver&) = default;
  StaticSolver& operator=(const StaticSolver&) = delete;

  /// Assembles, factorizes and solves the three basis cases for the current bond state.
  core::Status solve();
  /// Breaks the given bonds and re-solves: by a low-rank update of the factor when incremental
  /// (CHOLMOD rank-k update/downdate; exact up to round-off), else by refactorizing (the oracle).
  core::Status break_bonds(std::span<const mesh::BondIndex> bonds);
  /// Sets the stiffness factor f_b = 1 − D_b of each listed bond (1 intact, 0 broken; 0 ≤ f ≤ 1),
  /// bond-based models only (std::logic_error for state-based). Incremental: CHOLMOD rank update/
  /// downdate with the bond vector scaled by sqrt(|f_old − f_new|·c); otherwise refactorization
  /// (the oracle). Re-solves the basis cases like break_bonds. A factor of 0 is the same as
  /// breaking the bond. std::invalid_argument for a factor outside [0, 1], a size mismatch, or a
  /// factor above 0 for a broken bond (a broken bond stays broken).
  core::Status set_bond_factors(std::span<const mesh::BondIndex> bonds,
                                std::span<const double> factors);
  /// The bond's stiffness factor: 1 for intact, 0 for broken, in between for a softened bond.
  [[nodiscard]] double bond_factor(mesh::BondIndex b) const {
    return factor_[static_cast<std::size_t>(b)];
  }
  [[nodiscard]] const std::vector<double>& bond_factors() const { return factor_; }
  void set_incremental(bool incremental) { incremental_ = incremental; }
  /// The fill-reducing ordering of the node graph (default METIS or AMD, whichever fills less;
  /// another choice gives another factor, hence other rounding: for measurements).
  void set_ordering(linalg::Ordering ordering) { ordering_ = ordering; }
  [[nodiscard]] bool incremental() const { return incremental_; }
  /// Non-incremental set_bond_factors by preconditioned conjugate gradients instead of a
  /// refactorization per call (003's bilinear increments, see docs/solver.md): K(f)·u = F is
  /// solved with the Cholesky factor of the reference stiffness K(f_ref) as the preconditioner,
  /// f_ref = reference_factor(f, step) bond by bond (the next power of 2^step at or above f, 0 for
  /// a broken bond), refactorized only when some bond's reference changes. Since
  /// f ≤ f_ref < 2^step·f, the spectrum of K(f_ref)⁻¹·K(f) lies in (2^−step, 1], and the
  /// iterations stop when sqrt(rᵀM⁻¹r / bᵀM⁻¹b) ≤ tolerance (M = K(f_ref), x0 = 0). The
  /// reference and x0 depend only on the factors, so the result does too (import_state stays
  /// bit-identical). More than max_iterations falls back to refactorizing K(f) (counted).
  void set_preconditioned(bool on, double tolerance = 1e-12, int step = 1,
                          int max_iterations = 200);
  [[nodiscard]] bool preconditioned() const { return preconditioned_; }
  /// f_ref of a stiffness factor f ∈ [0, 1]: 2^L with L the largest multiple of −step whose
  /// power is ≥ f (1 for f ≥ 1, 0 for f = 0). Exact (frexp/ldexp).
  [[nodiscard]] static double reference_factor(double f, int step);
  /// Work of the preconditioned path: calls, block iterations (each one multiplication by K(f)
  /// and one solve with the reference factor per loaded basis), refactorizations of the
  /// reference, refactorizations of K(f) after max_iterations, seconds in the iterations.
  struct PcgStats {
    std::int64_t solves = 0;
    std::int64_t iterations = 0;
    int max_iterations = 0;  ///< the most any call needed
    std::int64_t reference_factorizations = 0;
    std::int64_t fallbacks = 0;
    double seconds = 0.0;
  };
  [[nodiscard]] const PcgStats& pcg_stats() const { return pcg_; }
  /// y = K(f)·x over the free DOFs with the given bond stiffness factors, bond by bond (plus the
  /// ground springs of isolated nodes): the matrix of the preconditioned path, never assembled.
  void multiply(const std::vector<double>& factors, const double* x, double* y) const;
  /// x = K⁻¹·rhs over the free DOFs with the current factor (full DOF vectors: rhs is read on the
  /// free DOFs only, x is 0 elsewhere). Not in the mixed form (std::logic_error). The Newton steps
  /// of elastoplastic bonds (statics/elastoplastic.h) solve with it after set_bond_factors.
  void solve_free(const std::vector<double>& rhs, std::vector<double>& x) const;
  /// x ← K⁻¹·x in place, x over the unknowns (free index order): the preconditioner of
  /// iterations on another matrix of the same DOFs (multiply()).
  void solve_unknowns(std::vector<double>& x) const;
  /// Seconds spent in low-rank updates.
  [[nodiscard]] double update_seconds() const { return update_s_; }
  [[nodiscard]] int updates() const { return updates_; }
  /// Seconds in the rank updates' sweeps alone (SparseCholesky::modify_fused), part of
  /// update_seconds().
  [[nodiscard]] double sweep_seconds() const { return sweep_s_; }
  /// Σ SparseCholesky::update_flops of the sweeps: the rank updates' floating-point operations.
  [[nodiscard]] double update_flops() const { return update_flops_; }
  /// Groups of breaks refactorized because their rank updates would have cost more (see
  /// kRefactorOverUpdate).
  [[nodiscard]] int refactorized_groups() const { return refactorized_groups_; }
  /// A group of breaks is refactorized instead of updated when its update's flops
  /// (SparseCholesky::update_flops) exceed this fraction of the factorization's: the fused sweep
  /// ran at 5.6 Gflop/s and CHOLMOD's supernodal factorization at 16 Gflop/s on the 15k-node B1
  /// factor (2 cores, issue 37), so above about 0.35 refactorizing is faster.
  static constexpr double kRefactorOverUpdate = 0.3;
  /// ... and the group has at least this many update columns (a few bonds' worth is always
  /// cheaper to update) ...
  static constexpr std::size_t kRefactorMinimumRanks = 64;
  /// ... and a factorization costs at least this many flops (set_refactor_minimum_flops): below
  /// it (B1 below about 4,500 nodes: 13 Gflop at 15k, growing as n^1.5) a factorization costs too
  /// little for the choice to matter, and small models keep every group on the update path the
  /// tests compare.
  static constexpr double kRefactorMinimumFlops = 2e9;
  /// Tests: the factorization flops from which a dear group is refactorized (0: any model).
  void set_refactor_minimum_flops(double flops) { refactor_minimum_flops_ = flops; }
  /// Seconds spent in the triangular solves of the basis cases (all paths).
  [[nodiscard]] double basis_solve_seconds() const { return basis_solve_s_; }

  [[nodiscard]] const std::vector<std::uint8_t>& intact() const { return intact_; }
  /// Basis displacement (full DOF vector, zeros on supports) and basis bond stretches.
  [[nodiscard]] const std::vector<double>& basis_displacement(Basis b) const { return u_[b]; }
  [[nodiscard]] const std::vector<double>& basis_stretch(Basis b) const { return s_[b]; }
  /// u = P·(U_const + cos α·U_cos + sin α·U_sin).
  void displacement(double p, double alpha, std::vector<double>& u) const;
  /// s = P·(s_const + cos α·s_cos + sin α·s_sin), bond by bond.
  void stretch(double p, double alpha, std::vector<double>& s) const;
  /// External force vector of the basis case (full DOFs).
  [[nodiscard]] std::vector<double> basis_force(Basis b) const;
  /// The prescribed displacements of the basis case (full DOFs, zero elsewhere).
  [[nodiscard]] std::vector<double> basis_prescribed(Basis b) const;
  [[nodiscard]] const std::vector<PrescribedDisplacement>& prescribed() const {
    return prescribed_;
  }
  /// Reaction of prescribed term t (N): the sum over its nodes of the force the grips apply in
  /// its component, K·u − F there (equal and opposite to the body's pull on the grips), at the
  /// load (P, α): P·(R_const + cos α·R_cos + sin α·R_sin). Zero once the body is cut through.
  [[nodiscard]] double reaction(std::size_t term, double p, double alpha) const;
  [[nodiscard]] double basis_reaction(std::size_t term, Basis b) const {
    return reaction_[static_cast<std::size_t>(b)][term];
  }
  /// Internal force f = K·u over the intact bonds and the ties, computed bond by bond (not from
  /// the matrix): the independent check of equilibrium.
  [[nodiscard]] std::vector<double> internal_force(const std::vector<double>& u) const;

  [[nodiscard]] const SolveTimings& timings() const { return timings_; }
  [[nodiscard]] std::int32_t num_free_dofs() const { return num_free_; }
  /// True when the state-based system is solved in its mixed form (see docs/solver.md): the
  /// unknowns are the free displacements followed by one w_k = α_k·θ_k/s per node (s: w_scale_).
  [[nodiscard]] bool mixed_form() const { return mixed_; }
  [[nodiscard]] std::int32_t num_unknowns() const { return num_unknowns_; }
  /// The matrix of the current factor (upper triangle); on the preconditioned path K(f_ref).
  [[nodiscard]] const linalg::SparseMatrix& stiffness_upper() const { return upper_; }
  /// The same matrix for the current bond factors by the products-and-triplets assembly: the
  /// oracle the scatter assembly is tested against, bit for bit.
  [[nodiscard]] linalg::SparseMatrix stiffness_upper_by_products() const;
  [[nodiscard]] const std::vector<std::int32_t>& free_index() const { return free_index_; }
  [[nodiscard]] const mesh::Discretization& discretization() const { return disc_; }
  [[nodiscard]] const model::PdModel& model() const { return model_; }
  [[nodiscard]] const linalg::SparseCholesky& factor() const { return cholesky_; }
  /// Incremental only: frees the factor's values while it is still the factor of the assembled
  /// stiffness (no update since the last factorization), keeping the analysis and the solution;
  /// the next break_bonds() or set_bond_factors() factorizes the same matrix with the same
  /// analysis first — the same factor bit for bit — then updates it. For details that idle:
  /// the factor is most of their memory (issue 18, a fleet of details). Returns whether it did.
  bool release_factor();
  [[nodiscard]] bool factor_released() const { return released_; }
  /// Number of numeric factorizations done so far.
  [[nodiscard]] int factorizations() const { return factorizations_; }
  /// Per free DOF: held by a pin, a ground spring on that one DOF against a mechanism — a part
  /// of the model that moves without straining any intact bond although it is still attached
  /// (e.g. nodes left with bonds along one line only). A pin changes no stretch: the mechanism's
  /// loads are zero, so the pinned DOF's reaction is zero. Set when a factorization fails on a
  /// mechanism (docs/solver.md, "Mechanisms are pinned"); never removed.
  [[nodiscard]] const std::vector<std::uint8_t>& pinned() const { return pinned_; }
  [[nodiscard]] std::int32_t pinned_dofs() const;

 private:
  /// Assembles upper_ with the given bond stiffness factors (factor_ or the reference): by
  /// scatter into the pattern (bond-based and mixed form), else by products.
  void assemble(const std::vector<double>& factors);
  /// The oracle of the scatter: K = Gᵀ·diag(w)·G (+ Bᵀ·A·B) with Eigen products and triplets.
  void assemble_by_products(const std::vector<double>& factors, linalg::SparseMatrix& out) const;
  /// Direct scatter of every bond's terms into upper_'s known pattern (built on first use),
  /// adding each entry's terms in the order the products add them, so the values are the
  /// same bits as assemble_by_products (tested).
  void assemble_by_scatter(const std::vector<double>& factors);
  /// The pattern of upper_: the bonds' node pairs (precut bonds included, as explicit zeros),
  /// every free diagonal, the ties, and in the mixed form the Bᵀ block and the w diagonal.
  void build_pattern();
  /// Position of entry (row, col), row ≤ col, in upper_'s arrays (it must be in the pattern).
  [[nodiscard]] std::size_t entry(int row, int col) const;
  /// Preconditioned re-solve after factor_ changed (see set_preconditioned).
  core::Status preconditioned_resolve(bool broke);
  /// PCG on the loaded bases with the current factor as M; false if max_iterations was hit.
  bool pcg_solve_bases();
  void append_ground(std::vector<Eigen::Triplet<double, int>>& entries) const;
  [[nodiscard]] std::vector<int> dof_ordering() const;
  /// Solves the basis cases with the current factor; bases without load are zero.
  void solve_bases();
  /// Right-hand side of basis b over the full DOFs: F − K·ū (ū its prescribed displacements,
  /// K·ū by internal_force with the current bond factors); `loaded` says whether any is nonzero.
  [[nodiscard]] std::vector<double> basis_rhs(Basis b, bool& loaded) const;
  /// Completes a solved basis: ū on its prescribed DOFs, the stretches and the reactions.
  void finish_basis(Basis b, std::vector<double>& u);
  /// The bond's gradient scale·e·(u_j − u_i) as (free index, coefficient) pairs; supported DOFs
  /// have index −1.
  [[nodiscard]] std::array<std::pair<int, double>, 4> bond_gradient(std::size_t b,
                                                                    double scale) const;
  /// The tie's g over the free DOFs as (free index, coefficient) pairs; supported DOFs have index
  /// −1, like bond_gradient.
  [[nodiscard]] std::vector<std::pair<int, double>> tie_gradient(const Tie& tie) const;
  /// k·g·gᵀ of every tie, upper triangle, as triplets over the free DOFs.
  void append_ties(std::vector<Eigen::Triplet<double, int>>& entries) const;
  /// Row of B (θ_k = B_k·u) of node k over the free DOFs, for the current bond state.
  [[nodiscard]] linalg::SparseCholesky::Column dilatation_row(mesh::NodeIndex k) const;
  /// Nodes with no intact bond get a ground spring (they would make K singular).
  [[nodiscard]] bool isolated(mesh::NodeIndex k) const;
  /// Refactorizing re-solve after intact_/factor_ changed (grounds nodes that became isolated).
  core::Status refactor_resolve();
  /// Assembles upper_ with `factors`, analyzes on first use and factorizes. A factorization that
  /// fails is retried after pin_mechanisms() at the node of its weakest pivot, as long as that
  /// pins something; otherwise its failure says what came loose.
  core::Status factorize_pinning(const std::vector<double>& factors);
  /// Pins the mechanisms of the stiffness with `factors` that lie within 2δ of `node` (else, if
  /// `wide`, within 4δ) (mechanisms.cpp); a failure saying why it cannot: a mechanism carries
  /// load, the stiffness is indefinite there, or no mechanism was found.
  core::Status pin_mechanisms(mesh::NodeIndex node, const std::vector<double>& factors, bool wide,
                              bool none_is_failure = true);
  /// After a factorization failed with breaks just made: pin_mechanisms (2δ, finding none is no
  /// failure) around centres at least δ apart covering group_nodes_, the ends of the group's
  /// bonds — every mechanism the group made in one round instead of one factorization each.
  core::Status pin_group_mechanisms(const std::vector<double>& factors);
  /// The node of an unknown: a free DOF's node, or node k for w_k of the mixed form.
  [[nodiscard]] mesh::NodeIndex node_of_unknown(int row) const;
  /// The pieces that no intact bond or tie connects to a support: a failure naming the largest
  /// ("a piece of N nodes came loose (x from .. to .. mm, y ..)") if one carries load or has as
  /// many nodes as a full family; else grounds every node of the others (unloaded debris, like
  /// isolated nodes) and says whether it grounded any.
  core::Status ground_loose_debris(bool& grounded_any);
  /// Ground springs (added columns) for the nodes that became isolated.
  void ground_isolated(const std::vector<mesh::NodeIndex>& nodes,
                       std::vector<linalg::SparseCholesky::Column>& added);
  /// Applies the added then the removed columns to the factor and re-solves the basis cases.
  core::Status update_resolve(const std::vector<linalg::SparseCholesky::Column>& added,
                              const std::vector<linalg::SparseCholesky::Column>& removed,
                              std::chrono::steady_clock::time_point t0);

  const mesh::Discretization& disc_;
  const model::PdModel& model_;
  std::vector<Support> supports_;
  std::vector<LoadTerm> loads_;
  std::vector<Tie> ties_;
  std::vector<PrescribedDisplacement> prescribed_;
  std::array<std::vector<double>, 3> reaction_;  ///< per basis, per prescribed term
  std::vector<std::uint8_t> intact_;
  std::vector<double> factor_;  ///< stiffness factor of each bond's pair term (0 when broken)
  std::vector<std::int32_t> free_index_;  ///< DOF -> free index, -1 when supported
  std::int32_t num_free_ = 0;
  bool mixed_ = false;
  /// Mixed form: the w unknowns are solved as w/w_scale_, which brings their diagonal (−A⁻¹, in
  /// other units than the stiffness) to the size of a node's stiffness diagonal; see constructor.
  double w_scale_ = 1.0;
  std::int32_t num_unknowns_ = 0;
  linalg::SparseMatrix upper_;
  bool pattern_ready_ = false;  ///< upper_ holds the scatter pattern
  linalg::Ordering ordering_ = linalg::Ordering::metis_or_amd;
  linalg::SparseCholesky cholesky_;
  std::array<std::vector<double>, 3> u_;
  std::array<std::vector<double>, 3> s_;
  SolveTimings timings_;
  int factorizations_ = 0;
  bool incremental_ = false;
  /// The factor is LDLᵀ now (updated in place, or converted after solve()).
  bool modified_ = false;
  bool updated_ = false;   ///< a rank update since the last factorization
  bool released_ = false;  ///< release_factor(): factorize upper_ again before the next update
  bool preconditioned_ = false;
  double pcg_tolerance_ = 1e-12;
  int pcg_step_ = 1;
  int pcg_max_iterations_ = 200;
  /// Bond factors of the matrix the factor was computed from (refactorizing paths: factor_).
  std::vector<double> reference_;
  PcgStats pcg_;
  double ground_stiffness_ = 0.0;
  std::vector<std::uint8_t> grounded_;
  std::vector<std::uint8_t> pinned_;  ///< per free DOF, see pinned()
  double update_s_ = 0.0;
  int updates_ = 0;
  int refactorized_groups_ = 0;
  /// The end nodes of the bonds the last break_bonds broke, until the update holds or the next
  /// factorization (pin_group_mechanisms).
  std::vector<mesh::NodeIndex> group_nodes_;
  double refactor_minimum_flops_ = kRefactorMinimumFlops;
  double sweep_s_ = 0.0;
  double update_flops_ = 0.0;
  double basis_solve_s_ = 0.0;
};

}  // namespace peritwin::statics
