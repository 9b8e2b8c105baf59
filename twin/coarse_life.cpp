#include "twin/coarse_life.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <limits>
#include <utility>

#include "solver/fatigue/law_registry.h"
#include "solver/fatigue/laws/strain_range.h"
#include "solver/model/pd_model.h"

namespace peritwin::twin {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Orientation of c against the line a -> b (the sign of the cross product); 0 counts as +: a
/// point exactly on a facet's line (a -> b in (x, y) order) is on its left, i.e. above a
/// horizontal facet, right of a vertical one.
bool left_of(mesh::Point a, mesh::Point b, mesh::Point c) {
  return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) >= 0.0;
}

/// Whether segment p-q crosses segment a-b (a point on a line counts on its positive side).
bool crosses(mesh::Point p, mesh::Point q, mesh::Point a, mesh::Point b) {
  return left_of(a, b, p) != left_of(a, b, q) && left_of(p, q, a) != left_of(p, q, b);
}

/// A facet is open (part of the crack) when at least this fraction of the fine bonds crossing it
/// are broken: 1 on a crack's faces, about 0.45-0.65 beside them where only the nearest
/// neighbours broke (B1, δ = 3.015Δx: 8 to 12 of the 18 crossings per Δx).
constexpr double kOpenFacet = 0.5;

/// The criterion's crack length of a bond state.
double length_of(const DetailModel& model, const std::vector<std::uint8_t>& intact) {
  std::vector<double> damage;
  model::damage_index(model.disc(), intact, damage);
  return criterion_crack_length(model, damage, intact);
}

}  // namespace

namespace {

/// A discretization's nodes in square cells of side `cell`: the bonds near a point are those of
/// the nodes in the 3x3 cells around it (for bonds up to `cell` − reach long that cross a segment
/// reaching up to `reach` from the point).
class NodeCells {
 public:
  NodeCells(const mesh::Discretization& disc, double cell) : disc_(disc), cell_(cell) {
    x0_ = y0_ = std::numeric_limits<double>::infinity();
    double x1 = -x0_, y1 = -y0_;
    for (const mesh::Point& p : disc.position) {
      x0_ = std::min(x0_, p.x);
      y0_ = std::min(y0_, p.y);
      x1 = std::max(x1, p.x);
      y1 = std::max(y1, p.y);
    }
    nx_ = static_cast<int>((x1 - x0_) / cell) + 1;
    ny_ = static_cast<int>((y1 - y0_) / cell) + 1;
    cells_.resize(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
    for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
      const auto [i, j] = cell_of(disc.position[static_cast<std::size_t>(k)]);
      cells_[index(i, j)].push_back(k);
    }
  }
  /// Calls visit(bond) once for every bond of a node in the 3x3 cells around `p`.
  template <class Visit>
  void bonds_near(mesh::Point p, Visit&& visit) const {
    const auto [ci, cj] = cell_of(p);
    for (int j = std::max(0, cj - 1); j <= std::min(ny_ - 1, cj + 1); ++j) {
      for (int i = std::max(0, ci - 1); i <= std::min(nx_ - 1, ci + 1); ++i) {
        for (mesh::NodeIndex k : cells_[index(i, j)]) {
          const auto ku = static_cast<std::size_t>(k);
          for (auto e = disc_.family_offset[ku]; e < disc_.family_offset[ku + 1]; ++e) {
            const mesh::BondIndex b = disc_.family_bonds[static_cast<std::size_t>(e)];
            // Each bond once: from its first node, or from the other when that one is not in
            // the 3x3 cells (then only this end is).
            const auto other = static_cast<std::size_t>(disc_.other_end(b, k));
            const bool first = disc_.bond_i[static_cast<std::size_t>(b)] == k;
            if (first || !near(cell_of(disc_.position[other]), ci, cj)) visit(b);
          }
        }
      }
    }
  }

 private:
  [[nodiscard]] std::pair<int, int> cell_of(mesh::Point p) const {
    return {std::clamp(static_cast<int>((p.x - x0_) / cell_), 0, nx_ - 1),
            std::clamp(static_cast<int>((p.y - y0_) / cell_), 0, ny_ - 1)};
  }
  [[nodiscard]] static bool near(std::pair<int, int> c, int ci, int cj) {
    return std::abs(c.first - ci) <= 1 && std::abs(c.second - cj) <= 1;
  }
  [[nodiscard]] std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) +
           static_cast<std::size_t>(i);
  }
  const mesh::Discretization& disc_;
  double cell_;
  double x0_ = 0.0, y0_ = 0.0;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<mesh::NodeIndex>> cells_;
};

mesh::Point end_i(const mesh::Discretization& d, std::size_t b) {
  return d.position[static_cast<std::size_t>(d.bond_i[b])];
}
mesh::Point end_j(const mesh::Discretization& d, std::size_t b) {
  return d.position[static_cast<std::size_t>(d.bond_j[b])];
}

}  // namespace

std::vector<mesh::BondIndex> map_crack(const mesh::Discretization& fine,
                                       const std::vector<std::uint8_t>& fine_intact,
                                       const mesh::Discretization& coarse) {
  // Candidate facets: the Voronoi edge between two nearest neighbours whose bond broke (precut
  // bonds are the notch, which the coarse model cuts itself).
  struct Facet {
    mesh::Point a, b;
  };
  const NodeCells fine_cells(fine, fine.horizon + fine.dx);
  std::vector<Facet> facets;
  const double neighbour = 1.2 * fine.dx;
  for (std::size_t b = 0; b < fine_intact.size(); ++b) {
    if (fine_intact[b] || fine.bond_precut[b] || fine.bond_length[b] >= neighbour) continue;
    const mesh::Point pi = end_i(fine, b);
    const mesh::Point pj = end_j(fine, b);
    const mesh::Point m{(pi.x + pj.x) / 2, (pi.y + pj.y) / 2};
    const double h = fine.dx / 2;  // along the bisector: −sin, cos of the bond
    mesh::Point a{m.x + h * fine.bond_sin[b], m.y - h * fine.bond_cos[b]};
    mesh::Point e{m.x - h * fine.bond_sin[b], m.y + h * fine.bond_cos[b]};
    // Ends in (x, y) order, whatever the bond's direction: a coarse node on the line of two
    // facets of one crack is then on the same side of both (left_of's tie rule).
    if (e.x < a.x || (e.x == a.x && e.y < a.y)) std::swap(a, e);
    // Open: half or more of the fine bonds across the facet are broken (kOpenFacet). A crack's
    // faces have all of them broken; a second layer of broken nearest neighbours beside it (a
    // local zig-zag, a branch that did not run) keeps most of its longer bonds.
    int across = 0, broken = 0;
    fine_cells.bonds_near(m, [&](mesh::BondIndex c) {
      const auto cu = static_cast<std::size_t>(c);
      if (!crosses(end_i(fine, cu), end_j(fine, cu), a, e)) return;
      ++across;
      broken += fine_intact[cu] && !fine.bond_precut[cu] ? 0 : 1;
    });
    if (across > 0 && broken >= kOpenFacet * across) facets.push_back({a, e});
  }
  std::vector<mesh::BondIndex> cut_bonds;
  if (facets.empty()) return cut_bonds;
  // A coarse bond crossing a facet has an end within coarse horizon + facet half-length of the
  // facet's middle.
  const NodeCells coarse_cells(coarse, coarse.horizon + fine.dx);
  std::vector<std::uint8_t> cut(static_cast<std::size_t>(coarse.num_bonds()), 0);
  for (const Facet& f : facets) {
    coarse_cells.bonds_near({(f.a.x + f.b.x) / 2, (f.a.y + f.b.y) / 2}, [&](mesh::BondIndex c) {
      const auto cu = static_cast<std::size_t>(c);
      if (!cut[cu] && !coarse.bond_precut[cu] &&
          crosses(end_i(coarse, cu), end_j(coarse, cu), f.a, f.b)) {
        cut[cu] = 1;
      }
    });
  }
  for (std::size_t b = 0; b < cut.size(); ++b) {
    if (cut[b]) cut_bonds.push_back(static_cast<mesh::BondIndex>(b));
  }
  return cut_bonds;
}

GrowthWindow recent_growth(const DetailModel& fine, const fatigue::EngineState& state,
                           double target, double min_growth) {
  const auto& events = state.events;
  const std::size_t n = events.size();
  if (n == 0) return {};
  // len(k): the length with only the first k breaks (the later ones undone); nondecreasing in k
  // up to the crack finder's rounding, which the bisection tolerates (it finds a k, not the k).
  const auto len = [&](std::size_t k) {
    std::vector<std::uint8_t> intact = state.intact;
    for (std::size_t e = k; e < n; ++e) intact[static_cast<std::size_t>(events[e].bond)] = 1;
    return length_of(fine, intact);
  };
  // Smallest k with len(k) >= level (k in [1, n]; len(n) is the current length).
  const auto first_reaching = [&](double level) {
    std::size_t lo = 0, hi = n;  // len(hi) >= level; lo: not known to
    while (hi - lo > 1) {
      const std::size_t mid = lo + (hi - lo) / 2;
      (len(mid) >= level ? hi : lo) = mid;
    }
    return hi;
  };
  const double now = len(n);
  const double none = len(0);
  if (!(now - none >= min_growth)) return {};
  const std::size_t kb = first_reaching(now);
  std::size_t ka = 0;
  if (now - none >= target) {
    ka = first_reaching(now - target);
  } else {
    ka = first_reaching(std::nextafter(none, 1.0));  // the first growth
  }
  const double growth = len(kb) - len(ka);
  const double cycles =
      static_cast<double>(events[kb - 1].cycle) - static_cast<double>(events[ka - 1].cycle);
  if (!(growth >= min_growth) || !(cycles > 0)) return {};
  return {growth, cycles, ka};
}

core::Expected<std::shared_ptr<const DetailModel>> coarse_model(const DetailModel& fine,
                                                                double dx) {
  config::DetailConfig config = fine.config();
  // 000 Eq. (29): A2 for the coarse horizon (the calibration below corrects what it misses).
  auto& strain = config.fatigue.strain;
  strain.A2 = fatigue::a2_scaled(strain.A2, config.horizon(), config.horizon_ratio * dx, strain.m2);
  config.dx = dx;
  config.life.dx = 0.0;
  return DetailModel::build(config);
}

LifeEstimate estimate_life_coarse(const DetailModel& fine, double dx,
                                  const fatigue::EngineState& state,
                                  const std::vector<core::LoadBlock>& spectrum, bool parallel,
                                  const std::atomic<bool>* cancel, CoarseLifeReport* report) {
  const auto t_start = std::chrono::steady_clock::now();
  CoarseLifeReport local;
  CoarseLifeReport& rep = report != nullptr ? *report : local;
  rep = CoarseLifeReport{};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  LifeEstimate out;
  out.start_cycles = state.total_cycles;
  out.coarse = true;
  const auto done = [&](double central, double low, double high) {
    out.central = central;
    out.low = low;
    out.high = high;
    out.wall_s = seconds_since(t_start);
    return out;
  };
  if (spectrum.empty()) return done(nan, nan, nan);
  const config::LifeConfig& life = fine.config().life;
  // The fine state's own end: 0 (as simulate_life), whatever the coarse model would say.
  if (state.failed) return done(0.0, 0.0, 0.0);
  std::vector<double> fine_damage;
  model::damage_index(fine.disc(), state.intact, fine_damage);
  rep.fine_length = criterion_crack_length(fine, fine_damage, state.intact);
  if (life.criterion == config::LifeCriterion::crack_length &&
      rep.fine_length >= life.critical_crack_length) {
    return done(0.0, 0.0, 0.0);
  }
  if (life.criterion == config::LifeCriterion::phase3) {
    for (const auto& e : state.events) {
      if (e.cause == fatigue::BreakCause::overload) return done(0.0, 0.0, 0.0);
    }
  }

  // 1. The coarse model and its first solve.
  auto t0 = std::chrono::steady_clock::now();
  auto built = coarse_model(fine, dx);
  if (!built) return done(nan, nan, nan);
  const DetailModel& coarse = **built;
  rep.coarse_nodes = coarse.disc().num_nodes();
  rep.coarse_bonds = coarse.disc().num_bonds();
  // A fresh coarse engine with the crack of a fine bond state mapped onto it: the coarse bonds
  // across it broken, as one group of fatigue breaks at cycle 0 (one update of its factor).
  // Null when the mapped crack cuts a piece loose.
  const auto mapped_engine = [&](const std::vector<std::uint8_t>& fine_intact,
                                 std::int64_t* count) -> std::unique_ptr<fatigue::FatigueEngine> {
    auto engine = coarse.make_engine();
    if (!engine->initialize()) return nullptr;
    const std::vector<mesh::BondIndex> mapped = map_crack(fine.disc(), fine_intact, coarse.disc());
    if (count != nullptr) *count = static_cast<std::int64_t>(mapped.size());
    if (mapped.empty()) return engine;
    fatigue::EngineState s = engine->export_state();
    for (mesh::BondIndex b : mapped) {
      s.intact[static_cast<std::size_t>(b)] = 0;
      s.events.push_back({0, b, fatigue::BreakCause::fatigue});
    }
    s.resolve_groups.push_back(static_cast<std::int64_t>(mapped.size()));
    if (!engine->import_state(s)) return nullptr;
    return engine;
  };
  const auto coarse_length = [&](const fatigue::FatigueEngine& e) {
    return criterion_crack_length(coarse, e.node_damage(), e.solver().intact());
  };
  rep.build_s = seconds_since(t0);

  // 2. The current crack mapped.
  t0 = std::chrono::steady_clock::now();
  const auto base = mapped_engine(state.intact, &rep.mapped_bonds);
  if (base == nullptr) return done(0.0, 0.0, 0.0);  // the coarse model has failed at the start
  rep.coarse_start_length = coarse_length(*base);
  rep.coarse_critical_length =
      rep.coarse_start_length + (life.critical_crack_length - rep.fine_length);
  // The calibration window: about one coarse horizon of the most recent growth, at least 2 coarse
  // spacings; its start state (the fine bonds broken by then) mapped too.
  const GrowthWindow window =
      recent_growth(fine, state, coarse.disc().horizon, 2 * coarse.disc().dx);
  rep.window_growth = window.growth;
  rep.fine_window_cycles = window.cycles;
  std::unique_ptr<fatigue::FatigueEngine> window_start;
  if (window.growth > 0) {
    std::vector<std::uint8_t> intact = state.intact;
    for (std::size_t e = window.first_event; e < state.events.size(); ++e) {
      intact[static_cast<std::size_t>(state.events[e].bond)] = 1;
    }
    window_start = mapped_engine(intact, nullptr);
  }
  rep.map_s = seconds_since(t0);

  // 3. Calibration of A2 on the window's growth.
  t0 = std::chrono::steady_clock::now();
  double factor = 1.0;
  if (window_start != nullptr) {
    // The coarse model grows the window's crack from the window's start, as the fine one did:
    // the same stretch of crack length, so that the rate's growth with K does not bias the ratio,
    // and from a fresh mapping like the estimate's, so that the fresh bond lives at the mapped
    // tip count the same in both.
    const double target = coarse_length(*window_start) + window.growth;
    const fatigue::FatigueEngine::StopCheck grown = [&](const fatigue::FatigueEngine& e) {
      return e.failed() || coarse_length(e) >= target;
    };
    for (int run = 0; run < 3; ++run) {
      const auto engine = window_start->fork(coarse.engine_settings(factor));
      const double cycles = run_to_end(*engine, spectrum, grown, cancel);
      ++rep.calibration_runs;
      if (!(std::isfinite(cycles) && cycles > 0) || coarse_length(*engine) < target) break;
      rep.coarse_window_cycles = cycles;
      const double ratio = cycles / window.cycles;
      if (std::abs(ratio - 1.0) <= 0.02) {
        rep.calibrated = true;
        break;
      }
      // Phase II lives fall by A2·ε^m per cycle (000 Eq. 17): cycles ∝ 1/A2.
      factor *= ratio;
      rep.calibrated = run == 2;  // the last correction is used without another check run
    }
    if (!rep.calibrated) factor = 1.0;
  }
  rep.a2_factor = factor;
  if (rep.calibrated) out.coarse_a2_factor = factor;
  rep.calibrate_s = seconds_since(t0);
  if (cancel != nullptr && cancel->load()) return done(nan, nan, nan);

  // 4. The estimate: forks of the mapped coarse engine to the coarse criterion.
  t0 = std::chrono::steady_clock::now();
  const fatigue::FatigueEngine::StopCheck ended = [&](const fatigue::FatigueEngine& e) {
    if (life.criterion == config::LifeCriterion::crack_length) {
      return e.failed() || coarse_length(e) >= rep.coarse_critical_length;
    }
    return end_of_life(coarse, e) != Failure::none;
  };
  const auto simulate = [&](double a2) {
    const auto engine = base->fork(coarse.engine_settings(factor * a2));
    if (ended(*engine)) return 0.0;
    return run_to_end(*engine, spectrum, ended, cancel);
  };
  const bool band = life.band == config::BandSource::a2_scatter &&
                    peritwin::fatigue::law_entry(fine.settings().law).scatter_band;
  if (!band) {
    const double c = simulate(1.0);
    rep.simulate_s = seconds_since(t0);
    return done(c, c, c);
  }
  const double s = life.a2_relative_scatter;
  const auto policy = parallel ? std::launch::async : std::launch::deferred;
  auto low = std::async(policy, [&] { return simulate(1 + s); });
  auto high = std::async(policy, [&] { return simulate(1 - s); });
  const double central = simulate(1.0);
  const double a = low.get(), b = high.get();
  rep.simulate_s = seconds_since(t0);
  return done(central, std::min({a, b, central}), std::max({a, b, central}));
}

}  // namespace peritwin::twin
