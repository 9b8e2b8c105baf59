#include "solver/linalg/sparse_cholesky.h"

#include <cholmod.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "solver/linalg/cholesky_impl.h"

namespace peritwin {

/// After a downdate: D of LDLᵀ must stay positive, and rcond as cholmod_rcond computes it,
/// min(D) / max(D), above 1e-14 — else the model has come loose.
Status check_after_downdate(const std::vector<double>& diagonal) {
  double d_min = diagonal.empty() ? 0.0 : diagonal.front();
  double d_max = d_min;
  bool positive = true;
  for (const double d : diagonal) {
    positive = positive && d > 0.0;
    d_min = std::min(d_min, d);
    d_max = std::max(d_max, d);
  }
  if (!positive) {
    return failure(
        "stiffness is not positive definite after breaking bonds: a part of the model has "
        "come loose");
  }
  const double rcond = d_min / d_max;
  if (!(rcond > 1e-14)) {
    return failure("stiffness is numerically singular (rcond " + std::to_string(rcond) +
                   "): a part of the model has come loose");
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
  // Everything the updates and solves read, so that the copy continues bit for bit as the
  // original would (the common's settings are the constructor's, never changed afterwards).
  impl_->inverse_perm = o.inverse_perm;
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
}  // namespace

void SparseCholesky::allow_automatic_two_threads(bool allow) {
  g_automatic_two_threads.store(allow, std::memory_order_relaxed);
}

bool SparseCholesky::automatic_two_threads() {
  return g_automatic_two_threads.load(std::memory_order_relaxed) &&
         std::thread::hardware_concurrency() > 1;
}

bool SparseCholesky::analyzed() const { return impl_->factor != nullptr; }

double SparseCholesky::factor_nonzeros() const {
  if (impl_->factor == nullptr) return 0.0;
  const cholmod_factor* l = impl_->factor;
  if (l->is_super) return static_cast<double>(l->xsize);
  return static_cast<double>(l->nzmax);
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

Status SparseCholesky::analyze(const SparseMatrix& upper, const std::vector<int>* permutation) {
  if (!upper.isCompressed()) return failure("matrix is not compressed");
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
    return failure("cholmod_analyze failed (status " + std::to_string(impl_->common.status) + ")");
  }
  return {};
}

Status SparseCholesky::factorize(const SparseMatrix& upper) {
  if (impl_->factor == nullptr) {
    if (auto r = analyze(upper); !r.ok()) return r;
  }
  cholmod_sparse a = Impl::view(upper);
  impl_->schedule = {};
  impl_->diagonal.clear();
  impl_->forward_valid = false;
  const int ok = cholmod_factorize(&a, impl_->factor, &impl_->common);
  if (impl_->common.status == CHOLMOD_NOT_POSDEF) {
    return failure("stiffness is not positive definite (pivot " +
                   std::to_string(impl_->factor->minor) +
                   "): a part of the model is unconstrained or has come loose");
  }
  if (!ok || impl_->common.status < CHOLMOD_OK) {
    return failure("cholmod_factorize failed (status " + std::to_string(impl_->common.status) +
                   ")");
  }
  const double rcond = cholmod_rcond(impl_->factor, &impl_->common);
  if (!(rcond > 1e-14)) {
    return failure("stiffness is numerically singular (rcond " + std::to_string(rcond) +
                   "): a part of the model is unconstrained or has come loose");
  }
  return {};
}

Status SparseCholesky::modify(const std::vector<Column>& columns, bool add) {
  if (columns.empty()) return {};
  impl_->forward_valid = false;  // CHOLMOD's updown does not update our forward solve
  cholmod_factor* l = impl_->factor;
  if (l == nullptr) return failure("modify before factorize");
  auto& common = impl_->common;
  if (l->is_super || l->is_ll) {
    if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, l, &common)) {
      return failure("cholmod_change_factor failed");
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
  if (c == nullptr) return failure("cholmod_allocate_sparse failed");
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
    return failure("cholmod_updown failed (status " + std::to_string(common.status) + ")");
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
                        (impl.solve_threads == 2 ||
                         (impl.solve_threads == 0 && nnz > 2'000'000 && automatic_two_threads()));
  auto run = [&](bool do_forward, bool do_backward) {
    double* y = impl.work.data();
    ldlt::solve(static_cast<int>(r), *l, impl.schedule, threaded, y, do_forward, do_backward);
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
