#include "solver/statics/crack_contact.h"

#include <algorithm>
#include <iterator>
#include <utility>

namespace peritwin::statics {

namespace {
mesh::Discretization with_cuts_closed(const mesh::Discretization& disc) {
  mesh::Discretization d = disc;
  std::fill(d.bond_precut.begin(), d.bond_precut.end(), std::uint8_t{0});
  return d;
}
}  // namespace

CrackFaceContact::CrackFaceContact(const mesh::Discretization& disc, const model::PdModel& model,
                                   std::vector<Support> supports, std::vector<LoadTerm> loads,
                                   std::vector<Tie> ties)
    : closed_disc_(with_cuts_closed(disc)),
      model_(model),
      supports_(std::move(supports)),
      loads_(std::move(loads)),
      ties_(std::move(ties)) {}

core::Status CrackFaceContact::append_by_rank(std::vector<mesh::BondIndex> bonds,
                                              const std::vector<std::int64_t>& rank) {
  const auto rank_of = [&](mesh::BondIndex b) { return rank[static_cast<std::size_t>(b)]; };
  std::stable_sort(bonds.begin(), bonds.end(), [&](mesh::BondIndex a, mesh::BondIndex b) {
    return rank_of(a) < rank_of(b);  // ascending bond order within a rank (stable)
  });
  std::vector<mesh::BondIndex> group;
  for (std::size_t i = 0; i < bonds.size();) {
    const std::int64_t r = rank_of(bonds[i]);
    group.clear();
    for (; i < bonds.size() && rank_of(bonds[i]) == r; ++i) group.push_back(bonds[i]);
    if (auto status = held_->break_bonds(group); !status.ok()) return status;
    held_last_rank_ = r;
    ++appended_updates_;
  }
  return {};
}

core::Status CrackFaceContact::solve_with_open(const std::vector<mesh::BondIndex>& open,
                                               const std::vector<std::int64_t>& rank, double alpha,
                                               std::vector<double>& stretch) {
  if (!virgin_) {
    auto solver = std::make_unique<StaticSolver>(closed_disc_, model_, supports_, loads_, ties_);
    solver->set_incremental(true);
    if (auto r = solver->solve(); !r.ok()) return r;
    virgin_ = std::move(solver);
  }
  if (open.empty()) {
    virgin_->stretch(-1.0, alpha, stretch);
    return {};
  }
  // Reuse the held solver when `open` only adds bonds ranked after its last update.
  std::vector<mesh::BondIndex> added;
  bool reuse = held_ != nullptr &&
               std::includes(open.begin(), open.end(), held_open_.begin(), held_open_.end());
  if (reuse) {
    std::set_difference(open.begin(), open.end(), held_open_.begin(), held_open_.end(),
                        std::back_inserter(added));
    for (auto b : added) {
      if (rank[static_cast<std::size_t>(b)] <= held_last_rank_) reuse = false;
    }
  }
  if (!reuse) {
    ++rebuilds_;
    held_ = std::make_unique<StaticSolver>(*virgin_);
    held_open_.clear();
    added = open;
  }
  if (!added.empty()) {
    if (auto r = append_by_rank(added, rank); !r.ok()) {
      held_.reset();  // an unknown state: the next call rebuilds
      held_open_.clear();
      return r;
    }
    held_open_ = open;
  }
  held_->stretch(-1.0, alpha, stretch);
  return {};
}

core::Status CrackFaceContact::compressive_stretch(const std::vector<std::uint8_t>& intact,
                                                   const std::vector<std::int64_t>& rank,
                                                   double alpha, std::vector<double>& stretch) {
  // The warm start: the last open set, restricted to bonds still broken (all are: bonds never
  // heal), in ascending order.
  std::vector<mesh::BondIndex> open;
  for (auto b : open_) {
    if (!intact[static_cast<std::size_t>(b)]) open.push_back(b);
  }
  std::vector<mesh::BondIndex> next;
  last_iterations_ = 0;
  for (int it = 0;; ++it) {
    if (auto r = solve_with_open(open, rank, alpha, stretch); !r.ok()) return r;
    ++last_iterations_;
    next.clear();
    for (std::size_t b = 0; b < intact.size(); ++b) {
      if (!intact[b] && stretch[b] > 0.0) next.push_back(static_cast<mesh::BondIndex>(b));
    }
    if (next == open) break;
    if (it + 1 >= kMaxIterations) {
      ++unconverged_;
      break;
    }
    open.swap(next);
  }
  open_ = std::move(open);
  return {};
}

}  // namespace peritwin::statics
