// U and γ of the kinetic law from an S-N curve (004 Fig. 4a, 8b); contracts in
// kinetic_calibration.h.
#include "solver/fatigue/laws/kinetic_calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "solver/fatigue/laws/law_math.h"

namespace peritwin::fatigue {

using detail::positive;

namespace {

/// σ_max of a cycle of amplitude σ_a at R: σ_a = σ_max(1 − R)/2 (004 Sec. KTF).
double sigma_max_of(double stress_amplitude, double load_ratio) {
  return 2.0 * stress_amplitude / (1.0 - load_ratio);
}

/// The stress part of ln Φ (004 Eq. 15, kt_cycle_dose) at b = γ/θ, R < 1: with x = bσ_max,
/// w = x(1 − R), g = x + ln((1 − e^−w)/w), so that ln Φ = ln(θ/(h f)) − U/θ + g.
double log_bracket(double b, double sigma_max, double load_ratio) {
  const double x = b * sigma_max;
  const double w = x * (1.0 - load_ratio);
  return x + std::log(-std::expm1(-w) / w);
}

/// dg/db of log_bracket: σ_max + σ_max(1 − R)(1/(e^w − 1) − 1/w).
double log_bracket_slope(double b, double sigma_max, double load_ratio) {
  const double w = b * sigma_max * (1.0 - load_ratio);
  return sigma_max + sigma_max * (1.0 - load_ratio) * (1.0 / std::expm1(w) - 1.0 / w);
}

/// For fixed b the least-squares u = U/θ and the residuals' sum of squares and its derivative in
/// ln b (the residuals sum to zero, so d/db Σe² = 2 Σ e_i g_i'(b)).
struct Profile {
  double u = 0.0;
  double sum_squares = 0.0;
  double slope = 0.0;  // d(sum_squares)/d ln b
};

Profile profile(double log_b, const std::vector<double>& log_n, const std::vector<double>& sigma,
                double load_ratio, double c0) {
  const double b = std::exp(log_b);
  const std::size_t m = log_n.size();
  std::vector<double> y(m);
  double mean = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    // ln N_i = c0 − g_i(b) + u, c0 = ln r0 − ln(θ/(h f)).
    y[i] = log_n[i] - c0 + log_bracket(b, sigma[i], load_ratio);
    mean += y[i];
  }
  mean /= static_cast<double>(m);
  Profile p;
  p.u = mean;
  for (std::size_t i = 0; i < m; ++i) {
    const double e = y[i] - mean;
    p.sum_squares += e * e;
    p.slope += 2.0 * e * log_bracket_slope(b, sigma[i], load_ratio) * b;
  }
  return p;
}

core::Error point_error(std::size_t i, const char* field, const std::string& reason) {
  return {"points[" + std::to_string(i) + "]." + field, reason};
}

}  // namespace

double kt_sn_life(double stress_amplitude, double load_ratio, double frequency, double U,
                  double gamma, double lambda, double n0, double thermal_energy) {
  const double dose = kt_cycle_dose(sigma_max_of(stress_amplitude, load_ratio), load_ratio,
                                    frequency, U, gamma, thermal_energy);
  return kt_remaining_life(0.0, lambda, n0) / dose;  // 004 Eq. (15) solved for N at n = 1
}

core::Expected<KineticFit> kt_calibrate_segment(std::span<const SnPoint> points, double load_ratio,
                                                const KineticParams& fixed, double thermal_energy) {
  if (points.size() < 2) {
    return core::Error{"points", "need at least 2 S-N points to fit U and gamma (got " +
                                     std::to_string(points.size()) + ")"};
  }
  if (!(std::isfinite(load_ratio) && load_ratio < 1.0)) {
    return core::Error{"load_ratio",
                       "must be finite and < 1 (got " + core::format_number(load_ratio) + ")"};
  }
  if (!positive(thermal_energy)) {
    return core::Error{"thermal_energy", "must be finite and > 0 J"};
  }
  if (!positive(fixed.lambda) || !(std::isfinite(fixed.n0) && fixed.n0 > 1.0) ||
      !positive(fixed.frequency)) {
    return core::Error{"fixed", "lambda > 0, n0 > 1 and frequency > 0 needed (004 Eq. 12, 15)"};
  }
  std::vector<double> log_n, sigma;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SnPoint& p = points[i];
    if (!positive(p.stress_amplitude)) {
      return point_error(
          i, "stress_amplitude",
          "must be finite and > 0 Pa (got " + core::format_number(p.stress_amplitude) + ")");
    }
    if (!positive(p.cycles)) {
      return point_error(i, "cycles",
                         "must be finite and > 0 (got " + core::format_number(p.cycles) + ")");
    }
    log_n.push_back(std::log(p.cycles));
    sigma.push_back(sigma_max_of(p.stress_amplitude, load_ratio));
  }
  const auto [lo_it, hi_it] = std::minmax_element(sigma.begin(), sigma.end());
  const double sigma_lo = *lo_it, sigma_hi = *hi_it;
  if (!(sigma_hi > sigma_lo)) {
    return core::Error{"points", "need at least 2 distinct stress amplitudes (gamma is the slope)"};
  }
  const double r0 = kt_remaining_life(0.0, fixed.lambda, fixed.n0);
  const double c0 = std::log(r0) - std::log(thermal_energy / (kPlanck * fixed.frequency));

  // Grid in t = ln b: γσ_max/θ from 1e-3 at the highest stress to 1e4 at the lowest.
  const double t_lo = std::log(1e-3 / sigma_hi);
  const double t_hi = std::log(1e4 / sigma_lo);
  constexpr int kGrid = 512;
  const double dt = (t_hi - t_lo) / kGrid;
  int best = 0;
  double best_s = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= kGrid; ++k) {
    const double s = profile(t_lo + k * dt, log_n, sigma, load_ratio, c0).sum_squares;
    if (s < best_s) {
      best_s = s;
      best = k;
    }
  }
  if (best == 0 || best == kGrid) {
    return core::Error{"points", std::string("no interior best fit: the points ask for gamma -> ") +
                                     (best == 0 ? "0 (life hardly falls with stress)"
                                                : "infinity (life falls too steeply)") +
                                     "; check the points and the load ratio"};
  }
  // Bisect the derivative's sign change in [t_{k-1}, t_{k+1}] (the grid minimum lies there);
  // if the sum is flat to rounding there (exact data), it is already at the bit level.
  double lo = t_lo + (best - 1) * dt, hi = t_lo + (best + 1) * dt;
  if (profile(lo, log_n, sigma, load_ratio, c0).slope < 0.0 &&
      profile(hi, log_n, sigma, load_ratio, c0).slope > 0.0) {
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      (profile(mid, log_n, sigma, load_ratio, c0).slope < 0.0 ? lo : hi) = mid;
    }
  } else {
    lo = hi = t_lo + best * dt;
  }
  const double t = 0.5 * (lo + hi);
  const Profile p = profile(t, log_n, sigma, load_ratio, c0);
  KineticFit fit;
  fit.U = p.u * thermal_energy;
  fit.gamma = std::exp(t) * thermal_energy;
  double sum = 0.0;
  for (const SnPoint& pt : points) {
    const double e = std::log(pt.cycles) -
                     std::log(kt_sn_life(pt.stress_amplitude, load_ratio, fixed.frequency, fit.U,
                                         fit.gamma, fixed.lambda, fixed.n0, thermal_energy));
    fit.max_abs_log_error = std::max(fit.max_abs_log_error, std::abs(e));
    sum += e * e;
  }
  fit.rms_log_error = std::sqrt(sum / static_cast<double>(points.size()));
  if (!positive(fit.U)) {
    return core::Error{"points", "the best fit has U <= 0 (" + core::format_number(fit.U) +
                                     " J): the lives are too short for Eq. (15) at this θ"};
  }
  return fit;
}

}  // namespace peritwin::fatigue
