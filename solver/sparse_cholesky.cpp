#include "solver/sparse_cholesky.h"

#include <cholmod.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <system_error>
#include <thread>

namespace peritwin {

namespace {

/// After a downdate: D of LDLᵀ must stay positive, and rcond as cholmod_rcond computes it,
/// min(D) / max(D), above 1e-14 — else the model has come loose.
FactorReport check_after_downdate(const std::vector<double>& diagonal) {
  double d_min = diagonal.empty() ? 0.0 : diagonal.front();
  double d_max = d_min;
  bool positive = true;
  for (const double d : diagonal) {
    positive = positive && d > 0.0;
    d_min = std::min(d_min, d);
    d_max = std::max(d_max, d);
  }
  if (!positive) {
    return {FactorStatus::not_positive_definite,
            "stiffness is not positive definite after breaking bonds: a part of the model has "
            "come loose"};
  }
  const double rcond = d_min / d_max;
  if (!(rcond > 1e-14)) {
    return {FactorStatus::singular, "stiffness is numerically singular (rcond " +
                                        std::to_string(rcond) +
                                        "): a part of the model has come loose"};
  }
  return {};
}

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

SolveSchedule make_schedule(const cholmod_factor& l, std::int64_t pattern_nnz) {
  SolveSchedule schedule;
  schedule.pattern_nnz = pattern_nnz;
  const auto n = static_cast<int>(l.n);
  const auto* lp = static_cast<const int*>(l.p);
  const auto* li = static_cast<const int*>(l.i);
  const auto* lnz = static_cast<const int*>(l.nz);
  // Elimination tree: the parent of j is the smallest row below the diagonal of column j.
  std::vector<int> parent(static_cast<std::size_t>(n), -1);
  std::vector<double> weight(static_cast<std::size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    int p = n;
    for (int q = lp[j] + 1; q < lp[j] + lnz[j]; ++q) p = std::min(p, li[q]);
    parent[static_cast<std::size_t>(j)] = p < n ? p : -1;
    weight[static_cast<std::size_t>(j)] += lnz[j];
    if (p < n) weight[static_cast<std::size_t>(p)] += weight[static_cast<std::size_t>(j)];
  }
  std::vector<int> child_start(static_cast<std::size_t>(n) + 1, 0), children;
  for (int j = 0; j < n; ++j) {
    if (parent[static_cast<std::size_t>(j)] >= 0)
      ++child_start[static_cast<std::size_t>(parent[static_cast<std::size_t>(j)]) + 1];
  }
  for (int j = 0; j < n; ++j) {
    child_start[static_cast<std::size_t>(j) + 1] += child_start[static_cast<std::size_t>(j)];
  }
  children.resize(static_cast<std::size_t>(child_start[static_cast<std::size_t>(n)]));
  {
    std::vector<int> next(child_start.begin(), child_start.end() - 1);
    for (int j = 0; j < n; ++j) {
      const int p = parent[static_cast<std::size_t>(j)];
      if (p >= 0) children[static_cast<std::size_t>(next[static_cast<std::size_t>(p)]++)] = j;
    }
  }
  // Split the heaviest candidate subtree (its root goes to the top) until the candidates pack
  // into two bins within 2 % of each other (largest-first greedy packing).
  std::vector<int> candidates;
  for (int j = 0; j < n; ++j) {
    if (parent[static_cast<std::size_t>(j)] < 0) candidates.push_back(j);
  }
  std::vector<std::uint8_t> part(static_cast<std::size_t>(n), 0);
  std::vector<std::uint8_t> bin_of;
  double total = 0.0;
  for (int j : candidates) total += weight[static_cast<std::size_t>(j)];
  const double all = total;
  auto heavier = [&](int a, int b) {
    const double wa = weight[static_cast<std::size_t>(a)];
    const double wb = weight[static_cast<std::size_t>(b)];
    return wa != wb ? wa > wb : a < b;
  };
  bool balanced = false;
  for (int iteration = 0; iteration < 100000 && !candidates.empty() && candidates.size() < 4096;
       ++iteration) {
    std::sort(candidates.begin(), candidates.end(), heavier);
    double bins[2] = {0.0, 0.0};
    bin_of.assign(candidates.size(), 0);
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      const std::uint8_t b = bins[0] <= bins[1] ? 0 : 1;
      bin_of[c] = b;
      bins[b] += weight[static_cast<std::size_t>(candidates[c])];
    }
    if (candidates.size() >= 2 && std::max(bins[0], bins[1]) <= 0.51 * total) {
      balanced = true;
      break;
    }
    // Too much left in the top: not worth splitting further.
    if (total < 0.5 * all) break;
    const int h = candidates.front();
    candidates.erase(candidates.begin());
    total -= weight[static_cast<std::size_t>(h)];
    for (int q = child_start[static_cast<std::size_t>(h)];
         q < child_start[static_cast<std::size_t>(h) + 1]; ++q) {
      const int c = children[static_cast<std::size_t>(q)];
      candidates.push_back(c);
      total += weight[static_cast<std::size_t>(c)];
    }
  }
  if (balanced) {
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      part[static_cast<std::size_t>(candidates[c])] = static_cast<std::uint8_t>(1 + bin_of[c]);
    }
    // A column belongs to the part of its parent unless it is a candidate root or in the top.
    for (int j = n - 1; j >= 0; --j) {
      const int p = parent[static_cast<std::size_t>(j)];
      if (part[static_cast<std::size_t>(j)] == 0 && p >= 0) {
        part[static_cast<std::size_t>(j)] = part[static_cast<std::size_t>(p)];
      }
    }
  }
  auto same_below = [&](int j, int t) {  // column j+t equals column j below row j+t
    if (j + t >= n || part[static_cast<std::size_t>(j + t)] != part[static_cast<std::size_t>(j)])
      return false;
    const int a = lp[j], b = lp[j + t];
    if (lnz[j + t] != lnz[j] - t || lnz[j] <= t || li[a + t] != j + t) return false;
    for (int q = 0; q < lnz[j + t]; ++q) {
      if (li[b + q] != li[a + t + q]) return false;
    }
    return true;
  };
  for (int j = 0; j < n;) {
    int k = 1;
    while (k < 4 && same_below(j, k)) ++k;
    schedule.chains[part[static_cast<std::size_t>(j)]].emplace_back(j, k);
    j += k;
  }
  schedule.balanced = balanced;
  schedule.sorted = true;
  for (int j = 0; j < n && schedule.sorted; ++j) {
    for (int q = lp[j] + 1; q < lp[j] + lnz[j]; ++q) {
      schedule.sorted = schedule.sorted && li[q] > li[q - 1];
    }
  }
  schedule.nested = schedule.sorted;
  for (int j = 0; j < n && schedule.nested; ++j) {
    const int p = parent[static_cast<std::size_t>(j)];
    if (p < 0) continue;
    // Rows of j after p (sorted, p is the first below the diagonal) must be among p's rows.
    int q = lp[p] + 1;
    const int q_end = lp[p] + lnz[p];
    for (int e = lp[j] + 2; e < lp[j] + lnz[j] && schedule.nested; ++e) {
      while (q < q_end && li[q] < li[e]) ++q;
      schedule.nested = q < q_end && li[q] == li[e];
    }
  }
  // Top blocks. Rows must be sorted in the top's columns (they are in CHOLMOD's simplicial
  // factors); otherwise one block with everything inside it (thread 0 alone).
  bool sorted = true;
  for (const auto& [j0, k] : schedule.chains[0]) {
    for (int q = lp[j0] + 1; q < lp[j0] + lnz[j0]; ++q) sorted = sorted && li[q] > li[q - 1];
  }
  constexpr int block_columns = 64;
  for (std::size_t c = 0; c < schedule.chains[0].size();) {
    schedule.top_block_start.push_back(static_cast<int>(schedule.top_chains.size()));
    int columns = 0;
    while (c < schedule.chains[0].size() && (columns < block_columns || !sorted)) {
      const auto [j, k] = schedule.chains[0][c++];
      schedule.top_chains.push_back({j, k, 0, 0});
      columns += k;
    }
  }
  schedule.top_block_start.push_back(static_cast<int>(schedule.top_chains.size()));
  const std::size_t blocks = schedule.top_block_start.size() - 1;
  auto last_column = [&](std::size_t b) {
    const auto& t =
        schedule.top_chains[static_cast<std::size_t>(schedule.top_block_start[b + 1]) - 1];
    return t.j + t.k - 1;
  };
  std::vector<std::pair<int, int>> below;  // (row, weight) of the block's rows below it
  for (std::size_t b = 0; b < blocks; ++b) {
    const int last = sorted ? last_column(b) : n;
    const int floor_m = b + 1 < blocks ? last_column(b + 1) : n;
    below.clear();
    double inside = 0.0, outside = 0.0;
    for (int c = schedule.top_block_start[b]; c < schedule.top_block_start[b + 1]; ++c) {
      auto& t = schedule.top_chains[static_cast<std::size_t>(c)];
      const int* rows = li + lp[t.j] + t.k;
      const int len = lnz[t.j] - t.k;
      t.lo = static_cast<int>(std::upper_bound(rows, rows + len, last) - rows);
      inside += static_cast<double>(t.lo) * t.k;
      for (int q = t.lo; q < len; ++q) below.emplace_back(rows[q], t.k);
      outside += static_cast<double>(len - t.lo) * t.k;
    }
    // Thread 0 also solves the next block's inside: give it less of the rows below.
    std::sort(below.begin(), below.end());
    const double target = std::max(0.0, 0.5 * (outside - inside));
    int m = floor_m;
    double sum = 0.0;
    for (const auto& [row, w] : below) {
      if (sum >= target) break;
      sum += w;
      m = std::max(m, row);
    }
    if (!sorted) m = n;
    for (int c = schedule.top_block_start[b]; c < schedule.top_block_start[b + 1]; ++c) {
      auto& t = schedule.top_chains[static_cast<std::size_t>(c)];
      const int* rows = li + lp[t.j] + t.k;
      const int len = lnz[t.j] - t.k;
      t.mid = sorted ? static_cast<int>(std::upper_bound(rows, rows + len, m) - rows) : len;
      if (!sorted) t.lo = len;
    }
  }
  schedule.parent = std::move(parent);
  return schedule;
}

/// The top's forward solve, chain by chain: solve the chain's own columns (in_chain) and scatter
/// rows [from, to) of its shared rows below.
template <int R, int K>
void top_forward_chain(const int* lp, const int* li, const double* lx, int j, bool in_chain,
                       int from, int to, double* y) {
  double v[K][R];
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  for (int t = 0; t < K; ++t) {
    for (int r = 0; r < R; ++r) {
      double a = y[static_cast<std::size_t>(j + t) * R + r];
      if (in_chain) {
        for (int u = 0; u < t; ++u) a -= lx[p[u] + t - u] * v[u][r];
        y[static_cast<std::size_t>(j + t) * R + r] = a;
      }
      v[t][r] = a;
    }
  }
  const int* rows = li + p[0] + K;
  for (int q = from; q < to; ++q) {
    double* yi = y + static_cast<std::size_t>(rows[q]) * R;
    double l[K];
    for (int t = 0; t < K; ++t) l[t] = lx[p[t] + K - t + q];
    for (int r = 0; r < R; ++r) {
      double a = 0.0;
      for (int t = 0; t < K; ++t) a += l[t] * v[t][r];
      yi[r] -= a;
    }
  }
}

/// Forward solve L·y = y (unit diagonal) with a chain of K columns j..j+K-1; y is n × R row-major:
/// the whole chain, all of its shared rows.
template <int R, int K>
void forward_chain(const int* lp, const int* li, const int* lnz, const double* lx, int j,
                   double* y) {
  top_forward_chain<R, K>(lp, li, lx, j, true, 0, lnz[j] - K, y);
}

/// Backward solve D·Lᵀ·x = y with a chain of K columns; x overwrites y.
template <int R, int K>
void backward_chain(const int* lp, const int* li, const int* lnz, const double* lx, int j,
                    double* y) {
  double v[K][R];
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  for (int t = 0; t < K; ++t) {
    for (int r = 0; r < R; ++r) v[t][r] = y[static_cast<std::size_t>(j + t) * R + r] / lx[p[t]];
  }
  const int len = lnz[j] - K;
  const int* rows = li + p[0] + K;
  for (int q = 0; q < len; ++q) {
    const double* xi = y + static_cast<std::size_t>(rows[q]) * R;
    for (int t = 0; t < K; ++t) {
      const double l = lx[p[t] + K - t + q];
      for (int r = 0; r < R; ++r) v[t][r] -= l * xi[r];
    }
  }
  for (int t = K - 1; t >= 0; --t) {
    for (int r = 0; r < R; ++r) {
      double a = v[t][r];
      for (int u = t + 1; u < K; ++u)
        a -= lx[p[t] + u - t] * y[static_cast<std::size_t>(j + u) * R + r];
      y[static_cast<std::size_t>(j + t) * R + r] = a;
    }
  }
}

inline int lnz_of(const cholmod_factor& l, int j) { return static_cast<const int*>(l.nz)[j]; }

/// The top's backward solve: partial sums Σ L(i, j+t)·x_i over rows [from, to) of the chain's
/// shared rows into s[K][R].
template <int R, int K>
void top_backward_partial(const int* lp, const int* li, const double* lx, int j, int from, int to,
                          const double* y, double* s) {
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  double v[K][R] = {};
  const int* rows = li + p[0] + K;
  for (int q = from; q < to; ++q) {
    const double* xi = y + static_cast<std::size_t>(rows[q]) * R;
    for (int t = 0; t < K; ++t) {
      const double l = lx[p[t] + K - t + q];
      for (int r = 0; r < R; ++r) v[t][r] += l * xi[r];
    }
  }
  for (int t = 0; t < K; ++t) {
    for (int r = 0; r < R; ++r) s[t * R + r] = v[t][r];
  }
}

/// The top's backward solve of a chain's own columns given the two partial sums of its rows
/// below the block; rows [0, lo) (inside the block) are summed here.
template <int R, int K>
void top_backward_finish(const int* lp, const int* li, const double* lx, int j, int lo,
                         const double* s0, const double* s1, double* y) {
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  double v[K][R];
  for (int t = 0; t < K; ++t) {
    for (int r = 0; r < R; ++r) {
      v[t][r] =
          y[static_cast<std::size_t>(j + t) * R + r] / lx[p[t]] - s0[t * R + r] - s1[t * R + r];
    }
  }
  const int* rows = li + p[0] + K;
  for (int q = 0; q < lo; ++q) {
    const double* xi = y + static_cast<std::size_t>(rows[q]) * R;
    for (int t = 0; t < K; ++t) {
      const double l = lx[p[t] + K - t + q];
      for (int r = 0; r < R; ++r) v[t][r] -= l * xi[r];
    }
  }
  for (int t = K - 1; t >= 0; --t) {
    for (int r = 0; r < R; ++r) {
      double a = v[t][r];
      for (int u = t + 1; u < K; ++u) {
        a -= lx[p[t] + u - t] * y[static_cast<std::size_t>(j + u) * R + r];
      }
      y[static_cast<std::size_t>(j + t) * R + r] = a;
    }
  }
}

/// Calls f(std::integral_constant<int, K>{}) with K = k, the length of a chain of columns (1 to 4:
/// the schedule stops a chain at 4), so that each kernel is unrolled for its length.
template <class F>
void with_chain_length(int k, F&& f) {
  switch (k) {
    case 1:
      f(std::integral_constant<int, 1>{});
      break;
    case 2:
      f(std::integral_constant<int, 2>{});
      break;
    case 3:
      f(std::integral_constant<int, 3>{});
      break;
    default:
      f(std::integral_constant<int, 4>{});
      break;
  }
}

/// Two threads meeting between pipeline steps (spin, then yield).
class PairBarrier {
 public:
  void wait() {
    const int phase = phase_.load(std::memory_order_acquire);
    if (count_.fetch_add(1, std::memory_order_acq_rel) == 1) {
      count_.store(0, std::memory_order_relaxed);
      phase_.store(phase + 1, std::memory_order_release);
      return;
    }
    for (int spins = 0; phase_.load(std::memory_order_acquire) == phase; ++spins) {
      if (spins > 2000) std::this_thread::yield();
    }
  }

 private:
  std::atomic<int> count_{0};
  std::atomic<int> phase_{0};
};

template <int R>
void forward(const cholmod_factor& l, const std::vector<std::pair<int, int>>& chains, double* y) {
  const auto* lp = static_cast<const int*>(l.p);
  const auto* li = static_cast<const int*>(l.i);
  const auto* lnz = static_cast<const int*>(l.nz);
  const auto* lx = static_cast<const double*>(l.x);
  for (const auto& [j, k] : chains) {
    with_chain_length(k, [&](auto K) { forward_chain<R, decltype(K)::value>(lp, li, lnz, lx, j, y); });
  }
}

template <int R>
void backward(const cholmod_factor& l, const std::vector<std::pair<int, int>>& chains, double* y) {
  const auto* lp = static_cast<const int*>(l.p);
  const auto* li = static_cast<const int*>(l.i);
  const auto* lnz = static_cast<const int*>(l.nz);
  const auto* lx = static_cast<const double*>(l.x);
  for (auto it = chains.rbegin(); it != chains.rend(); ++it) {
    with_chain_length(it->second, [&](auto K) {
      backward_chain<R, decltype(K)::value>(lp, li, lnz, lx, it->first, y);
    });
  }
}

/// L·D·Lᵀ·y = y for the simplicial factor. Parts 1 and 2 (disjoint subtrees) run on the two
/// threads; part 2's forward solve accumulates into its own vector (its contributions to the top
/// rows are added after both parts). The top is solved block by block in a pipeline: thread 0
/// solves a block's own columns and the rows just below, thread 1 the rows further down, with one
/// barrier per block. On one thread the same steps run in the same order, so the results are
/// bit-identical.
template <int R>
void ldl_solve(const cholmod_factor& l, const SolveSchedule& schedule, bool threaded, double* y,
               bool do_forward = true, bool do_backward = true) {
  const auto n = static_cast<std::size_t>(l.n);
  const auto* lp = static_cast<const int*>(l.p);
  const auto* li = static_cast<const int*>(l.i);
  const auto* lx = static_cast<const double*>(l.x);
  std::vector<double> second(n * R, 0.0);
  for (const auto& [j0, k] : schedule.chains[2]) {
    for (int j = j0; j < j0 + k; ++j) {
      for (int r = 0; r < R; ++r) second[static_cast<std::size_t>(j) * R + r] = y[j * R + r];
    }
  }
  const auto& top = schedule.top_chains;
  const auto& start = schedule.top_block_start;
  const int blocks = static_cast<int>(start.size()) - 1;
  std::size_t widest = 0;
  for (int b = 0; b < blocks; ++b) {
    widest = std::max(widest, static_cast<std::size_t>(start[static_cast<std::size_t>(b) + 1] -
                                                       start[static_cast<std::size_t>(b)]));
  }
  // Partial sums of the backward solve: [buffer (block parity)][thread][chain][4][R].
  std::vector<double> partial(2 * 2 * widest * 4 * R, 0.0);
  auto partial_at = [&](int b, int thread, int c) {
    const auto chain = static_cast<std::size_t>(c - start[static_cast<std::size_t>(b)]);
    return partial.data() +
           ((static_cast<std::size_t>(b & 1) * 2 + static_cast<std::size_t>(thread)) * widest +
            chain) *
               4 * R;
  };
  auto chains_of = [&](int b) {
    return std::pair(start[static_cast<std::size_t>(b)], start[static_cast<std::size_t>(b) + 1]);
  };
  // Forward, block b: A = own columns + rows inside the block (thread 0); B(me) = rows below.
  auto forward_a = [&](int b) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c0; c < c1; ++c) {
      const auto& t = top[static_cast<std::size_t>(c)];
with_chain_length(t.k, [&](auto K) { top_forward_chain<R, decltype(K)::value>(lp, li, lx, t.j, true, 0, t.lo, y); });
    }
  };
  auto forward_b = [&](int b, int me) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c0; c < c1; ++c) {
      const auto& t = top[static_cast<std::size_t>(c)];
      const int from = me == 0 ? t.lo : t.mid;
      const int to = me == 0 ? t.mid : lnz_of(l, t.j) - t.k;
with_chain_length(t.k, [&](auto K) { top_forward_chain<R, decltype(K)::value>(lp, li, lx, t.j, false, from, to, y); });
    }
  };
  // Backward, block b: B'(me) = partial sums over the rows below; A' = the block's columns.
  auto backward_b = [&](int b, int me) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c0; c < c1; ++c) {
      const auto& t = top[static_cast<std::size_t>(c)];
      const int from = me == 0 ? t.lo : t.mid;
      const int to = me == 0 ? t.mid : lnz_of(l, t.j) - t.k;
      double* s = partial_at(b, me, c);
with_chain_length(t.k, [&](auto K) { top_backward_partial<R, decltype(K)::value>(lp, li, lx, t.j, from, to, y, s); });
    }
  };
  auto backward_a = [&](int b) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c1 - 1; c >= c0; --c) {
      const auto& t = top[static_cast<std::size_t>(c)];
      const double* s0 = partial_at(b, 0, c);
      const double* s1 = partial_at(b, 1, c);
with_chain_length(t.k, [&](auto K) { top_backward_finish<R, decltype(K)::value>(lp, li, lx, t.j, t.lo, s0, s1, y); });
    }
  };
  auto combine = [&] {
    for (const auto& [j0, k] : schedule.chains[2]) {
      for (int j = j0; j < j0 + k; ++j) {
        for (int r = 0; r < R; ++r) y[j * R + r] = second[static_cast<std::size_t>(j) * R + r];
      }
    }
    for (const auto& [j0, k] : schedule.chains[0]) {
      for (int j = j0; j < j0 + k; ++j) {
        for (int r = 0; r < R; ++r) y[j * R + r] += second[static_cast<std::size_t>(j) * R + r];
      }
    }
  };
  if (!threaded) {
    if (do_forward) {
      forward<R>(l, schedule.chains[1], y);
      forward<R>(l, schedule.chains[2], second.data());
      combine();
      for (int b = 0; b < blocks; ++b) {
        forward_a(b);
        forward_b(b, 0);
        forward_b(b, 1);
      }
    }
    if (!do_backward) return;
    for (int b = blocks - 1; b >= 0; --b) {
      backward_b(b, 0);
      backward_b(b, 1);
      backward_a(b);
    }
    backward<R>(l, schedule.chains[1], y);
    backward<R>(l, schedule.chains[2], y);
    return;
  }
  PairBarrier barrier;
  auto worker = [&](int me) {
    if (do_forward) {
      forward<R>(l, schedule.chains[static_cast<std::size_t>(me) + 1], me == 0 ? y : second.data());
      barrier.wait();
      if (me == 0) combine();
      barrier.wait();
      // Forward pipeline: thread 0 does A(b), meets thread 1, then B(b, 0) and A(b + 1) while
      // thread 1 does B(b, 1) (its rows lie below the next block: m_b >= last column of b + 1).
      for (int b = 0; b < blocks; ++b) {
        if (me == 0) forward_a(b);
        barrier.wait();
        forward_b(b, me);
      }
      barrier.wait();
    }
    if (!do_backward) return;
    // Backward pipeline: B'(b, me), meet, then thread 0 finishes block b while thread 1 already
    // sums block b − 1's rows below m_{b−1} (all final: they lie below block b).
    for (int b = blocks - 1; b >= 0; --b) {
      backward_b(b, me);
      barrier.wait();
      if (me == 0) backward_a(b);
    }
    barrier.wait();
    backward<R>(l, schedule.chains[static_cast<std::size_t>(me) + 1], y);
  };
  std::thread helper;
  try {
    helper = std::thread(worker, 1);
  } catch (const std::system_error&) {
    ldl_solve<R>(l, schedule, false, y, do_forward, do_backward);
    return;
  }
  worker(0);
  helper.join();
}

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  std::vector<int> inverse_perm;  ///< row -> position in the factor's ordering
  SolveSchedule schedule;         ///< for the simplicial factor after modify()
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
    schedule = make_schedule(*factor, nnz);
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

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

void SparseCholesky::set_solve_threads(int threads) { impl_->solve_threads = threads; }

bool SparseCholesky::analyzed() const { return impl_->factor != nullptr; }

double SparseCholesky::factor_nonzeros() const {
  if (impl_->factor == nullptr) return 0.0;
  const cholmod_factor* l = impl_->factor;
  if (l->is_super) return static_cast<double>(l->xsize);
  return static_cast<double>(l->nzmax);
}

std::vector<int> SparseCholesky::fill_reducing_ordering(const SparseMatrix& upper) {
  Impl impl;
  impl.common.nmethods = 2;  // keep whichever of METIS and AMD fills less
  impl.common.method[0].ordering = CHOLMOD_METIS;
  impl.common.method[1].ordering = CHOLMOD_AMD;
  impl.common.postorder = 1;
  cholmod_sparse a = Impl::view(upper);
  a.xtype = CHOLMOD_PATTERN;
  a.x = nullptr;
  cholmod_factor* l = cholmod_analyze(&a, &impl.common);
  std::vector<int> perm;
  if (l != nullptr) {
    const int* p = static_cast<const int*>(l->Perm);
    perm.assign(p, p + l->n);
    cholmod_free_factor(&l, &impl.common);
  }
  return perm;
}

FactorReport SparseCholesky::analyze(const SparseMatrix& upper,
                                     const std::vector<int>* permutation) {
  if (!upper.isCompressed()) return {FactorStatus::failed, "matrix is not compressed"};
  if (impl_->factor != nullptr) cholmod_free_factor(&impl_->factor, &impl_->common);
  impl_->inverse_perm.clear();
  impl_->schedule = {};
  impl_->diagonal.clear();
  impl_->forward_valid = false;
  cholmod_sparse a = Impl::view(upper);
  if (permutation != nullptr) {
    const int saved_methods = impl_->common.nmethods;
    const int saved_ordering = impl_->common.method[0].ordering;
    impl_->common.nmethods = 1;
    impl_->common.method[0].ordering = CHOLMOD_GIVEN;
    impl_->factor =
        cholmod_analyze_p(&a, const_cast<int*>(permutation->data()), nullptr, 0, &impl_->common);
    impl_->common.nmethods = saved_methods;
    impl_->common.method[0].ordering = saved_ordering;
  } else {
    impl_->factor = cholmod_analyze(&a, &impl_->common);
  }
  if (impl_->factor == nullptr || impl_->common.status < CHOLMOD_OK) {
    return {FactorStatus::failed,
            "cholmod_analyze failed (status " + std::to_string(impl_->common.status) + ")"};
  }
  return {};
}

FactorReport SparseCholesky::factorize(const SparseMatrix& upper) {
  if (impl_->factor == nullptr) {
    if (auto r = analyze(upper); !r.ok()) return r;
  }
  cholmod_sparse a = Impl::view(upper);
  impl_->schedule = {};
  impl_->diagonal.clear();
  impl_->forward_valid = false;
  const int ok = cholmod_factorize(&a, impl_->factor, &impl_->common);
  if (impl_->common.status == CHOLMOD_NOT_POSDEF) {
    return {FactorStatus::not_positive_definite,
            "stiffness is not positive definite (pivot " + std::to_string(impl_->factor->minor) +
                "): a part of the model is unconstrained or has come loose"};
  }
  if (!ok || impl_->common.status < CHOLMOD_OK) {
    return {FactorStatus::failed,
            "cholmod_factorize failed (status " + std::to_string(impl_->common.status) + ")"};
  }
  const double rcond = cholmod_rcond(impl_->factor, &impl_->common);
  if (!(rcond > 1e-14)) {
    return {FactorStatus::singular,
            "stiffness is numerically singular (rcond " + std::to_string(rcond) +
                "): a part of the model is unconstrained or has come loose"};
  }
  return {};
}

FactorReport SparseCholesky::modify(const std::vector<Column>& columns, bool add) {
  if (columns.empty()) return {};
  impl_->forward_valid = false;  // CHOLMOD's updown does not update our forward solve
  cholmod_factor* l = impl_->factor;
  if (l == nullptr) return {FactorStatus::failed, "modify before factorize"};
  auto& common = impl_->common;
  if (l->is_super || l->is_ll) {
    if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, l, &common)) {
      return {FactorStatus::failed, "cholmod_change_factor failed"};
    }
  }
  impl_->ensure_schedule();
  const auto n = static_cast<std::size_t>(l->n);
  if (impl_->inverse_perm.size() != n) {
    impl_->inverse_perm.assign(n, 0);
    const int* perm = static_cast<const int*>(l->Perm);
    for (std::size_t k = 0; k < n; ++k)
      impl_->inverse_perm[static_cast<std::size_t>(perm[k])] = static_cast<int>(k);
  }
  std::size_t nnz = 0;
  for (const auto& c : columns) nnz += c.rows.size();
  cholmod_sparse* c =
      cholmod_allocate_sparse(n, columns.size(), nnz, 1, 1, 0, CHOLMOD_REAL, &common);
  if (c == nullptr) return {FactorStatus::failed, "cholmod_allocate_sparse failed"};
  auto* cp = static_cast<int*>(c->p);
  auto* ci = static_cast<int*>(c->i);
  auto* cx = static_cast<double*>(c->x);
  std::vector<std::pair<int, double>> entries;
  std::vector<int> first_rows;
  first_rows.reserve(columns.size());
  std::size_t pos = 0;
  for (std::size_t col = 0; col < columns.size(); ++col) {
    cp[col] = static_cast<int>(pos);
    entries.clear();
    for (std::size_t e = 0; e < columns[col].rows.size(); ++e) {
      entries.emplace_back(impl_->inverse_perm[static_cast<std::size_t>(columns[col].rows[e])],
                           columns[col].values[e]);
    }
    std::sort(entries.begin(), entries.end());
    if (!entries.empty()) first_rows.push_back(entries.front().first);
    for (const auto& [row, value] : entries) {
      ci[pos] = row;
      cx[pos] = value;
      ++pos;
    }
  }
  cp[columns.size()] = static_cast<int>(pos);
  const int ok = cholmod_updown(add ? 1 : 0, c, l, &common);
  cholmod_free_sparse(&c, &common);
  if (!ok || common.status < CHOLMOD_OK) {
    return {FactorStatus::failed,
            "cholmod_updown failed (status " + std::to_string(common.status) + ")"};
  }
  // The update changed the columns on the elimination-tree paths from each column's first row
  // to the root: refresh D there (all of it if the update added fill), then check the whole D.
  auto& impl = *impl_;
  const auto* lp = static_cast<const int*>(l->p);
  const auto* lx = static_cast<const double*>(l->x);
  if (impl.pattern_nnz() != impl.schedule.pattern_nnz) {
    impl.ensure_schedule();
  } else {
    if (++impl.stamp == 0) {
      std::fill(impl.mark.begin(), impl.mark.end(), 0);
      impl.stamp = 1;
    }
    for (int j : first_rows) {
      while (j >= 0 && impl.mark[static_cast<std::size_t>(j)] != impl.stamp) {
        impl.mark[static_cast<std::size_t>(j)] = impl.stamp;
        impl.diagonal[static_cast<std::size_t>(j)] = lx[lp[j]];
        j = impl.schedule.parent[static_cast<std::size_t>(j)];
      }
    }
  }
  if (!add) {
    // LDLᵀ: D is the first entry of every column.
    if (auto r = check_after_downdate(impl.diagonal); !r.ok()) return r;
  }
  return {};
}

namespace {

constexpr int kGroup = 16;  ///< ranks per sweep of the fused update

struct RankScalars {
  int rank;
  double p, beta;
};

/// Entries q in [from, to) of column j: w_i −= p·l_ij, l_ij += β·w_i for each active rank; with
/// R tracked right-hand sides also δ_i += l_ij·y_j − l̄_ij·ȳ_j (the forward solve's change).
template <int R>
void apply_column(const int* li, double* lx, double* w, int from, int to, const RankScalars* active,
                  int count, double* delta, const double* y_old, const double* y_new) {
  for (int q = from; q < to; ++q) {
    const int i = li[q];
    double* wi = w + static_cast<std::size_t>(i) * kGroup;
    const double l_old = lx[q];
    double l = l_old;
    for (int a = 0; a < count; ++a) {
      double& x = wi[active[a].rank];
      x -= active[a].p * l;
      l += active[a].beta * x;
    }
    lx[q] = l;
    if constexpr (R > 0) {
      double* di = delta + static_cast<std::size_t>(i) * 3;
      for (int r = 0; r < R; ++r) {
        di[r] += l_old * y_old[r];
        di[r] -= l * y_new[r];
      }
    }
  }
}

inline void apply_column(int tracked, const int* li, double* lx, double* w, int from, int to,
                         const RankScalars* active, int count, double* delta, const double* y_old,
                         const double* y_new) {
  switch (tracked) {
    case 0:
      apply_column<0>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    case 1:
      apply_column<1>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    case 2:
      apply_column<2>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
    default:
      apply_column<3>(li, lx, w, from, to, active, count, delta, y_old, y_new);
      break;
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

}  // namespace

FactorReport SparseCholesky::modify_fused(const std::vector<Column>& added,
                                          const std::vector<Column>& removed) {
  if (added.empty() && removed.empty()) return {};
  cholmod_factor* l = impl_->factor;
  if (l == nullptr) return {FactorStatus::failed, "modify before factorize"};
  auto& impl = *impl_;
  auto& common = impl.common;
  if (l->is_super || l->is_ll) {
    if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, l, &common)) {
      return {FactorStatus::failed, "cholmod_change_factor failed"};
    }
  }
  impl.ensure_schedule();
  const auto n = static_cast<std::size_t>(l->n);
  if (impl.inverse_perm.size() != n) {
    impl.inverse_perm.assign(n, 0);
    const int* perm = static_cast<const int*>(l->Perm);
    for (std::size_t k = 0; k < n; ++k)
      impl.inverse_perm[static_cast<std::size_t>(perm[k])] = static_cast<int>(k);
  }
  const auto* lp = static_cast<const int*>(l->p);
  const auto* li = static_cast<const int*>(l->i);
  const auto* lnz = static_cast<const int*>(l->nz);
  auto* lx = static_cast<double*>(l->x);
  // Permuted, sorted columns with their signs, updates first. The fused sweep needs the rows of
  // each column below its first one to be in that column of L (no fill; true for the bond
  // vectors, whose pairs are all in the matrix's pattern); otherwise CHOLMOD does it.
  struct Rank {
    std::vector<std::pair<int, double>> entries;
    double sign;
  };
  std::vector<Rank> ranks;
  bool fits = impl.schedule.sorted && impl.schedule.nested;
  for (int pass = 0; pass < 2 && fits; ++pass) {
    for (const auto& c : pass == 0 ? added : removed) {
      Rank rank{{}, pass == 0 ? 1.0 : -1.0};
      for (std::size_t e = 0; e < c.rows.size(); ++e) {
        rank.entries.emplace_back(impl.inverse_perm[static_cast<std::size_t>(c.rows[e])],
                                  c.values[e]);
      }
      std::sort(rank.entries.begin(), rank.entries.end());
      if (rank.entries.empty()) continue;
      const int first = rank.entries.front().first;
      const int* rows = li + lp[first] + 1;
      const int* end = li + lp[first] + lnz[first];
      for (std::size_t e = 1; e < rank.entries.size() && fits; ++e) {
        fits = rank.entries[e].first != rank.entries[e - 1].first &&
               std::binary_search(rows, end, rank.entries[e].first);
      }
      ranks.push_back(std::move(rank));
    }
  }
  if (!fits) {
    FactorReport r = modify(added, true);
    if (r.ok()) r = modify(removed, false);
    return r;
  }
  if (impl.w.size() != n * kGroup) impl.w.assign(n * kGroup, 0.0);
  double* w = impl.w.data();
  const int tracked = impl.forward_valid ? static_cast<int>(impl.tracked_rhs.cols()) : 0;
  if (impl.delta.size() != n * 3) impl.delta.assign(n * 3, 0.0);
  double* delta = impl.delta.data();
  double* fy = impl.forward_y.data();
  if (++impl.stamp == 0) {
    std::fill(impl.mark.begin(), impl.mark.end(), 0);
    impl.stamp = 1;
  }
  const int all_stamp = impl.stamp;  // columns touched by any group, for the D refresh
  std::vector<int> touched;
  std::vector<int> path;
  std::vector<int> group_mark(n, 0);
  std::vector<RankScalars> scalars;
  std::vector<int> counts;
  std::vector<double> pivots;
  std::vector<std::uint8_t> moves;
  for (std::size_t g0 = 0; g0 < ranks.size(); g0 += kGroup) {
    const int group = static_cast<int>(std::min<std::size_t>(kGroup, ranks.size() - g0));
    double alpha[kGroup];
    path.clear();
    const int gstamp = static_cast<int>(g0 / kGroup) + 1;
    for (int r = 0; r < group; ++r) {
      const Rank& rank = ranks[g0 + static_cast<std::size_t>(r)];
      alpha[r] = rank.sign;
      for (const auto& [row, value] : rank.entries) {
        w[static_cast<std::size_t>(row) * kGroup + static_cast<std::size_t>(r)] = value;
      }
      for (int j = rank.entries.front().first;
           j >= 0 && group_mark[static_cast<std::size_t>(j)] != gstamp;
           j = impl.schedule.parent[static_cast<std::size_t>(j)]) {
        group_mark[static_cast<std::size_t>(j)] = gstamp;
        path.push_back(j);
        if (impl.mark[static_cast<std::size_t>(j)] != all_stamp) {
          impl.mark[static_cast<std::size_t>(j)] = all_stamp;
          touched.push_back(j);
        }
      }
    }
    std::sort(path.begin(), path.end());
    const int columns = static_cast<int>(path.size());
    double entries = 0.0;
    for (int j : path) entries += lnz[j];
    const bool threaded =
        impl.solve_threads == 2 ||
        (impl.solve_threads == 0 && entries > 200'000 && std::thread::hardware_concurrency() > 1);
    if (!threaded) {
      RankScalars active[kGroup];
      double y_old[3], y_new[3];
      for (int j : path) {
        const int count = column_scalars(lp, lx, w, j, group, alpha, active);
        const bool moved = forward_pivot(tracked, j, fy, delta, y_old, y_new);
        if (count > 0 || moved) {
          apply_column(tracked, li, lx, w, lp[j] + 1, lp[j] + lnz[j], active, count, delta, y_old,
                       y_new);
        }
      }
      continue;
    }
    // Two threads: rows below the split row S belong to thread 0, the others to thread 1. For the
    // path's columns below S, thread 0 computes the scalars (it owns w_j) and publishes them;
    // thread 1 follows with its rows. Columns from S on are thread 1's alone. Every entry gets
    // the same operations as on one thread. S balances the entries (rows assumed spread evenly
    // between a column's first and last row).
    auto below = [&](int split) {
      double count = 0.0;
      for (int j : path) {
        if (j >= split) break;
        const int len = lnz[j] - 1;
        if (len <= 0) continue;
        const int first = li[lp[j] + 1];
        const int last = li[lp[j] + lnz[j] - 1];
        const double f = last > first ? static_cast<double>(split - first) / (last - first + 1)
                                      : (split > first ? 1.0 : 0.0);
        count += len * std::clamp(f, 0.0, 1.0);
      }
      return count;
    };
    int lo_split = path.front(), hi_split = static_cast<int>(n);
    while (hi_split - lo_split > 1) {
      const int mid = lo_split + (hi_split - lo_split) / 2;
      (below(mid) < 0.5 * entries ? lo_split : hi_split) = mid;
    }
    const int split = hi_split;
    const int k0 =
        static_cast<int>(std::lower_bound(path.begin(), path.end(), split) - path.begin());
    scalars.resize(static_cast<std::size_t>(columns) * kGroup);
    counts.assign(static_cast<std::size_t>(columns), 0);
    pivots.resize(static_cast<std::size_t>(columns) * 6);  // y_old[3], y_new[3] per column
    moves.assign(static_cast<std::size_t>(columns), 0);
    std::atomic<int> ready{0};
    auto thread0 = [&] {
      for (int k = 0; k < k0; ++k) {
        const int j = path[static_cast<std::size_t>(k)];
        RankScalars* active = scalars.data() + static_cast<std::size_t>(k) * kGroup;
        const int count = column_scalars(lp, lx, w, j, group, alpha, active);
        double* piv = pivots.data() + static_cast<std::size_t>(k) * 6;
        const bool moved = forward_pivot(tracked, j, fy, delta, piv, piv + 3);
        counts[static_cast<std::size_t>(k)] = count;
        moves[static_cast<std::size_t>(k)] = moved ? 1 : 0;
        ready.store(k + 1, std::memory_order_release);
        if (count == 0 && !moved) continue;
        const int* rows = li + lp[j] + 1;
        const int end = lp[j] + lnz[j];
        const int cut = static_cast<int>(std::lower_bound(rows, li + end, split) - li);
        apply_column(tracked, li, lx, w, lp[j] + 1, cut, active, count, delta, piv, piv + 3);
      }
    };
    auto thread1 = [&] {
      for (int k = 0; k < columns; ++k) {
        const int j = path[static_cast<std::size_t>(k)];
        const RankScalars* active;
        int count;
        int from;
        bool moved;
        const double* piv;
        RankScalars own[kGroup];
        double own_pivot[6];
        if (k < k0) {
          for (int spins = 0; ready.load(std::memory_order_acquire) <= k; ++spins) {
            if (spins > 2000) std::this_thread::yield();
          }
          active = scalars.data() + static_cast<std::size_t>(k) * kGroup;
          count = counts[static_cast<std::size_t>(k)];
          moved = moves[static_cast<std::size_t>(k)] != 0;
          piv = pivots.data() + static_cast<std::size_t>(k) * 6;
          const int* rows = li + lp[j] + 1;
          from = static_cast<int>(std::lower_bound(rows, li + lp[j] + lnz[j], split) - li);
        } else {
          if (k == k0) {  // thread 0 is done with α (it published column k0 − 1 last)
            for (int spins = 0; ready.load(std::memory_order_acquire) < k0; ++spins) {
              if (spins > 2000) std::this_thread::yield();
            }
          }
          count = column_scalars(lp, lx, w, j, group, alpha, own);
          moved = forward_pivot(tracked, j, fy, delta, own_pivot, own_pivot + 3);
          piv = own_pivot;
          active = own;
          from = lp[j] + 1;
        }
        if (count > 0 || moved) {
          apply_column(tracked, li, lx, w, from, lp[j] + lnz[j], active, count, delta, piv,
                       piv + 3);
        }
      }
    };
    std::thread helper;
    try {
      helper = std::thread(thread1);
    } catch (const std::system_error&) {
      thread0();
      thread1();
      continue;
    }
    thread0();
    helper.join();
  }
  for (int j : touched) {
    impl.diagonal[static_cast<std::size_t>(j)] = lx[lp[j]];
  }
  if (!removed.empty()) {
    if (auto r = check_after_downdate(impl.diagonal); !r.ok()) return r;
  }
  return {};
}

void SparseCholesky::solve(Eigen::MatrixXd& rhs) const {
  const cholmod_factor* l = impl_->factor;
  if (l == nullptr) throw std::logic_error("SparseCholesky::solve before factorize");
  const auto cols = rhs.cols();
  if (l->is_super || l->is_ll || l->xtype != CHOLMOD_REAL || cols < 1 || cols > 3) {
    solve_with_cholmod(rhs);
    return;
  }
  // Simplicial LDLᵀ (after modify): our own solve with the two subtree parts on two threads.
  const auto n = static_cast<std::size_t>(l->n);
  const auto* lnz = static_cast<const int*>(l->nz);
  std::int64_t nnz = 0;
  for (std::size_t j = 0; j < n; ++j) nnz += lnz[j];
  auto& impl = *impl_;
  if (impl.schedule.pattern_nnz != nnz) impl.ensure_schedule();
  const int* perm = static_cast<const int*>(l->Perm);
  const auto r = static_cast<std::size_t>(cols);
  const bool threaded = impl.schedule.balanced &&
                        (impl.solve_threads == 2 || (impl.solve_threads == 0 && nnz > 2'000'000 &&
                                                     std::thread::hardware_concurrency() > 1));
  auto run = [&](bool do_forward, bool do_backward) {
    double* y = impl.work.data();
    if (r == 1) ldl_solve<1>(*l, impl.schedule, threaded, y, do_forward, do_backward);
    if (r == 2) ldl_solve<2>(*l, impl.schedule, threaded, y, do_forward, do_backward);
    if (r == 3) ldl_solve<3>(*l, impl.schedule, threaded, y, do_forward, do_backward);
  };
  if (impl.forward_valid && impl.tracked_rhs.rows() == rhs.rows() &&
      impl.tracked_rhs.cols() == cols && impl.tracked_rhs == rhs) {
    impl.work = impl.forward_y;  // the same b: the forward solve is up to date
  } else {
    impl.work.resize(n * r);
    for (std::size_t k = 0; k < n; ++k) {
      for (std::size_t c = 0; c < r; ++c) {
        impl.work[k * r + c] = rhs(perm[k], static_cast<Eigen::Index>(c));
      }
    }
    run(true, false);
    impl.forward_y = impl.work;
    impl.tracked_rhs = rhs;
    impl.forward_valid = true;
  }
  run(false, true);
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t c = 0; c < r; ++c) {
      rhs(perm[k], static_cast<Eigen::Index>(c)) = impl.work[k * r + c];
    }
  }
}

void SparseCholesky::solve_with_cholmod(Eigen::MatrixXd& rhs) const {
  if (impl_->factor == nullptr) throw std::logic_error("SparseCholesky::solve before factorize");
  cholmod_dense b{};
  b.nrow = static_cast<size_t>(rhs.rows());
  b.ncol = static_cast<size_t>(rhs.cols());
  b.nzmax = b.nrow * b.ncol;
  b.d = b.nrow;
  b.x = rhs.data();
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  auto& common = const_cast<cholmod_common&>(impl_->common);
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, impl_->factor, &b, &common);
  if (x == nullptr) throw std::runtime_error("cholmod_solve failed");
  std::memcpy(rhs.data(), x->x, sizeof(double) * b.nzmax);
  cholmod_free_dense(&x, &common);
}

}  // namespace peritwin
