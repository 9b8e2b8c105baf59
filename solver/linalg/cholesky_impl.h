// SparseCholesky's internals, shared by its two source files: sparse_cholesky.cpp (analysis,
// factorization, solves, CHOLMOD's own updates) and rank_update.cpp (the fused rank update).
#pragma once

#include <cholmod.h>

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

#include "solver/linalg/ldlt_solve.h"
#include "solver/linalg/sparse_cholesky.h"

namespace peritwin {

/// After a downdate: D of LDLᵀ must stay positive, and rcond as cholmod_rcond computes it,
/// min(D) / max(D), above 1e-14 — else the model has come loose.
Status check_after_downdate(const std::vector<double>& diagonal);

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  std::vector<int> inverse_perm;  ///< row -> position in the factor's ordering
  ldlt::SolveSchedule schedule;   ///< for the simplicial factor after modify()
  std::vector<double> diagonal;   ///< D of the simplicial factor (refreshed along update paths)
  std::vector<int> mark;          ///< per column: last modify() whose path reached it
  int stamp = 0;
  int solve_threads = 0;  ///< 0 automatic, 1, 2
  std::vector<double> w;  ///< n × kGroup workspace of the fused update (zero between calls)
  /// The forward solve y = L⁻¹·P·b of the last right-hand sides b solved with the simplicial
  /// factor, kept up to date by the fused update (only the update paths' rows change), so that
  /// solving the same b again is only the backward half.
  Eigen::MatrixXd tracked_rhs;
  std::vector<double> forward_y;  ///< n × columns of tracked_rhs, row-major, permuted
  std::vector<double> delta;      ///< n × 3 workspace of the forward update (zero between calls)
  bool forward_valid = false;
  /// Σ Lnz of the simplicial factor: grows when an update adds fill (the pattern changes).
  [[nodiscard]] std::int64_t pattern_nnz() const {
    const auto* lnz = static_cast<const int*>(factor->nz);
    std::int64_t nnz = 0;
    for (std::size_t j = 0; j < factor->n; ++j) nnz += lnz[j];
    return nnz;
  }
  void ensure_schedule() {
    const std::int64_t nnz = pattern_nnz();
    if (schedule.pattern_nnz == nnz) return;
    schedule = ldlt::make_schedule(*factor, nnz);
    const auto* lp = static_cast<const int*>(factor->p);
    const auto* lx = static_cast<const double*>(factor->x);
    diagonal.resize(factor->n);
    for (std::size_t j = 0; j < factor->n; ++j) diagonal[j] = lx[lp[j]];
    mark.assign(factor->n, 0);
    stamp = 0;
  }
  std::vector<double> work;  ///< permuted right-hand sides, row-major
  Impl() {
    cholmod_start(&common);
    common.print = 0;
    common.error_handler = nullptr;
    common.quick_return_if_not_posdef = 1;
  }
  ~Impl() {
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

}  // namespace peritwin
