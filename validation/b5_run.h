// peritwin-validate --case B5 (issue 35, docs/validation.md): paper 004's strain-controlled
// low-cycle fatigue of 316L (validation/b5_low_cycle.h) for its three loadings and both models.
//
// The kinetic law's U, γ per S–N segment (210–250, 250–290, 290–294 MPa) are fitted here on the
// NUREG/CR-6909 Rev. 0 curve through 004's tensile curve (004 Fig. 8b and 12a are lost): the
// conventional model with θ = kT, the modified one with θ = kT + ψ·A at each segment's midpoint
// loop (A230, A270 of the Masing loop on the curve). The modified runs then take the paper's
// measured-area mode (004 Fig. 12b): A(±0.18 %) for the symmetric loading, 0.78·A230 for POL,
// 0.45·A270 for PUL; with --b5-own-loops, each bond's own loop from the model instead.
//
// JSON lines: {"case":"B5-calibration",…} per model and segment, then per run {"case":"B5",
// "loading","model","n25_cycles","paper_n25","to_paper",…,"wall_s"}. Pictures: the specimen's
// σ–ε loops at N = 10, 1,000, 100,000 (004 Fig. 16, 18, 19) in <out>/b5_<loading>_<model>.png.
#pragma once

#include <filesystem>
#include <string>

namespace peritwin::validation {

struct B5RunOptions {
  std::string loadings = "all";  ///< all | symmetric | pol | pul
  std::string models = "all";    ///< all | conventional | modified
  int points_across = 17;
  /// ψ of Eq. (26) (m³): 004's "ψ = 50" has no SI meaning (docs/kinetic.md); this default puts
  /// ψ·A270 at 0.17 kT, which gives 004's three modified/conventional ratios on one bond
  /// (fitted on PUL, so PUL's modified life is not a prediction).
  double psi = 1.85e-28;
  bool own_loops = false;
  double k_u = 1.2;  ///< 004 step 6
};

int run_b5(const B5RunOptions& options, const std::filesystem::path& out_dir);

}  // namespace peritwin::validation
