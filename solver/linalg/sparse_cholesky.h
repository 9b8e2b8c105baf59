// RAII wrapper over CHOLMOD for the symmetric positive definite peridynamic stiffness:
// analyze once per sparsity pattern, factorize per stiffness state, solve many right-hand sides.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

#include "core/expected.h"

namespace peritwin::linalg {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Factorizations, updates and solves report a Status (core/expected.h): OK, or the
// reason (not positive definite, numerically singular — a part of the model has come loose — or
// a CHOLMOD failure).

/// Fill-reducing orderings of fill_reducing_ordering(): METIS nested dissection or AMD, whichever
/// fills less (peritwin's choice, docs/solver.md "Ordering"); CHOLMOD's own nested dissection
/// (NESDIS: METIS bisections, constrained minimum degree on the parts); METIS alone; AMD alone.
enum class Ordering { metis_or_amd, nesdis, metis, amd };

class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  /// A deep copy (the factor by cholmod_copy_factor, with the update and solve state), for a
  /// forward simulation that continues from a live solver's factor (FatigueEngine::fork); explicit
  /// so that a factor of hundreds of MB is never copied by accident.
  explicit SparseCholesky(const SparseCholesky& other);
  SparseCholesky& operator=(const SparseCholesky&) = delete;
  SparseCholesky(SparseCholesky&&) noexcept;
  SparseCholesky& operator=(SparseCholesky&&) noexcept;

  /// Fill-reducing ordering and symbolic factorization of the upper triangle `upper`. With a
  /// permutation (new position -> row), that ordering is used as given.
  core::Status analyze(const SparseMatrix& upper, const std::vector<int>* permutation = nullptr);
  /// A fill-reducing ordering (METIS nested dissection, AMD when METIS does worse) of the
  /// symmetric pattern whose upper triangle is `upper`; values are ignored.
  static std::vector<int> fill_reducing_ordering(const SparseMatrix& upper,
                                                 Ordering method = Ordering::metis_or_amd);
  /// Numeric factorization; the pattern must be the analyzed one. Reports a matrix that is not
  /// positive definite or numerically singular (reciprocal condition estimate below 1e-14, e.g.
  /// a piece of the model that came loose) as a typed failure.
  core::Status factorize(const SparseMatrix& upper);
  /// After factorize() reported a matrix that is not positive definite or numerically singular:
  /// the row (in the matrix's own numbering) of the pivot it stopped at, or of the smallest pivot
  /// (min l_jj); after a modify() or modify_fused() that did: the row of the first pivot (in the
  /// factor's order) at most 1e-14·max(D). −1 when no pivot is known. Where a StaticSolver looks
  /// for a mechanism (docs/solver.md, "Mechanisms are pinned").
  [[nodiscard]] int weakest_pivot_row() const;
  /// A sparse column in the analyzed matrix's (unpermuted) row numbering.
  struct Column {
    std::vector<int> rows;
    std::vector<double> values;
  };
  /// Low-rank modification of the factor: A ← A + Σ c·cᵀ (add = true) or A − Σ c·cᵀ, by CHOLMOD's
  /// rank-k update/downdate (the factor becomes simplicial LDLᵀ on the first call). Reports a
  /// downdate that leaves the matrix not positive definite or numerically singular.
  core::Status modify(const std::vector<Column>& columns, bool add);
  /// A ← A + Σ a·aᵀ − Σ r·rᵀ in one sweep over the factor (peritwin's own multiple-rank update,
  /// method C1 rank by rank, the updates before the downdates, 16 ranks per sweep, the rows split
  /// between two threads on large paths; same arithmetic on one thread). Requires the rows of
  /// each column to be in the factor's column of its first row (no fill), else falls back to
  /// modify(added, true) then modify(removed, false). Reports like modify().
  core::Status modify_fused(const std::vector<Column>& added, const std::vector<Column>& removed);
  /// The floating-point operations modify_fused(added, removed) would do on the ranks: 4 per
  /// entry of L on each column's elimination-tree path from its first row (w_i −= p·l_ij,
  /// l_ij += β·w_i), the floor a rank update of the touched columns cannot go below. Converts the
  /// factor to LDLᵀ like modify_fused() (same values); +inf when that fails. Deterministic: it
  /// reads only the factor's pattern, so StaticSolver can choose between updating and
  /// refactorizing by it without making results depend on timing.
  double update_flops(const std::vector<Column>& added, const std::vector<Column>& removed);
  /// CHOLMOD's flop count of the analyzed factorization (cholmod_common::fl after the analysis),
  /// 0 before one.
  [[nodiscard]] double factorization_flops() const;
  /// Σ update_flops of every modify_fused() of this factor (since its construction).
  [[nodiscard]] double update_flops_total() const;
  /// Turns the supernodal LLᵀ factor into LDLᵀ in place, in its own storage (what the first
  /// modify_fused() does, with the same values): 8 B per entry of L, the supernodes' upper
  /// triangles given back. Solves with 1-3 columns then use peritwin's solve instead of
  /// CHOLMOD's (another rounding); factorize() restores the supernodal factor.
  core::Status convert_to_ldlt();
  /// Frees the factor's values, keeping the analysis (factorize() computes them again). Only a
  /// supernodal or packed factor (CHOLMOD's simplicial one has no analysis to keep): returns
  /// whether it freed them.
  bool release_values();
  /// The factor has values (factorize() since the analysis or the last release_values()).
  [[nodiscard]] bool has_values() const;
  /// Solves A·X = B in place for every column of B. After modify() (simplicial LDLᵀ) with 1-3
  /// columns this is peritwin's own triangular solve, whose two independent elimination subtrees
  /// run on two threads (same arithmetic with one); otherwise CHOLMOD's.
  void solve(Eigen::MatrixXd& rhs) const;
  /// CHOLMOD's cholmod_solve, always (the reference for the own solve).
  void solve_with_cholmod(Eigen::MatrixXd& rhs) const;
  /// Threads of the own solve: 0 automatic (two for factors above 2M nonzeros on a machine with
  /// two cores or more), 1 or 2. The arithmetic, hence the result, is the same for all.
  void set_solve_threads(int threads);
  /// Process-wide: whether automatic mode (set_solve_threads(0)) may use two threads at all
  /// (default true). A daemon serving several details turns it off: its worker pool already
  /// keeps the cores busy, and a loud detail's two-thread re-solve would take the core the quiet
  /// details' batches run on. Same arithmetic either way, so no result changes.
  static void allow_automatic_two_threads(bool allow);
  [[nodiscard]] static bool automatic_two_threads();
  /// Process-wide: whether modify_fused() runs four entries of a column through the ranks side by
  /// side (default true) or one entry at a time (the slow path it is tested against and benched
  /// beside). The same operations per entry in the same order either way: the same bits.
  static void set_interleaved_update(bool interleaved);
  [[nodiscard]] static bool interleaved_update();

  [[nodiscard]] bool analyzed() const;
  /// The analysis is CHOLMOD's supernodal one (also under the packed LDLᵀ of convert_to_ldlt() and
  /// modify_fused()), so factorize() refactorizes with it; false before analyze() and after
  /// modify() turned the factor into CHOLMOD's simplicial one, which must be analyzed again.
  [[nodiscard]] bool supernodal_analysis() const;
  [[nodiscard]] double factor_nonzeros() const;
  /// Entries of the supernodal storage of the analysis (LLᵀ after factorize(), and what the
  /// packed LDLᵀ was packed from); 0 for CHOLMOD's simplicial factor.
  [[nodiscard]] double supernodal_nonzeros() const;
  /// Bytes the factor holds (values, row indices, column pointers; not CHOLMOD's workspace):
  /// supernodal LLᵀ after factorize(), packed LDLᵀ after modify_fused() (8 B per entry plus the
  /// supernodes' rows), CHOLMOD's simplicial LDLᵀ after modify() (12 B per entry).
  [[nodiscard]] double factor_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace peritwin::linalg
