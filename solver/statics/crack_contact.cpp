#include "solver/statics/crack_contact.h"

#include <algorithm>
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

core::Status CrackFaceContact::solve_with_open(const std::vector<mesh::BondIndex>& open,
                                               double alpha, std::vector<double>& stretch) {
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
  // The last solve with an open set, when it had this one at this angle: the same numbers (the
  // result is a function of (open set, α) alone). After a break whose new faces close, the set
  // does not change and no factor is copied.
  if (last_valid_ && last_alpha_ == alpha && last_open_ == open) {
    stretch = last_stretch_;
    return {};
  }
  ++updated_solves_;
  StaticSolver copy(*virgin_);  // the virgin factor, then the open set broken by rank updates
  if (auto r = copy.break_bonds(open); !r.ok()) return r;
  copy.stretch(-1.0, alpha, stretch);
  last_valid_ = true;
  last_alpha_ = alpha;
  last_open_ = open;
  last_stretch_ = stretch;
  return {};
}

core::Status CrackFaceContact::compressive_stretch(const std::vector<std::uint8_t>& intact,
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
    if (auto r = solve_with_open(open, alpha, stretch); !r.ok()) return r;
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
