// SparseCholesky::modify_fused: a group of rank-one updates and downdates of the simplicial LDLᵀ
// factor in one sweep along their elimination-tree paths, keeping the tracked forward solve up to
// date (see sparse_cholesky.h).
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "solver/linalg/cholesky_impl.h"

namespace peritwin::linalg {

namespace {

constexpr int kGroup = 16;  ///< ranks per sweep of the fused update

struct RankScalars {
  int rank;
  double p, beta;
};

/// The tracked right-hand sides' change at row i of column j: δ_i += l_ij·y_j − l̄_ij·ȳ_j.
template <int R>
inline void forward_change(double* delta, int i, double l_old, double l, const double* y_old,
                           const double* y_new) {
  if constexpr (R > 0) {
    double* di = delta + static_cast<std::size_t>(i) * 3;
    for (int r = 0; r < R; ++r) {
      di[r] += l_old * y_old[r];
      di[r] -= l * y_new[r];
    }
  }
}

/// Entries q in [from, to) of column j (rows li[q], values lx[q]: the column's own arrays):
/// w_i −= p·l_ij, l_ij += β·w_i for each active rank; with R tracked right-hand sides also
/// δ_i += l_ij·y_j − l̄_ij·ȳ_j (the forward solve's change).
///
/// Interleaved (the default, SparseCholesky::set_interleaved_update): each entry's ranks are a
/// chain of dependent operations (l_ij after rank a feeds rank a + 1), so one entry at a time runs
/// at the latency of that chain. Four entries go through the ranks side by side (their rows are
/// distinct, so their W rows are too): four independent chains in flight, the same operations on
/// every entry in the same order, hence the same bits. Issue 37: 1.6x on a 204-bond group of B1 at
/// 15k nodes; no gain on a growing crack's groups of 5-15 bonds (docs/benchmarks.md).
template <int R, bool Interleaved>
void apply_column(const int* li, double* lx, double* w, int from, int to, const RankScalars* active,
                  int count, double* delta, const double* y_old, const double* y_new) {
  int q = from;
  for (; Interleaved && q + 4 <= to; q += 4) {
    double* w0 = w + static_cast<std::size_t>(li[q]) * kGroup;
    double* w1 = w + static_cast<std::size_t>(li[q + 1]) * kGroup;
    double* w2 = w + static_cast<std::size_t>(li[q + 2]) * kGroup;
    double* w3 = w + static_cast<std::size_t>(li[q + 3]) * kGroup;
    const double o0 = lx[q], o1 = lx[q + 1], o2 = lx[q + 2], o3 = lx[q + 3];
    double l0 = o0, l1 = o1, l2 = o2, l3 = o3;
    for (int a = 0; a < count; ++a) {
      const int r = active[a].rank;
      const double p = active[a].p;
      const double beta = active[a].beta;
      double x0 = w0[r];
      double x1 = w1[r];
      double x2 = w2[r];
      double x3 = w3[r];
      x0 -= p * l0;
      x1 -= p * l1;
      x2 -= p * l2;
      x3 -= p * l3;
      l0 += beta * x0;
      l1 += beta * x1;
      l2 += beta * x2;
      l3 += beta * x3;
      w0[r] = x0;
      w1[r] = x1;
      w2[r] = x2;
      w3[r] = x3;
    }
    lx[q] = l0;
    lx[q + 1] = l1;
    lx[q + 2] = l2;
    lx[q + 3] = l3;
    forward_change<R>(delta, li[q], o0, l0, y_old, y_new);
    forward_change<R>(delta, li[q + 1], o1, l1, y_old, y_new);
    forward_change<R>(delta, li[q + 2], o2, l2, y_old, y_new);
    forward_change<R>(delta, li[q + 3], o3, l3, y_old, y_new);
  }
  for (; q < to; ++q) {
    double* wi = w + static_cast<std::size_t>(li[q]) * kGroup;
    const double l_old = lx[q];
    double l = l_old;
    for (int a = 0; a < count; ++a) {
      double& x = wi[active[a].rank];
      x -= active[a].p * l;
      l += active[a].beta * x;
    }
    lx[q] = l;
    forward_change<R>(delta, li[q], l_old, l, y_old, y_new);
  }
}

template <bool Interleaved>
inline void apply_tracked(int tracked, const int* li, double* lx, double* w, int from, int to,
                          const RankScalars* active, int count, double* delta, const double* y_old,
                          const double* y_new) {
  switch (tracked) {
    case 0:
      apply_column<0, Interleaved>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    case 1:
      apply_column<1, Interleaved>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    case 2:
      apply_column<2, Interleaved>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    default:
      apply_column<3, Interleaved>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
  }
}

inline void apply_column(int tracked, const int* li, double* lx, double* w, int from, int to,
                         const RankScalars* active, int count, double* delta, const double* y_old,
                         const double* y_new) {
  if (SparseCholesky::interleaved_update()) {
    apply_tracked<true>(tracked, li, lx, w, from, to, active, count, delta, y_old, y_new);
  } else {  // the oracle: one entry at a time
    apply_tracked<false>(tracked, li, lx, w, from, to, active, count, delta, y_old, y_new);
  }
}

/// The forward solve's value at row j: ȳ_j = y_j + δ_j (δ_j is complete once the path's earlier
/// columns are done); δ_j is cleared. Returns whether it changed (the column must then be swept
/// even without an active rank).
inline bool forward_pivot(int tracked, int j, double* y, double* delta, double* y_old,
                          double* y_new) {
  bool moved = false;
  for (int r = 0; r < tracked; ++r) {
    double& yj = y[static_cast<std::size_t>(j) * static_cast<std::size_t>(tracked) +
                   static_cast<std::size_t>(r)];
    double& dj = delta[static_cast<std::size_t>(j) * 3 + static_cast<std::size_t>(r)];
    y_old[r] = yj;
    y_new[r] = yj + dj;
    moved = moved || dj != 0.0;
    dj = 0.0;
    yj = y_new[r];
  }
  return moved;
}

/// The scalars of column j (method C1 of Gill, Golub, Murray and Saunders, rank by rank in
/// order): p = w_j, d̄ = d + α·p², β = α·p/d̄, α ← α·d/d̄; row j of W is cleared. Returns the number
/// of active ranks (p ≠ 0: a rank whose path does not reach j has w_j = 0 and leaves it alone).
inline int column_scalars(const int* lp, double* lx, double* w, int j, int ranks, double* alpha,
                          RankScalars* active) {
  double d = lx[lp[j]];
  double* wj = w + static_cast<std::size_t>(j) * kGroup;
  int count = 0;
  for (int r = 0; r < ranks; ++r) {
    const double p = wj[r];
    if (p == 0.0) continue;
    wj[r] = 0.0;
    const double dbar = d + alpha[r] * p * p;
    const double beta = alpha[r] * p / dbar;
    alpha[r] *= d / dbar;
    d = dbar;
    active[count++] = {r, p, beta};
  }
  lx[lp[j]] = d;
  return count;
}

/// A column of the fused update in the factor's ordering, its entries sorted by row, with its sign
/// (+1 update, −1 downdate).
struct Rank {
  std::vector<std::pair<int, double>> entries;
  double sign;
};

/// Permuted, sorted columns with their signs, updates first. The fused sweep needs the rows of
/// each column below its first one to be in that column of L (no fill; true for the bond
/// vectors, whose pairs are all in the matrix's pattern); returns false otherwise (CHOLMOD then
/// does it).
bool fused_ranks(const std::vector<int>& inverse_perm, const ldlt::FactorView& l,
                 const std::vector<SparseCholesky::Column>& added,
                 const std::vector<SparseCholesky::Column>& removed, std::vector<Rank>& ranks) {
  bool fits = true;
  for (int pass = 0; pass < 2 && fits; ++pass) {
    for (const auto& c : pass == 0 ? added : removed) {
      Rank rank{{}, pass == 0 ? 1.0 : -1.0};
      for (std::size_t e = 0; e < c.rows.size(); ++e) {
        rank.entries.emplace_back(inverse_perm[static_cast<std::size_t>(c.rows[e])], c.values[e]);
      }
      std::sort(rank.entries.begin(), rank.entries.end());
      if (rank.entries.empty()) continue;
      const int first = rank.entries.front().first;
      const int* rows = l.rows_of(first) + 1;
      const int* end = l.rows_of(first) + l.lnz[first];
      for (std::size_t e = 1; e < rank.entries.size() && fits; ++e) {
        fits = rank.entries[e].first != rank.entries[e - 1].first &&
               std::binary_search(rows, end, rank.entries[e].first);
      }
      ranks.push_back(std::move(rank));
    }
  }
  return fits;
}

/// What a sweep reads and writes: the factor's columns, the workspace W (n × kGroup, row j's
/// kGroup entries together), and the tracked forward solve y with its change δ.
struct Sweep {
  ldlt::FactorView l;
  double* w;
  int tracked;
  double* delta;
  double* fy;
  [[nodiscard]] const int* rows_of(int j) const { return l.rows_of(j); }
  [[nodiscard]] double* values_of(int j) const { return l.lx + l.lp[j]; }
};

/// Where a group's sweep goes: loads the group's ranks (from `first` on) into W and α, and
/// returns the union of their elimination-tree paths in increasing order in `path`. Columns
/// reached for the first time in this call of modify_fused (mark ≠ all_stamp) go to `touched`.
void group_path(const Sweep& s, const std::vector<int>& parent, const std::vector<Rank>& ranks,
                std::size_t first, int group, int gstamp, double* alpha,
                std::vector<int>& group_mark, std::vector<int>& mark, int all_stamp,
                std::vector<int>& touched, std::vector<int>& path) {
  path.clear();
  for (int r = 0; r < group; ++r) {
    const Rank& rank = ranks[first + static_cast<std::size_t>(r)];
    alpha[r] = rank.sign;
    for (const auto& [row, value] : rank.entries) {
      s.w[static_cast<std::size_t>(row) * kGroup + static_cast<std::size_t>(r)] = value;
    }
    for (int j = rank.entries.front().first;
         j >= 0 && group_mark[static_cast<std::size_t>(j)] != gstamp;
         j = parent[static_cast<std::size_t>(j)]) {
      group_mark[static_cast<std::size_t>(j)] = gstamp;
      path.push_back(j);
      if (mark[static_cast<std::size_t>(j)] != all_stamp) {
        mark[static_cast<std::size_t>(j)] = all_stamp;
        touched.push_back(j);
      }
    }
  }
  std::sort(path.begin(), path.end());
}

/// One group along its path on the calling thread.
void sweep_one_thread(const Sweep& s, const std::vector<int>& path, int group, double* alpha) {
  RankScalars active[kGroup];
  double y_old[3], y_new[3];
  for (int j : path) {
    const int count = column_scalars(s.l.lp, s.l.lx, s.w, j, group, alpha, active);
    const bool moved = forward_pivot(s.tracked, j, s.fy, s.delta, y_old, y_new);
    if (count > 0 || moved) {
      apply_column(s.tracked, s.rows_of(j), s.values_of(j), s.w, 1, s.l.lnz[j], active, count,
                   s.delta, y_old, y_new);
    }
  }
}

/// The split row S of the two-thread sweep: balances the path's entries below S against the
/// others (rows assumed spread evenly between a column's first and last row).
int balanced_split(const Sweep& s, const std::vector<int>& path, double entries, int n) {
  auto below = [&](int split) {
    double count = 0.0;
    for (int j : path) {
      if (j >= split) break;
      const int len = s.l.lnz[j] - 1;
      if (len <= 0) continue;
      const int first = s.rows_of(j)[1];
      const int last = s.rows_of(j)[s.l.lnz[j] - 1];
      const double f = last > first ? static_cast<double>(split - first) / (last - first + 1)
                                    : (split > first ? 1.0 : 0.0);
      count += len * std::clamp(f, 0.0, 1.0);
    }
    return count;
  };
  int lo_split = path.front(), hi_split = n;
  while (hi_split - lo_split > 1) {
    const int mid = lo_split + (hi_split - lo_split) / 2;
    (below(mid) < 0.5 * entries ? lo_split : hi_split) = mid;
  }
  return hi_split;
}

/// What thread 0 publishes to thread 1 for the path's columns below the split row: each column's
/// scalars, active count, forward pivots (y_old[3], y_new[3]) and whether its y moved; `ready`
/// counts the columns published. Kept across groups (reused storage).
struct Handoff {
  std::vector<RankScalars> scalars;
  std::vector<int> counts;
  std::vector<double> pivots;
  std::vector<std::uint8_t> moves;
  std::atomic<int> ready{0};
  int split = 0;  ///< S: rows below it are thread 0's
  int k0 = 0;     ///< the path's first column at or after S
};

/// Thread 0: the scalars of the path's columns below S (it owns w_j there), published one by one,
/// and their rows below S.
void sweep_lower(const Sweep& s, const std::vector<int>& path, int group, double* alpha,
                 Handoff& h) {
  for (int k = 0; k < h.k0; ++k) {
    const int j = path[static_cast<std::size_t>(k)];
    RankScalars* active = h.scalars.data() + static_cast<std::size_t>(k) * kGroup;
    const int count = column_scalars(s.l.lp, s.l.lx, s.w, j, group, alpha, active);
    double* piv = h.pivots.data() + static_cast<std::size_t>(k) * 6;
    const bool moved = forward_pivot(s.tracked, j, s.fy, s.delta, piv, piv + 3);
    h.counts[static_cast<std::size_t>(k)] = count;
    h.moves[static_cast<std::size_t>(k)] = moved ? 1 : 0;
    h.ready.store(k + 1, std::memory_order_release);
    if (count == 0 && !moved) continue;
    const int* rows = s.rows_of(j);
    const int cut = static_cast<int>(std::lower_bound(rows + 1, rows + s.l.lnz[j], h.split) - rows);
    apply_column(s.tracked, rows, s.values_of(j), s.w, 1, cut, active, count, s.delta, piv,
                 piv + 3);
  }
}

/// Thread 1: the rows from S on of the columns below S, with thread 0's published scalars; then
/// the columns from S on, alone.
void sweep_upper(const Sweep& s, const std::vector<int>& path, int group, double* alpha,
                 Handoff& h) {
  const int columns = static_cast<int>(path.size());
  for (int k = 0; k < columns; ++k) {
    const int j = path[static_cast<std::size_t>(k)];
    const RankScalars* active;
    int count;
    int from;
    bool moved;
    const double* piv;
    RankScalars own[kGroup];
    double own_pivot[6];
    if (k < h.k0) {
      for (int spins = 0; h.ready.load(std::memory_order_acquire) <= k; ++spins) {
        if (spins > 2000) std::this_thread::yield();
      }
      active = h.scalars.data() + static_cast<std::size_t>(k) * kGroup;
      count = h.counts[static_cast<std::size_t>(k)];
      moved = h.moves[static_cast<std::size_t>(k)] != 0;
      piv = h.pivots.data() + static_cast<std::size_t>(k) * 6;
      const int* rows = s.rows_of(j);
      from = static_cast<int>(std::lower_bound(rows + 1, rows + s.l.lnz[j], h.split) - rows);
    } else {
      if (k == h.k0) {  // thread 0 is done with α (it published column k0 − 1 last)
        for (int spins = 0; h.ready.load(std::memory_order_acquire) < h.k0; ++spins) {
          if (spins > 2000) std::this_thread::yield();
        }
      }
      count = column_scalars(s.l.lp, s.l.lx, s.w, j, group, alpha, own);
      moved = forward_pivot(s.tracked, j, s.fy, s.delta, own_pivot, own_pivot + 3);
      piv = own_pivot;
      active = own;
      from = 1;
    }
    if (count > 0 || moved) {
      apply_column(s.tracked, s.rows_of(j), s.values_of(j), s.w, from, s.l.lnz[j], active, count,
                   s.delta, piv, piv + 3);
    }
  }
}

/// One group along its path on two threads. Rows below the split row S belong to thread 0, the
/// others to thread 1. For the path's columns below S, thread 0 computes the scalars (it owns
/// w_j) and publishes them; thread 1 follows with its rows. Columns from S on are thread 1's
/// alone. Every entry gets the same operations as on one thread.
void sweep_two_threads(const Sweep& s, const std::vector<int>& path, int group, double* alpha,
                       double entries, Handoff& h) {
  const int columns = static_cast<int>(path.size());
  h.split = balanced_split(s, path, entries, s.l.n);
  h.k0 = static_cast<int>(std::lower_bound(path.begin(), path.end(), h.split) - path.begin());
  h.scalars.resize(static_cast<std::size_t>(columns) * kGroup);
  h.counts.assign(static_cast<std::size_t>(columns), 0);
  h.pivots.resize(static_cast<std::size_t>(columns) * 6);  // y_old[3], y_new[3] per column
  h.moves.assign(static_cast<std::size_t>(columns), 0);
  h.ready.store(0);
  std::thread helper;
  try {
    helper = std::thread([&] { sweep_upper(s, path, group, alpha, h); });
  } catch (const std::system_error&) {
    sweep_lower(s, path, group, alpha, h);
    sweep_upper(s, path, group, alpha, h);
    return;
  }
  sweep_lower(s, path, group, alpha, h);
  helper.join();
}

/// 4 flops per entry of L on each column's elimination-tree path from its first row (see
/// SparseCholesky::update_flops).
double path_flops(const std::vector<int>& inverse_perm, const std::vector<int>& parent,
                  const ldlt::FactorView& l, const std::vector<SparseCholesky::Column>& added,
                  const std::vector<SparseCholesky::Column>& removed) {
  double entries = 0.0;
  for (const auto* columns : {&added, &removed}) {
    for (const auto& c : *columns) {
      if (c.rows.empty()) continue;
      int first = l.n;
      for (int row : c.rows) first = std::min(first, inverse_perm[static_cast<std::size_t>(row)]);
      for (int j = first; j >= 0; j = parent[static_cast<std::size_t>(j)]) {
        entries += l.lnz[j] - 1;
      }
    }
  }
  return 4.0 * entries;
}

}  // namespace

double SparseCholesky::update_flops(const std::vector<Column>& added,
                                    const std::vector<Column>& removed) {
  if (added.empty() && removed.empty()) return 0.0;
  auto& impl = *impl_;
  if (!impl.to_ldlt(true).ok()) return std::numeric_limits<double>::infinity();
  impl.ensure_schedule();
  const ldlt::FactorView l = impl.view();
  impl.ensure_inverse_perm(l);
  return path_flops(impl.inverse_perm, impl.schedule.parent, l, added, removed);
}

core::Status SparseCholesky::modify_fused(const std::vector<Column>& added,
                                          const std::vector<Column>& removed) {
  if (added.empty() && removed.empty()) return {};
  auto& impl = *impl_;
  // The supernodal factor becomes LDLᵀ in its own storage (cholesky_impl.h, PackedLdlt): no
  // second copy of the factor, no row index per entry.
  if (auto r = impl.to_ldlt(true); !r.ok()) return r;
  impl.ensure_schedule();
  const ldlt::FactorView l = impl.view();
  const auto n = static_cast<std::size_t>(l.n);
  impl.ensure_inverse_perm(l);
  std::vector<Rank> ranks;
  const bool fits = impl.schedule.sorted && impl.schedule.nested &&
                    fused_ranks(impl.inverse_perm, l, added, removed, ranks);
  if (!fits) {
    core::Status r = modify(added, true);
    if (r.ok()) r = modify(removed, false);
    return r;
  }
  impl.update_flops_total += path_flops(impl.inverse_perm, impl.schedule.parent, l, added, removed);
  if (impl.w.size() != n * kGroup) impl.w.assign(n * kGroup, 0.0);
  const int tracked = impl.forward_valid ? static_cast<int>(impl.tracked_rhs.cols()) : 0;
  if (impl.delta.size() != n * 3) impl.delta.assign(n * 3, 0.0);
  const Sweep sweep{l, impl.w.data(), tracked, impl.delta.data(), impl.forward_y.data()};
  if (++impl.stamp == 0) {
    std::fill(impl.mark.begin(), impl.mark.end(), 0);
    impl.stamp = 1;
  }
  const int all_stamp = impl.stamp;  // columns touched by any group, for the D refresh
  std::vector<int> touched;
  std::vector<int> path;
  std::vector<int> group_mark(n, 0);
  Handoff handoff;
  for (std::size_t g0 = 0; g0 < ranks.size(); g0 += kGroup) {
    const int group = static_cast<int>(std::min<std::size_t>(kGroup, ranks.size() - g0));
    double alpha[kGroup];
    const int gstamp = static_cast<int>(g0 / kGroup) + 1;
    group_path(sweep, impl.schedule.parent, ranks, g0, group, gstamp, alpha, group_mark, impl.mark,
               all_stamp, touched, path);
    double entries = 0.0;
    for (int j : path) entries += l.lnz[j];
    const bool threaded =
        impl.solve_threads == 2 ||
        (impl.solve_threads == 0 && entries > 200'000 && SparseCholesky::automatic_two_threads());
    if (threaded) {
      sweep_two_threads(sweep, path, group, alpha, entries, handoff);
    } else {
      sweep_one_thread(sweep, path, group, alpha);
    }
  }
  for (int j : touched) {
    impl.diagonal[static_cast<std::size_t>(j)] = l.lx[l.lp[j]];
  }
  if (!removed.empty()) {
    if (auto r = check_after_downdate(impl.diagonal, impl.weakest_row); !r.ok()) {
      impl.weakest_row = impl.row_of(impl.weakest_row);
      return r;
    }
  }
  return {};
}

}  // namespace peritwin::linalg
