#include "twin/gauges.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "solver/statics/gauges.h"

namespace peritwin::twin {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

std::vector<ModelGauge> model_gauges(const std::vector<config::GaugeConfig>& gauges,
                                     const mesh::Discretization& disc) {
  std::vector<ModelGauge> out;
  out.reserve(gauges.size());
  for (const auto& g : gauges) {
    out.push_back({g, statics::gauge_nodes(disc, {g.at, g.angle, g.length})});
  }
  return out;
}

std::vector<std::array<double, 3>> gauge_influences(const std::vector<ModelGauge>& gauges,
                                                    const statics::StaticSolver& solver) {
  std::vector<std::array<double, 3>> out;
  out.reserve(gauges.size());
  for (const auto& g : gauges) {
    out.push_back(statics::gauge_influence(solver, g.nodes, g.config.angle));
  }
  return out;
}

GaugeResiduals GaugeResiduals::none(const std::vector<ModelGauge>& gauges) {
  GaugeResiduals r;
  for (const auto& g : gauges) r.ids.push_back(g.config.id);
  r.residual.assign(gauges.size(), kNaN);
  r.sigma.assign(gauges.size(), kNaN);
  r.in_a_row.assign(gauges.size(), 0);
  return r;
}

GaugeResiduals GaugeResiduals::for_gauges(const std::vector<ModelGauge>& gauges) const {
  GaugeResiduals r = none(gauges);
  for (std::size_t k = 0; k < r.ids.size(); ++k) {
    for (std::size_t j = 0; j < ids.size(); ++j) {
      if (ids[j] != r.ids[k] || j >= residual.size() || j >= sigma.size() || j >= in_a_row.size()) {
        continue;
      }
      r.residual[k] = residual[j];
      r.sigma[k] = sigma[j];
      r.in_a_row[k] = in_a_row[j];
    }
  }
  return r;
}

std::string GaugeResiduals::alarm() const {
  std::string out;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    if (in_a_row[k] < kGaugeAlarmAfter) continue;
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "gauge %s: compliance residual %+.1f %% (%.1f σ) in %lld gauge observations in a "
                  "row",
                  ids[k].c_str(), 100.0 * residual[k], std::abs(residual[k]) / sigma[k],
                  static_cast<long long>(in_a_row[k]));
    if (!out.empty()) out += "; ";
    out += buf;
  }
  return out;
}

core::Expected<std::vector<std::size_t>> observed_gauge_indices(
    const messages::Observation& o, const std::vector<ModelGauge>& gauges) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < o.gauges.size(); ++i) {
    std::size_t k = 0;
    while (k < gauges.size() && gauges[k].config.id != o.gauges[i].id) ++k;
    if (k == gauges.size()) {
      return core::Error{"gauges[" + std::to_string(i) + "].id",
                         "the detail has no gauge \"" + o.gauges[i].id + "\""};
    }
    out.push_back(k);
  }
  return out;
}

std::vector<double> predicted_compliance(const messages::Observation& o,
                                         const std::vector<std::size_t>& indices,
                                         const std::vector<ModelGauge>& gauges,
                                         const std::vector<std::array<double, 3>>& influences) {
  const std::size_t n = o.gauges.size();
  bool weighted = true;
  for (std::size_t i = 0; i < n; ++i) {
    if (o.gauges[i].identifies) weighted = weighted && gauges[indices[i]].config.noise > 0;
  }
  std::vector<double> model(n);
  double tx = 0.0, tt = 0.0;  // Σ w v^t v^X, Σ w (v^t)²
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t k = indices[i];
    model[i] = statics::gauge_strain(influences[k], 1.0, o.gauge_angle_rad);
    const double noise = gauges[k].config.noise;
    const double w = weighted ? 1.0 / (noise * noise) : 1.0;
    if (!o.gauges[i].identifies) continue;  // compared only: not in the identification
    tx += w * o.gauges[i].model * model[i];
    tt += w * o.gauges[i].model * o.gauges[i].model;
  }
  // k_X = tx / tt (see the top of gauges.h); m^X = v^X / k_X.
  const double k_x = tx / tt;
  std::vector<double> out(n);
  for (std::size_t i = 0; i < n; ++i)
    out[i] = std::isfinite(k_x) && k_x != 0 ? model[i] / k_x : kNaN;
  return out;
}

double gauge_log_likelihood(const messages::Observation& o, const std::vector<double>& predicted,
                            const std::vector<double>& model_sigma) {
  double sum = 0.0;
  for (std::size_t i = 0; i < o.gauges.size(); ++i) {
    if (!std::isfinite(predicted[i])) return -std::numeric_limits<double>::infinity();
    const double extra =
        i < model_sigma.size() && std::isfinite(model_sigma[i]) ? model_sigma[i] : 0;
    const double window = kGaugeModelFraction * predicted[i];
    const double variance = o.gauges[i].sigma * o.gauges[i].sigma + extra * extra + window * window;
    const double d = o.gauges[i].compliance - predicted[i];
    sum += d * d / variance + std::log(variance);
  }
  return -0.5 * sum;
}

void take_in(GaugeResiduals& residuals, const messages::Observation& o,
             const std::vector<std::size_t>& indices, const std::vector<double>& predicted) {
  for (std::size_t i = 0; i < o.gauges.size(); ++i) {
    const std::size_t k = indices[i];
    const double scale = std::abs(predicted[i]);
    const bool readable = std::isfinite(predicted[i]) && scale > 0;
    residuals.residual[k] = readable ? (o.gauges[i].compliance - predicted[i]) / scale : kNaN;
    residuals.sigma[k] = readable ? o.gauges[i].sigma / scale : kNaN;
    const bool beyond =
        !readable || std::abs(o.gauges[i].compliance - predicted[i]) >
                         std::max(kGaugeAlarmSigmas * o.gauges[i].sigma, kGaugeAlarmFloor * scale);
    residuals.in_a_row[k] = beyond ? residuals.in_a_row[k] + 1 : 0;
  }
}

}  // namespace peritwin::twin
