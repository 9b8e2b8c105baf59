#include "validation/ct_calibration.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace peritwin::validation {

double paris_c_in_mm_mpa(double c, double m, ParisUnits units) {
  // da/dN [mm] = 1e3 da/dN [m]; ΔK [Pa√m] = 1e6 ΔK [MPa√m].
  switch (units) {
    case ParisUnits::mm_per_cycle_mpa:
      return c;
    case ParisUnits::m_per_cycle_pa:
      return c * 1e3 * std::pow(1e6, m);
    case ParisUnits::m_per_cycle_mpa:
      return c * 1e3;
  }
  return c;
}

LifeComparison compare_lives(const CalibrationSetup& setup, const fatigue::StrainLawParams& law,
                             double p_max, double r, CrackHistory* history) {
  LifeComparison life;
  life.p_max = p_max;
  life.r = r;
  life.a_end = critical_crack_length(setup.coupon, p_max);
  // Run 2 mm (at least 2Δx) past a_end so that the PD crack is seen crossing it.
  const double a_stop = life.a_end + std::max(0.002, 2 * setup.dx);
  CrackHistory h = run_compact_tension(setup.coupon, setup.dx, law, p_max, r, a_stop,
                                       setup.record_every, true, setup.model);
  const double pd = cycles_at_length(h, life.a_end);
  life.pd_life = pd > 0 ? pd : std::nan("");
  life.paris_life = paris_life(setup.coupon, setup.paris, p_max, r, life.a_end);
  life.wall_s = h.wall_s;
  life.broken_bonds = h.broken_bonds;
  if (history != nullptr) *history = std::move(h);
  return life;
}

namespace {

/// 000 Eq. (26b) in the integral form of peritwin-validate: C_trial is the Paris C whose life to
/// a_end equals the PD life (Paris life ∝ 1/C at fixed M).
double eq26b_step(const CalibrationSetup& setup, const CalibrationRun& run) {
  const double c_trial = setup.paris.c * run.life.paris_life / run.life.pd_life;
  return fatigue::a2_calibrated(run.a2, setup.paris.c, c_trial);
}

/// The two-point model N_PD = N1 + k/A2 through the last two runs, solved for N_PD = N_Paris;
/// Eq. (26b) when the two runs do not define it (k <= 0, N1 >= N_Paris). The step is kept within
/// a factor 10 of the last A2.
double two_point_step(const CalibrationSetup& setup, const CalibrationRun& prev,
                      const CalibrationRun& last) {
  const double fallback = eq26b_step(setup, last);
  if (prev.a2 == last.a2) return fallback;
  const double k = (prev.life.pd_life - last.life.pd_life) / (1 / prev.a2 - 1 / last.a2);
  const double n1 = last.life.pd_life - k / last.a2;  // cycles that do not scale with 1/A2
  const double target = last.life.paris_life;
  if (!(k > 0) || !(n1 < target)) return fallback;
  return std::clamp(k / (target - n1), 0.1 * last.a2, 10 * last.a2);
}

}  // namespace

double next_a2(const CalibrationSetup& setup, const std::vector<CalibrationRun>& runs) {
  const std::size_t n = runs.size();
  return setup.step == A2Step::two_point && n >= 2 ? two_point_step(setup, runs[n - 2], runs[n - 1])
                                                   : eq26b_step(setup, runs[n - 1]);
}

CalibrationResult calibrate_a2(const CalibrationSetup& setup,
                               const std::function<void(const CalibrationRun&)>& on_run) {
  CalibrationResult result;
  fatigue::StrainLawParams law = setup.law;
  for (int i = 0; i < setup.max_runs; ++i) {
    CalibrationRun run;
    run.a2 = law.A2;
    run.life = compare_lives(setup, law, setup.p_max, setup.r, &run.history);
    result.runs.push_back(run);
    if (on_run) on_run(result.runs.back());
    if (!std::isfinite(run.life.pd_life)) {
      char text[200];
      std::snprintf(text, sizeof text,
                    "the PD crack at A2 = %.6g did not reach a = %.4g m (K_max = K_c) within %.3g "
                    "cycles",
                    run.a2, run.life.a_end,
                    run.history.cycles.empty() ? 0.0 : run.history.cycles.back());
      result.failure = text;
      if (!run.history.failure.empty()) result.failure += ": " + run.history.failure;
      result.a2 = std::nan("");
      return result;
    }
    if (std::abs(run.life.relative_error()) <= setup.tolerance) {
      result.converged = true;
      result.a2 = run.a2;
      return result;
    }
    law.A2 = next_a2(setup, result.runs);
  }
  result.a2 = law.A2;
  return result;
}

double default_calibration_load(const CompactTensionSpec& coupon) {
  return 4000.0 * (coupon.material.fracture_toughness / 48.7e6) * (coupon.thickness / 0.010) *
         std::sqrt(coupon.width / 0.050);
}

double a2_first_trial(const CompactTensionSpec& coupon, const ParisLaw& paris, double dx,
                      double horizon_ratio) {
  // log of C_SI·(E√δ)^M/Δx, C_SI in m/cycle with ΔK in Pa√m (from mm/cycle, MPa√m).
  auto log_g = [](double c_mm_mpa, double m, double e, double delta, double spacing) {
    const double log_c_si = std::log(c_mm_mpa * 1e-3) - m * std::log(1e6);
    return log_c_si + m * std::log(e * std::sqrt(delta)) - std::log(spacing);
  };
  const double b1 = log_g(4.34e-7, 2.6183, 68e9, 3.015e-3, 1e-3);
  const double user =
      log_g(paris.c, paris.m, coupon.material.youngs_modulus, horizon_ratio * dx, dx);
  return 1301.0 * std::exp(user - b1);
}

std::optional<std::string> coupon_grid_problem(const CompactTensionSpec& coupon, double dx) {
  char text[400];
  const double rows = 0.6 * coupon.width / dx;  // node rows between y = 0 and the top edge
  if (std::abs(rows - std::round(rows)) > 1e-6 * rows) {
    const double n = std::max(1.0, std::floor(rows));
    std::snprintf(text, sizeof text,
                  "the crack line y = 0 must fall midway between two node rows, i.e. 0.6W/dx must "
                  "be a whole number (W = %g m, dx = %g m give %.4g): use dx = %.6g or %.6g m",
                  coupon.width, dx, rows, 0.6 * coupon.width / (n + 1), 0.6 * coupon.width / n);
    return text;
  }
  const double ligament = (coupon.width - coupon.initial_crack) / dx;
  if (ligament < 20) {
    std::snprintf(
        text, sizeof text,
        "the ligament W - a0 = %g m holds only %.0f grid spacings; at least 20 are needed "
        "for a crack growth curve (dx <= %.4g m)",
        coupon.width - coupon.initial_crack, std::floor(ligament),
        (coupon.width - coupon.initial_crack) / 20);
    return text;
  }
  return std::nullopt;
}

}  // namespace peritwin::validation
