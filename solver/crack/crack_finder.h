// Cracks wherever they start: every connected set of crack nodes is a crack, whether it grew from
// a notch tip, nucleated on a free surface (a hole, an edge, a re-entrant corner) or inside the
// body (docs/design.md "Crack metrics").
//
// A crack node has damage φ ≥ φ0 (000 Eq. 13; φ0 the phase switch of 000 Sec. 4.4) and at least
// one bond broken by the engine: the faces of a notch, damaged by its pre-cut bonds alone, are not
// crack nodes. Two crack nodes belong to the same crack when a bond no longer than the path link
// (√2Δx and a margin) joins them; every crack node in a notch's zone (ahead of the tip within δ of
// it — the seeds of CrackTracker — or within δ of the notch's faces) joins that notch's crack. A
// notch crack is measured exactly as CrackTracker measures it (one crack per notch, unchanged
// numbers); any other crack from its own nodes: its mouth is the crack node nearest a free surface,
// its tip the node farthest from the mouth along the crack (Dijkstra over the links), its length
// that path plus the mouth's depth below the surface. The tip node is the last node with φ ≥ φ0:
// the damage at a cut's end is about half the face value, so it lies 1–2Δx behind the last broken
// bond (as CrackTracker's does). A crack that touches no surface (its nearest node deeper than δ)
// is an interior crack with two tips, the ends of its longest path. That node-based length moves
// in steps of about Δx; the published `length` is the sub-grid one (crack_tracker.h,
// subgrid_crack_length: the node-based length plus the fraction of the bonds crossing the crack's
// line ahead of the tip that are broken, less the tip node's mean lag, within Δx/2 of the
// node-based length).
//
// Ids: notch n's crack is id n + 1 (fixed); other cracks are numbered from N_notches + 1 in the
// order they were born, by replaying the engine's break events (find_with_history). Ids are
// therefore functions of the damage history alone: equal across batchings of the same cycles,
// restarts from checkpoints and replays. Cracks that join keep the smaller id; the merge is kept
// with its cycle.
// Units: SI (m, rad, cycles).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "solver/crack/crack_tracker.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/mesh/discretization.h"

namespace peritwin::crack {

enum class CrackOrigin : std::int8_t { notch = 1, surface = 2, interior = 3 };

struct CrackTipState {
  mesh::Point position;
  mesh::Point
      direction;  ///< unit vector of growth at the tip (from the crack behind it); 0 if unknown
};

struct FoundCrack {
  std::int32_t id = 0;  ///< 1, 2, ... (see the file comment); 0 from find() without history
  CrackOrigin origin = CrackOrigin::surface;
  int notch = -1;  ///< the notch it grows from (origin notch), else -1
  mesh::Point
      origin_point;  ///< the notch tip, the mouth node (surface) or the path's middle (interior)
  std::vector<CrackTipState> tips;  ///< one (notch, surface) or two (interior) tips
  /// Along the path to the sub-grid front (m): subgrid_crack_length() of node_length and the
  /// front's progress at each tip; notch: CrackMetrics::subgrid_length. What the twin publishes.
  double length = 0.0;
  double node_length = 0.0;  ///< along the path to the tip node(s) (m); notch: CrackMetrics::length
  double projected_length = 0.0;       ///< notch: along the notch; else straight origin → tip (m)
  double kink_angle = 0.0;             ///< notch cracks: CrackMetrics::kink_angle; else 0
  double mouth_depth = 0.0;            ///< surface cracks: the mouth node's distance to the surface
  std::int32_t nodes = 0;              ///< crack nodes
  std::int64_t birth_cycle = -1;       ///< the cycle its first crack node appeared (history only)
  std::vector<std::int32_t> absorbed;  ///< ids of cracks that joined it (history only), ascending
};

struct CrackMerge {
  std::int64_t cycle = 0;
  std::int32_t kept = 0;      ///< the surviving (smaller) id
  std::int32_t absorbed = 0;  ///< the id that ended
};

struct CrackFindings {
  std::vector<FoundCrack> cracks;  ///< ordered by id (notch cracks first, in notch order)
  std::vector<CrackMerge> merges;  ///< in cycle order (history only)
};

class CrackFinder {
 public:
  /// `tracker` measures the notch cracks (its notches are the finder's, in the same order);
  /// `notch_paths` from each notch's mouth to its tip (≥ 2 points; the tip direction is the last
  /// segment's). disc and tracker must outlive the finder.
  CrackFinder(const mesh::Discretization& disc, const CrackTracker& tracker,
              std::vector<std::vector<mesh::Point>> notch_paths, double phase_switch_damage);

  /// The cracks of a state (node damage by 000 Eq. 13 and the intact flags it came from), without
  /// ids: the snapshot path, for crack lengths inside forward simulations. Notch cracks are
  /// listed for every notch (length 0 before growth), as CrackTracker lists them.
  [[nodiscard]] CrackFindings find(const std::vector<double>& node_damage,
                                   const std::vector<std::uint8_t>& intact) const;

  /// The same cracks with ids, birth cycles and merges, from the break events (in engine order)
  /// that led from the virgin (pre-cut) state to the state of `node_damage`: the replay rebuilds
  /// the bond state, so no intact flags are needed.
  [[nodiscard]] CrackFindings find_with_history(const std::vector<double>& node_damage,
                                                std::span<const fatigue::BreakEvent> events) const;

  /// Distance from each node to the nearest free surface (outline, hole; not a notch), estimated
  /// from the grid sites without a node: min over such sites of |x_k − site| − Δx/2, ≥ 0;
  /// +∞ when none lies within δ + Δx.
  [[nodiscard]] const std::vector<double>& surface_distance() const { return surface_distance_; }
  /// The link length: crack nodes joined by a bond no longer than this are one crack.
  [[nodiscard]] double link() const { return link_; }

 private:
  /// Whether node k lies in notch n's zone: its tip zone (CrackTracker's seeds) or within δ of
  /// its path (its faces).
  [[nodiscard]] bool in_notch_zone(std::size_t k, std::size_t n) const;
  /// Calls visit(j) for every node j that crack node k links to: crack nodes j joined to k by a
  /// bond no longer than link(), and notch n's virtual node (num_nodes() + n) when k lies in its
  /// zone. One rule for the snapshot and the history paths.
  template <class Visit>
  void for_each_link(std::size_t k, const std::vector<std::uint8_t>& crack, Visit&& visit) const;
  /// Crack nodes: φ ≥ φ0 and a broken bond that no notch cut.
  [[nodiscard]] std::vector<std::uint8_t> crack_nodes(
      const std::vector<double>& node_damage, const std::vector<std::uint8_t>& intact) const;
  /// Metrics of every component (`intact`: the bond state of the damage, for the sub-grid length);
  /// `component[k]` = component index or -1, components [0, N_notches) are the notches' (possibly
  /// empty).
  [[nodiscard]] std::vector<FoundCrack> measure_components(
      const std::vector<double>& node_damage, const std::vector<std::uint8_t>& intact,
      const std::vector<std::int32_t>& component, std::int32_t num_components) const;

  const mesh::Discretization& disc_;
  const CrackTracker& tracker_;
  std::vector<std::vector<mesh::Point>> notch_paths_;
  std::vector<mesh::Point> notch_tips_;
  std::vector<mesh::Point> notch_directions_;
  double phi0_ = 0.398;
  double link_ = 0.0;
  std::vector<double> surface_distance_;
};

}  // namespace peritwin::crack
