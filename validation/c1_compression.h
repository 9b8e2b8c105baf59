// peritwin-validate --case C1 (issue 34, docs/compression.md): lives under reversed loading by
// each compression rule, against the Paris law with ASTM E647's ΔK = K_max for R <= 0 and against
// Newman's closure function.
//
// Geometries: the demo's CT (examples/b1-ct-al6061.toml, 4 kN, end of life at 8 mm of growth) at
// R = 0.3, 0.1, 0, −0.5, −1, −2, and the middle-crack tension panel (examples/
// mt-panel-al6061.toml, its 40 kN, end of life at phase III) at R = 0.1, 0, −1, where the crack
// closes symmetrically. For each rule (full_range, contact, closure with Newman's α = 2,
// S_max/σ0 = 0.3) the life from the virgin state under constant-amplitude blocks of 1000 cycles
// (twin::simulate_life, the detail's own end criterion).
//
// References, each anchored at the same rule's life at R = 0.1 (the calibration's load ratio):
//   Paris, ΔK = K_max(1 − max(R, 0)) (ASTM E647 for R <= 0): N(R) = N(0.1)·(0.9/(1 − R⁺))^M
//   Newman: ΔK_eff = (1 − f(R))K_max:            N(R) = N(0.1)·((1 − f(0.1))/(1 − f(R)))^M
// with M = m2 (the Paris exponent, 000 Eq. 25). The twin's lives mix phase I (exponent m1) and
// phase II (m2), so even a rule that is exactly one of the references differs from it by the
// phase I share.
//
// JSON lines: {"case":"C1","geometry":"ct"|"mt","rule":…,"r":…,"end_of_life_cycles":…,
// "paris_kmax_cycles":…,"newman_cycles":…,"to_paris":…,"to_newman":…,"ratio_to_r0":…,
// "breaks":…,"wall_s":…}, then per geometry {"case":"C1-cost",…}: the wall time of the contact
// rule's life at each R < 0 over the full-range rule's at R = 0.1 (the same crack grown).
// The plot: <out>/c1_ct_lives.png (life against R, each rule and both references).
#pragma once

#include <filesystem>
#include <string>

namespace peritwin::validation {

/// Runs C1 on the CT config and (unless empty) the panel config; pictures into `out_dir`.
/// Returns the exit code (0; 3 when a config does not load or a life cannot be simulated).
int run_c1_compression(const std::string& ct_config, const std::string& panel_config,
                       const std::filesystem::path& out_dir);

}  // namespace peritwin::validation
