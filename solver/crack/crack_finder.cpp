#include "solver/crack/crack_finder.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <stdexcept>

#include "solver/model/pd_model.h"

namespace peritwin::crack {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Union-find over the nodes plus one virtual node per notch (its tip zone).
class Components {
 public:
  explicit Components(std::size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0); }
  std::size_t root(std::size_t a) {
    while (parent_[a] != a) {
      parent_[a] = parent_[parent_[a]];
      a = parent_[a];
    }
    return a;
  }
  /// Joins the sets of a and b; the new root is the smaller root (deterministic).
  std::size_t join(std::size_t a, std::size_t b) {
    a = root(a);
    b = root(b);
    if (a == b) return a;
    if (b < a) std::swap(a, b);
    parent_[b] = a;
    return a;
  }

 private:
  std::vector<std::size_t> parent_;
};

mesh::Point unit(mesh::Point v) {
  const double n = std::hypot(v.x, v.y);
  return n > 0 ? mesh::Point{v.x / n, v.y / n} : mesh::Point{};
}

/// Dijkstra over the crack nodes of one component from `source`, links no longer than `link`.
struct PathTree {
  std::vector<double> dist;
  std::vector<std::int32_t> parent;
};
PathTree shortest_paths(const mesh::Discretization& disc,
                        const std::vector<std::int32_t>& component, std::int32_t c,
                        std::size_t source, double link) {
  const auto nn = static_cast<std::size_t>(disc.num_nodes());
  PathTree t{std::vector<double>(nn, kInf), std::vector<std::int32_t>(nn, -1)};
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  t.dist[source] = 0.0;
  queue.emplace(0.0, source);
  while (!queue.empty()) {
    const auto [d, k] = queue.top();
    queue.pop();
    if (d > t.dist[k]) continue;
    for (auto f = disc.family_offset[k]; f < disc.family_offset[k + 1]; ++f) {
      const auto b = disc.family_bonds[static_cast<std::size_t>(f)];
      const double xi = disc.bond_length[static_cast<std::size_t>(b)];
      if (xi > link) continue;
      const auto j = static_cast<std::size_t>(disc.other_end(b, static_cast<mesh::NodeIndex>(k)));
      if (component[j] != c) continue;
      if (d + xi < t.dist[j]) {
        t.dist[j] = d + xi;
        t.parent[j] = static_cast<std::int32_t>(k);
        queue.emplace(d + xi, j);
      }
    }
  }
  return t;
}

/// The reached node farthest from the source (ties: the lower index).
std::size_t farthest(const PathTree& t) {
  std::size_t best = t.dist.size();
  for (std::size_t k = 0; k < t.dist.size(); ++k) {
    if (std::isfinite(t.dist[k]) && (best == t.dist.size() || t.dist[k] > t.dist[best])) best = k;
  }
  return best;
}

/// Direction of growth at `tip` (crack_tracker.h tip_line).
mesh::Point tip_direction(const mesh::Discretization& disc, const PathTree& t, std::size_t tip,
                          double back) {
  return tip_line(disc, t.dist, tip, back).direction;
}

}  // namespace

CrackFinder::CrackFinder(const mesh::Discretization& disc, const CrackTracker& tracker,
                         std::vector<std::vector<mesh::Point>> notch_paths,
                         double phase_switch_damage)
    : disc_(disc),
      tracker_(tracker),
      notch_paths_(std::move(notch_paths)),
      phi0_(phase_switch_damage),
      // As CrackTracker's path steps: the diagonal neighbour and what a perturbed grid adds.
      link_((1.5 + 2.0 * std::numbers::sqrt2 * disc.perturbation.amplitude) * disc.dx) {
  for (const auto& path : notch_paths_) {
    if (path.size() < 2) throw std::invalid_argument("CrackFinder: a notch path has < 2 points");
    const mesh::Point a = path[path.size() - 2], b = path.back();
    notch_tips_.push_back(b);
    notch_directions_.push_back(unit({b.x - a.x, b.y - a.y}));
  }
  // Surface distance from the empty grid sites (node (i, j) stays in its cell: amplitude < 0.25).
  const auto nn = static_cast<std::size_t>(disc.num_nodes());
  surface_distance_.assign(nn, kInf);
  if (nn == 0) return;
  const double dx = disc.dx;
  const auto margin = static_cast<std::int64_t>(std::ceil((disc.horizon + dx) / dx)) + 1;
  std::vector<std::int64_t> ci(nn), cj(nn);
  std::int64_t ni = 0, nj = 0;
  for (std::size_t k = 0; k < nn; ++k) {
    ci[k] = static_cast<std::int64_t>(std::floor((disc.position[k].x - disc.box.x_min) / dx));
    cj[k] = static_cast<std::int64_t>(std::floor((disc.position[k].y - disc.box.y_min) / dx));
    ni = std::max(ni, ci[k] + 1);
    nj = std::max(nj, cj[k] + 1);
  }
  const std::int64_t wi = ni + 2 * margin, wj = nj + 2 * margin;
  std::vector<std::uint8_t> occupied(static_cast<std::size_t>(wi * wj), 0);
  for (std::size_t k = 0; k < nn; ++k) {
    occupied[static_cast<std::size_t>((ci[k] + margin) * wj + cj[k] + margin)] = 1;
  }
  const double reach = disc.horizon + dx;
  for (std::size_t k = 0; k < nn; ++k) {
    double best = kInf;
    for (std::int64_t i = ci[k] - margin; i <= ci[k] + margin; ++i) {
      for (std::int64_t j = cj[k] - margin; j <= cj[k] + margin; ++j) {
        if (occupied[static_cast<std::size_t>((i + margin) * wj + j + margin)]) continue;
        const double sx = disc.box.x_min + (static_cast<double>(i) + 0.5) * dx;
        const double sy = disc.box.y_min + (static_cast<double>(j) + 0.5) * dx;
        const double d = std::hypot(disc.position[k].x - sx, disc.position[k].y - sy);
        if (d <= reach) best = std::min(best, std::max(0.0, d - 0.5 * dx));
      }
    }
    surface_distance_[k] = best;
  }
}

bool CrackFinder::in_notch_zone(std::size_t k, std::size_t n) const {
  const mesh::Point p = disc_.position[k], tip = notch_tips_[n], dir = notch_directions_[n];
  const double ax = p.x - tip.x, ay = p.y - tip.y;
  // CrackTracker's seeds: ahead of the tip (by more than −Δx/2) and within δ of it.
  if (ax * dir.x + ay * dir.y > -0.5 * disc_.dx && std::hypot(ax, ay) <= disc_.horizon) return true;
  // The notch's faces: within δ of its path (a face node broken by fatigue is part of its crack).
  const auto& path = notch_paths_[n];
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const mesh::Point a = path[i], b = path[i + 1];
    const double lx = b.x - a.x, ly = b.y - a.y, l2 = lx * lx + ly * ly;
    const double t = l2 > 0 ? std::clamp(((p.x - a.x) * lx + (p.y - a.y) * ly) / l2, 0.0, 1.0) : 0;
    if (std::hypot(p.x - a.x - t * lx, p.y - a.y - t * ly) <= disc_.horizon) return true;
  }
  return false;
}

template <class Visit>
void CrackFinder::for_each_link(std::size_t k, const std::vector<std::uint8_t>& crack,
                                Visit&& visit) const {
  for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
    const auto b = disc_.family_bonds[static_cast<std::size_t>(f)];
    if (disc_.bond_length[static_cast<std::size_t>(b)] > link_) continue;
    const auto j = static_cast<std::size_t>(disc_.other_end(b, static_cast<mesh::NodeIndex>(k)));
    if (crack[j]) visit(j);
  }
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  for (std::size_t n = 0; n < notch_tips_.size(); ++n) {
    if (in_notch_zone(k, n)) visit(nn + n);
  }
}

std::vector<std::uint8_t> CrackFinder::crack_nodes(const std::vector<double>& node_damage,
                                                   const std::vector<std::uint8_t>& intact) const {
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  std::vector<std::uint8_t> crack(nn, 0);
  for (std::size_t k = 0; k < nn; ++k) {
    if (node_damage[k] < phi0_) continue;
    for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
      const auto b = static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(f)]);
      if (!intact[b] && !disc_.bond_precut[b]) {
        crack[k] = 1;
        break;
      }
    }
  }
  return crack;
}

CrackFindings CrackFinder::find(const std::vector<double>& node_damage,
                                const std::vector<std::uint8_t>& intact) const {
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  const std::size_t notches = notch_tips_.size();
  const auto crack = crack_nodes(node_damage, intact);
  Components sets(nn + notches);
  for (std::size_t k = 0; k < nn; ++k) {
    if (crack[k]) for_each_link(k, crack, [&](std::size_t other) { sets.join(k, other); });
  }
  // Component indices: notch n's is n (a notch whose zone joined an earlier notch's crack has
  // none of its own); the others from N_notches on, in the order of their lowest node.
  std::vector<std::int32_t> label(nn + notches, -1);
  for (std::size_t n = 0; n < notches; ++n) {
    const std::size_t r = sets.root(nn + n);
    if (label[r] < 0) label[r] = static_cast<std::int32_t>(n);
  }
  auto next = static_cast<std::int32_t>(notches);
  std::vector<std::int32_t> component(nn, -1);
  for (std::size_t k = 0; k < nn; ++k) {
    if (!crack[k]) continue;
    const std::size_t r = sets.root(k);
    if (label[r] < 0) label[r] = next++;
    component[k] = label[r];
  }
  CrackFindings findings;
  findings.cracks = measure_components(node_damage, intact, component, next);
  // A notch whose zone joined an earlier notch's crack is listed with that crack only.
  std::vector<std::uint8_t> absorbed_notch(notches, 0);
  for (std::size_t n = 0; n < notches; ++n) {
    if (label[sets.root(nn + n)] != static_cast<std::int32_t>(n)) absorbed_notch[n] = 1;
  }
  std::erase_if(findings.cracks, [&](const FoundCrack& c) {
    return c.origin == CrackOrigin::notch && absorbed_notch[static_cast<std::size_t>(c.notch)];
  });
  return findings;
}

CrackFindings CrackFinder::find_with_history(const std::vector<double>& node_damage,
                                             std::span<const fatigue::BreakEvent> events) const {
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  const std::size_t notches = notch_tips_.size();
  // Replay: from the virgin state (only the notches' cuts) through every break event.
  std::vector<std::uint8_t> replayed(disc_.bond_precut.size());
  for (std::size_t b = 0; b < replayed.size(); ++b) replayed[b] = disc_.bond_precut[b] ? 0 : 1;
  std::vector<std::uint8_t> crack(nn, 0);
  Components sets(nn + notches);
  // Id and birth per set root; notch n's crack is id n + 1 from the start.
  std::vector<std::int32_t> id(nn + notches, 0);
  std::vector<std::int64_t> birth(nn + notches, -1);
  std::vector<std::vector<std::int32_t>> absorbed(nn + notches);
  for (std::size_t n = 0; n < notches; ++n) id[nn + n] = static_cast<std::int32_t>(n + 1);
  auto next_id = static_cast<std::int32_t>(notches + 1);
  CrackFindings findings;
  auto join = [&](std::size_t a, std::size_t b, std::int64_t cycle) {
    const std::size_t ra = sets.root(a), rb = sets.root(b);
    if (ra == rb) return;
    const std::size_t r = sets.join(ra, rb), other = r == ra ? rb : ra;
    const std::int32_t ia = id[r], ib = id[other];
    if (ia > 0 && ib > 0) {
      const std::int32_t kept = std::min(ia, ib), gone = std::max(ia, ib);
      findings.merges.push_back({cycle, kept, gone});
      auto& list = absorbed[r];
      list.insert(list.end(), absorbed[other].begin(), absorbed[other].end());
      list.push_back(gone);
      std::sort(list.begin(), list.end());
      id[r] = kept;
      birth[r] = (ia == kept) ? birth[r] : birth[other];
    } else if (ib > 0) {
      id[r] = ib;
      birth[r] = birth[other];
      absorbed[r] = absorbed[other];
    }
  };
  auto becomes_crack = [&](std::size_t k, std::int64_t cycle) {
    crack[k] = 1;
    for_each_link(k, crack, [&](std::size_t other) { join(k, other, cycle); });
    const std::size_t r = sets.root(k);
    if (id[r] == 0) id[r] = next_id++;   // a crack of its own
    if (birth[r] < 0) birth[r] = cycle;  // its first crack node (a notch's crack too)
  };
  for (const fatigue::BreakEvent& e : events) {
    const auto b = static_cast<std::size_t>(e.bond);
    if (b >= replayed.size() || !replayed[b]) continue;
    replayed[b] = 0;
    for (const mesh::NodeIndex end : {disc_.bond_i[b], disc_.bond_j[b]}) {
      const auto k = static_cast<std::size_t>(end);
      // The engine's own damage_index arithmetic: a threshold decision here equals one there.
      if (!crack[k] && model::node_damage_index(disc_, replayed, k) >= phi0_)
        becomes_crack(k, e.cycle);
    }
  }
  // Components in id order: notch n's is n; the others follow by id.
  std::vector<std::int32_t> root_ids;
  for (std::size_t k = 0; k < nn; ++k) {
    if (crack[k] && id[sets.root(k)] > static_cast<std::int32_t>(notches)) {
      root_ids.push_back(id[sets.root(k)]);
    }
  }
  std::sort(root_ids.begin(), root_ids.end());
  root_ids.erase(std::unique(root_ids.begin(), root_ids.end()), root_ids.end());
  auto index_of_id = [&](std::int32_t i) -> std::int32_t {
    if (i <= static_cast<std::int32_t>(notches)) return i - 1;
    return static_cast<std::int32_t>(notches) +
           static_cast<std::int32_t>(std::lower_bound(root_ids.begin(), root_ids.end(), i) -
                                     root_ids.begin());
  };
  std::vector<std::int32_t> component(nn, -1);
  for (std::size_t k = 0; k < nn; ++k) {
    if (crack[k]) component[k] = index_of_id(id[sets.root(k)]);
  }
  const auto count = static_cast<std::int32_t>(notches + root_ids.size());
  findings.cracks = measure_components(node_damage, replayed, component, count);
  // Ids, births and joins per crack; a notch whose crack joined another's is not listed.
  std::vector<std::uint8_t> listed(notches, 1);
  for (std::size_t n = 0; n < notches; ++n) {
    if (id[sets.root(nn + n)] != static_cast<std::int32_t>(n + 1)) listed[n] = 0;
  }
  std::vector<std::size_t> root_of(findings.cracks.size(), nn + notches);
  for (std::size_t n = 0; n < notches; ++n) root_of[n] = sets.root(nn + n);
  for (std::size_t k = 0; k < nn; ++k) {
    if (component[k] >= static_cast<std::int32_t>(notches)) {
      root_of[static_cast<std::size_t>(component[k])] = sets.root(k);
    }
  }
  for (std::size_t i = 0; i < findings.cracks.size(); ++i) {
    FoundCrack& c = findings.cracks[i];
    const std::size_t r = root_of[i];
    c.id = c.origin == CrackOrigin::notch ? c.notch + 1 : id[r];
    c.birth_cycle = birth[r];
    c.absorbed = absorbed[r];
  }
  std::erase_if(findings.cracks, [&](const FoundCrack& c) {
    return c.origin == CrackOrigin::notch && !listed[static_cast<std::size_t>(c.notch)];
  });
  return findings;
}

std::vector<FoundCrack> CrackFinder::measure_components(const std::vector<double>& node_damage,
                                                        const std::vector<std::uint8_t>& intact,
                                                        const std::vector<std::int32_t>& component,
                                                        std::int32_t num_components) const {
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  const std::size_t notches = notch_tips_.size();
  std::vector<FoundCrack> cracks(static_cast<std::size_t>(num_components));
  // Notch cracks: CrackTracker's numbers, unchanged.
  const auto metrics = tracker_.measure(node_damage, intact);
  for (std::size_t n = 0; n < notches && n < cracks.size(); ++n) {
    const CrackMetrics& m = metrics[n];
    FoundCrack& c = cracks[n];
    c.origin = CrackOrigin::notch;
    c.notch = static_cast<int>(n);
    c.origin_point = m.origin;
    const double cs = std::cos(m.kink_angle), sn = std::sin(m.kink_angle);
    const mesh::Point d = notch_directions_[n];
    c.tips = {{m.tip, {cs * d.x - sn * d.y, sn * d.x + cs * d.y}}};
    c.length = m.subgrid_length;
    c.node_length = m.length;
    c.projected_length = m.projected_length;
    c.kink_angle = m.kink_angle;
    c.nodes = m.nodes;
  }
  std::vector<std::vector<std::size_t>> members(cracks.size());
  for (std::size_t k = 0; k < nn; ++k) {
    if (component[k] >= static_cast<std::int32_t>(notches)) {
      members[static_cast<std::size_t>(component[k])].push_back(k);
    }
  }
  const double back = 2.0 * disc_.horizon;  // tip direction over the last 2δ of the path
  // The cut beyond a tip along the crack's line there (0 while its direction is unknown).
  const auto progress = [&](const PathTree& t, std::size_t tip) {
    const CrackLine line = tip_line(disc_, t.dist, tip, back);
    if (line.direction.x == 0.0 && line.direction.y == 0.0) return 0.0;
    return front_progress(disc_, intact, disc_.position[tip], line);
  };
  for (std::size_t ci = notches; ci < cracks.size(); ++ci) {
    FoundCrack& c = cracks[ci];
    const auto& nodes = members[ci];
    c.nodes = static_cast<std::int32_t>(nodes.size());
    if (nodes.empty()) continue;
    const auto cid = static_cast<std::int32_t>(ci);
    std::size_t mouth = nodes.front();
    for (const std::size_t k : nodes) {
      if (surface_distance_[k] < surface_distance_[mouth]) mouth = k;
    }
    if (surface_distance_[mouth] <= disc_.horizon) {
      c.origin = CrackOrigin::surface;
      c.mouth_depth = surface_distance_[mouth];
      const PathTree t = shortest_paths(disc_, component, cid, mouth, link_);
      const std::size_t tip = farthest(t);
      const mesh::Point m = disc_.position[mouth], p = disc_.position[tip];
      c.origin_point = m;
      c.node_length = t.dist[tip] + c.mouth_depth;
      c.length = subgrid_crack_length(c.node_length, progress(t, tip), disc_.dx);
      c.projected_length = std::hypot(p.x - m.x, p.y - m.y) + c.mouth_depth;
      c.tips = {{p, tip_direction(disc_, t, tip, back)}};
      continue;
    }
    // Interior: the ends of the longest path (two sweeps).
    c.origin = CrackOrigin::interior;
    const PathTree first = shortest_paths(disc_, component, cid, nodes.front(), link_);
    const std::size_t a = farthest(first);
    const PathTree t = shortest_paths(disc_, component, cid, a, link_);
    const std::size_t b = farthest(t);
    c.node_length = t.dist[b];
    std::size_t middle = b;
    for (auto k = static_cast<std::int32_t>(b); k >= 0; k = t.parent[static_cast<std::size_t>(k)]) {
      const auto ku = static_cast<std::size_t>(k);
      if (std::abs(t.dist[ku] - 0.5 * c.node_length) <
          std::abs(t.dist[middle] - 0.5 * c.node_length)) {
        middle = ku;
      }
    }
    c.origin_point = disc_.position[middle];
    const mesh::Point pa = disc_.position[a], pb = disc_.position[b];
    c.projected_length = std::hypot(pb.x - pa.x, pb.y - pa.y);
    // At a: the path from b reversed; the direction from the node `back` along it towards a.
    const PathTree from_b = shortest_paths(disc_, component, cid, b, link_);
    // The front moves at both tips (the cut beyond b from a's tree, beyond a from b's) and each
    // tip node lags its cut: subgrid_crack_length takes one lag off, the second one here.
    c.length = subgrid_crack_length(
        c.node_length, progress(t, b) + progress(from_b, a) - kSubgridLag * disc_.dx, disc_.dx);
    c.tips = {{pa, tip_direction(disc_, from_b, a, back)}, {pb, tip_direction(disc_, t, b, back)}};
  }
  return cracks;
}

}  // namespace peritwin::crack
