// Remaining life on a coarser grid of the same detail (`[detail.life] dx`, issue 18 item 3): the
// forward simulations of an estimate run on a model with the larger grid spacing instead of the
// detail's own, still peridynamic fatigue simulations to the detail's end criterion. Per estimate:
//  1. the coarse model: the detail's config at dx = life.dx (same outline, notches, loads,
//  material,
//     horizon ratio), its A2 rescaled to the coarse horizon by 000 Eq. (29);
//  2. the crack mapped onto it (map_crack): every fine bond broken by fatigue or overload that
//     joins nearest neighbours (ξ < 1.2·Δx_fine) stands for a facet of the crack surface, the
//     segment of length Δx_fine on the bond's perpendicular bisector (the Voronoi edge between the
//     two nodes); a coarse bond whose segment crosses a facet is broken. The facets of a crack
//     tile its path from face to face, so the coarse bonds across the path break and no others;
//  3. the calibration of A2: the fine model's recent growth rate is read from its break history
//     (recent_growth: the crack length with the latest breaks undone, the criterion's measure), a
//     growth of about 3·Δx_coarse (one coarse horizon) and the cycles it took; the window's start
//     state (the later breaks undone) is mapped onto the coarse model too, which is run from there
//     until its crack has grown as much, and its A2 is rescaled by the ratio of the cycles (phase
//     II bond lives fall in proportion to A2, 000 Eq. 17, so the cycles scale as 1/A2), up to 3
//     runs until they agree within 2 %;
//  4. the estimate: central and band (A2_cal·(1 ± s)) forward simulations from the mapped state,
//     forks of one coarse engine, until the coarse crack has grown what the fine crack still has
//     to grow (critical_crack_length − the fine length; the coarse crack's start length is its
//     own measure of the mapped crack), or the criterion phase3 / connectivity on the coarse model.
// Without enough fine growth to calibrate on (before initiation, or less than 2·Δx_coarse of
// growth so far) the A2 of step 1 is used and the report says so (calibrated = false).
// Deterministic: a pure function of (fine model, state, spectrum), like estimate_life.
#pragma once

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "core/expected.h"
#include "twin/detail_model.h"
#include "twin/life.h"

namespace peritwin::twin {

/// What one coarse estimate did.
struct CoarseLifeReport {
  int coarse_nodes = 0;
  std::int64_t coarse_bonds = 0;
  std::int64_t mapped_bonds = 0;        ///< coarse bonds broken by the mapping
  double fine_length = 0.0;             ///< the criterion's crack length of the fine state (m)
  double coarse_start_length = 0.0;     ///< the same measure on the mapped coarse state (m)
  double coarse_critical_length = 0.0;  ///< coarse_start_length + critical − fine_length (m)
  double window_growth = 0.0;           ///< growth of the calibration window (m); 0: none
  double fine_window_cycles = 0.0;      ///< cycles the fine model took for it
  /// Cycles the coarse model took for the same growth at the final A2 (NaN: not calibrated).
  double coarse_window_cycles = std::numeric_limits<double>::quiet_NaN();
  double a2_factor = 1.0;  ///< calibrated A2 over the 000 Eq. (29) one
  int calibration_runs = 0;
  bool calibrated = false;
  double build_s = 0.0;      ///< coarse model and its engine (first factorization)
  double map_s = 0.0;        ///< mapping and the fine growth window
  double calibrate_s = 0.0;  ///< the calibration runs
  double simulate_s = 0.0;   ///< the estimate's forward simulations
};

/// The coarse bonds crossing a crack facet of the fine bond state `fine_intact` (step 2 above).
std::vector<mesh::BondIndex> map_crack(const mesh::Discretization& fine,
                                       const std::vector<std::uint8_t>& fine_intact,
                                       const mesh::Discretization& coarse);

/// The fine model's recent crack growth (step 3): `growth` (m) between the break that brought the
/// criterion's crack length to L_now − target (or, with less growth so far, the first growth)
/// and the break that brought it to L_now, and the cycles between those breaks. growth 0 when
/// the crack has grown less than `min_growth`.
struct GrowthWindow {
  double growth = 0.0;
  double cycles = 0.0;
  /// The window starts with the state of the first `first_event` breaks (state.events order).
  std::size_t first_event = 0;
};
GrowthWindow recent_growth(const DetailModel& fine, const fatigue::EngineState& state,
                           double target, double min_growth);

/// The coarse estimate model of `fine` at grid spacing `dx` (step 1).
core::Expected<std::shared_ptr<const DetailModel>> coarse_model(const DetailModel& fine, double dx);

/// The estimate on the coarser grid of spacing `dx` (steps 1-4; estimate_life calls it with
/// [detail.life] dx). Fills wall_s and start_cycles like estimate_life; `report` (optional)
/// receives what it did.
LifeEstimate estimate_life_coarse(const DetailModel& fine, double dx,
                                  const fatigue::EngineState& state,
                                  const std::vector<core::LoadBlock>& spectrum,
                                  bool parallel = true, const std::atomic<bool>* cancel = nullptr,
                                  CoarseLifeReport* report = nullptr);

}  // namespace peritwin::twin
