#include "solver/linalg/ldlt_solve.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <system_error>
#include <thread>

namespace peritwin::linalg::ldlt {

FactorView view_of(const cholmod_factor& l) {
  FactorView v;
  v.n = static_cast<int>(l.n);
  v.lp = static_cast<const int*>(l.p);
  v.ri = v.lp;
  v.lnz = static_cast<const int*>(l.nz);
  v.rows = static_cast<const int*>(l.i);
  v.lx = static_cast<double*>(l.x);
  v.perm = static_cast<const int*>(l.Perm);
  return v;
}

SolveSchedule make_schedule(const FactorView& l, std::int64_t pattern_nnz) {
  SolveSchedule schedule;
  schedule.pattern_nnz = pattern_nnz;
  const int n = l.n;
  const int* lnz = l.lnz;
  auto col = [&](int j) { return l.rows_of(j); };
  // Elimination tree: the parent of j is the smallest row below the diagonal of column j.
  std::vector<int> parent(static_cast<std::size_t>(n), -1);
  std::vector<double> weight(static_cast<std::size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    int p = n;
    const int* cj = col(j);
    for (int e = 1; e < lnz[j]; ++e) p = std::min(p, cj[e]);
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
    const int* a = col(j);
    const int* b = col(j + t);
    if (lnz[j + t] != lnz[j] - t || lnz[j] <= t || a[t] != j + t) return false;
    for (int q = 0; q < lnz[j + t]; ++q) {
      if (b[q] != a[t + q]) return false;
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
    const int* cj = col(j);
    for (int e = 1; e < lnz[j]; ++e) schedule.sorted = schedule.sorted && cj[e] > cj[e - 1];
  }
  schedule.nested = schedule.sorted;
  for (int j = 0; j < n && schedule.nested; ++j) {
    const int p = parent[static_cast<std::size_t>(j)];
    if (p < 0) continue;
    // Rows of j after p (sorted, p is the first below the diagonal) must be among p's rows.
    const int* cp = col(p);
    const int* cj = col(j);
    int q = 1;
    for (int e = 2; e < lnz[j] && schedule.nested; ++e) {
      while (q < lnz[p] && cp[q] < cj[e]) ++q;
      schedule.nested = q < lnz[p] && cp[q] == cj[e];
    }
  }
  // Top blocks. Rows must be sorted in the top's columns (they are in CHOLMOD's simplicial
  // factors); otherwise one block with everything inside it (thread 0 alone).
  bool sorted = true;
  for (const auto& [j0, k] : schedule.chains[0]) {
    const int* cj = col(j0);
    for (int e = 1; e < lnz[j0]; ++e) sorted = sorted && cj[e] > cj[e - 1];
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
      const int* rows = col(t.j) + t.k;
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
      const int* rows = col(t.j) + t.k;
      const int len = lnz[t.j] - t.k;
      t.mid = sorted ? static_cast<int>(std::upper_bound(rows, rows + len, m) - rows) : len;
      if (!sorted) t.lo = len;
    }
  }
  schedule.parent = std::move(parent);
  return schedule;
}

namespace {

/// The top's forward solve, chain by chain: solve the chain's own columns (in_chain) and scatter
/// rows [from, to) of its shared rows below.
template <int R, int K>
void top_forward_chain(const int* lp, const int* rows_j, const double* lx, int j, bool in_chain,
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
  const int* rows = rows_j + K;
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
void forward_chain(const FactorView& l, int j, double* y) {
  top_forward_chain<R, K>(l.lp, l.rows_of(j), l.lx, j, true, 0, l.lnz[j] - K, y);
}

/// Backward solve D·Lᵀ·x = y with a chain of K columns; x overwrites y.
template <int R, int K>
void backward_chain(const FactorView& f, int j, double* y) {
  const int* lp = f.lp;
  const int* lnz = f.lnz;
  const double* lx = f.lx;
  const int* rows_j = f.rows_of(j);
  double v[K][R];
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  for (int t = 0; t < K; ++t) {
    for (int r = 0; r < R; ++r) v[t][r] = y[static_cast<std::size_t>(j + t) * R + r] / lx[p[t]];
  }
  const int len = lnz[j] - K;
  const int* rows = rows_j + K;
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

inline int lnz_of(const FactorView& l, int j) { return l.lnz[j]; }

/// The top's backward solve: partial sums Σ L(i, j+t)·x_i over rows [from, to) of the chain's
/// shared rows into s[K][R].
template <int R, int K>
void top_backward_partial(const int* lp, const int* rows_j, const double* lx, int j, int from,
                          int to, const double* y, double* s) {
  int p[K];
  for (int t = 0; t < K; ++t) p[t] = lp[j + t];
  double v[K][R] = {};
  const int* rows = rows_j + K;
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
void top_backward_finish(const int* lp, const int* rows_j, const double* lx, int j, int lo,
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
  const int* rows = rows_j + K;
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
void forward(const FactorView& l, const std::vector<std::pair<int, int>>& chains, double* y) {
  // chain.first, not a structured binding: clang 14 (the fuzz and sanitizer builds) cannot
  // capture one in a lambda.
  for (const auto& chain : chains) {
    with_chain_length(chain.second,
                      [&](auto K) { forward_chain<R, decltype(K)::value>(l, chain.first, y); });
  }
}

template <int R>
void backward(const FactorView& l, const std::vector<std::pair<int, int>>& chains, double* y) {
  for (auto it = chains.rbegin(); it != chains.rend(); ++it) {
    with_chain_length(it->second,
                      [&](auto K) { backward_chain<R, decltype(K)::value>(l, it->first, y); });
  }
}

/// L·D·Lᵀ·y = y for the simplicial factor. Parts 1 and 2 (disjoint subtrees) run on the two
/// threads; part 2's forward solve accumulates into its own vector (its contributions to the top
/// rows are added after both parts). The top is solved block by block in a pipeline: thread 0
/// solves a block's own columns and the rows just below, thread 1 the rows further down, with one
/// barrier per block. On one thread the same steps run in the same order, so the results are
/// bit-identical.
template <int R>
void ldl_solve(const FactorView& l, const SolveSchedule& schedule, bool threaded, double* y,
               bool do_forward = true, bool do_backward = true) {
  const auto n = static_cast<std::size_t>(l.n);
  const int* lp = l.lp;
  const double* lx = l.lx;
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
      with_chain_length(t.k, [&](auto K) {
        top_forward_chain<R, decltype(K)::value>(lp, l.rows_of(t.j), lx, t.j, true, 0, t.lo, y);
      });
    }
  };
  auto forward_b = [&](int b, int me) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c0; c < c1; ++c) {
      const auto& t = top[static_cast<std::size_t>(c)];
      const int from = me == 0 ? t.lo : t.mid;
      const int to = me == 0 ? t.mid : lnz_of(l, t.j) - t.k;
      with_chain_length(t.k, [&](auto K) {
        top_forward_chain<R, decltype(K)::value>(lp, l.rows_of(t.j), lx, t.j, false, from, to, y);
      });
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
      with_chain_length(t.k, [&](auto K) {
        top_backward_partial<R, decltype(K)::value>(lp, l.rows_of(t.j), lx, t.j, from, to, y, s);
      });
    }
  };
  auto backward_a = [&](int b) {
    const auto [c0, c1] = chains_of(b);
    for (int c = c1 - 1; c >= c0; --c) {
      const auto& t = top[static_cast<std::size_t>(c)];
      const double* s0 = partial_at(b, 0, c);
      const double* s1 = partial_at(b, 1, c);
      with_chain_length(t.k, [&](auto K) {
        top_backward_finish<R, decltype(K)::value>(lp, l.rows_of(t.j), lx, t.j, t.lo, s0, s1, y);
      });
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

void solve(int rhs_columns, const FactorView& l, const SolveSchedule& schedule, bool threaded,
           double* y, bool do_forward, bool do_backward) {
  switch (rhs_columns) {
    case 1:
      ldl_solve<1>(l, schedule, threaded, y, do_forward, do_backward);
      break;
    case 2:
      ldl_solve<2>(l, schedule, threaded, y, do_forward, do_backward);
      break;
    case 3:
      ldl_solve<3>(l, schedule, threaded, y, do_forward, do_backward);
      break;
    default:
      throw std::invalid_argument("ldlt::solve: 1 to 3 right-hand sides");
  }
}

}  // namespace peritwin::linalg::ldlt
