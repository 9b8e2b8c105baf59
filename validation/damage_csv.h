// Node damage snapshot as CSV (x_m,y_m,damage), the format peritwin-snapshot-png renders.
#pragma once

#include <fstream>
#include <string>
#include <vector>

#include "solver/mesh/discretization.h"

namespace peritwin::validation {

inline void write_damage_csv(const std::string& path, const mesh::Discretization& disc,
                             const std::vector<double>& damage) {
  std::ofstream out(path);
  out << "x_m,y_m,damage\n";
  for (mesh::NodeIndex n = 0; n < disc.num_nodes(); ++n) {
    out << disc.position[n].x << ',' << disc.position[n].y << ','
        << damage[static_cast<std::size_t>(n)] << '\n';
  }
}

}  // namespace peritwin::validation
