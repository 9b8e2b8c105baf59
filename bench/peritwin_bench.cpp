// peritwin-bench: performance figures as one JSON line per run.
//   peritwin-bench static --model bb|osb --nodes N
// builds the B1 compact-tension specimen with about N nodes and times one cold static solve.
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>

#include "solver/specimens.h"
#include "solver/static_solver.h"

namespace {

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

int run_static(const std::string& model_name, double target_nodes) {
  using namespace peritwin;
  ModelOptions options;
  options.kind = model_name == "bb" ? ModelKind::bond_based : ModelKind::state_based;
  const CompactTensionSpec spec;
  const auto t0 = std::chrono::steady_clock::now();
  const Specimen specimen =
      make_compact_tension(spec, options, compact_tension_spacing(spec, target_nodes));
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  StaticSolver solver(specimen.disc, specimen.model, specimen.supports, specimen.loads);
  const FactorReport report = solver.solve();
  if (!report.ok()) {
    std::fprintf(stderr, "peritwin-bench: static solve failed: %s\n", report.message.c_str());
    return 1;
  }
  const auto& t = solver.timings();
  const auto& u = solver.basis_displacement(basis_constant);
  // Load-line opening at 1 kN: the upper pin centre's displacement minus the lower one's.
  const double w = spec.width;
  const auto up = static_cast<std::size_t>(specimen.disc.nearest_node({0.25 * w, 0.275 * w}));
  const auto low = static_cast<std::size_t>(specimen.disc.nearest_node({0.25 * w, -0.275 * w}));
  std::printf(
      "{\"bench\":\"static\",\"model\":\"%s\",\"nodes\":%d,\"bonds\":%d,\"dx_m\":%.6g,"
      "\"build_s\":%.3f,\"assemble_s\":%.3f,\"analyze_s\":%.3f,\"factor_s\":%.3f,"
      "\"solve_s\":%.3f,\"total_s\":%.3f,\"factor_nnz\":%.0f,\"load_line_opening_m_per_kN\":%.6e,"
      "\"peak_rss_mb\":%.1f}\n",
      model_name.c_str(), specimen.disc.num_nodes(), specimen.disc.num_bonds(), specimen.disc.dx,
      build_s, t.assemble_s, t.analyze_s, t.factor_s, t.solve_s,
      build_s + t.assemble_s + t.analyze_s + t.factor_s + t.solve_s,
      solver.factor().factor_nonzeros(), 1000.0 * (u[2 * up + 1] - u[2 * low + 1]),
      peak_rss_mb());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"peritwin-bench: performance figures as JSON lines"};
  app.require_subcommand(1);
  auto* stat = app.add_subcommand("static", "one cold static solve of the B1 CT specimen");
  std::string model = "osb";
  double nodes = 15000;
  stat->add_option("--model", model, "bb (bond-based) or osb (ordinary state-based)")
      ->check(CLI::IsMember({"bb", "osb"}));
  stat->add_option("--nodes", nodes, "approximate number of nodes")->check(CLI::Range(100.0, 1e7));
  CLI11_PARSE(app, argc, argv);
  if (stat->parsed()) return run_static(model, nodes);
  return 2;
}
