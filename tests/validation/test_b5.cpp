// B5 (issue 35): paper 004's low-cycle fatigue scheme on a coarse strip.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "validation/b5_low_cycle.h"

namespace peritwin {
namespace {

constexpr double kEv = 1.602176634e-19;

validation::B5Kinetics note_kinetics() {
  return *validation::calibrate_b5_kinetics(model::PowerLawCurve{}, 0.0, 1.2);
}

TEST(B5, Explore) {
  validation::B5Specimen spec;
  spec.points_across = 17;
  const auto strip = validation::make_b5_specimen(spec);
  std::printf("nodes %d bonds %d\n", strip.disc.num_nodes(), strip.disc.num_bonds());
  validation::B5Options o;
  const auto r = validation::run_b5_loading(strip, model::PowerLawCurve{},
                                            validation::symmetric_loading(), note_kinetics(), o);
  std::printf(
      "n25 %lld cycles %lld broken %lld static %lld groups %lld ph2 %lld tps %lld newton %lld "
      "stalled %lld sub %lld peak "
      "%.1f final %.1f kappa %.4f wall %.1f depth %d dropped %lld reason %s\n",
      (long long)r.n25_cycles, (long long)r.cycles, (long long)r.broken_bonds,
      (long long)r.static_breaks, (long long)r.break_groups, (long long)r.phase_two_breaks,
      (long long)r.turning_points, (long long)r.newton_iterations,
      (long long)r.stalled_turning_points, (long long)r.substepped_turning_points,
      r.peak_stress / 1e6, r.final_stress / 1e6, r.kappa, r.wall_s, r.deepest_memory, (long long)r.dropped_reversals, r.reason.c_str());
}

}  // namespace
}  // namespace peritwin
