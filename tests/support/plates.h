// Small analytical test problems shared by the solver tests.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>
#include <vector>

#include "solver/fatigue/fatigue_engine.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"
#include "solver/statics/specimen.h"
#include "solver/statics/static_solver.h"

namespace peritwin::testing {

/// Rectangular plate [0,L]×[−H/2,H/2] under a uniform traction σ on its right edge layer, the
/// left edge layer on rollers (u = 0) and one left node pinned in y: uniaxial stress σ.
using TensionPlate = statics::Specimen;  // geometry, discretization, model, supports, loads

inline TensionPlate make_tension_plate(const model::Material& material,
                                       const model::ModelOptions& options, double length,
                                       double height, double dx, double sigma,
                                       const mesh::GridPerturbation& grid = {}) {
  TensionPlate p;
  p.geometry.thickness = 0.002;
  p.geometry.outline = {mesh::Rectangle{0.0, -0.5 * height, length, 0.5 * height}};
  p.disc = discretize(p.geometry, dx, 3.015 * dx, grid);
  p.model = model::build_model(p.disc, material, options, p.geometry.rigid_factor);
  const mesh::Region left = mesh::Region::of(mesh::Rectangle{0.0, -height, dx, height});
  const mesh::Region right =
      mesh::Region::of(mesh::Rectangle{length - dx, -height, length, height});
  p.supports.push_back({p.disc.nodes_in(left), true, false});
  p.supports.push_back({{p.disc.nearest_node({0.0, 0.0})}, true, true});
  p.loads.push_back({p.disc.nodes_in(right), {sigma * height * p.geometry.thickness, 0.0}, {}, {}});
  return p;
}

/// A small edge-notched plate in tension (24 × 16 nodes at Δx = 1 mm by default), the
/// peridynamic analogue of a fatigue coupon: the bottom edge layer clamped, an opening load P in
/// +y on the top edge layer and a sin α part in x (to exercise the load basis). The engine tests
/// only need something that cracks in a few hundred cycles.
inline statics::Specimen make_notched_plate(model::ModelKind kind, bool notched = true,
                                            int columns = 24, int rows = 16,
                                            double poisson_ratio = 0.33) {
  statics::Specimen p;
  const double dx = 0.001;
  p.geometry.thickness = 0.005;
  p.geometry.outline = {mesh::Rectangle{0.0, -0.5 * rows * dx, columns * dx, 0.5 * rows * dx}};
  if (notched) p.geometry.notches = {{"notch", {{-dx, 0.0}, {0.25 * columns * dx, 0.0}}}};
  p.disc = discretize(p.geometry, dx, 3.015 * dx);
  model::ModelOptions o;
  o.kind = kind;
  p.model = model::build_model(p.disc, model::Material{68e9, poisson_ratio, 0.0}, o, 200.0);
  const double h = 0.5 * rows * dx;
  p.supports.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1, -h, 1, -h + dx})), true, true});
  p.loads.push_back(
      {p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1, h - dx, 1, h})), {0, 1}, {}, {0.5, 0}});
  return p;
}

/// The largest stretch of an intact bond at load P (α = 0) on the undamaged specimen (a bond cut
/// by a notch "stretches" by the opening: left out); every bond's stretch into `all` if given.
inline double largest_intact_stretch(const statics::Specimen& p, double load,
                                     std::vector<double>* all = nullptr) {
  statics::StaticSolver probe(p.disc, p.model, p.supports, p.loads);
  EXPECT_TRUE(probe.solve().ok());
  std::vector<double> s;
  probe.stretch(load, 0.0, s);
  double smax = 0.0;
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (probe.intact()[b]) smax = std::max(smax, s[b]);
  }
  if (all != nullptr) *all = s;
  return smax;
}

/// The same total cycles and the same break events (bond, cycle, cause), in order.
inline void expect_same_breaks(const fatigue::FatigueEngine& a, const fatigue::FatigueEngine& b) {
  ASSERT_EQ(a.total_cycles(), b.total_cycles());
  ASSERT_EQ(a.break_events().size(), b.break_events().size());
  for (std::size_t e = 0; e < a.break_events().size(); ++e) {
    EXPECT_EQ(a.break_events()[e].bond, b.break_events()[e].bond) << "event " << e;
    EXPECT_EQ(a.break_events()[e].cycle, b.break_events()[e].cycle) << "event " << e;
    EXPECT_EQ(a.break_events()[e].cause, b.break_events()[e].cause) << "event " << e;
  }
}

/// Least-squares slope of values against coordinates.
inline double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(x.size());
  my /= static_cast<double>(y.size());
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxy / sxx;
}

/// Interior strains ε_xx = ∂u/∂x and ε_yy = ∂v/∂y from nodes more than `margin` from every edge.
inline std::pair<double, double> interior_strains(const mesh::Discretization& d,
                                                  const std::vector<double>& u, double margin) {
  const mesh::Rectangle& box = d.box;
  std::vector<double> xs, us, ys, vs;
  for (mesh::NodeIndex k = 0; k < d.num_nodes(); ++k) {
    const mesh::Point p = d.position[k];
    if (p.x < box.x_min + margin || p.x > box.x_max - margin || p.y < box.y_min + margin ||
        p.y > box.y_max - margin) {
      continue;
    }
    xs.push_back(p.x);
    us.push_back(u[2 * static_cast<std::size_t>(k)]);
    ys.push_back(p.y);
    vs.push_back(u[2 * static_cast<std::size_t>(k) + 1]);
  }
  return {slope(xs, us), slope(ys, vs)};
}

}  // namespace peritwin::testing

// Parameterized suites print their parameters as words (gtest's default for an enum class or a
// struct is its bytes, padding and pointers included, which differ from build to build).
namespace peritwin {

inline std::string model_kind_name(model::ModelKind kind) {
  return kind == model::ModelKind::bond_based ? "bond_based" : "state_based";
}
inline std::string kernel_name(model::Kernel kernel) {
  switch (kernel) {
    case model::Kernel::constant:
      return "constant";
    case model::Kernel::conical:
      return "conical";
    case model::Kernel::gaussian:
      return "gaussian";
  }
  return "unknown";
}
/// Found by argument-dependent lookup: gtest's printer of a ModelKind parameter.
inline void PrintTo(model::ModelKind kind, std::ostream* os) { *os << model_kind_name(kind); }

namespace testing {
/// Name generator of a suite parameterized by ModelKind (4th argument of
/// INSTANTIATE_TEST_SUITE_P): ".../bond_based", ".../state_based".
inline std::string model_kind_param_name(const ::testing::TestParamInfo<model::ModelKind>& info) {
  return model_kind_name(info.param);
}
}  // namespace testing

}  // namespace peritwin
