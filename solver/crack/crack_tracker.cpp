#include "solver/crack/crack_tracker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>

namespace peritwin::crack {

CrackTracker::CrackTracker(const mesh::Discretization& disc, std::vector<mesh::Notch> notches,
                           CrackTrackerOptions options)
    : disc_(disc), notches_(std::move(notches)), options_(options) {
  if (options_.kink_distance <= 0.0) options_.kink_distance = 8.0 * disc.horizon / 3.0;
}

std::vector<CrackMetrics> CrackTracker::measure(const std::vector<double>& node_damage) const {
  return measure(node_damage, nullptr);
}

std::vector<CrackMetrics> CrackTracker::measure(const std::vector<double>& node_damage,
                                                const std::vector<std::uint8_t>& intact) const {
  return measure(node_damage, &intact);
}

std::vector<CrackMetrics> CrackTracker::measure(const std::vector<double>& node_damage,
                                                const std::vector<std::uint8_t>* intact) const {
  std::vector<CrackMetrics> cracks;
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  // Path steps join neighbouring damaged nodes: the diagonal neighbour (√2Δx) on the regular grid,
  // plus what a perturbed grid can add to a pair's distance (2√2·amplitude·Δx).
  const double link = (1.5 + 2.0 * std::numbers::sqrt2 * disc_.perturbation.amplitude) * disc_.dx;
  for (std::size_t n = 0; n < notches_.size(); ++n) {
    const mesh::Segment notch = notches_[n].last_segment();  // the tip is its end b
    const double len = std::hypot(notch.b.x - notch.a.x, notch.b.y - notch.a.y);
    const mesh::Point dir{(notch.b.x - notch.a.x) / len, (notch.b.y - notch.a.y) / len};
    CrackMetrics crack;
    crack.notch = static_cast<int>(n);
    crack.origin = notch.b;
    crack.tip = notch.b;
    // Damaged nodes ahead of the notch tip (the notch's own faces are damaged too: skip them).
    auto ahead = [&](std::size_t k) {
      const double ax = disc_.position[k].x - notch.b.x;
      const double ay = disc_.position[k].y - notch.b.y;
      return ax * dir.x + ay * dir.y > -0.5 * disc_.dx;
    };
    std::vector<double> dist(nn, std::numeric_limits<double>::infinity());
    std::vector<std::int32_t> parent(nn, -1);
    using Item = std::pair<double, std::size_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
    for (std::size_t k = 0; k < nn; ++k) {
      if (node_damage[k] < options_.phase_switch_damage || !ahead(k)) continue;
      const double d = std::hypot(disc_.position[k].x - notch.b.x, disc_.position[k].y - notch.b.y);
      if (d <= disc_.horizon) {
        dist[k] = d;
        queue.emplace(d, k);
      }
    }
    // Dijkstra over damaged nodes joined by bonds no longer than `link`.
    while (!queue.empty()) {
      const auto [d, k] = queue.top();
      queue.pop();
      if (d > dist[k]) continue;
      for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
        const auto b = disc_.family_bonds[static_cast<std::size_t>(f)];
        const double xi = disc_.bond_length[static_cast<std::size_t>(b)];
        if (xi > link) continue;
        const auto j =
            static_cast<std::size_t>(disc_.other_end(b, static_cast<mesh::NodeIndex>(k)));
        if (node_damage[j] < options_.phase_switch_damage || !ahead(j)) continue;
        if (d + xi < dist[j]) {
          dist[j] = d + xi;
          parent[j] = static_cast<std::int32_t>(k);
          queue.emplace(d + xi, j);
        }
      }
    }
    std::size_t tip = nn;
    for (std::size_t k = 0; k < nn; ++k) {
      if (!std::isfinite(dist[k])) continue;
      ++crack.nodes;
      if (tip == nn || dist[k] > dist[tip]) tip = k;
    }
    if (tip != nn) {
      crack.tip = disc_.position[tip];
      crack.length = dist[tip];
      crack.projected_length =
          (crack.tip.x - notch.b.x) * dir.x + (crack.tip.y - notch.b.y) * dir.y;
      if (intact != nullptr) {
        // The crack's line over its last 2δ; the notch's line while the crack is shorter (the
        // principal axis of a few nodes on two rows is not the crack's).
        const double back = 2.0 * disc_.horizon;
        CrackLine line{notch.b, dir};
        if (crack.length >= back) line = tip_line(disc_, dist, tip, back);
        // A seed tip's path distance is its straight distance from the notch tip, partly across
        // the crack line (Δx/2 at the first node): its front counts from its projection on the
        // notch, as the cut does (else the front would step back at the first link).
        const double base = parent[tip] < 0 ? crack.projected_length : crack.length;
        crack.subgrid_length = subgrid_crack_length(
            crack.length, base - crack.length + front_progress(disc_, *intact, crack.tip, line),
            disc_.dx);
      }
      const double at = std::min(options_.kink_distance, crack.length);
      // β is measured on the branch that leads to the tip: where the crack branches (near-pure
      // mode II grows one branch up and one down) the centroid of every node `at` along the path
      // would average the branches to β ≈ 0. The anchor is the node on the tip's path nearest to
      // path distance `at`; the centroid takes the band's nodes within a horizon of it.
      std::size_t anchor = tip;
      for (auto c = static_cast<std::int32_t>(tip); c >= 0;
           c = parent[static_cast<std::size_t>(c)]) {
        const auto cu = static_cast<std::size_t>(c);
        if (std::abs(dist[cu] - at) < std::abs(dist[anchor] - at)) anchor = cu;
      }
      const mesh::Point a = disc_.position[anchor];
      double cx = 0, cy = 0;
      int count = 0;
      for (std::size_t k = 0; k < nn; ++k) {
        const mesh::Point p = disc_.position[k];
        if (std::isfinite(dist[k]) && std::abs(dist[k] - at) <= disc_.dx &&
            std::hypot(p.x - a.x, p.y - a.y) <= disc_.horizon) {
          cx += p.x;
          cy += p.y;
          ++count;
        }
      }
      if (count > 0 && at > 0) {
        const double vx = cx / count - notch.b.x;
        const double vy = cy / count - notch.b.y;
        crack.kink_angle = std::atan2(dir.x * vy - dir.y * vx, dir.x * vx + dir.y * vy);
      }
    }
    cracks.push_back(crack);
  }
  return cracks;
}

CrackLine tip_line(const mesh::Discretization& disc, const std::vector<double>& dist,
                   std::size_t tip, double back) {
  const double from = dist[tip] - back;
  double cx = 0, cy = 0;
  int count = 0;
  for (std::size_t k = 0; k < dist.size(); ++k) {
    if (std::isfinite(dist[k]) && dist[k] >= from) {
      cx += disc.position[k].x;
      cy += disc.position[k].y;
      ++count;
    }
  }
  if (count < 2) return {disc.position[tip], {}};
  cx /= count;
  cy /= count;
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t k = 0; k < dist.size(); ++k) {
    if (std::isfinite(dist[k]) && dist[k] >= from) {
      const double dx = disc.position[k].x - cx, dy = disc.position[k].y - cy;
      sxx += dx * dx;
      sxy += dx * dy;
      syy += dy * dy;
    }
  }
  // Major axis of the 2x2 scatter matrix.
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  mesh::Point d{std::cos(angle), std::sin(angle)};
  const mesh::Point p = disc.position[tip];
  if ((p.x - cx) * d.x + (p.y - cy) * d.y < 0) d = {-d.x, -d.y};
  return {{cx, cy}, d};
}

double front_progress(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                      mesh::Point tip, const CrackLine& line) {
  const double dx = disc.dx;
  const mesh::Point d = line.direction, n{-d.y, d.x}, c = line.point;
  const double from = (tip.x - c.x) * d.x + (tip.y - c.y) * d.y - dx;  // s_t − Δx
  const auto bins = static_cast<std::size_t>(std::ceil((disc.horizon + 2.0 * dx) / dx - 1e-9));
  std::vector<int> total(bins, 0), broken(bins, 0);
  // A bond crossing the window has both ends within its reach of the window's nodes.
  const double scan = 2.0 * disc.horizon + 3.0 * dx;
  for (std::size_t k = 0; k < disc.position.size(); ++k) {
    const mesh::Point pk = disc.position[k];
    if (std::hypot(pk.x - tip.x, pk.y - tip.y) > scan) continue;
    for (auto f = disc.family_offset[k]; f < disc.family_offset[k + 1]; ++f) {
      const auto b = static_cast<std::size_t>(disc.family_bonds[static_cast<std::size_t>(f)]);
      if (static_cast<std::size_t>(disc.bond_i[b]) != k) continue;  // each bond once
      const mesh::Point pj = disc.position[static_cast<std::size_t>(disc.bond_j[b])];
      const double ni = (pk.x - c.x) * n.x + (pk.y - c.y) * n.y;
      const double nj = (pj.x - c.x) * n.x + (pj.y - c.y) * n.y;
      if ((ni < 0.0) == (nj < 0.0)) continue;  // does not cross the line
      const double si = (pk.x - c.x) * d.x + (pk.y - c.y) * d.y;
      const double sj = (pj.x - c.x) * d.x + (pj.y - c.y) * d.y;
      const double u = (si + (sj - si) * ni / (ni - nj) - from) / dx;
      if (u < 0.0 || u >= static_cast<double>(bins)) continue;
      const auto i = static_cast<std::size_t>(u);
      ++total[i];
      if (!intact[b]) ++broken[i];
    }
  }
  double cut = 0.0;
  for (std::size_t i = 0; i < bins; ++i) {
    if (total[i] > 0) cut += dx * broken[i] / total[i];
  }
  return cut - dx;
}

double subgrid_crack_length(double node_length, double progress, double dx) {
  const double a = std::max(node_length + progress - kSubgridLag * dx, node_length - 0.5 * dx);
  return std::max(0.0, std::min(a, node_length + 0.5 * dx));
}

FaceNodePair extrapolation_face_nodes(const mesh::Discretization& disc, mesh::Point tip,
                                      mesh::Point direction, double r) {
  const mesh::Point normal{-direction.y, direction.x};
  const mesh::Point behind{tip.x - r * direction.x, tip.y - r * direction.y};
  FaceNodePair pair;
  pair.upper_target = {behind.x + 0.5 * disc.dx * normal.x, behind.y + 0.5 * disc.dx * normal.y};
  pair.lower_target = {behind.x - 0.5 * disc.dx * normal.x, behind.y - 0.5 * disc.dx * normal.y};
  pair.upper = disc.nearest_node(pair.upper_target);
  pair.lower = disc.nearest_node(pair.lower_target);
  return pair;
}

bool separated_by_crack(const mesh::Discretization& disc, const std::vector<std::uint8_t>& intact,
                        mesh::NodeIndex a, mesh::NodeIndex b) {
  const auto k = static_cast<std::size_t>(a);
  for (auto f = disc.family_offset[k]; f < disc.family_offset[k + 1]; ++f) {
    const auto bond = disc.family_bonds[static_cast<std::size_t>(f)];
    if (disc.other_end(bond, a) == b) return intact[static_cast<std::size_t>(bond)] == 0;
  }
  return false;
}

StressIntensity stress_intensity_by_extrapolation(const mesh::Discretization& disc,
                                                  const std::vector<double>& u, mesh::Point tip,
                                                  mesh::Point direction, double r1, double r2,
                                                  double mu, double kappa) {
  const mesh::Point normal{-direction.y, direction.x};
  // Face jumps [u_t, u_n] (upper minus lower) at distance r behind the tip; half of it is the
  // displacement of one face relative to the crack line, u(r, π) of 001 Eq. (57)-(58).
  auto half_jump = [&](double r, double& ut, double& un, double& r_actual) {
    const FaceNodePair pair = extrapolation_face_nodes(disc, tip, direction, r);
    const auto up = static_cast<std::size_t>(pair.upper);
    const auto low = static_cast<std::size_t>(pair.lower);
    const double jx = u[2 * up] - u[2 * low];
    const double jy = u[2 * up + 1] - u[2 * low + 1];
    ut = 0.5 * (jx * direction.x + jy * direction.y);
    un = 0.5 * (jx * normal.x + jy * normal.y);
    const mesh::Point mid{0.5 * (disc.position[up].x + disc.position[low].x),
                          0.5 * (disc.position[up].y + disc.position[low].y)};
    r_actual = (tip.x - mid.x) * direction.x + (tip.y - mid.y) * direction.y;
  };
  double ut1, un1, ra, ut2, un2, rb;
  half_jump(r1, ut1, un1, ra);
  half_jump(r2, ut2, un2, rb);
  const double scale = 2 * mu * std::sqrt(2 * std::numbers::pi) / (kappa + 1);
  // 001 Eq. (62)-(63): linear extrapolation of u·r^(-1/2) to r = 0.
  auto extrapolate = [&](double v1, double v2) {
    return scale * (v1 * rb / std::sqrt(ra) - v2 * ra / std::sqrt(rb)) / (rb - ra);
  };
  return {extrapolate(un1, un2), extrapolate(ut1, ut2)};
}

double t_stress_from_crack_faces(const mesh::Discretization& disc, const std::vector<double>& u,
                                 mesh::Point tip, double r1, double r2, double youngs_modulus) {
  double sum = 0.0;
  int count = 0;
  const auto steps = static_cast<int>(std::floor((r2 - r1) / disc.dx + 1e-9));
  for (int i = 0; i <= steps; ++i) {
    const double r = r1 + i * disc.dx;
    for (const double side : {0.5, -0.5}) {
      auto ux = [&](double x) {
        return u[2 * static_cast<std::size_t>(disc.nearest_node({x, tip.y + side * disc.dx}))];
      };
      sum += (ux(tip.x - r + disc.dx) - ux(tip.x - r - disc.dx)) / (2 * disc.dx);
      ++count;
    }
  }
  return count > 0 ? youngs_modulus * sum / count : 0.0;
}

WilliamsFit williams_series_fit(const mesh::Discretization& disc, const std::vector<double>& u,
                                mesh::Point tip, mesh::Point direction, double r_in, double r_out,
                                int terms, double mu, double kappa) {
  const mesh::Point normal{-direction.y, direction.x};
  std::vector<std::size_t> annulus;
  for (std::size_t i = 0; i < disc.position.size(); ++i) {
    const double dx = disc.position[i].x - tip.x, dy = disc.position[i].y - tip.y;
    const double r = std::hypot(dx, dy);
    if (r >= r_in && r <= r_out) annulus.push_back(i);
  }
  WilliamsFit fit;
  fit.nodes = static_cast<int>(annulus.size());
  const int unknowns = 2 * terms + 2;  // aₙ, bₙ, rigid translation (t, n)
  if (fit.nodes < unknowns) return fit;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * fit.nodes, unknowns);
  Eigen::VectorXd b(2 * fit.nodes);
  for (int row = 0; row < fit.nodes; ++row) {
    const std::size_t i = annulus[static_cast<std::size_t>(row)];
    const double dx = disc.position[i].x - tip.x, dy = disc.position[i].y - tip.y;
    const double xt = dx * direction.x + dy * direction.y;  // along the crack
    const double yn = dx * normal.x + dy * normal.y;        // across it
    const double r = std::hypot(xt, yn), theta = std::atan2(yn, xt);
    const Eigen::Index rt = 2 * row, rn = 2 * row + 1;
    b(rt) = u[2 * i] * direction.x + u[2 * i + 1] * direction.y;
    b(rn) = u[2 * i] * normal.x + u[2 * i + 1] * normal.y;
    for (int n = 1; n <= terms; ++n) {
      const double h = 0.5 * n, sign = (n % 2 == 0) ? 1.0 : -1.0;
      const double scale = std::pow(r, h) / (2 * mu);
      const Eigen::Index ca = n - 1, cb = terms + n - 1;
      a(rt, ca) =
          scale * ((kappa + h + sign) * std::cos(h * theta) - h * std::cos((h - 2) * theta));
      a(rn, ca) =
          scale * ((kappa - h - sign) * std::sin(h * theta) + h * std::sin((h - 2) * theta));
      a(rt, cb) =
          scale * ((kappa + h - sign) * std::sin(h * theta) - h * std::sin((h - 2) * theta));
      a(rn, cb) =
          scale * (-(kappa - h + sign) * std::cos(h * theta) - h * std::cos((h - 2) * theta));
    }
    a(rt, 2 * terms) = 1.0;
    a(rn, 2 * terms + 1) = 1.0;
  }
  // Columns scaled to unit norm: r^(n/2) spans orders of magnitude over the annulus.
  const Eigen::VectorXd norms = a.colwise().norm().transpose();
  const Eigen::VectorXd y =
      (a * norms.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(b).cwiseQuotient(norms);
  fit.k_i = std::sqrt(2 * std::numbers::pi) * y(0);
  fit.k_ii = std::sqrt(2 * std::numbers::pi) * y(terms);
  fit.t_stress = 4 * y(1);
  fit.fitted = true;
  return fit;
}

double kolosov_kappa(double poisson_ratio, model::PlaneCondition plane) {
  return plane == model::PlaneCondition::plane_strain ? 3 - 4 * poisson_ratio
                                                      : (3 - poisson_ratio) / (1 + poisson_ratio);
}

double compact_tension_delta_k(double delta_p, double thickness, double width, double q) {
  const double a = q / width;  // 000 Eq. (A2b)
  return delta_p / (thickness * std::sqrt(width)) * (2 + a) / std::pow(1 - a, 1.5) *
         (0.886 + 4.64 * a - 13.32 * a * a + 14.72 * a * a * a - 5.6 * a * a * a * a);
}

}  // namespace peritwin::crack
