#include "solver/linalg/sparse_cholesky.h"

#include <cholmod.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "solver/linalg/cholesky_impl.h"

namespace peritwin::linalg {

/// After a downdate: D of LDLᵀ must stay positive, and rcond as cholmod_rcond computes it,
/// min(D) / max(D), above 1e-14 — else the model has come loose.
core::Status check_after_downdate(const std::vector<double>& diagonal, int& first_bad) {
  first_bad = -1;
  double d_min = diagonal.empty() ? 0.0 : diagonal.front();
  double d_max = d_min;
  bool positive = true;
  for (const double d : diagonal) {
    positive = positive && d > 0.0;
    d_min = std::min(d_min, d);
    d_max = std::max(d_max, d);
  }
  const double rcond = d_min / d_max;
  if (positive && rcond > 1e-14) return {};
  // The first bad pivot in the factor's order: the columns before it were updated exactly (up
  // to round-off), those after it on its path took its noise.
  for (std::size_t j = 0; j < diagonal.size() && first_bad < 0; ++j) {
    if (!(diagonal[j] > 1e-14 * d_max)) first_bad = static_cast<int>(j);
  }
  if (!positive) {
    return core::failure(
        "stiffness is not positive definite after breaking bonds: a part of the model has "
        "come loose");
  }
  return core::failure("stiffness is numerically singular (rcond " + std::to_string(rcond) +
                       "): a part of the model has come loose");
}

core::Status SparseCholesky::Impl::to_packed_ldlt() {
  cholmod_factor* l = factor;
  if (l == nullptr || !l->is_super || !l->is_ll || l->xtype != CHOLMOD_REAL || l->x == nullptr) {
    return core::failure("packed LDLt: the factor is not a supernodal numeric LLt factor");
  }
  const auto n = static_cast<std::size_t>(l->n);
  const auto nsuper = static_cast<std::size_t>(l->nsuper);
  const auto* super = static_cast<const int*>(l->super);
  const auto* lpi = static_cast<const int*>(l->pi);
  const auto* lpx = static_cast<const int*>(l->px);
  auto* lx = static_cast<double*>(l->x);
  packed.col_x.assign(n + 1, 0);
  packed.col_rows.assign(n, 0);
  packed.col_nz.assign(n, 0);
  // CHOLMOD's ll_super_to_simplicial_numeric (to_packed, LDLᵀ), values only: column j of
  // supernode s holds rows psi + jj .. psend − 1 of Ls; d_j = l_jj², then l_ij / l_jj, written
  // at p <= the entry's supernodal position q, so in place (q only grows).
  std::size_t p = 0;
  for (std::size_t s = 0; s < nsuper; ++s) {
    const int k1 = super[s], k2 = super[s + 1];
    const int psi = lpi[s], nsrow = lpi[s + 1] - psi;
    const std::size_t psx = static_cast<std::size_t>(lpx[s]);
    for (int jj = 0; jj < k2 - k1; ++jj) {
      const auto j = static_cast<std::size_t>(k1 + jj);
      packed.col_x[j] = static_cast<int>(p);
      packed.col_rows[j] = psi + jj;
      packed.col_nz[j] = nsrow - jj;
      const std::size_t column =
          psx + static_cast<std::size_t>(jj) * static_cast<std::size_t>(nsrow);
      double ljj = lx[column + static_cast<std::size_t>(jj)];
      if (ljj <= 0.0) {  // not positive definite (factorize reports it first): do not divide
        lx[p] = ljj;
        ljj = 1.0;
      } else {
        lx[p] = ljj * ljj;
      }
      ++p;
      for (int ii = jj + 1; ii < nsrow; ++ii)
        lx[p++] = lx[column + static_cast<std::size_t>(ii)] / ljj;
    }
  }
  packed.col_x[n] = static_cast<int>(p);
  // Give the tail (the diagonal blocks' upper triangles) back: cholmod_realloc cannot fail when
  // it shrinks.
  std::size_t xsize = l->xsize;
  void* x = cholmod_realloc(std::max<std::size_t>(p, 1), sizeof(double), l->x, &xsize, &common);
  if (x == nullptr) return core::failure("packed LDLt: cholmod_realloc failed");
  packed.x = static_cast<double*>(x);
  packed.xsize = xsize;
  // The factor keeps its supernodal analysis as a symbolic factor (CHOLMOD's
  // ll_super_to_super_symbolic, without freeing the values, which are now packed.x).
  l->x = nullptr;
  l->xtype = CHOLMOD_PATTERN;
  l->minor = l->n;
  l->is_ll = 1;
  return {};
}

core::Status SparseCholesky::Impl::to_cholmod_simplicial() {
  if (!packed_active()) return {};
  cholmod_factor* l = factor;
  const auto n = static_cast<std::size_t>(l->n);
  // The rows per column, before CHOLMOD frees the supernodal pattern.
  const auto* ls = static_cast<const int*>(l->s);
  const std::size_t lnz = static_cast<std::size_t>(packed.col_x[n]);
  auto* li = static_cast<int*>(cholmod_malloc(std::max<std::size_t>(lnz, 1), sizeof(int), &common));
  if (li == nullptr) return core::failure("CHOLMOD simplicial factor: out of memory");
  for (std::size_t j = 0; j < n; ++j) {
    std::memcpy(li + packed.col_x[j], ls + packed.col_rows[j],
                sizeof(int) * static_cast<std::size_t>(packed.col_nz[j]));
  }
  // Supernodal symbolic -> simplicial symbolic (Perm and ColCount only), then the simplicial
  // numeric arrays around the packed values: Lp = col_x, Li = the rows above, Lx = packed.x.
  if (!cholmod_change_factor(CHOLMOD_PATTERN, 0, 0, 1, 1, l, &common)) {
    cholmod_free(std::max<std::size_t>(lnz, 1), sizeof(int), li, &common);
    return core::failure("cholmod_change_factor failed");
  }
  auto* lp = static_cast<int*>(cholmod_malloc(n + 1, sizeof(int), &common));
  auto* nz = static_cast<int*>(cholmod_malloc(n, sizeof(int), &common));
  auto* prev = static_cast<int*>(cholmod_malloc(n + 2, sizeof(int), &common));
  auto* next = static_cast<int*>(cholmod_malloc(n + 2, sizeof(int), &common));
  if (lp == nullptr || nz == nullptr || prev == nullptr || next == nullptr) {
    cholmod_free(n + 1, sizeof(int), lp, &common);
    cholmod_free(n, sizeof(int), nz, &common);
    cholmod_free(n + 2, sizeof(int), prev, &common);
    cholmod_free(n + 2, sizeof(int), next, &common);
    cholmod_free(std::max<std::size_t>(lnz, 1), sizeof(int), li, &common);
    return core::failure("CHOLMOD simplicial factor: out of memory");
  }
  std::memcpy(lp, packed.col_x.data(), sizeof(int) * (n + 1));
  std::memcpy(nz, packed.col_nz.data(), sizeof(int) * n);
  // Columns in natural order (CHOLMOD's natural_list): head n + 1, tail n.
  const int ni = static_cast<int>(n);
  for (int j = 0; j < ni; ++j) {
    next[j] = j + 1;
    prev[j] = j - 1;
  }
  next[n + 1] = 0;
  prev[n + 1] = -1;
  next[n] = -1;
  prev[n] = ni - 1;
  prev[0] = ni + 1;
  l->p = lp;
  l->i = li;
  l->x = packed.x;
  l->nz = nz;
  l->prev = prev;
  l->next = next;
  l->nzmax = packed.xsize;
  l->is_monotonic = 1;
  l->is_ll = 0;
  l->xtype = CHOLMOD_REAL;
  l->dtype = CHOLMOD_DOUBLE;
  l->minor = l->n;
  packed = {};  // the values belong to the CHOLMOD factor now
  return {};
}

core::Status SparseCholesky::Impl::to_ldlt(bool packed_form) {
  if (factor == nullptr) return core::failure("modify before factorize");
  if (packed_active()) return packed_form ? core::Status{} : to_cholmod_simplicial();
  if (factor->xtype != CHOLMOD_REAL) return core::failure("modify before factorize");
  if (!factor->is_super && !factor->is_ll) return {};
  if (packed_form && factor->is_super) return to_packed_ldlt();
  if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, factor, &common)) {
    return core::failure("cholmod_change_factor failed");
  }
  return {};
}

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;

SparseCholesky::SparseCholesky(const SparseCholesky& other) : impl_(std::make_unique<Impl>()) {
  const Impl& o = *other.impl_;
  if (o.factor != nullptr) {
    impl_->factor = cholmod_copy_factor(o.factor, &impl_->common);
    if (impl_->factor == nullptr) throw std::bad_alloc();
  }
  if (o.packed_active()) {  // the LDLᵀ values kept in the supernodal storage (PackedLdlt)
    auto* x = static_cast<double*>(cholmod_malloc(o.packed.xsize, sizeof(double), &impl_->common));
    if (x == nullptr) throw std::bad_alloc();
    std::memcpy(x, o.packed.x, o.packed.xsize * sizeof(double));
    impl_->packed = o.packed;
    impl_->packed.x = x;
  }
  // Everything the updates and solves read, so that the copy continues bit for bit as the
  // original would (the common's settings are the constructor's, never changed afterwards).
  impl_->inverse_perm = o.inverse_perm;
  impl_->analysis_flops = o.analysis_flops;
  impl_->update_flops_total = o.update_flops_total;
  impl_->schedule = o.schedule;
  impl_->diagonal = o.diagonal;
  impl_->mark = o.mark;
  impl_->stamp = o.stamp;
  impl_->solve_threads = o.solve_threads;
  impl_->w = o.w;
  impl_->tracked_rhs = o.tracked_rhs;
  impl_->forward_y = o.forward_y;
  impl_->delta = o.delta;
  impl_->forward_valid = o.forward_valid;
  impl_->work = o.work;
}
SparseCholesky::SparseCholesky(SparseCholesky&&) noexcept = default;
SparseCholesky& SparseCholesky::operator=(SparseCholesky&&) noexcept = default;

void SparseCholesky::set_solve_threads(int threads) { impl_->solve_threads = threads; }

namespace {
std::atomic<bool> g_automatic_two_threads{true};
std::atomic<bool> g_interleaved_update{true};
}  // namespace

void SparseCholesky::set_interleaved_update(bool interleaved) {
  g_interleaved_update.store(interleaved, std::memory_order_relaxed);
}

bool SparseCholesky::interleaved_update() {
  return g_interleaved_update.load(std::memory_order_relaxed);
}

void SparseCholesky::allow_automatic_two_threads(bool allow) {
  g_automatic_two_threads.store(allow, std::memory_order_relaxed);
}

bool SparseCholesky::automatic_two_threads() {
  return g_automatic_two_threads.load(std::memory_order_relaxed) &&
         std::thread::hardware_concurrency() > 1;
}

core::Status SparseCholesky::convert_to_ldlt() { return impl_->to_ldlt(true); }

bool SparseCholesky::release_values() {
  auto& impl = *impl_;
  cholmod_factor* l = impl.factor;
  if (l == nullptr || !l->is_super) return false;
  impl.free_packed();
  if (l->xtype != CHOLMOD_PATTERN) {
    // Supernodal numeric -> supernodal symbolic (CHOLMOD's ll_super_to_super_symbolic).
    if (!cholmod_change_factor(CHOLMOD_PATTERN, 1, 1, 1, 1, l, &impl.common)) return false;
  }
  impl.schedule = {};
  impl.diagonal.clear();
  impl.forward_valid = false;
  impl.w = {};
  impl.delta = {};
  impl.forward_y = {};
  impl.tracked_rhs.resize(0, 0);
  return true;
}

bool SparseCholesky::has_values() const {
  const cholmod_factor* l = impl_->factor;
  return l != nullptr && (impl_->packed_active() || l->xtype != CHOLMOD_PATTERN);
}

bool SparseCholesky::analyzed() const { return impl_->factor != nullptr; }

double SparseCholesky::factorization_flops() const {
  return impl_->factor != nullptr ? impl_->analysis_flops : 0.0;
}

double SparseCholesky::update_flops_total() const { return impl_->update_flops_total; }

bool SparseCholesky::supernodal_analysis() const {
  return impl_->factor != nullptr && impl_->factor->is_super;
}

double SparseCholesky::factor_nonzeros() const {
  if (impl_->factor == nullptr) return 0.0;
  if (impl_->packed_active()) return static_cast<double>(impl_->packed.xsize);
  const cholmod_factor* l = impl_->factor;
  if (l->is_super) return static_cast<double>(l->xsize);
  return static_cast<double>(l->nzmax);
}

double SparseCholesky::supernodal_nonzeros() const {
  const cholmod_factor* l = impl_->factor;
  return l != nullptr && l->is_super ? static_cast<double>(l->xsize) : 0.0;
}

double SparseCholesky::factor_bytes() const {
  const cholmod_factor* l = impl_->factor;
  if (l == nullptr) return 0.0;
  const double n = static_cast<double>(l->n);
  const double ints = static_cast<double>(sizeof(int));
  double bytes = 2.0 * n * ints;  // Perm, ColCount
  if (l->is_super) {
    const double nsuper = static_cast<double>(l->nsuper);
    bytes += static_cast<double>(l->ssize) * ints + 3.0 * (nsuper + 1.0) * ints;
    if (l->x != nullptr) bytes += static_cast<double>(l->xsize) * sizeof(double);
    if (impl_->packed_active()) {
      bytes += static_cast<double>(impl_->packed.xsize) * sizeof(double) + 3.0 * n * ints;
    }
  } else if (l->xtype != CHOLMOD_PATTERN) {
    bytes += static_cast<double>(l->nzmax) * (sizeof(double) + ints) + (4.0 * n + 5.0) * ints;
  }
  return bytes;
}

std::vector<int> SparseCholesky::fill_reducing_ordering(const SparseMatrix& upper,
                                                        Ordering method) {
  Impl impl;
  if (method == Ordering::metis_or_amd) {
    impl.common.nmethods = 2;  // keep whichever of METIS and AMD fills less
    impl.common.method[0].ordering = CHOLMOD_METIS;
    impl.common.method[1].ordering = CHOLMOD_AMD;
  } else {
    impl.common.nmethods = 1;
    impl.common.method[0].ordering = method == Ordering::nesdis  ? CHOLMOD_NESDIS
                                     : method == Ordering::metis ? CHOLMOD_METIS
                                                                 : CHOLMOD_AMD;
  }
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

core::Status SparseCholesky::analyze(const SparseMatrix& upper,
                                     const std::vector<int>* permutation) {
  if (!upper.isCompressed()) return core::failure("matrix is not compressed");
  impl_->free_packed();
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
    return core::failure("cholmod_analyze failed (status " + std::to_string(impl_->common.status) +
                         ")");
  }
  impl_->analysis_flops = impl_->common.fl;
  return {};
}

core::Status SparseCholesky::factorize(const SparseMatrix& upper) {
  if (impl_->factor == nullptr) {
    if (auto r = analyze(upper); !r.ok()) return r;
  }
  cholmod_sparse a = Impl::view(upper);
  impl_->free_packed();  // the factor is the supernodal analysis again: refactorize with it
  impl_->schedule = {};
  impl_->diagonal.clear();
  impl_->forward_valid = false;
  impl_->weakest_row = -1;
  const int ok = cholmod_factorize(&a, impl_->factor, &impl_->common);
  if (impl_->common.status == CHOLMOD_NOT_POSDEF) {
    impl_->weakest_row = impl_->row_of(static_cast<int>(impl_->factor->minor));
    return core::failure("stiffness is not positive definite (pivot " +
                         std::to_string(impl_->factor->minor) +
                         "): a part of the model is unconstrained or has come loose");
  }
  if (!ok || impl_->common.status < CHOLMOD_OK) {
    return core::failure("cholmod_factorize failed (status " +
                         std::to_string(impl_->common.status) + ")");
  }
  const double rcond = cholmod_rcond(impl_->factor, &impl_->common);
  if (!(rcond > 1e-14)) {
    impl_->weakest_row = impl_->row_of(impl_->smallest_supernodal_pivot());
    return core::failure("stiffness is numerically singular (rcond " + std::to_string(rcond) +
                         "): a part of the model is unconstrained or has come loose");
  }
  return {};
}

int SparseCholesky::weakest_pivot_row() const { return impl_->weakest_row; }

int SparseCholesky::Impl::smallest_supernodal_pivot() const {
  const cholmod_factor* l = factor;
  if (l == nullptr || !l->is_super || !l->is_ll || l->xtype != CHOLMOD_REAL || l->x == nullptr) {
    return -1;
  }
  const auto* super = static_cast<const int*>(l->super);
  const auto* lpi = static_cast<const int*>(l->pi);
  const auto* lpx = static_cast<const int*>(l->px);
  const auto* lx = static_cast<const double*>(l->x);
  int weakest = -1;
  double smallest = 0.0;
  for (std::size_t s = 0; s < l->nsuper; ++s) {
    const int nsrow = lpi[s + 1] - lpi[s];
    for (int j = super[s]; j < super[s + 1]; ++j) {
      const int jj = j - super[s];
      const double d = std::abs(lx[lpx[s] + jj * nsrow + jj]);
      if (weakest < 0 || !(d >= smallest)) {  // a NaN pivot is the weakest
        weakest = j;
        smallest = d;
      }
    }
  }
  return weakest;
}

core::Status SparseCholesky::modify(const std::vector<Column>& columns, bool add) {
  if (columns.empty()) return {};
  impl_->forward_valid = false;  // CHOLMOD's updown does not update our forward solve
  if (auto r = impl_->to_ldlt(false); !r.ok()) return r;
  cholmod_factor* l = impl_->factor;
  auto& common = impl_->common;
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
  if (c == nullptr) return core::failure("cholmod_allocate_sparse failed");
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
    return core::failure("cholmod_updown failed (status " + std::to_string(common.status) + ")");
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
    if (auto r = check_after_downdate(impl.diagonal, impl.weakest_row); !r.ok()) {
      impl.weakest_row = impl.row_of(impl.weakest_row);
      return r;
    }
  }
  return {};
}

void SparseCholesky::solve(Eigen::MatrixXd& rhs) const {
  if (impl_->factor == nullptr) throw std::logic_error("SparseCholesky::solve before factorize");
  auto& impl = *impl_;
  const auto cols = rhs.cols();
  if (!impl.is_ldlt() || ((cols < 1 || cols > 3) && !impl.packed_active())) {
    solve_with_cholmod(rhs);
    return;
  }
  if (cols > 3) {  // the packed factor: three columns at a time (each column's arithmetic alone)
    for (Eigen::Index c0 = 0; c0 < cols; c0 += 3) {
      const Eigen::Index k = std::min<Eigen::Index>(3, cols - c0);
      Eigen::MatrixXd part = rhs.middleCols(c0, k);
      solve(part);
      rhs.middleCols(c0, k) = part;
    }
    return;
  }
  if (cols < 1) return;
  // LDLᵀ (after an update): our own solve with the two subtree parts on two threads.
  const ldlt::FactorView l = impl.view();
  const auto n = static_cast<std::size_t>(l.n);
  std::int64_t nnz = 0;
  for (std::size_t j = 0; j < n; ++j) nnz += l.lnz[j];
  if (impl.schedule.pattern_nnz != nnz) impl.ensure_schedule();
  const int* perm = l.perm;
  const auto r = static_cast<std::size_t>(cols);
  const bool threaded = impl.schedule.balanced &&
                        (impl.solve_threads == 2 ||
                         (impl.solve_threads == 0 && nnz > 2'000'000 && automatic_two_threads()));
  auto run = [&](bool do_forward, bool do_backward) {
    double* y = impl.work.data();
    ldlt::solve(static_cast<int>(r), l, impl.schedule, threaded, y, do_forward, do_backward);
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
  if (impl_->packed_active()) {
    throw std::logic_error(
        "SparseCholesky::solve_with_cholmod after modify_fused: the factor is peritwin's packed "
        "LDLt, which CHOLMOD cannot read (solve() solves with it)");
  }
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

}  // namespace peritwin::linalg
