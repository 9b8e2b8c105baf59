// estimate_resources (config/resources.h): lattice counts of the outline, the family sums of
// the horizon, the nested-dissection bound of the factor and the bytes of each part.
#include "config/resources.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "solver/fatigue/law_registry.h"

namespace peritwin::config {

namespace {

// Bytes per item, read off the code that allocates them (8 = double, 4 = int32, 1 = uint8).
// Discretization (solver/mesh/discretization.h): position 16, volume 8, rigid 1, no_fail 1,
// family_offset 4 per node; bond_i, bond_j 8, bond_length 8, bond_cos, bond_sin 16,
// bond_volume_factor 8, bond_precut 1, family_bonds 2·4 per bond; the lattice of the bounding box
// (4 per cell) while discretize runs.
constexpr double kDiscretizationNodeBytes = 30.0;
constexpr double kDiscretizationBondBytes = 49.0;
constexpr double kLatticeCellBytes = 4.0;
// PdModel (solver/model/pd_model.h): bond_stiffness 8 per bond; state-based also
// dilatation_weight 8 per bond and dilatation_stiffness 8 per node; with material scatter
// (E_std > 0) node_youngs_modulus 8 per node.
constexpr double kModelBondBytes = 8.0;
constexpr double kStateBasedBondBytes = 8.0;
constexpr double kStateBasedNodeBytes = 8.0;
constexpr double kScatterNodeBytes = 8.0;
// One FatigueEngine (solver/fatigue/fatigue_engine.h): EngineState anchor_life 8 and intact 1,
// rate_ 8, phase_ 1, breakable_ 1, stretch_ 8 per bond, node_damage_ 8 per node; the exported
// copy of anchor_life and intact the twin and the life jobs hold (9 per bond); the bilinear law's
// damage and max_stretch (16 per bond, in the state and in its copy). Its StaticSolver
// (solver/statics/static_solver.h): intact_ 1, factor_ 8, reference_ 8, the three basis stretches
// s_ 24 per bond; the three basis displacements u_ 48, free_index_ 8, grounded_ 1 per node.
constexpr double kEngineBondBytes = 27.0 + 9.0 + 41.0;
constexpr double kBilinearBondBytes = 32.0;
constexpr double kEngineNodeBytes = 8.0 + 48.0 + 8.0 + 1.0;
// The assembled upper triangle (Eigen, column-major): value 8 + row index 4 per entry.
constexpr double kMatrixEntryBytes = 12.0;
// The Cholesky factor: CHOLMOD's supernodal values (8 per entry of xsize) and, from the first
// rank update on, the simplicial LDLᵀ (value 8 + row index 4 per entry); both exist while the
// first update converts the factor and while the engine rebuilds its solver
// (refactor_every_resolves), so 20 per entry. The same reserve covers the assembly's temporaries
// (triplets and Gᵀ·G, < 200 bytes per bond, freed before the factorization).
constexpr double kFactorEntryBytes = 8.0 + 12.0;
// nnz(L) ≈ κ·d²·w²·N·log2(√N/w): see resources.h; κ bounds every measurement in docs/limits.md.
constexpr double kNestedDissection = 5.0;
// The slab sweep takes up to 2R slabs × R rectangles × (1 + H holes) steps; beyond this many the
// bounding box's lattice is used instead (an over-estimate), so that no outline stalls parsing.
constexpr double kMaxSweepSteps = 5e7;
// Any count above this is far beyond every limit; clamping keeps inf − inf (NaN) out.
constexpr double kHuge = 1e30;

double finite_or_huge(double v) { return std::isfinite(v) ? std::min(v, kHuge) : kHuge; }

/// F and S of resources.h for δ = horizon on a grid of spacing dx, by discretize()'s rule
/// (an offset (p, q) ≠ 0 belongs when dx·hypot(p, q) ≤ δ).
struct FamilySums {
  double family = 0.0;  ///< F
  double edge = 0.0;    ///< S
};

FamilySums family_sums(double dx, double horizon) {
  const double ratio = horizon / dx;
  FamilySums sums;
  if (!(ratio <= 64.0)) {  // continuum: π·m² lattice points, ∫∫ over the half disc of y = 2m³/3
    const double m = finite_or_huge(ratio);
    sums.family = finite_or_huge(std::numbers::pi * m * m);
    sums.edge = finite_or_huge(2.0 * m * m * m / 3.0);
    return sums;
  }
  const int reach = static_cast<int>(std::floor(ratio)) + 1;
  for (int q = -reach; q <= reach; ++q) {
    for (int p = -reach; p <= reach; ++p) {
      if (p == 0 && q == 0) continue;
      if (dx * std::hypot(static_cast<double>(p), static_cast<double>(q)) > horizon) continue;
      sums.family += 1.0;
      if (q > 0) sums.edge += q;
    }
  }
  return sums;
}

/// Cell centres x0 + (i + ½)·dx, i ∈ [0, n), below v (strictly) and at or below v.
struct Axis {
  double origin = 0.0;
  double dx = 1.0;
  double count = 0.0;
  [[nodiscard]] double below(double v) const {
    return std::clamp(std::ceil((v - origin) / dx - 0.5), 0.0, count);
  }
  [[nodiscard]] double at_or_below(double v) const {
    return std::clamp(std::floor((v - origin) / dx - 0.5) + 1.0, 0.0, count);
  }
};

/// ∫_0^x √(r² − t²) dt for |x| ≤ r.
double half_chord_integral(double x, double r) {
  const double t = std::clamp(x, -r, r);
  return 0.5 * (t * std::sqrt(std::max(0.0, r * r - t * t)) + r * r * std::asin(t / r));
}

/// Area of the disc (centre at the origin, radius r) inside [x0, x1] × [y0, y1], exactly: the
/// chord's clipped height is piecewise y1 or √(r²−x²) above and y0 or −√(r²−x²) below, with the
/// pieces cut where √(r²−x²) = |y0| or |y1|.
double disc_rectangle_area(double r, double x0, double x1, double y0, double y1) {
  x0 = std::max(x0, -r);
  x1 = std::min(x1, r);
  if (!(x1 > x0) || !(y1 > y0)) return 0.0;
  std::array<double, 6> cuts{x0, x1, x0, x0, x0, x0};
  std::size_t n = 2;
  for (const double y : {y0, y1}) {
    if (std::abs(y) < r) {
      const double c = std::sqrt(r * r - y * y);
      for (const double x : {-c, c}) {
        if (x > x0 && x < x1) cuts[n++] = x;
      }
    }
  }
  for (std::size_t k = 1; k < n; ++k) {  // insertion sort of at most 6
    for (std::size_t j = k; j > 0 && cuts[j] < cuts[j - 1]; --j) std::swap(cuts[j], cuts[j - 1]);
  }
  double area = 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double a = cuts[k], b = cuts[k + 1];
    if (!(b > a)) continue;
    const double mid = 0.5 * (a + b);
    const double s = std::sqrt(std::max(0.0, r * r - mid * mid));
    const bool top_is_chord = s < y1;
    const bool bottom_is_chord = -s > y0;
    if ((top_is_chord ? s : y1) <= (bottom_is_chord ? -s : y0)) continue;
    const double chords = (top_is_chord ? 1.0 : 0.0) + (bottom_is_chord ? 1.0 : 0.0);
    const double flat = (top_is_chord ? 0.0 : y1) - (bottom_is_chord ? 0.0 : y0);
    area += chords * (half_chord_integral(b, r) - half_chord_integral(a, r)) + flat * (b - a);
  }
  return area;
}

/// Nodes, area and perimeter of the body (outline union minus holes) on the grid.
struct BodyMeasure {
  double nodes = 0.0;
  double perimeter = 0.0;  ///< m
  double cells = 0.0;      ///< lattice cells of the bounding box
};

struct Interval {
  double lo = 0.0;
  double hi = 0.0;
};

/// Length of the symmetric difference of two sorted lists of disjoint closed intervals.
double symmetric_difference(const std::vector<Interval>& a, const std::vector<Interval>& b) {
  double covered_a = 0.0, covered_b = 0.0, common = 0.0;
  for (const auto& i : a) covered_a += i.hi - i.lo;
  for (const auto& i : b) covered_b += i.hi - i.lo;
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    common += std::max(0.0, std::min(a[i].hi, b[j].hi) - std::max(a[i].lo, b[j].lo));
    if (a[i].hi < b[j].hi) {
      ++i;
    } else {
      ++j;
    }
  }
  return covered_a + covered_b - 2.0 * common;
}

/// The bounding box's lattice with every cell counted: an over-estimate for outlines too large to
/// sweep.
BodyMeasure box_measure(const mesh::Rectangle& box, const Axis& ax, const Axis& ay) {
  BodyMeasure m;
  m.cells = finite_or_huge(ax.count * ay.count);
  m.nodes = m.cells;
  m.perimeter = finite_or_huge(2.0 * ((box.x_max - box.x_min) + (box.y_max - box.y_min)));
  return m;
}

/// The slab sweep: the x-coordinates of the rectangles' sides cut the plane into slabs; in each,
/// the rectangles spanning it give merged y-intervals, whose lattice rows times the slab's lattice
/// columns are its nodes; the intervals' ends give the horizontal boundary, the change of the
/// intervals from slab to slab the vertical boundary; each hole's area inside the intervals
/// (disc_rectangle_area) is taken off the nodes, its circumference inside the body added to the
/// boundary. Overlapping holes are taken off twice (an under-estimate by their overlap).
BodyMeasure sweep(const mesh::DetailGeometry& g, const Axis& ax, const Axis& ay) {
  BodyMeasure m;
  m.cells = finite_or_huge(ax.count * ay.count);
  std::vector<double> xs;
  xs.reserve(2 * g.outline.size());
  for (const auto& entry : g.outline) {
    const mesh::Rectangle& r = entry.rectangle;
    xs.push_back(r.x_min);
    xs.push_back(r.x_max);
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end()), xs.end());
  std::vector<double> hole_area(g.holes.size(), 0.0);
  std::vector<Interval> previous, current;
  double nodes = 0.0;
  for (std::size_t k = 0; k + 1 < xs.size(); ++k) {
    const double xa = xs[k], xb = xs[k + 1];
    current.clear();
    for (const auto& entry : g.outline) {
      const mesh::Rectangle& r = entry.rectangle;
      if (r.x_min <= xa && r.x_max >= xb) current.push_back({r.y_min, r.y_max});
    }
    std::sort(current.begin(), current.end(),
              [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
    std::size_t merged = 0;
    for (const auto& i : current) {
      if (merged > 0 && i.lo <= current[merged - 1].hi) {
        current[merged - 1].hi = std::max(current[merged - 1].hi, i.hi);
      } else {
        current[merged++] = i;
      }
    }
    current.resize(merged);
    // Columns of the slab [xa, xb), the last slab closed (Rectangle::contains is inclusive).
    const bool last = k + 2 == xs.size();
    const double columns = (last ? ax.at_or_below(xb) : ax.below(xb)) - ax.below(xa);
    double rows = 0.0;
    for (const auto& i : current) {
      rows += ay.at_or_below(i.hi) - ay.below(i.lo);
      m.perimeter += 2.0 * (xb - xa);
    }
    nodes += columns * rows;
    m.perimeter += symmetric_difference(previous, current);
    for (std::size_t h = 0; h < g.holes.size(); ++h) {
      const mesh::Circle& c = g.holes[h].circle;
      if (c.centre.x + c.radius <= xa || c.centre.x - c.radius >= xb) continue;
      for (const auto& i : current) {
        hole_area[h] += disc_rectangle_area(c.radius, xa - c.centre.x, xb - c.centre.x,
                                            i.lo - c.centre.y, i.hi - c.centre.y);
      }
    }
    std::swap(previous, current);
  }
  m.perimeter += symmetric_difference(previous, {});
  double removed = 0.0;
  for (std::size_t h = 0; h < g.holes.size(); ++h) {
    const double r = g.holes[h].circle.radius;
    removed += hole_area[h] / (ax.dx * ay.dx);
    // The circumference inside the body, as the inside share of the hole's area.
    const double full = std::numbers::pi * r * r;
    if (full > 0) m.perimeter += 2.0 * std::numbers::pi * r * std::min(1.0, hole_area[h] / full);
  }
  m.nodes = std::max(0.0, finite_or_huge(nodes) - finite_or_huge(removed));
  m.perimeter = finite_or_huge(m.perimeter);
  return m;
}

/// Outlines with polygons or circles, or polygon holes: nodes from the areas (the entries' sum less
/// the holes', an over-estimate where entries overlap), boundary from their perimeters.
BodyMeasure shape_measure(const mesh::DetailGeometry& g, const Axis& ax, const Axis& ay) {
  BodyMeasure m;
  m.cells = finite_or_huge(ax.count * ay.count);
  double area = 0.0;
  double perimeter = 0.0;
  const auto length = [](const mesh::Region& r) {
    switch (r.shape) {
      case mesh::Region::Shape::rectangle:
        return 2.0 *
               ((r.rectangle.x_max - r.rectangle.x_min) + (r.rectangle.y_max - r.rectangle.y_min));
      case mesh::Region::Shape::circle:
        return 2.0 * std::numbers::pi * r.circle.radius;
      case mesh::Region::Shape::polygon:
        return r.polygon.perimeter();
    }
    return 0.0;
  };
  for (const mesh::Region& r : g.outline) {
    area += r.area();
    perimeter += length(r);
  }
  for (const mesh::Region& h : g.holes) {
    area -= h.area();
    perimeter += length(h);
  }
  m.nodes = std::min(m.cells, finite_or_huge(std::max(0.0, area) / (ax.dx * ay.dx)));
  m.perimeter = finite_or_huge(perimeter);
  return m;
}

BodyMeasure measure_body(const DetailConfig& d) {
  const mesh::Rectangle box = d.geometry.bounding_box();
  // discretize()'s grid: nx = floor(width/dx + 1e-9) columns from the box's lower left corner.
  const Axis ax{box.x_min, d.dx, finite_or_huge(std::floor((box.x_max - box.x_min) / d.dx + 1e-9))};
  const Axis ay{box.y_min, d.dx, finite_or_huge(std::floor((box.y_max - box.y_min) / d.dx + 1e-9))};
  const auto rectangles = static_cast<double>(d.geometry.outline.size());
  const auto holes = static_cast<double>(d.geometry.holes.size());
  const bool rectangles_and_circles =
      std::all_of(
          d.geometry.outline.begin(), d.geometry.outline.end(),
          [](const mesh::Region& r) { return r.shape == mesh::Region::Shape::rectangle; }) &&
      std::all_of(d.geometry.holes.begin(), d.geometry.holes.end(),
                  [](const mesh::Region& r) { return r.shape == mesh::Region::Shape::circle; });
  if (!rectangles_and_circles) return shape_measure(d.geometry, ax, ay);
  if (2.0 * rectangles * rectangles * (1.0 + holes) > kMaxSweepSteps) {
    return box_measure(box, ax, ay);
  }
  try {
    return sweep(d.geometry, ax, ay);
  } catch (...) {  // std::bad_alloc of the slab lists: the over-estimate needs no memory
    return box_measure(box, ax, ay);
  }
}

/// ½·(N·F − (P/Δx)·S), at least 0.
double bond_count(double nodes, double perimeter, double dx, const FamilySums& sums) {
  const double full = finite_or_huge(nodes * sums.family);
  const double lost = finite_or_huge(perimeter / dx * sums.edge);
  return std::max(0.0, 0.5 * (full - std::min(full, lost)));
}

}  // namespace

ResourceEstimate estimate_resources(const DetailConfig& d) noexcept {
  ResourceEstimate e;
  if (!(d.dx > 0.0) || !(d.horizon_ratio >= 1.0) || d.geometry.outline.empty()) return e;
  const double horizon = d.horizon();
  const BodyMeasure body = measure_body(d);
  const FamilySums sums = family_sums(d.dx, horizon);
  e.nodes = body.nodes;
  e.family_size = sums.family;
  e.bonds = bond_count(body.nodes, body.perimeter, d.dx, sums);

  // Solver form (solver/statics/static_solver.cpp): bond-based and the state-based mixed form
  // (a < 0, 000 Eq. 4a) couple nodes within δ; the condensed state-based form Bᵀ·A·B within 2δ.
  const bool state_based = d.model.kind == model::ModelKind::state_based;
  const bool mixed =
      state_based &&
      state_based_constants(d.material, d.model.plane, horizon, d.geometry.thickness).a < 0.0;
  const double per_node = mixed ? 3.0 : 2.0;
  e.unknowns = finite_or_huge(per_node * e.nodes);
  double reach = d.horizon_ratio;
  if (!state_based) {
    e.matrix_nonzeros = 4.0 * e.bonds + 3.0 * e.nodes;  // 2×2 blocks: 4 per bond, 3 per node
  } else if (mixed) {
    // K_bb, the Bᵀ block (2 per family member and 2 for the node itself), the w diagonal.
    e.matrix_nonzeros = 8.0 * e.bonds + 6.0 * e.nodes;
  } else {
    reach = 2.0 * d.horizon_ratio;
    const FamilySums twice = family_sums(d.dx, 2.0 * horizon);
    e.matrix_nonzeros = 4.0 * bond_count(body.nodes, body.perimeter, d.dx, twice) + 3.0 * e.nodes;
  }
  e.matrix_nonzeros = finite_or_huge(e.matrix_nonzeros);
  if (e.nodes > 0.0) {
    const double levels = std::max(1.0, std::log2(std::sqrt(e.nodes) / reach));
    const double nested =
        kNestedDissection * per_node * per_node * reach * reach * e.nodes * levels;
    const double dense = 0.5 * e.unknowns * (e.unknowns + 1.0);
    e.factor_nonzeros = finite_or_huge(std::min(nested, dense));
  }

  // Engines alive at once (twin/life.cpp, service/daemon.cpp): the live twin's, and
  // when remaining life is estimated (LifeConfig::estimates()) one simulation, or three with the A2
  // band (not for the kinetic law), run in parallel.
  const bool life = d.life.estimates();
  const bool band =
      d.life.band == BandSource::a2_scatter && fatigue::law_entry(d.fatigue.law).scatter_band;
  e.engines = 1 + (life ? (band ? 3 : 1) : 0);

  const bool bilinear = fatigue::law_entry(d.fatigue.law).damage_based;
  e.model_bytes = finite_or_huge(
      e.nodes * (kDiscretizationNodeBytes + (state_based ? kStateBasedNodeBytes : 0.0) +
                 (d.material.youngs_modulus_std > 0.0 ? kScatterNodeBytes : 0.0)) +
      e.bonds * (kDiscretizationBondBytes + kModelBondBytes +
                 (state_based ? kStateBasedBondBytes : 0.0)) +
      body.cells * kLatticeCellBytes);
  e.engine_bytes =
      finite_or_huge(e.bonds * (kEngineBondBytes + (bilinear ? kBilinearBondBytes : 0.0)) +
                     e.nodes * kEngineNodeBytes + e.matrix_nonzeros * kMatrixEntryBytes +
                     e.factor_nonzeros * kFactorEntryBytes);
  e.bytes = finite_or_huge(e.model_bytes + e.engines * e.engine_bytes);
  return e;
}

}  // namespace peritwin::config
