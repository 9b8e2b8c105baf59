// SparseCholesky's internals, shared by its two source files: sparse_cholesky.cpp (analysis,
// factorization, solves, CHOLMOD's own updates) and rank_update.cpp (the fused rank update).
#pragma once

#include <cholmod.h>

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "solver/linalg/ldlt_solve.h"
#include "solver/linalg/sparse_cholesky.h"

namespace peritwin::linalg {

/// After a downdate: D of LDLᵀ must stay positive, and rcond as cholmod_rcond computes it,
/// min(D) / max(D), above 1e-14 — else the model has come loose. `first_bad`: the first column
/// (factor order) whose D is at most 1e-14·max(D) when it fails, else −1.
core::Status check_after_downdate(const std::vector<double>& diagonal, int& first_bad);

/// The LDLᵀ factor after the first fused update, kept in the supernodal factor's storage instead
/// of CHOLMOD's simplicial one (issue 18, item 5). CHOLMOD's conversion (cholmod_change_factor
/// to simplicial LDLᵀ, packed) allocates a row index per entry (4 B: 0.49 GB for the 60k-node
/// state-based factor's 121.8M entries) while the supernodal values are still at full size;
/// here the values are converted and packed in place by the same arithmetic, in the same order
/// (d = l_jj², l_ij / l_jj: CHOLMOD's ll_super_to_simplicial_numeric), the tail is given back,
/// and the rows stay the supernodes' (Ls, shared by a supernode's columns). Same values, same
/// pattern, so the same update and solve arithmetic: bit for bit what CHOLMOD's simplicial
/// factor gave. The CHOLMOD factor object stays a supernodal symbolic factor (values detached),
/// so that factorize() can refactorize with the same analysis.
struct PackedLdlt {
  double* x = nullptr;        ///< packed values, D_jj first in each column (cholmod_malloc'ed)
  std::size_t xsize = 0;      ///< entries of x
  std::vector<int> col_x;     ///< column j's values start at x + col_x[j]
  std::vector<int> col_rows;  ///< column j's rows start at Ls + col_rows[j]
  std::vector<int> col_nz;    ///< entries of column j
};

struct SparseCholesky::Impl {
  cholmod_common common{};
  /// CHOLMOD's factor: supernodal LLᵀ after factorize(), simplicial LDLᵀ after modify(), or
  /// supernodal symbolic (its values moved to `packed`) after modify_fused().
  cholmod_factor* factor = nullptr;
  PackedLdlt packed;
  std::vector<int> inverse_perm;  ///< row -> position in the factor's ordering
  ldlt::SolveSchedule schedule;   ///< for the LDLᵀ factor after modify() / modify_fused()
  std::vector<double> diagonal;   ///< D of the LDLᵀ factor (refreshed along update paths)
  std::vector<int> mark;          ///< per column: last modify() whose path reached it
  int stamp = 0;
  int solve_threads = 0;  ///< 0 automatic, 1, 2
  std::vector<double> w;  ///< n × kGroup workspace of the fused update (zero between calls)
  /// The forward solve y = L⁻¹·P·b of the last right-hand sides b solved with the LDLᵀ factor,
  /// kept up to date by the fused update (only the update paths' rows change), so that solving
  /// the same b again is only the backward half.
  Eigen::MatrixXd tracked_rhs;
  std::vector<double> forward_y;  ///< n × columns of tracked_rhs, row-major, permuted
  std::vector<double> delta;      ///< n × 3 workspace of the forward update (zero between calls)
  bool forward_valid = false;
  int weakest_row = -1;             ///< SparseCholesky::weakest_pivot_row()
  double analysis_flops = 0.0;      ///< CHOLMOD's flop count of the analyzed factorization
  double update_flops_total = 0.0;  ///< SparseCholesky::update_flops_total()

  [[nodiscard]] bool packed_active() const { return packed.x != nullptr; }
  /// The factor is LDLᵀ (after an update): packed, or CHOLMOD's simplicial.
  [[nodiscard]] bool is_ldlt() const {
    return packed_active() || (factor != nullptr && !factor->is_super && !factor->is_ll &&
                               factor->xtype == CHOLMOD_REAL);
  }
  /// The LDLᵀ factor as the solves and updates read it (is_ldlt() must hold).
  [[nodiscard]] ldlt::FactorView view() const {
    if (!packed_active()) return ldlt::view_of(*factor);
    ldlt::FactorView v;
    v.n = static_cast<int>(factor->n);
    v.lp = packed.col_x.data();
    v.ri = packed.col_rows.data();
    v.lnz = packed.col_nz.data();
    v.rows = static_cast<const int*>(factor->s);
    v.lx = packed.x;
    v.perm = static_cast<const int*>(factor->Perm);
    return v;
  }
  /// Σ Lnz of the LDLᵀ factor: grows when an update adds fill (the pattern changes).
  [[nodiscard]] std::int64_t pattern_nnz() const {
    const ldlt::FactorView v = view();
    std::int64_t nnz = 0;
    for (int j = 0; j < v.n; ++j) nnz += v.lnz[j];
    return nnz;
  }
  /// inverse_perm for the factor's ordering (built once per analysis).
  void ensure_inverse_perm(const ldlt::FactorView& l) {
    const auto n = static_cast<std::size_t>(l.n);
    if (inverse_perm.size() == n) return;
    inverse_perm.assign(n, 0);
    for (std::size_t k = 0; k < n; ++k)
      inverse_perm[static_cast<std::size_t>(l.perm[k])] = static_cast<int>(k);
  }
  void ensure_schedule() {
    const std::int64_t nnz = pattern_nnz();
    if (schedule.pattern_nnz == nnz) return;
    const ldlt::FactorView v = view();
    schedule = ldlt::make_schedule(v, nnz);
    diagonal.resize(static_cast<std::size_t>(v.n));
    for (int j = 0; j < v.n; ++j) diagonal[static_cast<std::size_t>(j)] = v.lx[v.lp[j]];
    mark.assign(static_cast<std::size_t>(v.n), 0);
    stamp = 0;
  }
  /// Supernodal LLᵀ -> packed LDLᵀ in place (see PackedLdlt); the factor must be supernodal
  /// numeric.
  core::Status to_packed_ldlt();
  /// Packed LDLᵀ -> CHOLMOD's simplicial LDLᵀ (for cholmod_updown, when an update adds fill):
  /// holds both copies for a moment.
  core::Status to_cholmod_simplicial();
  /// Makes the factor LDLᵀ: packed from supernodal (`packed_form`) or CHOLMOD's simplicial.
  core::Status to_ldlt(bool packed_form);
  /// Column (in the factor's order) of the smallest |l_jj| of a supernodal numeric LLᵀ factor;
  /// −1 for any other factor.
  [[nodiscard]] int smallest_supernodal_pivot() const;
  /// The matrix row of column j of the factor (Perm[j]); −1 for j outside it.
  [[nodiscard]] int row_of(int j) const {
    if (factor == nullptr || j < 0 || static_cast<std::size_t>(j) >= factor->n) return -1;
    const auto* perm = static_cast<const int*>(factor->Perm);
    return perm != nullptr ? perm[j] : j;
  }
  void free_packed() {
    if (packed.x != nullptr) {
      cholmod_free(packed.xsize, sizeof(double), packed.x, &common);
    }
    packed = {};
  }
  std::vector<double> work;  ///< permuted right-hand sides, row-major
  Impl() {
    cholmod_start(&common);
    common.print = 0;
    common.error_handler = nullptr;
    common.quick_return_if_not_posdef = 1;
  }
  ~Impl() {
    free_packed();
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  /// A non-owning CHOLMOD view of an Eigen upper triangle.
  static cholmod_sparse view(const SparseMatrix& upper) {
    cholmod_sparse a{};
    a.nrow = static_cast<size_t>(upper.rows());
    a.ncol = static_cast<size_t>(upper.cols());
    a.nzmax = static_cast<size_t>(upper.nonZeros());
    a.p = const_cast<int*>(upper.outerIndexPtr());
    a.i = const_cast<int*>(upper.innerIndexPtr());
    a.x = const_cast<double*>(upper.valuePtr());
    a.stype = 1;
    a.itype = CHOLMOD_INT;
    a.xtype = CHOLMOD_REAL;
    a.dtype = CHOLMOD_DOUBLE;
    a.sorted = 1;
    a.packed = 1;
    return a;
  }
};

}  // namespace peritwin::linalg
