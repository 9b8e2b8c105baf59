#include "solver/sparse_cholesky.h"

#include <cholmod.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace peritwin {

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_factor* factor = nullptr;
  std::vector<int> inverse_perm;  ///< row -> position in the factor's ordering
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
  cholmod_factor* l = impl_->factor;
  if (l == nullptr) return {FactorStatus::failed, "modify before factorize"};
  auto& common = impl_->common;
  if (l->is_super || l->is_ll) {
    if (!cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, l, &common)) {
      return {FactorStatus::failed, "cholmod_change_factor failed"};
    }
  }
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
  std::size_t pos = 0;
  for (std::size_t col = 0; col < columns.size(); ++col) {
    cp[col] = static_cast<int>(pos);
    entries.clear();
    for (std::size_t e = 0; e < columns[col].rows.size(); ++e) {
      entries.emplace_back(impl_->inverse_perm[static_cast<std::size_t>(columns[col].rows[e])],
                           columns[col].values[e]);
    }
    std::sort(entries.begin(), entries.end());
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
  if (!add) {
    // LDLᵀ: D is the first entry of every column.
    const int* lp = static_cast<const int*>(l->p);
    const double* lx = static_cast<const double*>(l->x);
    for (std::size_t j = 0; j < n; ++j) {
      if (!(lx[lp[j]] > 0.0)) {
        return {FactorStatus::not_positive_definite,
                "stiffness is not positive definite after breaking bonds: a part of the model has "
                "come loose"};
      }
    }
    const double rcond = cholmod_rcond(l, &common);
    if (!(rcond > 1e-14)) {
      return {FactorStatus::singular, "stiffness is numerically singular (rcond " +
                                          std::to_string(rcond) +
                                          "): a part of the model has come loose"};
    }
  }
  return {};
}

void SparseCholesky::solve(Eigen::MatrixXd& rhs) const {
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
