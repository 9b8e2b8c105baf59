#include "bench/gauge_bench.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/json_line.h"
#include "stream/gauge_feed.h"
#include "stream/gauge_identification.h"
#include "stream/stream_tool.h"

namespace peritwin::bench {

namespace {

constexpr int kGauges = 8;
constexpr std::size_t kDistinct = 4096;  ///< distinct samples, used in turn
constexpr double kGoal = 1e4;            ///< samples/s on one core (issue 33)

/// Eight gauges of a rosette-like layout (strain per N ~ 1e-7), with a constant part when
/// `constant`, an angle part when `angle` (the layout of tests/stream/test_gauge_identification).
std::vector<stream::GaugeInfluence> rosette(bool constant, bool angle) {
  std::vector<stream::GaugeInfluence> gauges;
  for (int g = 0; g < kGauges; ++g) {
    const double theta = 0.3 + 0.7 * g;
    stream::GaugeInfluence gi;
    gi.id = std::to_string(g + 1);
    gi.id.insert(0, 1, 'g');
    gi.per_basis[0] = constant ? 1e-7 * (0.8 - 0.2 * g + 0.03 * g * g) : 0.0;
    gi.per_basis[1] = angle ? 1e-7 * std::cos(2.0 * theta) * (1.0 + 0.1 * g) : 0.0;
    gi.per_basis[2] = angle ? 1e-7 * std::sin(2.0 * theta + 0.4) : 0.0;
    gi.noise = 1e-6 * (1.0 + 0.25 * g);
    gauges.push_back(gi);
  }
  return gauges;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Timed {
  double seconds = 0.0;
  double sink = 0.0;
};

/// `samples` identify() calls over `strains` (kGauges per sample) in turn.
Timed time_identify(const stream::LoadIdentifier& id, const std::vector<double>& strains,
                    std::int64_t samples, std::vector<double>* residuals) {
  Timed t;
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t at = 0;
  for (std::int64_t s = 0; s < samples; ++s) {
    const stream::IdentifiedLoad l =
        id.identify(std::span<const double>(strains.data() + at * kGauges, kGauges), residuals);
    t.sink += l.p + l.alpha;
    at = at + 1 == kDistinct ? 0 : at + 1;
  }
  t.seconds = seconds_since(t0);
  return t;
}

/// The stream's whole per-sample path for `samples` text lines "t,<8 strains>" (kDistinct of
/// them, in turn, with increasing times at 10 kHz): GaugeFeed::line (parse, identify, the
/// compliance window's sums) then Pipeline::sample (rainflow, blocks, batches), with a compliance
/// observation taken every 5000 cycles' worth of samples as peritwin-stream does. Only the
/// reading of the line from the file or pipe and the sending are left out.
Timed time_stream(const std::vector<stream::GaugeInfluence>& gauges,
                  const std::vector<double>& strains, std::int64_t samples, std::int64_t* batches) {
  std::string header = "time_s";
  for (const auto& g : gauges) header += "," + g.id;
  stream::GaugeFeed feed;
  if (!feed.header(header, gauges)) return {};
  config::DetailConfig detail;
  detail.id = "bench";
  stream::Pipeline pipeline(detail, "bench", loads::BatchingOptions{}, 1);
  // The strain columns of each distinct sample as text once; the time is written per sample.
  std::vector<std::string> tails(kDistinct);
  char buffer[64];
  for (std::size_t k = 0; k < kDistinct; ++k)
    for (int g = 0; g < kGauges; ++g) {
      std::snprintf(buffer, sizeof buffer, ",%.6e", strains[k * kGauges + g]);
      tails[k] += buffer;
    }
  std::vector<messages::Batch> out;
  std::string line;
  Timed t;
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t at = 0;
  for (std::int64_t s = 0; s < samples; ++s) {
    std::snprintf(buffer, sizeof buffer, "%.4f", static_cast<double>(s) * 1e-4);
    line.assign(buffer);
    line += tails[at];
    const auto taken = feed.line(line);
    if (!taken || !*taken) return {};
    const auto& sample = **taken;
    pipeline.sample(sample.t, sample.load.p, sample.load.alpha, out);
    if (s % 250'000 == 249'999) t.sink += feed.take_observation().has_value() ? 1.0 : 0.0;
    *batches += static_cast<std::int64_t>(out.size());
    out.clear();
    at = at + 1 == kDistinct ? 0 : at + 1;
  }
  t.seconds = seconds_since(t0);
  return t;
}

}  // namespace

int run_gauge_identification(std::int64_t samples) {
  const struct {
    const char* name;
    bool constant, angle;
  } cases[] = {
      {"p_only", true, false}, {"linear_pair", false, true}, {"constant_and_angle", true, true}};
  double sink = 0.0;
  for (const auto& c : cases) {
    const auto gauges = rosette(c.constant, c.angle);
    std::vector<std::string> columns;
    for (const auto& g : gauges) columns.push_back(g.id);
    auto made = stream::LoadIdentifier::create(columns, gauges);
    if (!made) {
      std::fprintf(stderr, "peritwin-bench stream --gauges: %s\n", made.error().c_str());
      return 3;
    }
    const stream::LoadIdentifier& id = *made;
    // The samples: P = 2200 + 1800 sin(2π k/50) N (R 0.1 at 4 kN), α = 0.3 sin(2π k/4096) rad
    // (0 for p_only), normal noise of each gauge's σ.
    std::mt19937_64 rng(20261203);
    std::normal_distribution<double> unit(0.0, 1.0);
    std::vector<double> strains(kDistinct * kGauges), p_true(kDistinct);
    const double two_pi = 2.0 * std::numbers::pi;
    for (std::size_t k = 0; k < kDistinct; ++k) {
      const double kd = static_cast<double>(k);
      const double p = 2200.0 + 1800.0 * std::sin(two_pi * kd / 50.0);
      const double alpha = c.angle ? 0.3 * std::sin(two_pi * kd / kDistinct) : 0.0;
      p_true[k] = p;
      for (std::size_t g = 0; g < kGauges; ++g) {
        const auto& b = gauges[g].per_basis;
        strains[k * kGauges + g] = p * (b[0] + b[1] * std::cos(alpha) + b[2] * std::sin(alpha)) +
                                   gauges[g].noise * unit(rng);
      }
    }
    double error2 = 0.0;
    for (std::size_t k = 0; k < kDistinct; ++k) {
      const double p =
          id.identify(std::span<const double>(strains.data() + k * kGauges, kGauges)).p;
      error2 += (p - p_true[k]) * (p - p_true[k]);
    }
    time_identify(id, strains, static_cast<std::int64_t>(kDistinct), nullptr);  // warm-up
    const Timed plain = time_identify(id, strains, samples, nullptr);
    std::vector<double> residuals;
    const Timed with_residuals = time_identify(id, strains, samples, &residuals);
    sink += plain.sink + with_residuals.sink;
    std::int64_t batches = 0;
    const Timed whole = time_stream(gauges, strains, samples, &batches);
    if (whole.seconds <= 0.0) {
      std::fprintf(stderr, "peritwin-bench stream --gauges: the stream's path refused a line\n");
      return 3;
    }
    const double rate_stream = static_cast<double>(samples) / whole.seconds;
    const double rate = plain.seconds > 0.0 ? static_cast<double>(samples) / plain.seconds : 0.0;
    const double rate_residuals =
        with_residuals.seconds > 0.0 ? static_cast<double>(samples) / with_residuals.seconds : 0.0;
    core::JsonLine line;
    line["bench"] = "gauge_identification";
    line["gauges"] = kGauges;
    line["case"] = c.name;
    line["unknowns"] = id.unknowns();
    line["scan_angles"] = id.scan_angles();
    line["samples"] = static_cast<long long>(samples);
    line["seconds"] = core::fixed(plain.seconds, 4);
    line["samples_per_s"] = core::significant(rate, 4);
    line["ns_per_sample"] = core::significant(rate > 0.0 ? 1e9 / rate : 0.0, 3);
    line["with_residuals_samples_per_s"] = core::significant(rate_residuals, 4);
    line["p_rms_error_N"] =
        core::significant(std::sqrt(error2 / static_cast<double>(kDistinct)), 3);
    line["stream_path_samples_per_s"] = core::significant(rate_stream, 4);
    line["stream_path_batches"] = static_cast<long long>(batches);
    line["goal_samples_per_s"] = kGoal;
    line["ratio_to_goal"] = core::significant(rate / kGoal, 4);
    line["stream_path_ratio_to_goal"] = core::significant(rate_stream / kGoal, 4);
    core::print_line(line);
  }
  return std::isfinite(sink) ? 0 : 1;
}

}  // namespace peritwin::bench
