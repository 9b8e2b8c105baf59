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
// Signorini conditions on the bonds. Each solve is the virgin factor (every bond intact,
// notch cuts too: factorized once) with the open set broken by rank updates (StaticSolver::
// break_bonds, in ascending bond order) on a copy, so the result is a function of the converged
// open set alone: the same whatever the warm start (checkpoints resume bit for bit). With O empty
// the virgin solution itself is the answer: a mode-I crack under compression closes along its
// whole length and the body carries the load as if uncracked, at the cost of three
// multiply-adds per bond.
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
  /// bonds of `intact` (0 = broken, the detail solver's) in contact where they close. The
  /// solution for P_min < 0 is |P_min| times it. An error if a solve fails (a singular system
  /// with the open set broken).
  core::Status compressive_stretch(const std::vector<std::uint8_t>& intact, double alpha,
                                   std::vector<double>& stretch);

  /// The broken bonds left open by the last call (ascending), and its active-set iterations.
  [[nodiscard]] const std::vector<mesh::BondIndex>& open_bonds() const { return open_; }
  [[nodiscard]] int last_iterations() const { return last_iterations_; }
  /// Calls that reached kMaxIterations without a repeated set (the last iterate was used).
  [[nodiscard]] std::int64_t unconverged() const { return unconverged_; }
  /// Solves with a non-empty open set (each a factor copy and |O| rank updates); a set met again
  /// at the same angle reuses the last one's stretches.
  [[nodiscard]] std::int64_t updated_solves() const { return updated_solves_; }

  static constexpr int kMaxIterations = 50;

 private:
  /// The stretch at P = −1, α with exactly `open` broken; false with the reason in `why`.
  core::Status solve_with_open(const std::vector<mesh::BondIndex>& open, double alpha,
                               std::vector<double>& stretch);

  mesh::Discretization closed_disc_;
  const model::PdModel& model_;
  std::vector<Support> supports_;
  std::vector<LoadTerm> loads_;
  std::vector<Tie> ties_;
  std::unique_ptr<StaticSolver> virgin_;  ///< every bond intact, factorized on first use
  std::vector<mesh::BondIndex> open_;     ///< the last converged open set (the warm start)
  /// The last solve with a non-empty open set: its angle, set and stretches.
  bool last_valid_ = false;
  double last_alpha_ = 0.0;
  std::vector<mesh::BondIndex> last_open_;
  std::vector<double> last_stretch_;
  int last_iterations_ = 0;
  std::int64_t unconverged_ = 0;
  std::int64_t updated_solves_ = 0;
};

}  // namespace peritwin::statics
