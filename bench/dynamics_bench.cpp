#include "bench/dynamics_bench.h"

#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "core/json_line.h"
#include "solver/dynamics/explicit_dynamics.h"

namespace peritwin::bench {

namespace {
/// CPU seconds (user + system) of the whole process so far.
double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}
}  // namespace

int run_dynamics(double nodes, int threads, int steps) {
  const double dx = 1e-3;
  const double side = std::round(std::sqrt(nodes)) * dx;
  mesh::DetailGeometry g;
  g.thickness = 1.0;
  g.outline.push_back(mesh::Region(mesh::Rectangle{0.0, 0.0, side, side}));
  const auto build_start = std::chrono::steady_clock::now();
  const mesh::Discretization disc = discretize(g, dx, 3.0 * dx);
  dynamics::DynamicsSetup setup;
  setup.kernel = {dynamics::KernelChoice::Shape::gaussian, 2.0};
  setup.youngs_modulus = 210e9;
  setup.density = 8000;
  setup.time_step = 1e-8;
  setup.threads = threads;
  auto made = dynamics::ExplicitDynamics::create(disc, setup);
  if (!made) {
    std::fprintf(stderr, "peritwin-bench dynamics: %s\n", made.error().message().c_str());
    return 3;
  }
  auto& dyn = *made.value();
  for (mesh::NodeIndex k = 0; k < disc.num_nodes(); ++k) {
    if (disc.position[static_cast<std::size_t>(k)].y > side - dx) {
      dyn.add_body_force(k, 0.0, 1e6 / dx);
    }
  }
  const auto n2 = static_cast<std::size_t>(2 * disc.num_nodes());
  dyn.set_initial_state(std::vector<double>(n2, 0.0), std::vector<double>(n2, 0.0));
  const double build_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
  dyn.step(20);
  const double cpu_start = cpu_seconds();
  const auto start = std::chrono::steady_clock::now();
  dyn.step(steps);
  const double cpu = cpu_seconds() - cpu_start;
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double evaluations = static_cast<double>(dyn.entries()) * steps;
  core::JsonLine line;
  line["bench"] = "dynamics";
  line["nodes"] = disc.num_nodes();
  line["bonds"] = disc.num_bonds();
  line["evaluations_per_step"] = dyn.entries();
  line["kernel"] = "gaussian p=2";
  line["horizon_over_dx"] = 3.0;
  line["threads"] = threads;
  line["hardware_threads"] = std::thread::hardware_concurrency();
  line["steps"] = steps;
  line["wall_s"] = core::significant(wall, 4);
  line["bond_evaluations_per_s"] = core::significant(evaluations / wall, 4);
  line["bond_pairs_per_s"] =
      core::significant(disc.num_bonds() * static_cast<double>(steps) / wall, 4);
  line["ns_per_node_step"] =
      core::significant(1e9 * wall / (disc.num_nodes() * static_cast<double>(steps)), 4);
  // Per CPU second (all threads): what one core does, less sensitive to other load on the machine
  // than the wall-clock rate.
  line["cpu_s"] = core::significant(cpu, 4);
  line["bond_evaluations_per_cpu_s"] = core::significant(evaluations / cpu, 4);
  line["build_s"] = core::significant(build_s, 3);
  line["goal"] = "bond_evaluations_per_s >= 1e8";
  line["met"] = evaluations / wall >= 1e8;
  core::print_line(line);
  return 0;
}

}  // namespace peritwin::bench
