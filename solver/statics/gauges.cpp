#include "solver/statics/gauges.h"

#include <cmath>
#include <limits>

#include "solver/statics/pd_strain.h"

namespace peritwin::statics {

std::vector<mesh::NodeIndex> gauge_nodes(const mesh::Discretization& disc, const GaugeGeometry& g) {
  std::vector<mesh::NodeIndex> nodes;
  const double tx = std::cos(g.angle), ty = std::sin(g.angle);
  const double slack = 1.0 + 1e-9;
  const double across = 0.5 * disc.dx * slack;
  const double along = 0.5 * g.length * slack;
  if (g.length > 0.0) {
    for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
      const double rx = disc.position[static_cast<std::size_t>(k)].x - g.at.x;
      const double ry = disc.position[static_cast<std::size_t>(k)].y - g.at.y;
      if (std::abs(rx * tx + ry * ty) <= along && std::abs(-rx * ty + ry * tx) <= across) {
        nodes.push_back(k);
      }
    }
  }
  if (nodes.empty()) {
    const mesh::NodeIndex k = disc.nearest_node(g.at);
    if (k >= 0) nodes.push_back(k);
  }
  return nodes;
}

double pd_normal_strain(const mesh::Discretization& disc, std::span<const std::uint8_t> intact,
                        std::span<const double> u, mesh::NodeIndex k, double angle) {
  const auto h = pd_displacement_gradient(disc, intact, u, k);
  if (!h) return std::numeric_limits<double>::quiet_NaN();
  const double c = std::cos(angle), s = std::sin(angle);
  // n·sym(H)·n = H_xx c² + (H_xy + H_yx) c s + H_yy s².
  return h->xx * c * c + (h->xy + h->yx) * c * s + h->yy * s * s;
}

std::array<double, 3> gauge_influence(const StaticSolver& solver,
                                      const std::vector<mesh::NodeIndex>& nodes, double angle) {
  std::array<double, 3> c{};
  const auto& disc = solver.discretization();
  for (int b = 0; b < 3; ++b) {
    const auto& u = solver.basis_displacement(static_cast<Basis>(b));
    double sum = 0.0;
    int counted = 0;
    for (const mesh::NodeIndex k : nodes) {
      const double e = pd_normal_strain(disc, solver.intact(), u, k, angle);
      if (std::isnan(e)) continue;
      sum += e;
      ++counted;
    }
    c[static_cast<std::size_t>(b)] =
        counted > 0 ? sum / counted : std::numeric_limits<double>::quiet_NaN();
  }
  return c;
}

double gauge_strain(const std::array<double, 3>& c, double p, double alpha) {
  return p * (c[0] + std::cos(alpha) * c[1] + std::sin(alpha) * c[2]);
}

}  // namespace peritwin::statics
