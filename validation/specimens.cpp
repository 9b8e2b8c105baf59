#include "validation/specimens.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "solver/statics/rigid_regions.h"
#include "solver/statics/static_solver.h"

namespace peritwin::validation {

double compact_tension_spacing(const CompactTensionSpec& spec, double target_nodes) {
  const double w = spec.width;
  const double area = 1.25 * w * 1.2 * w;
  const double height = 1.2 * w;
  const double rows = 2.0 * std::round(height / std::sqrt(area / target_nodes) / 2.0);
  return height / rows;
}

statics::Specimen make_compact_tension(const CompactTensionSpec& spec,
                                       const model::ModelOptions& options, double dx,
                                       double horizon_ratio) {
  const double w = spec.width;
  statics::Specimen s;
  s.name = "B1-CT";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back(mesh::Rectangle{0.0, -0.6 * w, 1.25 * w, 0.6 * w});
  const mesh::Circle upper_pin{{0.25 * w, 0.275 * w}, 0.125 * w};
  const mesh::Circle lower_pin{{0.25 * w, -0.275 * w}, 0.125 * w};
  s.geometry.rigid_regions = {mesh::Region::of(upper_pin), mesh::Region::of(lower_pin)};
  s.geometry.rigid_model = spec.rigid_model;
  s.initial_crack_tip = {0.25 * w + spec.initial_crack, 0.0};
  s.geometry.notches.push_back({"pre-crack", {{-dx, 0.0}, s.initial_crack_tip}});
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx);
  s.model =
      model::build_model(s.disc, s.material, options, statics::material_rigid_factor(s.geometry));
  s.ties = statics::rigid_region_ties(s.disc, s.model, s.geometry);
  for (const double side : {1.0, -1.0}) {
    const mesh::NodeIndex k = s.disc.nearest_node({1.25 * w, side * 0.5 * dx});
    s.supports.push_back({{k}, true, true});
  }
  s.loads.push_back({s.disc.nodes_in(mesh::Region::of(upper_pin)), {0.0, 1.0}, {}, {}});
  s.loads.push_back({s.disc.nodes_in(mesh::Region::of(lower_pin)), {0.0, -1.0}, {}, {}});
  return s;
}

double compact_tension_shear_grid_spacing(const CompactTensionShearSpec& spec, double dx) {
  // Rows sit at y = −h/2 + (k + 1/2)·dx; one lies on y = 0 when h/(2dx) − 1/2 is an integer.
  const double offset = 0.5 * spec.height / dx - 0.5;
  if (std::abs(offset - std::round(offset)) > 0.25) return dx;
  return spec.height / (2.0 * std::max(1.0, std::round(0.5 * spec.height / dx)));
}

CtsStressIntensity richard_cts_stress_intensity(const CompactTensionShearSpec& spec, double p,
                                                double alpha) {
  const double a = spec.crack_length, w = spec.width, q = a / (w - a);
  const double nominal = p * std::sqrt(std::numbers::pi * a) / (w * spec.thickness) / (1 - a / w);
  return {
      nominal * std::cos(alpha) * std::sqrt((0.26 + 2.65 * q) / (1 + 0.55 * q - 0.08 * q * q)),
      nominal * std::sin(alpha) * std::sqrt((-0.23 + 1.40 * q) / (1 - 0.67 * q + 2.08 * q * q))};
}

std::vector<statics::LoadTerm> rigid_fixture_loads_by_flexibility(const statics::Specimen& s) {
  const auto n = static_cast<Eigen::Index>(s.loads.size());
  if (n == 0 || n % 3 != 0) {
    throw std::invalid_argument("rigid_fixture_loads_by_flexibility: three pin loads per fixture");
  }
  const Eigen::Index fixtures = n / 3;
  // Each pin's point: the centroid of the nodes its load is spread over (the resultant's point).
  std::vector<mesh::Point> centre;
  for (const statics::LoadTerm& load : s.loads) centre.push_back(s.disc.centroid(load.nodes));
  auto disc_mean = [&](const std::vector<double>& u, Eigen::Index h, int component) {
    double sum = 0.0;
    const auto& nodes = s.loads[static_cast<std::size_t>(h)].nodes;
    for (const mesh::NodeIndex k : nodes) sum += u[2 * static_cast<std::size_t>(k) + component];
    return sum / static_cast<double>(nodes.size());
  };
  // C(2h + c, j): pin h's displacement component c under unit pin force component j (pin j/2,
  // x if j even, y if odd); three unit cases per factorization (the solver's three bases).
  Eigen::MatrixXd flexibility(2 * n, 2 * n);
  for (Eigen::Index first = 0; first < 2 * n; first += 3) {
    std::vector<statics::LoadTerm> unit;
    for (Eigen::Index j = first; j < std::min(first + 3, 2 * n); ++j) {
      statics::LoadTerm t{s.loads[static_cast<std::size_t>(j / 2)].nodes, {}, {}, {}};
      const mesh::Point f = (j % 2 == 0) ? mesh::Point{1.0, 0.0} : mesh::Point{0.0, 1.0};
      (j - first == 0 ? t.constant : j - first == 1 ? t.per_cos : t.per_sin) = f;
      unit.push_back(t);
    }
    statics::StaticSolver solver(s.disc, s.model, s.supports, unit, s.ties);
    if (!solver.solve().ok()) throw std::runtime_error("CTS fixture: the unit pin solve failed");
    for (Eigen::Index j = first; j < std::min(first + 3, 2 * n); ++j) {
      const auto& u = solver.basis_displacement(static_cast<statics::Basis>(j - first));
      for (Eigen::Index h = 0; h < n; ++h) {
        flexibility(2 * h, j) = disc_mean(u, h, 0);
        flexibility(2 * h + 1, j) = disc_mean(u, h, 1);
      }
    }
  }
  // Compatibility rows scaled to O(1) (C is of order 1e-9 m/N).
  const double scale = 1.0 / flexibility.cwiseAbs().maxCoeff();
  const Eigen::Index unknowns = 2 * n + 3 * fixtures;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(unknowns, unknowns);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(unknowns, 2);  // cos α and sin α parts
  for (Eigen::Index h = 0; h < n; ++h) {
    const Eigen::Index motion = 2 * n + 3 * (h / 3);  // U_x, U_y, θ of h's fixture
    const mesh::Point ref = centre[static_cast<std::size_t>(3 * (h / 3) + 1)];
    const mesh::Point arm{centre[static_cast<std::size_t>(h)].x - ref.x,
                          centre[static_cast<std::size_t>(h)].y - ref.y};
    a.block(2 * h, 0, 2, 2 * n) = scale * flexibility.block(2 * h, 0, 2, 2 * n);
    a(2 * h, motion) = -scale;
    a(2 * h, motion + 2) = scale * arm.y;
    a(2 * h + 1, motion + 1) = -scale;
    a(2 * h + 1, motion + 2) = -scale * arm.x;
    const Eigen::Index row = motion;  // the fixture's equilibrium rows
    a(row, 2 * h) = 1.0;
    a(row + 1, 2 * h + 1) = 1.0;
    a(row + 2, 2 * h) = -arm.y;
    a(row + 2, 2 * h + 1) = arm.x;
    const statics::LoadTerm& f = s.loads[static_cast<std::size_t>(h)];
    int part = 0;
    for (const mesh::Point& p : {f.per_cos, f.per_sin}) {
      rhs(row, part) += p.x;
      rhs(row + 1, part) += p.y;
      rhs(row + 2, part) += arm.x * p.y - arm.y * p.x;
      ++part;
    }
  }
  const Eigen::MatrixXd z = a.fullPivLu().solve(rhs);
  std::vector<statics::LoadTerm> loads = s.loads;
  for (Eigen::Index h = 0; h < n; ++h) {
    auto& load = loads[static_cast<std::size_t>(h)];
    load.per_cos = {z(2 * h, 0), z(2 * h + 1, 0)};
    load.per_sin = {z(2 * h, 1), z(2 * h + 1, 1)};
  }
  return loads;
}

namespace {

/// Ties that hold the pins of one fixture to a rigid-body motion (small rotation). Pin h's point is
/// the centroid of its node set and its displacement the mean over those nodes, as for a load
/// spread over them (and as rigid_fixture_loads_by_flexibility reads it). The n pins' 2n mean
/// displacements may only lie in the span of the three rigid modes (x, y, turn about the pins'
/// centroid), so each of the 2n − 3 orthonormal directions g orthogonal to that span becomes a tie
/// gᵀu = 0 of stiffness k. Their sum k·Σ g·gᵀ is k times the projector off the rigid modes: no
/// energy for a rigid motion of the pins. Works for collinear pins (three on one line), where
/// pairwise length ties would leave the middle one free to move across the line. A pin turns
/// freely: only its mean displacement is tied, so it passes a force and no moment.
std::vector<statics::Tie> rigid_body_ties(const mesh::Discretization& disc,
                                          const std::vector<std::vector<mesh::NodeIndex>>& pins,
                                          double k) {
  const auto n = static_cast<Eigen::Index>(pins.size());
  std::vector<mesh::Point> point;
  mesh::Point centroid{};
  for (const auto& nodes : pins) {
    const mesh::Point c = disc.centroid(nodes);
    point.push_back(c);
    centroid = {centroid.x + c.x / static_cast<double>(n),
                centroid.y + c.y / static_cast<double>(n)};
  }
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(2 * n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const mesh::Point p = point[static_cast<std::size_t>(i)];
    modes(2 * i, 0) = 1.0;
    modes(2 * i + 1, 1) = 1.0;
    modes(2 * i, 2) = -(p.y - centroid.y);
    modes(2 * i + 1, 2) = p.x - centroid.x;
  }
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(modes);
  const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(2 * n, 2 * n);
  std::vector<statics::Tie> ties;
  for (Eigen::Index c = 3; c < 2 * n; ++c) {  // Q's columns past the first three: the complement
    statics::Tie tie{{}, k};
    for (Eigen::Index i = 0; i < 2 * n; ++i) {
      const auto& nodes = pins[static_cast<std::size_t>(i / 2)];
      const double share = q(i, c) / static_cast<double>(nodes.size());
      for (const mesh::NodeIndex node : nodes)
        tie.terms.push_back({node, static_cast<int>(i % 2), share});
    }
    ties.push_back(tie);
  }
  return ties;
}

}  // namespace

statics::Specimen make_compact_tension_shear(const CompactTensionShearSpec& spec,
                                             const model::ModelOptions& options, double dx,
                                             double horizon_ratio) {
  statics::Specimen s;
  s.name = "B2-CTS";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back(
      mesh::Rectangle{0.0, -0.5 * spec.height, spec.width, 0.5 * spec.height});
  s.initial_crack_tip = {spec.crack_length, 0.0};
  s.geometry.notches.push_back({"pre-crack", {{-dx, 0.0}, s.initial_crack_tip}});
  const double xc = 0.5 * spec.width;
  const double r = 0.5 * spec.hole_diameter;
  const double xs[3] = {xc - 0.5 * spec.hole_spacing, xc, xc + 0.5 * spec.hole_spacing};
  std::vector<mesh::Circle> upper, lower;
  for (double x : xs) {
    upper.push_back({{x, spec.hole_offset}, r});
    lower.push_back({{x, -spec.hole_offset}, r});
  }
  for (const auto& c : upper) s.geometry.rigid_regions.push_back(mesh::Region::of(c));
  for (const auto& c : lower) s.geometry.rigid_regions.push_back(mesh::Region::of(c));
  s.geometry.rigid_model = mesh::RigidModel::stiff_material;  // 000 Sec. 6.2's pin material
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx, spec.grid);
  s.model = model::build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  // 000 Eq. (51): F1 (upper left, y), F2 (middle, x), F3 (upper right, y).
  const double ef = spec.hole_offset / spec.hole_spacing;
  std::vector<mesh::Circle> loaded_holes = upper;
  struct PinForce {  // per N of P: F = P·(cos α·per_cos + sin α·per_sin)
    mesh::Point per_cos;
    mesh::Point per_sin;
  };
  std::vector<PinForce> forces = {
      {{0.0, 0.5}, {0.0, ef}}, {{}, {-1.0, 0.0}}, {{0.0, 0.5}, {0.0, -ef}}};
  if (spec.lower_holes_fixed) {
    for (const auto& c : lower)
      s.supports.push_back({s.disc.nodes_in(mesh::Region::of(c)), true, true});
  } else {
    // The lower half of the device applies the point reflection of the upper forces (the CTS
    // loading is antisymmetric under a half turn): −F3 at the lower left, +P sin α in x at the
    // middle, −F1 at the lower right; each half is then in force and moment equilibrium.
    loaded_holes.insert(loaded_holes.end(), lower.begin(), lower.end());
    forces.push_back({{0.0, -0.5}, {0.0, ef}});
    forces.push_back({{}, {1.0, 0.0}});
    forces.push_back({{0.0, -0.5}, {0.0, -ef}});
    s.supports.push_back({{s.disc.nearest_node(lower[1].centre)}, true, true});
    s.supports.push_back({{s.disc.nearest_node(lower[2].centre)}, false, true});
  }
  for (std::size_t h = 0; h < loaded_holes.size(); ++h)
    s.loads.push_back({s.disc.nodes_in(mesh::Region::of(loaded_holes[h])),
                       {},
                       forces[h].per_cos,
                       forces[h].per_sin});
  if (spec.rigid_fixtures) {
    // Richard's loading device: the pin centres of each loaded half move as one rigid body, the
    // holes turning freely on their pins (frictionless: a pin passes a force, no moment). The
    // pins keep their Eq. (51) forces; the fixture shares them out by compatibility in every
    // solve, so the split follows the crack as it grows. Tie stiffness: 10·rigid_factor·E·t,
    // about 10³ times the specimen's stiffness at a pin (its flexibility there is ~1e-9 m/N).
    const double k = 10.0 * s.geometry.rigid_factor * spec.material.youngs_modulus * spec.thickness;
    for (std::size_t fixture = 0; fixture < loaded_holes.size() / 3; ++fixture) {
      std::vector<std::vector<mesh::NodeIndex>> pins;
      for (std::size_t h = 0; h < 3; ++h) pins.push_back(s.loads[3 * fixture + h].nodes);
      const auto ties = rigid_body_ties(s.disc, pins, k);
      s.ties.insert(s.ties.end(), ties.begin(), ties.end());
    }
  }
  return s;
}

namespace {

struct PlaneStress {
  double xx, yy, xy;
};

/// Williams near-tip stresses per unit K_I and per unit K_II at (r, θ), crack along θ = π
/// (Anderson, Fracture Mechanics, Table 2.1).
PlaneStress mode_i_stress(double r, double th) {
  const double f = 1.0 / std::sqrt(2.0 * std::numbers::pi * r);
  const double c = std::cos(th / 2), s = std::sin(th / 2);
  const double c3 = std::cos(1.5 * th), s3 = std::sin(1.5 * th);
  return {f * c * (1 - s * s3), f * c * (1 + s * s3), f * s * c * c3};
}

PlaneStress mode_ii_stress(double r, double th) {
  const double f = 1.0 / std::sqrt(2.0 * std::numbers::pi * r);
  const double c = std::cos(th / 2), s = std::sin(th / 2);
  const double c3 = std::cos(1.5 * th), s3 = std::sin(1.5 * th);
  return {-f * s * (2 + c * c3), f * s * c * c3, f * c * (1 - s * s3)};
}

mesh::Point traction(const PlaneStress& sigma, mesh::Point normal) {
  return {sigma.xx * normal.x + sigma.xy * normal.y, sigma.xy * normal.x + sigma.yy * normal.y};
}

}  // namespace

statics::Specimen make_k_field_plate(const KFieldPlateSpec& spec,
                                     const model::ModelOptions& options, double dx,
                                     double horizon_ratio) {
  const double l = std::round(spec.half_size / dx) * dx;  // y = 0 falls between node rows
  statics::Specimen s;
  s.name = "K-field plate";
  s.material = spec.material;
  s.geometry.thickness = spec.thickness;
  s.geometry.outline.push_back(mesh::Rectangle{-l, -l, l, l});
  s.initial_crack_tip = {0.0, 0.0};
  s.geometry.notches.push_back({"pre-crack", {{-l - dx, 0.0}, s.initial_crack_tip}});
  s.disc = discretize(s.geometry, dx, horizon_ratio * dx, spec.grid);
  s.model = model::build_model(s.disc, s.material, options, s.geometry.rigid_factor);
  const double area = dx * spec.thickness;
  for (mesh::NodeIndex n = 0; n < s.disc.num_nodes(); ++n) {
    const mesh::Point p = s.disc.position[n];
    const mesh::Point normal{(p.x > l - dx ? 1.0 : 0.0) - (p.x < -l + dx ? 1.0 : 0.0),
                             (p.y > l - dx ? 1.0 : 0.0) - (p.y < -l + dx ? 1.0 : 0.0)};
    if (normal.x == 0.0 && normal.y == 0.0) continue;
    const double r = std::hypot(p.x, p.y);
    const double th = std::atan2(p.y, p.x);
    PlaneStress mode_i = mode_i_stress(r, th);
    mode_i.xx += spec.t_over_ki;
    const mesh::Point f_i = traction(mode_i, normal);
    const mesh::Point f_ii = traction(mode_ii_stress(r, th), normal);
    s.loads.push_back({{n}, {}, {f_i.x * area, f_i.y * area}, {-f_ii.x * area, -f_ii.y * area}});
  }
  s.supports.push_back({{s.disc.nearest_node({l, 0.0})}, true, true});
  s.supports.push_back({{s.disc.nearest_node({l, -0.5 * l})}, true, false});
  return s;
}

}  // namespace peritwin::validation
