// Crack faces in contact under a compressive load (issue 34, docs/compression.md).
//
// The linear model lets a crack's faces pass through each other: under P < 0 a broken bond whose
// end points approach (stretch < 0) carries nothing, so the compressive half of a reversed cycle
// loads the crack tip as much as the tensile half. Here a broken bond (a fatigue break or a notch
// cut) that would shorten carries compression again with its intact stiffness (pair term and, in
// the state-based model, its share of the dilatation): while closed it is an intact bond. That is
// the unilateral contact of the crack faces at the bonds' scale, the "broken bond's compressive
// stiffness restored while it is closed" of the issue.
//
// The contact problem at a load P·(constant + cos α·per_cos + sin α·per_sin) with a fixed open set
// O (broken bonds that stay broken) is linear, so its solution is positively homogeneous in P: the
// stretches at P < 0 are |P| times those at P = −1. One active-set solve per (broken set, α) at
// P = −1 gives every compressive load of that α.
//
// Active set (a primal one for unilateral constraints): start from the previous open set (empty
// at first), solve K(intact ∪ closed)·u = F(−1, α), and take as the next open set the broken bonds
// whose stretch is > 0 (those it treated closed are in tension: they open; those it treated open
// would interpenetrate: they close); stop when the set repeats. At the fixed point every closed
// bond is in compression or at zero stretch and every open one has a gap ≥ 0: the discrete
// Signorini conditions on the bonds.
//
// The solves: the virgin factor (every bond intact, notch cuts too: factorized once) with the
// open set broken by rank updates, in a CANONICAL order: the bonds grouped by their break rank
// (the caller's: the engine gives a notch cut −1 and a fatigue break the index of its re-solve
// group), one update per rank, ascending. A solver that holds set O is reused for O' ⊇ O when
// every bond of O' \ O ranks after the last rank applied (the updates it appends are those a fresh
// build of O' would make after O's); anything else rebuilds from the virgin factor. So the
// factor, hence every stretch, is a function of the open set and the ranks alone, whatever
// sequence of sets led there: resumed checkpoints and forks, whose contact solvers start afresh,
// continue bit for bit. A growing crack whose new faces open (the shallow bonds that a free
// side's Poisson expansion pulls) appends one small update per break; when they close, nothing
// changes at all. With O empty the virgin solution itself is the answer: a mode-I crack under
// compression closes along its whole length and the body carries the load as if uncracked.
// Units: SI (N, m).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "core/expected.h"
#include "solver/mesh/discretization.h"
#include "solver/model/pd_model.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

class CrackFaceContact {
 public:
  /// The same supports, loads and ties as the detail's solver; `disc` is copied with its notch
  /// cuts made contact candidates (bond_precut cleared), `model` is referred to.
  CrackFaceContact(const mesh::Discretization& disc, const model::PdModel& model,
                   std::vector<Support> supports, std::vector<LoadTerm> loads,
                   std::vector<Tie> ties);
  CrackFaceContact(const CrackFaceContact&) = delete;
  CrackFaceContact& operator=(const CrackFaceContact&) = delete;

  /// Every bond's stretch at the unit compressive load P = −1 at angle `alpha`, with the broken
  /// bonds of `intact` (0 = broken, the detail solver's) in contact where they close. `rank`: per
  /// bond, the canonical order of its break (used for broken bonds only; see the file comment).
  /// The solution for P_min < 0 is |P_min| times it. An error if a solve fails (a singular
  /// system with the open set broken).
  core::Status compressive_stretch(const std::vector<std::uint8_t>& intact,
                                   const std::vector<std::int64_t>& rank, double alpha,
                                   std::vector<double>& stretch);

  /// The broken bonds left open by the last call (ascending), and its active-set iterations.
  [[nodiscard]] const std::vector<mesh::BondIndex>& open_bonds() const { return open_; }
  [[nodiscard]] int last_iterations() const { return last_iterations_; }
  /// Calls that reached kMaxIterations without a repeated set (the last iterate was used).
  [[nodiscard]] std::int64_t unconverged() const { return unconverged_; }
  /// Rebuilds from the virgin factor (a copy and one update per rank of the open set), and updates
  /// appended to a held set.
  [[nodiscard]] std::int64_t rebuilds() const { return rebuilds_; }
  [[nodiscard]] std::int64_t appended_updates() const { return appended_updates_; }

  static constexpr int kMaxIterations = 50;

 private:
  /// The stretch at P = −1, α with exactly `open` (ascending) broken.
  core::Status solve_with_open(const std::vector<mesh::BondIndex>& open,
                               const std::vector<std::int64_t>& rank, double alpha,
                               std::vector<double>& stretch);
  /// Breaks `bonds` on held_ one rank at a time, ascending.
  core::Status append_by_rank(std::vector<mesh::BondIndex> bonds,
                              const std::vector<std::int64_t>& rank);

  mesh::Discretization closed_disc_;
  const model::PdModel& model_;
  std::vector<Support> supports_;
  std::vector<LoadTerm> loads_;
  std::vector<Tie> ties_;
  std::unique_ptr<StaticSolver> virgin_;  ///< every bond intact, factorized on first use
  std::vector<mesh::BondIndex> open_;     ///< the last converged open set (the warm start)
  /// The virgin factor with held_open_ broken in the canonical order (nullptr: none yet).
  std::unique_ptr<StaticSolver> held_;
  std::vector<mesh::BondIndex> held_open_;  ///< ascending
  std::int64_t held_last_rank_ = 0;         ///< the last rank applied to held_
  int last_iterations_ = 0;
  std::int64_t unconverged_ = 0;
  std::int64_t rebuilds_ = 0;
  std::int64_t appended_updates_ = 0;
};

}  // namespace peritwin::statics
