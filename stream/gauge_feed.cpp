#include "stream/gauge_feed.h"

#include <algorithm>
#include <cmath>

namespace peritwin::stream {

std::vector<GaugeInfluence> influences_of(const peritwin_msgs::damage_state_t& s) {
  std::vector<GaugeInfluence> out;
  const std::size_t n =
      std::min({s.gauge_ids.size(), s.gauge_per_constant.size(), s.gauge_per_cos.size(),
                s.gauge_per_sin.size(), s.gauge_noise.size()});
  for (std::size_t g = 0; g < n; ++g) {
    out.push_back({s.gauge_ids[g],
                   {s.gauge_per_constant[g], s.gauge_per_cos[g], s.gauge_per_sin[g]},
                   s.gauge_noise[g]});
  }
  return out;
}

core::Status GaugeFeed::header(std::string_view line,
                               const std::vector<GaugeInfluence>& influence) {
  auto columns = parse_gauge_header(line);
  if (!columns) return core::failure(columns.error());
  auto created = LoadIdentifier::create(*columns, influence);
  if (!created) return core::failure(created.error());
  identifier_.emplace(std::move(*created));
  noise_.clear();
  for (const auto& id : identifier_->columns()) {
    for (const auto& g : influence) {
      if (g.id == id) noise_.push_back(g.noise);
    }
  }
  reset_window();
  return {};
}

core::Status GaugeFeed::update(const std::vector<GaugeInfluence>& influence) {
  if (!identifier_) return {};
  return identifier_->update(influence);
}

void GaugeFeed::reset_window() {
  const std::size_t n = identifier_ ? identifier_->columns().size() : 0;
  window_ = Window{};
  window_.strain_times_model.assign(n, 0.0);
  window_.model_squared.assign(n, 0.0);
  window_.residual_squared.assign(n, 0.0);
}

core::Expected<std::optional<IdentifiedSample>, std::string> GaugeFeed::line(
    std::string_view text) {
  const std::size_t n = identifier_->columns().size();
  auto parsed = parse_gauge_line(text, n);
  if (!parsed) return parsed.error();
  if (!*parsed) return std::optional<IdentifiedSample>{};
  const GaugeSample& s = **parsed;
  IdentifiedSample out{s.t, identifier_->identify(s.strains)};
  if (!std::isfinite(out.load.p)) return std::string("the gauges' strains identify no load");
  for (std::size_t g = 0; g < n; ++g) {
    const double model = identifier_->model_strain(g, out.load.p, out.load.alpha);
    window_.strain_times_model[g] += s.strains[g] * model;
    window_.model_squared[g] += model * model;
    const double r = s.strains[g] - model;
    window_.residual_squared[g] += r * r;
  }
  window_.abs_p += std::abs(out.load.p);
  window_.abs_p_alpha += std::abs(out.load.p) * out.load.alpha;
  ++window_.samples;
  return std::optional<IdentifiedSample>{out};
}

std::optional<messages::Observation> GaugeFeed::take_observation() {
  if (!identifier_ || window_.samples == 0 || !(window_.abs_p > 0)) return std::nullopt;
  messages::Observation o;
  o.kind = messages::ObservationKind::gauge_compliance;
  o.gauge_angle_rad = window_.abs_p_alpha / window_.abs_p;
  const auto& columns = identifier_->columns();
  for (std::size_t g = 0; g < columns.size(); ++g) {
    const double yy = window_.model_squared[g];
    const double per_n = identifier_->model_strain(g, 1.0, o.gauge_angle_rad);
    if (!(yy > 0) || per_n == 0.0) continue;  // the model's gauge reads nothing of this load
    const double slope = window_.strain_times_model[g] / yy;
    const double noise =
        noise_[g] > 0
            ? noise_[g]
            : std::sqrt(window_.residual_squared[g] / static_cast<double>(window_.samples));
    const double sigma = noise * std::abs(per_n) / std::sqrt(yy);
    if (!(sigma > 0) || !std::isfinite(sigma)) continue;  // a perfect fit without a noise figure
    o.gauges.push_back({columns[g], slope * per_n, sigma, per_n});
  }
  reset_window();
  if (o.gauges.empty()) return std::nullopt;
  return o;
}

}  // namespace peritwin::stream
