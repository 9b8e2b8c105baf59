#include "validation/b1_compact_tension.h"

#include <chrono>
#include <cmath>

#include "solver/crack/crack_tracker.h"
#include "solver/fatigue/fatigue_engine.h"

namespace peritwin::validation {

double critical_crack_length(const CompactTensionSpec& spec, double p_max) {
  // Bisection on K_max(a) = K_c, K_max by 000 Eq. (A2) with ΔP = P_max.
  double lo = spec.initial_crack, hi = 0.95 * spec.width;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    const double k = crack::compact_tension_delta_k(p_max, spec.thickness, spec.width, mid);
    (k < spec.material.fracture_toughness ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double paris_life(const CompactTensionSpec& spec, const ParisLaw& paris, double p_max, double r,
                  double a_end) {
  auto dn_da = [&](double a) {  // cycles per metre
    const double dk =
        crack::compact_tension_delta_k(p_max * (1 - r), spec.thickness, spec.width, a) / 1e6;
    return 1.0 / (paris.c * std::pow(dk, paris.m) * 1e-3);
  };
  return integrate_simpson(dn_da, spec.initial_crack, a_end, 2000);
}

CrackHistory run_compact_tension(const CompactTensionSpec& spec, double dx,
                                 const fatigue::StrainLawParams& law, double p_max, double r,
                                 double a_stop, std::int64_t record_every, bool incremental,
                                 const CompactTensionModel& model) {
  const auto t0 = std::chrono::steady_clock::now();
  const statics::Specimen s = make_compact_tension(spec, model.options, dx, model.horizon_ratio);
  fatigue::FatigueSettings settings;
  settings.law = model.law;
  settings.strain = law;
  settings.phase_switch_damage = model.phase_switch_damage;
  settings.incremental = incremental;
  fatigue::FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings);
  CrackHistory history;
  if (!engine.initialize()) {
    history.failure = engine.failure_reason();
    return history;
  }
  const crack::CrackTracker tracker(s.disc, s.geometry.notches);
  const double load_line = 0.25 * spec.width;
  auto record = [&] {
    const auto cracks = tracker.measure(engine.node_damage());
    const double a = cracks.front().tip.x - load_line;
    history.cycles.push_back(static_cast<double>(engine.total_cycles()));
    history.crack_length.push_back(std::max(a, spec.initial_crack));
    return a;
  };
  record();
  while (true) {
    const auto status = engine.apply({p_max, r, 0.0, record_every});
    const double a = record();
    if (status == fatigue::EngineStatus::final_failure) {
      history.final_failure = true;
      break;
    }
    if (a >= a_stop || engine.total_cycles() > 100'000'000) break;
  }
  history.broken_bonds = engine.broken_bonds();
  history.solves = engine.solves();
  history.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return history;
}

double cycles_at_length(const CrackHistory& h, double a) {
  for (std::size_t i = 1; i < h.crack_length.size(); ++i) {
    if (h.crack_length[i] >= a) {
      const double a0 = h.crack_length[i - 1], a1 = h.crack_length[i];
      const double t = a1 > a0 ? (a - a0) / (a1 - a0) : 1.0;
      return h.cycles[i - 1] + t * (h.cycles[i] - h.cycles[i - 1]);
    }
  }
  return -1.0;
}

double fitted_paris_constant(const CompactTensionSpec& spec, const CrackHistory& h, double p_max,
                             double r, double m, double a_from, double a_to) {
  // Smooth by resampling the (monotone) history at crack-length steps of 1 mm: dq/dN over each
  // step against ΔK at its midpoint (000 App. A Step 2), log C = mean(log(dq/dN) − M log ΔK).
  double sum = 0;
  int count = 0;
  const double step = 0.001;
  for (double a = a_from; a + step <= a_to; a += step) {
    const double n0 = cycles_at_length(h, a);
    const double n1 = cycles_at_length(h, a + step);
    if (n0 < 0 || n1 <= n0) continue;
    const double rate_mm = step * 1e3 / (n1 - n0);
    const double dk = crack::compact_tension_delta_k(p_max * (1 - r), spec.thickness, spec.width,
                                                     a + 0.5 * step) /
                      1e6;
    sum += std::log(rate_mm) - m * std::log(dk);
    ++count;
  }
  return count > 0 ? std::exp(sum / count) : std::nan("");
}

}  // namespace peritwin::validation
