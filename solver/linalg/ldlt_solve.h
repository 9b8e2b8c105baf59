// The triangular solves with a simplicial LDLᵀ factor (after rank updates), on two threads: the
// schedule splits the factor's columns into two independent sets of elimination subtrees and a
// pipelined top (see SolveSchedule). Results do not depend on the thread count. Used by
// SparseCholesky::solve (sparse_cholesky.h); not an API of its own.
#pragma once

#include <cholmod.h>

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace peritwin::linalg::ldlt {

/// A simplicial LDLᵀ factor as the solves and the rank update read it: column j holds lnz[j]
/// entries, D_jj then the L_ij below the diagonal, values at lx + lp[j] and their rows (sorted,
/// the diagonal first) at rows + ri[j]. CHOLMOD's simplicial factor has ri = lp (a row index per
/// entry); the supernodal storage kept after the first update (cholesky_impl.h, PackedLdlt) has
/// the rows of a supernode once, shared by its columns (column j + 1's rows start one after
/// column j's), so the same kernels read both and do the same arithmetic on the same values.
struct FactorView {
  int n = 0;
  const int* lp = nullptr;
  const int* ri = nullptr;
  const int* lnz = nullptr;
  const int* rows = nullptr;
  double* lx = nullptr;
  const int* perm = nullptr;  ///< factor position -> row of the matrix
  [[nodiscard]] const int* rows_of(int j) const { return rows + ri[j]; }
};

/// The view of a CHOLMOD simplicial numeric factor.
FactorView view_of(const cholmod_factor& l);

/// The columns of a simplicial LDLᵀ factor split into two sets of whole elimination subtrees
/// (parts 1 and 2) and the rest (part 0, the "top": every ancestor of a part-1/2 column is in the
/// top). Forward and backward solves of parts 1 and 2 touch disjoint rows apart from the top ones,
/// so they run on two threads; the split depends only on the factor's pattern, never on the
/// machine, so results are the same with one thread or two.
struct SolveSchedule {
  std::int64_t pattern_nnz = -1;  ///< Σ Lnz when built: updates that add fill change it
  std::vector<int> parent;        ///< elimination tree of the pattern (−1 at a root)
  /// Per part, ascending: chains (first column, length 1-4) of columns j, j+1, ... where column
  /// j+1 has the pattern of column j below row j+1 (a supernode's columns), solved together so
  /// that each row of the right-hand side is read once per chain.
  std::array<std::vector<std::pair<int, int>>, 3> chains;
  bool balanced = false;  ///< parts 1 and 2 are not empty (else all columns are in the top)
  bool sorted = false;    ///< row indices ascending in every column
  /// Every column's rows below its parent are rows of the parent (the pattern is an elimination
  /// tree's: an update along a path then never needs an entry that is not stored).
  bool nested = false;
  /// The top's chains (part 0) in blocks of about 64 columns, for a pipelined two-thread solve of
  /// the top: the rows of a chain below its own columns are split into [0, lo) (inside the
  /// block: thread 0, in order), [lo, mid) (thread 0) and [mid, end) (thread 1), where mid is
  /// a row split m_b >= the last column of the next block.
  struct TopChain {
    int j, k, lo, mid;
  };
  std::vector<TopChain> top_chains;
  std::vector<int> top_block_start;  ///< block b is top_chains[start[b], start[b + 1])
};

/// The schedule of a factor whose pattern has Σ Lnz = pattern_nnz.
SolveSchedule make_schedule(const FactorView& l, std::int64_t pattern_nnz);

/// Solves in place with `rhs_columns` (1 to 3) right-hand sides stored row-major and permuted in
/// y: the forward half L·D·z = y, the backward half Lᵀ·x = z, or both; on two threads when
/// `threaded` and the schedule is balanced.
void solve(int rhs_columns, const FactorView& l, const SolveSchedule& schedule, bool threaded,
           double* y, bool do_forward, bool do_backward);

}  // namespace peritwin::linalg::ldlt
