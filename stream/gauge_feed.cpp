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

core::Status GaugeFeed::header(std::string_view line, const std::vector<GaugeInfluence>& influence,
                               const std::vector<std::string>& identify_with) {
  auto columns = parse_gauge_header(line);
  if (!columns) return core::failure(columns.error());
  columns_ = std::move(*columns);
  const std::vector<std::string> identifying = identify_with.empty() ? columns_ : identify_with;
  identifying_.clear();
  for (const auto& id : identifying) {
    const auto at = std::find(columns_.begin(), columns_.end(), id);
    if (at == columns_.end()) {
      return core::failure("--identify-with names gauge \"" + id +
                           "\", which is no column of the header");
    }
    identifying_.push_back(static_cast<std::size_t>(at - columns_.begin()));
  }
  if (const core::Status taken = take_coefficients(influence); !taken) return taken;
  auto created = LoadIdentifier::create(identifying, influence);
  if (!created) return core::failure(created.error());
  identifier_.emplace(std::move(*created));
  reset_window();
  return {};
}

core::Status GaugeFeed::take_coefficients(const std::vector<GaugeInfluence>& influence) {
  std::vector<std::array<double, 3>> per_basis;
  std::vector<double> noise;
  for (const auto& id : columns_) {
    const auto it = std::find_if(influence.begin(), influence.end(),
                                 [&](const GaugeInfluence& g) { return g.id == id; });
    if (it == influence.end()) {
      return core::failure("column \"" + id + "\" is no gauge of the detail");
    }
    per_basis.push_back(it->per_basis);
    noise.push_back(it->noise);
  }
  per_basis_ = std::move(per_basis);
  noise_ = std::move(noise);
  return {};
}

core::Status GaugeFeed::update(const std::vector<GaugeInfluence>& influence) {
  if (!identifier_) return {};
  if (const core::Status ok = identifier_->update(influence); !ok) return ok;
  return take_coefficients(influence);
}

double GaugeFeed::model_strain(std::size_t g, double p, double alpha) const {
  const auto& c = per_basis_[g];
  return p * (c[0] + std::cos(alpha) * c[1] + std::sin(alpha) * c[2]);
}

void GaugeFeed::reset_window() {
  const std::size_t n = columns_.size();
  window_ = Window{};
  window_.strain_times_model.assign(n, 0.0);
  window_.model_squared.assign(n, 0.0);
  window_.residual_squared.assign(n, 0.0);
}

core::Expected<std::optional<IdentifiedSample>, std::string> GaugeFeed::line(
    std::string_view text) {
  const std::size_t n = columns_.size();
  auto parsed = parse_gauge_line(text, n);
  if (!parsed) return parsed.error();
  if (!*parsed) return std::optional<IdentifiedSample>{};
  const GaugeSample& s = **parsed;
  subset_.resize(identifying_.size());
  for (std::size_t i = 0; i < identifying_.size(); ++i) subset_[i] = s.strains[identifying_[i]];
  IdentifiedSample out{s.t, identifier_->identify(subset_)};
  if (!std::isfinite(out.load.p)) return std::string("the gauges' strains identify no load");
  for (std::size_t g = 0; g < n; ++g) {
    const double model = model_strain(g, out.load.p, out.load.alpha);
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
  for (std::size_t g = 0; g < columns_.size(); ++g) {
    const double yy = window_.model_squared[g];
    const double per_n = model_strain(g, 1.0, o.gauge_angle_rad);
    if (!(yy > 0) || per_n == 0.0) continue;  // the model's gauge reads nothing of this load
    const double slope = window_.strain_times_model[g] / yy;
    const double noise =
        noise_[g] > 0
            ? noise_[g]
            : std::sqrt(window_.residual_squared[g] / static_cast<double>(window_.samples));
    const double sigma = noise * std::abs(per_n) / std::sqrt(yy);
    if (!(sigma > 0) || !std::isfinite(sigma)) continue;  // a perfect fit without a noise figure
    const bool identifies =
        std::find(identifying_.begin(), identifying_.end(), g) != identifying_.end();
    o.gauges.push_back({columns_[g], slope * per_n, sigma, per_n, identifies});
  }
  reset_window();
  if (std::none_of(o.gauges.begin(), o.gauges.end(),
                   [](const messages::GaugeCompliance& g) { return g.identifies; })) {
    return std::nullopt;
  }
  return o;
}

}  // namespace peritwin::stream
