#include "stream/gauge_identification.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <utility>

namespace peritwin::stream {

namespace {

constexpr double kNegligible = 1e-9;       ///< |c| <= this × max |c| counts as 0
constexpr double kRankTolerance = 1e-8;    ///< singular values below this × the largest: dependent
constexpr double kAngleTolerance = 1e-12;  ///< rad, the Newton refinement's stopping step
constexpr int kMaxRefinements = 100;
constexpr double kPi = std::numbers::pi;
constexpr int kScanMaxima = 3;  ///< the scan's largest local maxima refined

std::string join(const std::vector<std::string>& ids, std::size_t most = 12) {
  std::string out;
  for (std::size_t i = 0; i < ids.size() && i < most; ++i) {
    if (i > 0) out += ", ";
    out += ids[i];
  }
  if (ids.size() > most) out += ", ... (" + std::to_string(ids.size()) + " in all)";
  return out;
}

std::string equations(int rank) {
  return std::to_string(rank) + (rank == 1 ? " independent equation" : " independent equations");
}

/// The reason the columns' gauges cannot identify the load of `form` (rank < basis columns).
std::string too_few(LoadForm form, int rank, const std::vector<std::string>& columns) {
  const std::string gauges = columns.size() == 1 ? "the gauge " + columns[0] + " gives only "
                                                 : "the gauges " + join(columns) + " give only ";
  switch (form) {
    case LoadForm::p_only:
      return "1 unknown (P) but " + gauges + equations(rank);
    case LoadForm::linear_pair:
      return "2 unknowns (P, α) but " + gauges + equations(rank) +
             " (their cos α and sin α coefficients are in proportion: add a gauge that reads "
             "another direction of the load)";
    case LoadForm::constant_and_angle:
      break;
  }
  return "2 unknowns (P, α) of a load with a constant and an angle part need 3 independent "
         "gauges (with fewer, two different (P, α) give the same strains) but " +
         gauges + equations(rank) +
         " (add a gauge whose constant, cos α and sin α coefficients are no combination of "
         "theirs)";
}

/// (−π, π].
double wrap_angle(double a) {
  if (a > kPi) return a - 2.0 * kPi;
  if (a <= -kPi) return a + 2.0 * kPi;
  return a;
}

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

/// The line without blanks around it and without a UTF-8 byte order mark.
std::string_view clean_line(std::string_view line) {
  line = trim(line);
  if (line.starts_with("\xEF\xBB\xBF")) line = trim(line.substr(3));
  return line;
}

/// Calls `field(text)` for each comma-separated field, trimmed; stops when it returns false.
template <typename F>
void for_each_field(std::string_view line, F&& field) {
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (!field(trim(line.substr(start, comma - start)))) return;
    if (comma == std::string_view::npos) return;
    start = comma + 1;
  }
}

/// A whole field as a number (std::from_chars: '.' decimals, any locale; a leading '+' taken).
bool to_number(std::string_view s, double& v) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

}  // namespace

core::Expected<LoadIdentifier, std::string> LoadIdentifier::create(
    std::vector<std::string> columns, const std::vector<GaugeInfluence>& influence) {
  if (columns.empty()) return std::string("no gauge columns");
  std::unordered_map<std::string_view, std::size_t> model;
  for (std::size_t i = 0; i < influence.size(); ++i) {
    if (!model.emplace(influence[i].id, i).second) {
      return "the model gives gauge '" + influence[i].id + "' twice";
    }
  }
  std::unordered_map<std::string_view, std::size_t> seen;
  std::vector<const GaugeInfluence*> gauges;
  gauges.reserve(columns.size());
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const std::string& id = columns[i];
    const auto [first, fresh] = seen.emplace(id, i);
    if (!fresh) {
      return "gauge '" + id + "' is given twice (gauge columns " +
             std::to_string(first->second + 1) + " and " + std::to_string(i + 1) + ")";
    }
    const auto found = model.find(id);
    if (found == model.end()) {
      std::vector<std::string> known;
      known.reserve(influence.size());
      for (const GaugeInfluence& g : influence) known.push_back(g.id);
      return "column '" + id + "' is no gauge of the model (its gauges: " +
             (known.empty() ? std::string("none") : join(known)) + ")";
    }
    const GaugeInfluence& g = influence[found->second];
    for (std::size_t j = 0; j < 3; ++j) {
      if (!std::isfinite(g.per_basis[j])) {
        return "gauge '" + id + "': its coefficient per_basis[" + std::to_string(j) +
               "] is not finite";
      }
    }
    if (!std::isfinite(g.noise) || g.noise < 0.0) {
      return "gauge '" + id + "': its noise must be a finite number >= 0";
    }
    gauges.push_back(&g);
  }

  LoadIdentifier id;
  const std::size_t n = columns.size();
  id.n_ = n;
  id.columns_ = std::move(columns);
  double largest = 0.0;
  for (const GaugeInfluence* g : gauges) {
    for (const double c : g->per_basis) largest = std::max(largest, std::abs(c));
  }
  if (largest == 0.0) {
    return "every coefficient of " + std::string(n == 1 ? "the gauge " : "the gauges ") +
           join(id.columns_) + " is 0: they do not see the load";
  }
  const double negligible = kNegligible * largest;
  const auto kept = [negligible](double c) { return std::abs(c) <= negligible ? 0.0 : c; };
  id.c0_.resize(n);
  id.c1_.resize(n);
  id.c2_.resize(n);
  bool constant = false, angle = false;
  for (std::size_t i = 0; i < n; ++i) {
    id.c0_[i] = kept(gauges[i]->per_basis[0]);
    id.c1_[i] = kept(gauges[i]->per_basis[1]);
    id.c2_[i] = kept(gauges[i]->per_basis[2]);
    constant = constant || id.c0_[i] != 0.0;
    angle = angle || id.c1_[i] != 0.0 || id.c2_[i] != 0.0;
  }
  id.form_ = !angle      ? LoadForm::p_only
             : !constant ? LoadForm::linear_pair
                         : LoadForm::constant_and_angle;
  std::vector<const std::vector<double>*> basis;
  if (id.form_ != LoadForm::linear_pair) basis.push_back(&id.c0_);
  if (id.form_ != LoadForm::p_only) {
    basis.push_back(&id.c1_);
    basis.push_back(&id.c2_);
  }
  const auto m = static_cast<Eigen::Index>(basis.size());
  const auto rows = static_cast<Eigen::Index>(n);

  // Independence, of the coefficients as the model gives them.
  Eigen::MatrixXd a(rows, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    for (Eigen::Index i = 0; i < rows; ++i) {
      a(i, j) = (*basis[static_cast<std::size_t>(j)])[static_cast<std::size_t>(i)];
    }
  }
  {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
    const auto& sv = svd.singularValues();
    int rank = 0;
    for (Eigen::Index k = 0; k < sv.size(); ++k) rank += sv[k] > kRankTolerance * sv[0] ? 1 : 0;
    if (rank < m) return too_few(id.form_, rank, id.columns_);
  }

  // Weights: (σ_min/σ_g)², proportional to 1/σ_g², the largest 1; or all 1.
  id.w_.assign(n, 1.0);
  const bool weighted =
      std::all_of(gauges.begin(), gauges.end(), [](const auto* g) { return g->noise > 0.0; });
  if (weighted) {
    double smallest = std::numeric_limits<double>::infinity();
    for (const GaugeInfluence* g : gauges) smallest = std::min(smallest, g->noise);
    for (std::size_t i = 0; i < n; ++i) {
      const double s = smallest / gauges[i]->noise;
      id.w_[i] = s * s;
    }
  }
  id.w_sum_ = 0.0;
  for (const double w : id.w_) id.w_sum_ += w;

  // The weighted least-squares solution for the basis unknowns (P; P cos α, P sin α; or all
  // three) is a fixed linear map of the strains, pinv(S A) S with S = diag(√w), from the SVD of
  // S A (better conditioned than the normal equations).
  Eigen::VectorXd sqrt_w(rows);
  for (Eigen::Index i = 0; i < rows; ++i) sqrt_w[i] = std::sqrt(id.w_[static_cast<std::size_t>(i)]);
  const Eigen::MatrixXd sa = sqrt_w.asDiagonal() * a;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(sa, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const auto& sv = svd.singularValues();
  if (!(sv[m - 1] > 0.0)) return too_few(id.form_, static_cast<int>(m) - 1, id.columns_);

  if (id.form_ == LoadForm::constant_and_angle) {
    // b = CᵀWε per sample; G = CᵀWC; G⁻¹ = V Σ⁻² Vᵀ (for the linear candidate angle).
    id.map0_.resize(n);
    id.map1_.resize(n);
    id.map2_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      id.map0_[i] = id.w_[i] * id.c0_[i];
      id.map1_[i] = id.w_[i] * id.c1_[i];
      id.map2_[i] = id.w_[i] * id.c2_[i];
    }
    const Eigen::Matrix3d g = sa.transpose() * sa;
    const Eigen::Matrix3d ginv =
        svd.matrixV() * sv.cwiseInverse().cwiseAbs2().asDiagonal() * svd.matrixV().transpose();
    for (Eigen::Index r = 0; r < 3; ++r) {
      for (Eigen::Index c = 0; c < 3; ++c) {
        id.g_[static_cast<std::size_t>(3 * r + c)] = g(r, c);
        id.ginv_[static_cast<std::size_t>(3 * r + c)] = ginv(r, c);
      }
    }
    // The scan's step: half the narrowest width a minimum of the misfit can have, √(Dmin/Dmax)
    // rad (near an α where D = uᵀGu is smallest, N²/D is a peak of that width).
    // D is a trigonometric polynomial of degree 2 (at most 2 local minima): a grid of 256,
    // then golden section within a grid step around each grid minimum, to 1e-8 rad (the value
    // is then exact to rounding: D is flat there).
    const auto d_at = [&g](double alpha) {
      const Eigen::Vector3d u(1.0, std::cos(alpha), std::sin(alpha));
      return u.dot(g * u);
    };
    constexpr int kGrid = 256;
    constexpr double kGridStep = 2.0 * kPi / kGrid;
    std::array<double, kGrid> grid{};
    for (int k = 0; k < kGrid; ++k) grid[static_cast<std::size_t>(k)] = d_at(k * kGridStep);
    double d_min = std::numeric_limits<double>::infinity(), d_max = 0.0;
    for (int k = 0; k < kGrid; ++k) {
      const double here = grid[static_cast<std::size_t>(k)];
      d_max = std::max(d_max, here);
      d_min = std::min(d_min, here);
      if (here > grid[static_cast<std::size_t>((k + kGrid - 1) % kGrid)] ||
          here > grid[static_cast<std::size_t>((k + 1) % kGrid)]) {
        continue;
      }
      double lo = (k - 1) * kGridStep, hi = (k + 1) * kGridStep;
      constexpr double kGolden = 0.3819660112501051;  // (3 − √5)/2
      double m1 = lo + kGolden * (hi - lo), m2 = hi - kGolden * (hi - lo);
      double d1 = d_at(m1), d2 = d_at(m2);
      while (hi - lo > 1e-8) {
        if (d1 < d2) {
          hi = m2;
          m2 = m1;
          d2 = d1;
          m1 = lo + kGolden * (hi - lo);
          d1 = d_at(m1);
        } else {
          lo = m1;
          m1 = m2;
          d1 = d2;
          m2 = hi - kGolden * (hi - lo);
          d2 = d_at(m2);
        }
      }
      d_min = std::min({d_min, d1, d2});
    }
    if (!(d_min > 0.0)) return too_few(id.form_, 2, id.columns_);  // v(α) = 0: rank < 3
    const double wanted = std::ceil(4.0 * kPi / std::sqrt(d_min / d_max));
    const int angles =
        static_cast<int>(std::clamp(wanted, double{kMinScanAngles}, double{kMaxScanAngles}));
    id.scan_cos_.resize(static_cast<std::size_t>(angles));
    id.scan_sin_.resize(static_cast<std::size_t>(angles));
    id.scan_inv_d_.resize(static_cast<std::size_t>(angles));
    for (int k = 0; k < angles; ++k) {
      const double alpha = -kPi + (k + 1) * (2.0 * kPi / angles);
      const Eigen::Vector3d u(1.0, std::cos(alpha), std::sin(alpha));
      const auto kk = static_cast<std::size_t>(k);
      id.scan_cos_[kk] = u[1];
      id.scan_sin_[kk] = u[2];
      id.scan_inv_d_[kk] = 1.0 / u.dot(g * u);
    }
    return id;
  }

  const Eigen::MatrixXd map = svd.matrixV() * sv.cwiseInverse().asDiagonal() *
                              svd.matrixU().transpose() * sqrt_w.asDiagonal();
  id.map0_.resize(n);
  for (std::size_t i = 0; i < n; ++i) id.map0_[i] = map(0, static_cast<Eigen::Index>(i));
  if (m == 2) {
    id.map1_.resize(n);
    for (std::size_t i = 0; i < n; ++i) id.map1_[i] = map(1, static_cast<Eigen::Index>(i));
  }
  return id;
}

core::Status LoadIdentifier::update(const std::vector<GaugeInfluence>& influence) {
  auto made = create(columns_, influence);
  if (!made) return core::failure(made.error());
  *this = std::move(made).value();
  return {};
}

double LoadIdentifier::model_strain(std::size_t column, double p, double alpha) const {
  assert(column < n_);
  return p * (c0_[column] + c1_[column] * std::cos(alpha) + c2_[column] * std::sin(alpha));
}

double LoadIdentifier::weighted_rms(std::span<const double> strains, double p, double alpha,
                                    std::vector<double>* residuals) const {
  const double pc = p * std::cos(alpha), ps = p * std::sin(alpha);
  if (residuals != nullptr) residuals->resize(n_);
  double sum = 0.0;
  for (std::size_t i = 0; i < n_; ++i) {
    const double r = strains[i] - (p * c0_[i] + pc * c1_[i] + ps * c2_[i]);
    if (residuals != nullptr) (*residuals)[i] = r;
    sum += w_[i] * r * r;
  }
  return std::sqrt(sum / w_sum_);
}

IdentifiedLoad LoadIdentifier::identify(std::span<const double> strains,
                                        std::vector<double>* residuals) const {
  IdentifiedLoad out;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  const auto invalid = [&] {
    if (residuals != nullptr) residuals->assign(n_, kNaN);
    return IdentifiedLoad{kNaN, kNaN, kNaN};
  };
  if (strains.size() != n_) return invalid();
  switch (form_) {
    case LoadForm::p_only: {
      double p = 0.0;
      for (std::size_t i = 0; i < n_; ++i) p += map0_[i] * strains[i];
      out.p = p;
      break;
    }
    case LoadForm::linear_pair: {
      double x = 0.0, y = 0.0;
      for (std::size_t i = 0; i < n_; ++i) {
        x += map0_[i] * strains[i];
        y += map1_[i] * strains[i];
      }
      if (!std::isfinite(x) || !std::isfinite(y)) return invalid();
      const double r = std::hypot(x, y);
      double alpha = std::atan2(y, x);
      double p = r;
      if (alpha > 0.5 * kPi) {
        alpha -= kPi;
        p = -r;
      } else if (alpha <= -0.5 * kPi) {
        alpha += kPi;
        p = -r;
      }
      out.p = p;
      out.alpha = alpha;
      break;
    }
    case LoadForm::constant_and_angle:
      out = identify_constant_and_angle(strains);
      break;
  }
  if (!std::isfinite(out.p) || !std::isfinite(out.alpha)) return invalid();
  out.residual_rms = weighted_rms(strains, out.p, out.alpha, residuals);
  return out;
}

namespace {

/// The constant_and_angle misfit of one sample as a function of α alone: εᵀWε − N²/D with
/// N = u·b, D = uᵀGu, u = (1, cos α, sin α), b = CᵀWε. maximize N²/D.
struct AngleMisfit {
  const std::array<double, 9>& g;  ///< G = CᵀWC, row-major
  double b0, b1, b2;

  /// ψ = N·(N'D − N E), E = u'ᵀGu, has the sign of d(N²/D)/dα (= 2ψ/D²); with its derivative.
  struct At {
    double psi, dpsi, n, d;
  };
  [[nodiscard]] At at(double alpha) const {
    const double co = std::cos(alpha), si = std::sin(alpha);
    const double gu0 = g[0] + g[1] * co + g[2] * si;
    const double gu1 = g[3] + g[4] * co + g[5] * si;
    const double gu2 = g[6] + g[7] * co + g[8] * si;
    const double d = gu0 + co * gu1 + si * gu2;
    const double e = -si * gu1 + co * gu2;  // u'ᵀGu, u' = (0, −sin, cos)
    // E' = u''ᵀGu + u'ᵀGu', u'' = (0, −cos, −sin)
    const double gp1 = -g[4] * si + g[5] * co, gp2 = -g[7] * si + g[8] * co;
    const double de = -co * gu1 - si * gu2 + (-si * gp1 + co * gp2);
    const double n = b0 + b1 * co + b2 * si;
    const double dn = -b1 * si + b2 * co;
    const double ddn = b0 - n;
    const double phi = dn * d - n * e;
    const double dphi = ddn * d + dn * e - n * de;
    return {n * phi, dn * phi + n * dphi, n, d};
  }

  /// The local maximum of N²/D next to `start`, the side ψ(start) points to, within `width`;
  /// `start` when ψ changes no sign there. For a start that is no stationary point (a scan angle).
  [[nodiscard]] double refine_towards(double start, double width) const {
    const double psi = at(start).psi;
    if (psi == 0.0) return start;
    const double up = psi > 0.0 ? start : start - width;
    const double down = psi > 0.0 ? start + width : start;
    if (at(psi > 0.0 ? down : up).psi * psi >= 0.0) return start;
    return maximum(up, down);
  }

  /// The local maximum of N²/D around `start`, or nullopt: in the smallest bracket
  /// [start − h, start + h] where ψ falls from > 0 to < 0, h from 4 × the Newton step at `start`
  /// (1e-6 when N²/D is not concave there; at least 1e-9) growing × 100 up to `width`. For a
  /// start that may be a stationary point already (the linear candidate), whose ψ's sign is then
  /// rounding: a one-sided bracket could go to another stationary point (two local minima of the
  /// misfit can lie close together when the coefficients nearly make v'(α) ∥ v(α)).
  [[nodiscard]] std::optional<double> refine_around(double start, double width) const {
    const At s = at(start);
    if (s.psi == 0.0 && s.dpsi < 0.0) return start;
    double h = s.dpsi < 0.0 ? std::max(4.0 * std::abs(s.psi / s.dpsi), 1e-9) : 1e-6;
    for (bool last = false; !last; h *= 100.0) {
      if (h >= width) {
        h = width;
        last = true;
      }
      if (at(start - h).psi > 0.0 && at(start + h).psi < 0.0) return maximum(start - h, start + h);
    }
    return std::nullopt;
  }

  /// The root of ψ in the bracket ψ(up) > 0 > ψ(down): safeguarded Newton (Numerical Recipes'
  /// rtsafe: bisection when a Newton step would leave the bracket or converge slowly), to a step
  /// < kAngleTolerance.
  [[nodiscard]] double maximum(double up, double down) const {
    double x = 0.5 * (up + down);
    double dx_old = std::abs(down - up), dx = dx_old;
    At f = at(x);
    for (int it = 0; it < kMaxRefinements && f.psi != 0.0; ++it) {
      const bool leaves = ((x - down) * f.dpsi - f.psi) * ((x - up) * f.dpsi - f.psi) > 0.0;
      if (leaves || std::abs(2.0 * f.psi) > std::abs(dx_old * f.dpsi)) {
        dx_old = dx;
        dx = 0.5 * (up - down);
        x = down + dx;
        if (x == down || x == up) break;  // the bracket is two neighbouring doubles
      } else {
        dx_old = dx;
        dx = f.psi / f.dpsi;
        const double before = x;
        x -= dx;
        if (x == before) break;
      }
      if (std::abs(dx) < kAngleTolerance) break;
      f = at(x);
      if (f.psi > 0.0) {
        up = x;
      } else {
        down = x;
      }
    }
    return x;
  }
};

}  // namespace

IdentifiedLoad LoadIdentifier::identify_constant_and_angle(std::span<const double> strains) const {
  double b0 = 0.0, b1 = 0.0, b2 = 0.0;  // b = CᵀWε
  for (std::size_t i = 0; i < n_; ++i) {
    b0 += map0_[i] * strains[i];
    b1 += map1_[i] * strains[i];
    b2 += map2_[i] * strains[i];
  }
  if (!std::isfinite(b0) || !std::isfinite(b1) || !std::isfinite(b2)) {
    return {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  }
  if (b0 == 0.0 && b1 == 0.0 && b2 == 0.0) return {};  // no strain: P = 0, α = 0
  const AngleMisfit misfit{g_, b0, b1, b2};
  // Candidate 1: the angle of the unconstrained linear solution (P, P cos α, P sin α) = G⁻¹b,
  // exact for exact strains (and where a maximum narrower than the scan step hides).
  const auto& gi = ginv_;
  const double u0 = gi[0] * b0 + gi[1] * b1 + gi[2] * b2;
  const double u1 = gi[3] * b0 + gi[4] * b1 + gi[5] * b2;
  const double u2 = gi[6] * b0 + gi[7] * b1 + gi[8] * b2;
  const double linear = u0 >= 0.0 ? std::atan2(u2, u1) : std::atan2(-u2, -u1);
  // Candidates 2-4: the scan's largest local maxima of N²/D (cyclic; at most 3 exist).
  const int angles = scan_angles();
  const double step = 2.0 * kPi / angles;
  const auto q_at = [&](int k) {
    const auto kk = static_cast<std::size_t>(k);
    const double nk = b0 + b1 * scan_cos_[kk] + b2 * scan_sin_[kk];
    return nk * nk * scan_inv_d_[kk];
  };
  std::array<int, kScanMaxima> top{};
  std::array<double, kScanMaxima> top_q{};
  top_q.fill(-1.0);
  const double q_first = q_at(0);
  double before = q_at(angles - 1), here = q_first;
  for (int k = 0; k < angles; ++k) {
    const double after = k + 1 < angles ? q_at(k + 1) : q_first;
    if (here >= before && here > after && here > top_q[kScanMaxima - 1]) {
      int slot = kScanMaxima - 1;
      for (; slot > 0 && here > top_q[static_cast<std::size_t>(slot - 1)]; --slot) {
        top_q[static_cast<std::size_t>(slot)] = top_q[static_cast<std::size_t>(slot - 1)];
        top[static_cast<std::size_t>(slot)] = top[static_cast<std::size_t>(slot - 1)];
      }
      top_q[static_cast<std::size_t>(slot)] = here;
      top[static_cast<std::size_t>(slot)] = k;
    }
    before = here;
    here = after;
  }
  // Each refined; the largest N²/D (the smallest misfit) wins, the linear one on a tie. A scan
  // maximum within a step of the refined linear candidate is the same maximum (the step is half
  // the narrowest a peak can be): not refined again.
  const std::optional<double> refined = misfit.refine_around(linear, kPi / kMinScanAngles);
  double alpha = refined.value_or(linear);
  AngleMisfit::At best = misfit.at(alpha);
  double best_q = best.n * best.n / best.d;
  for (std::size_t i = 0; i < top.size() && top_q[i] >= 0.0; ++i) {
    const double scanned = -kPi + (top[i] + 1) * step;
    if (refined && std::abs(std::remainder(scanned - *refined, 2.0 * kPi)) < step) continue;
    const double a = misfit.refine_towards(scanned, step);
    const AngleMisfit::At f = misfit.at(a);
    const double q = f.n * f.n / f.d;
    if (q > best_q * (1.0 + 1e-12)) {
      alpha = a;
      best = f;
      best_q = q;
    }
  }
  return {best.n / best.d, wrap_angle(alpha), 0.0};
}

core::Expected<std::vector<std::string>, std::string> parse_gauge_header(std::string_view line) {
  line = clean_line(line);
  std::vector<std::string> ids;
  std::string why;
  bool first = true;
  for_each_field(line, [&](std::string_view field) {
    if (first) {
      first = false;
      if (field != "time_s") {
        why = "the header must begin with time_s (\"time_s,<gauge id>,...\"), not '" +
              std::string(field) + "'";
      }
      return why.empty();
    }
    if (field.empty()) {
      why = "gauge column " + std::to_string(ids.size() + 1) + " has an empty id";
      return false;
    }
    for (std::size_t i = 0; i < ids.size(); ++i) {
      if (ids[i] == field) {
        why = "gauge '" + std::string(field) + "' is given twice (gauge columns " +
              std::to_string(i + 1) + " and " + std::to_string(ids.size() + 1) + ")";
        return false;
      }
    }
    ids.emplace_back(field);
    return true;
  });
  if (!why.empty()) return why;
  if (ids.empty()) return std::string("the header names no gauge (\"time_s,<gauge id>,...\")");
  return ids;
}

core::Expected<std::optional<GaugeSample>, std::string> parse_gauge_line(std::string_view line,
                                                                         std::size_t gauges) {
  line = clean_line(line);
  if (line.empty() || line.front() == '#') return std::optional<GaugeSample>();
  const std::size_t fields =
      static_cast<std::size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  if (trim(line.substr(0, line.find(','))) == "time_s") {
    return std::string("a header line inside the data (the first header fixes the columns)");
  }
  if (fields != gauges + 1) {
    return "expected " + std::to_string(gauges + 1) + " fields (t and " + std::to_string(gauges) +
           (gauges == 1 ? " strain" : " strains") + "), not " + std::to_string(fields);
  }
  GaugeSample sample;
  sample.strains.reserve(gauges);
  std::string why;
  bool first = true;
  for_each_field(line, [&](std::string_view field) {
    if (first) {
      first = false;
      if (!to_number(field, sample.t)) {
        why = "the time '" + std::string(field) + "' is no number (or out of a double's range)";
      } else if (!std::isfinite(sample.t)) {
        why = "the time is not finite";
      }
      return why.empty();
    }
    const std::size_t column = sample.strains.size() + 1;
    double e = 0.0;
    if (!to_number(field, e)) {
      why = "the strain of gauge column " + std::to_string(column) + " ('" + std::string(field) +
            "') is no number (or out of a double's range)";
      return false;
    }
    if (!std::isfinite(e)) {
      why = "the strain of gauge column " + std::to_string(column) + " is not finite";
      return false;
    }
    sample.strains.push_back(e);
    return true;
  });
  if (!why.empty()) return why;
  return std::optional<GaugeSample>(std::move(sample));
}

}  // namespace peritwin::stream
