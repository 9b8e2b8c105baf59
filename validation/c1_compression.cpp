#include "validation/c1_compression.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

#include "config/config.h"
#include "core/json_line.h"
#include "outputs/damage_png.h"
#include "solver/fatigue/laws/crack_closure.h"
#include "twin/detail_model.h"
#include "twin/life.h"

namespace peritwin::validation {

namespace {

struct Rule {
  const char* name;
  fatigue::CompressionRule rule;
};
constexpr Rule kRules[] = {{"full_range", fatigue::CompressionRule::full_range},
                           {"contact", fatigue::CompressionRule::contact},
                           {"closure", fatigue::CompressionRule::closure}};

struct Life {
  double cycles = NAN;
  std::int64_t breaks = 0;
  double wall_s = 0.0;
};

/// The life of `detail` under the rule from its virgin state at (p_max, r), blocks of 1000.
Life life_of(const config::DetailConfig& detail, fatigue::CompressionRule rule, double p_max,
             double r) {
  config::DetailConfig d = detail;
  d.fatigue.compression = rule;
  const auto built = twin::DetailModel::build(d);
  if (!built) {
    std::fprintf(stderr, "C1: %s\n", built.error().message().c_str());
    return {};
  }
  const twin::DetailModel& model = **built;
  const auto t0 = std::chrono::steady_clock::now();
  auto engine = model.make_engine();
  if (!engine->initialize()) return {};
  twin::SimulationStats stats;
  Life life;
  life.cycles = twin::simulate_life(model, engine->export_state(), {{p_max, r, 0.0, 1000}}, 1.0,
                                    nullptr, engine.get(), &stats);
  life.breaks = stats.breaks;
  life.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return life;
}

}  // namespace

int run_c1_compression(const std::string& ct_config, const std::string& panel_config,
                       const std::filesystem::path& out_dir) {
  struct Geometry {
    const char* name;
    std::string config;
    std::vector<double> ratios;
  };
  std::vector<Geometry> geometries = {{"ct", ct_config, {0.3, 0.1, 0.0, -0.5, -1.0, -2.0}}};
  if (!panel_config.empty()) geometries.push_back({"mt", panel_config, {0.1, 0.0, -1.0}});
  std::filesystem::create_directories(out_dir);
  const fatigue::NewmanClosure newman;  // α = 2, S_max/σ0 = 0.3: the rule's defaults
  for (const Geometry& g : geometries) {
    const auto loaded = config::load_config(g.config);
    if (!loaded.ok()) {
      std::fprintf(stderr, "C1: %s\n", loaded.error_text().c_str());
      return 3;
    }
    const config::DetailConfig& detail = loaded.config->details.at(0);
    const auto& reference = detail.life.reference_spectrum;
    const double p_max = reference.empty() ? 4000.0 : reference.front().p_max;
    const double m = detail.fatigue.strain.m2;
    std::map<std::string, std::map<double, Life>> lives;
    outputs::LinePlot plot;
    plot.title = std::string("C1 ") + (g.name == std::string("ct") ? "CT" : "MT panel") +
                 ": life against R (P_max " + std::to_string(static_cast<int>(p_max)) + " N)";
    plot.x_title = "load ratio R";
    plot.y_title = "end of life (kcycles)";
    const outputs::Rgb colors[] = {{200, 40, 40}, {31, 90, 180}, {30, 150, 60}};
    int color = 0;
    for (const Rule& rule : kRules) {
      auto& by_r = lives[rule.name];
      for (const double r : g.ratios) {
        by_r[r] = life_of(detail, rule.rule, p_max, r);
        if (!std::isfinite(by_r[r].cycles)) {
          std::fprintf(stderr, "C1: no life for %s %s R = %g\n", g.name, rule.name, r);
          return 3;
        }
      }
      const double anchor = by_r.at(0.1).cycles;
      const double r0 = by_r.count(0.0) ? by_r.at(0.0).cycles : NAN;
      // The two references of the file comment, anchored at this rule's life at R = 0.1.
      const auto paris_cycles = [&](double r) {
        return anchor * std::pow(0.9 / (1.0 - std::max(r, 0.0)), m);
      };
      const auto newman_cycles = [&](double r) {
        return anchor * std::pow((1.0 - fatigue::newman_opening_ratio(0.1, newman)) /
                                     (1.0 - fatigue::newman_opening_ratio(r, newman)),
                                 m);
      };
      for (const double r : g.ratios) {
        const Life& l = by_r.at(r);
        const double paris_n = paris_cycles(r);
        const double newman_n = newman_cycles(r);
        core::JsonLine line;
        line["case"] = "C1";
        line["geometry"] = g.name;
        line["rule"] = rule.name;
        line["r"] = core::fixed(r, 2);
        line["p_max"] = core::whole(p_max);
        line["end_of_life_cycles"] = core::whole(l.cycles);
        line["paris_kmax_cycles"] = core::whole(paris_n);
        line["newman_cycles"] = core::whole(newman_n);
        line["to_paris"] = core::fixed(l.cycles / paris_n - 1.0, 4);
        line["to_newman"] = core::fixed(l.cycles / newman_n - 1.0, 4);
        line["ratio_to_r0"] = core::fixed(l.cycles / r0, 4);
        line["breaks"] = static_cast<long long>(l.breaks);
        line["wall_s"] = core::fixed(l.wall_s, 2);
        core::print_line(line);
        std::fflush(stdout);
      }
      // Each curve from R = max(ratios) down to min, as the plot's x axis runs.
      const auto series = [&](std::string label, bool dashed, const auto& cycles_at) {
        outputs::PlotSeries out{std::move(label), {}, {}, colors[color], dashed};
        for (auto it = g.ratios.rbegin(); it != g.ratios.rend(); ++it) {
          out.x.push_back(*it);
          out.y.push_back(cycles_at(*it) / 1000.0);
        }
        return out;
      };
      plot.series.push_back(series(std::string("twin, ") + rule.name, false,
                                   [&](double r) { return by_r.at(r).cycles; }));
      if (rule.rule == fatigue::CompressionRule::full_range) {
        plot.series.push_back(series(std::string("Paris K_max, ") + rule.name, true, paris_cycles));
      }
      if (rule.rule == fatigue::CompressionRule::closure) {
        plot.series.push_back(series("Newman f(R), closure's R = 0.1", true, newman_cycles));
      }
      ++color;
    }
    // The cost of reversed cycles: the contact rule's life at R < 0 (the same crack grown) over
    // the full-range rule's at R = 0.1.
    const Life& base = lives.at("full_range").at(0.1);
    for (const double r : g.ratios) {
      if (r >= 0.0) continue;
      const Life& l = lives.at("contact").at(r);
      core::JsonLine line;
      line["case"] = "C1-cost";
      line["geometry"] = g.name;
      line["r"] = core::fixed(r, 2);
      line["contact_wall_s"] = core::fixed(l.wall_s, 2);
      line["contact_breaks"] = static_cast<long long>(l.breaks);
      line["full_range_r0.1_wall_s"] = core::fixed(base.wall_s, 2);
      line["full_range_r0.1_breaks"] = static_cast<long long>(base.breaks);
      line["wall_ratio"] = core::fixed(l.wall_s / base.wall_s, 3);
      line["per_break_ratio"] = core::fixed(
          (l.wall_s / static_cast<double>(std::max<std::int64_t>(l.breaks, 1))) /
              (base.wall_s / static_cast<double>(std::max<std::int64_t>(base.breaks, 1))),
          3);
      core::print_line(line);
    }
    outputs::write_line_plot_png(out_dir / (std::string("c1_") + g.name + "_lives.png"), plot);
  }
  return 0;
}

}  // namespace peritwin::validation
