// A body ready to solve: what a static solve or a fatigue engine is built from. The twin builds
// one per detail from its config (twin/detail_model.h), the validation one per benchmark
// (validation/specimens.h).
#pragma once

#include <string>
#include <vector>

#include "solver/mesh/discretization.h"
#include "solver/mesh/geometry.h"
#include "solver/model/pd_model.h"
#include "solver/statics/static_solver.h"

namespace peritwin::statics {

/// A detail's geometry, discretization, model, supports and load pattern, owned together.
struct Specimen {
  std::string name;
  mesh::DetailGeometry geometry;
  model::Material material;
  mesh::Discretization disc;
  model::PdModel model;
  std::vector<Support> supports;
  std::vector<LoadTerm> loads;
  std::vector<Tie> ties;  ///< constraints outside the bond families (a loading fixture)
  /// strain control: displacements imposed on grips (the load's P in the control unit)
  std::vector<PrescribedDisplacement> prescribed;
  mesh::Point initial_crack_tip;
};

}  // namespace peritwin::statics
