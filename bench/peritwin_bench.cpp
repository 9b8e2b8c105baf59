// peritwin-bench: performance figures as one JSON line per run.
//   peritwin-bench static --model bb|osb --nodes N   one cold static solve of the B1 specimen
//                         [--baseline]               ... next to a plain triplets + CHOLMOD one
//   peritwin-bench fatigue --nodes N                 B1 at 4 kN from a0 to final failure
//                          [--kernel-groups N]       ... then N groups with each update kernel
//   peritwin-bench bilinear --nodes N                B1 bond-based with 003's bilinear law
//   peritwin-bench stream-rainflow [--samples N]     gate + RainflowCounter + CycleBlocks rate
//                                  [--gate N] [--noise]
//   peritwin-bench ingest [...]                      peritwin-bench-ingest (LCM ingest rate)
//   peritwin-bench soak --batches N [...]            peritwin-bench-soak (the daemon's RSS)
//   peritwin-bench stream [--seconds S] [...]        peritwin-bench-stream (sensor -> STATE)
//   peritwin-bench stream --gauges [--gauge-samples N]  ... instead gauge strains -> P, α rate
//   peritwin-bench dashboard [...]                   peritwin-bench-dashboard (SSE latency)
//   peritwin-bench fleet [--details N] [...]         peritwin-bench-fleet (one daemon, N details)
//   peritwin-bench life --nodes N [...]              peritwin-bench-life (one life estimate)
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "bench/dynamics_bench.h"
#include "core/cli_checks.h"
#include "core/json_line.h"
#include "core/proc_files.h"
#include "loads/cycle_blocks.h"
#include "loads/rainflow.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/statics/static_solver.h"
#include "validation/specimens.h"

namespace {

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

/// Peak resident memory per phase: VmHWM read at the end of a phase, then reset to the current
/// VmRSS (writing 5 to /proc/self/clear_refs, Linux ≥ 4.0), so each phase reports its own peak.
/// `reset_ok` is false where the kernel refuses the reset (the peaks are then cumulative).
class PhasePeaks {
 public:
  PhasePeaks() { reset(); }
  /// Records the phase's peak and current RSS under "<name>" in `line`, then resets the peak.
  void mark(peritwin::core::JsonLine& line, const std::string& name) {
    const double peak = peritwin::core::proc_status_mb("VmHWM");
    line["rss_peak_" + name + "_mb"] = peritwin::core::fixed(peak, 1);
    line["rss_after_" + name + "_mb"] =
        peritwin::core::fixed(peritwin::core::proc_status_mb("VmRSS"), 1);
    note(name, peak);
    reset();
  }
  /// A phase's peak measured outside mark() (the later blocks' maximum).
  void note(const std::string& name, double peak_mb) {
    if (peak_mb > peak_phase_mb_) {
      peak_phase_mb_ = peak_mb;
      peak_phase_ = name;
    }
  }
  /// The phase whose peak was the highest: where the process's peak comes from.
  [[nodiscard]] const std::string& peak_phase() const { return peak_phase_; }
  [[nodiscard]] bool reset_ok() const { return reset_ok_; }
  /// The process's peak over all phases (getrusage's ru_maxrss follows the resets).
  [[nodiscard]] double peak_mb() const {
    return std::max(overall_, peritwin::core::proc_status_mb("VmHWM"));
  }
  void reset() {
    overall_ = std::max(overall_, peritwin::core::proc_status_mb("VmHWM"));
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
    clear.flush();
    reset_ok_ = reset_ok_ && clear.good();
  }

 private:
  bool reset_ok_ = true;
  double overall_ = 0.0;
  double peak_phase_mb_ = 0.0;
  std::string peak_phase_;
};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The plain path the project's static solve is measured against (issue 18, item 4): the
/// bond-based K = Σ_b c_b·g_b·g_bᵀ (000 Eq. B1 with the bond stiffness of pd_model) as Eigen
/// triplets, one upper-triangle triplet per entry of each bond, setFromTriplets, then CHOLMOD
/// with its default settings (its own ordering choice: AMD, METIS when AMD fills much),
/// factorize, solve the three basis cases with cholmod_solve. Same supports and loads.
struct BaselineRun {
  peritwin::statics::SolveTimings t;
  double factor_nnz = 0.0;
  std::vector<double> u;  ///< constant basis, full DOFs
  bool ok = false;
};

BaselineRun run_baseline(const peritwin::statics::Specimen& specimen,
                         const peritwin::statics::StaticSolver& solver) {
  using namespace peritwin;
  BaselineRun run;
  const auto& disc = specimen.disc;
  const auto& free = solver.free_index();
  const int n = solver.num_free_dofs();
  auto t0 = std::chrono::steady_clock::now();
  std::vector<Eigen::Triplet<double, int>> entries;
  entries.reserve(10 * static_cast<std::size_t>(disc.num_bonds()));
  for (mesh::BondIndex b = 0; b < disc.num_bonds(); ++b) {
    const auto bi = static_cast<std::size_t>(b);
    if (disc.bond_precut[bi]) continue;
    const auto i = 2 * static_cast<std::size_t>(disc.bond_i[bi]);
    const auto j = 2 * static_cast<std::size_t>(disc.bond_j[bi]);
    const int f[4] = {free[i], free[i + 1], free[j], free[j + 1]};
    const double c = disc.bond_cos[bi], s = disc.bond_sin[bi];
    const double g[4] = {-c, -s, c, s};
    const double k = specimen.model.bond_stiffness[bi];
    for (int p = 0; p < 4; ++p) {
      for (int q = 0; q < 4; ++q) {
        if (f[p] >= 0 && f[q] >= 0 && f[p] <= f[q])
          entries.emplace_back(f[p], f[q], k * g[p] * g[q]);
      }
    }
  }
  linalg::SparseMatrix upper(n, n);
  upper.setFromTriplets(entries.begin(), entries.end());
  upper.makeCompressed();
  entries = {};
  run.t.assemble_s = seconds_since(t0);
  linalg::SparseCholesky cholesky;
  t0 = std::chrono::steady_clock::now();
  if (!cholesky.analyze(upper).ok()) return run;
  run.t.analyze_s = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  if (!cholesky.factorize(upper).ok()) return run;
  run.t.factor_s = seconds_since(t0);
  run.factor_nnz = cholesky.factor_nonzeros();
  t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  for (int basis = 0; basis < 3; ++basis) {
    const auto force = solver.basis_force(static_cast<statics::Basis>(basis));
    for (std::size_t dof = 0; dof < force.size(); ++dof) {
      if (free[dof] >= 0) rhs(free[dof], basis) = force[dof];
    }
  }
  cholesky.solve_with_cholmod(rhs);
  run.t.solve_s = seconds_since(t0);
  run.u.assign(free.size(), 0.0);
  for (std::size_t dof = 0; dof < free.size(); ++dof) {
    if (free[dof] >= 0) run.u[dof] = rhs(free[dof], 0);
  }
  run.ok = true;
  return run;
}

int run_static(const std::string& model_name, double target_nodes, bool baseline,
               const std::string& ordering) {
  using namespace peritwin;
  using namespace peritwin::validation;
  model::ModelOptions options;
  options.kind = model_name == "bb" ? model::ModelKind::bond_based : model::ModelKind::state_based;
  if (baseline && options.kind != model::ModelKind::bond_based) {
    std::fprintf(stderr, "peritwin-bench: --baseline is the bond-based plain path (--model bb)\n");
    return 2;
  }
  const CompactTensionSpec spec;
  core::JsonLine line;
  PhasePeaks peaks;
  const auto t0 = std::chrono::steady_clock::now();
  const statics::Specimen specimen =
      make_compact_tension(spec, options, compact_tension_spacing(spec, target_nodes));
  const double build_s = seconds_since(t0);
  peaks.mark(line, "build");
  // Load-line opening at 1 kN: the upper pin centre's displacement minus the lower one's.
  const double w = spec.width;
  const auto up = static_cast<std::size_t>(specimen.disc.nearest_node({0.25 * w, 0.275 * w}));
  const auto low = static_cast<std::size_t>(specimen.disc.nearest_node({0.25 * w, -0.275 * w}));
  auto opening = [&](const std::vector<double>& u) {
    return 1000.0 * (u[2 * up + 1] - u[2 * low + 1]);
  };
  double project_s = 0.0, project_opening = 0.0;
  BaselineRun first;
  if (baseline) {
    // The baseline needs the free DOFs and loads only: a solver that is never solved.
    const statics::StaticSolver plain(specimen.disc, specimen.model, specimen.supports,
                                      specimen.loads);
    first = run_baseline(specimen, plain);
    first.u = {};
    peaks.mark(line, "baseline_first");
  }
  {
    statics::StaticSolver solver(specimen.disc, specimen.model, specimen.supports, specimen.loads);
    solver.set_ordering(ordering == "nesdis"  ? linalg::Ordering::nesdis
                        : ordering == "metis" ? linalg::Ordering::metis
                        : ordering == "amd"   ? linalg::Ordering::amd
                                              : linalg::Ordering::metis_or_amd);
    const core::Status report = solver.solve();
    if (!report.ok()) {
      std::fprintf(stderr, "peritwin-bench: static solve failed: %s\n",
                   core::message_of(report).c_str());
      return 1;
    }
    const auto& t = solver.timings();
    project_s = t.assemble_s + t.analyze_s + t.factor_s + t.solve_s;
    project_opening = opening(solver.basis_displacement(statics::basis_constant));
    line["bench"] = "static";
    line["model"] = model_name;
    line["ordering"] = ordering;
    line["nodes"] = specimen.disc.num_nodes();
    line["bonds"] = specimen.disc.num_bonds();
    line["dx_m"] = core::significant(specimen.disc.dx, 6);
    line["build_s"] = core::fixed(build_s, 3);
    line["assemble_s"] = core::fixed(t.assemble_s, 3);
    line["analyze_s"] = core::fixed(t.analyze_s, 3);
    line["factor_s"] = core::fixed(t.factor_s, 3);
    line["solve_s"] = core::fixed(t.solve_s, 3);
    line["total_s"] = core::fixed(build_s + project_s, 3);
    line["factor_nnz"] = core::whole(solver.factor().factor_nonzeros());
    line["load_line_opening_m_per_kN"] = core::significant(project_opening, 7);
    peaks.mark(line, "solve");
    {  // the products-and-triplets assembly the scatter replaced (its oracle), in this run
      const auto ta = std::chrono::steady_clock::now();
      const linalg::SparseMatrix by_products = solver.stiffness_upper_by_products();
      line["assemble_by_products_s"] = core::fixed(seconds_since(ta), 3);
      line["assemblies_equal"] =
          by_products.nonZeros() == solver.stiffness_upper().nonZeros() &&
          std::equal(by_products.valuePtr(), by_products.valuePtr() + by_products.nonZeros(),
                     solver.stiffness_upper().valuePtr());
    }
    peaks.mark(line, "assemble_by_products");
    if (baseline) {
      // After the project's solve here, and once before it (above): the first factorization of
      // a process pays for page faults and BLAS start-up, so each path is timed once in each
      // position and the ratio uses the baseline's mean.
      const BaselineRun after = run_baseline(specimen, solver);
      BaselineRun plain = after;
      if (plain.ok && first.ok) {
        plain.t.assemble_s = 0.5 * (first.t.assemble_s + after.t.assemble_s);
        plain.t.analyze_s = 0.5 * (first.t.analyze_s + after.t.analyze_s);
        plain.t.factor_s = 0.5 * (first.t.factor_s + after.t.factor_s);
        plain.t.solve_s = 0.5 * (first.t.solve_s + after.t.solve_s);
        line["baseline_first_total_s"] = core::fixed(
            first.t.assemble_s + first.t.analyze_s + first.t.factor_s + first.t.solve_s, 3);
        line["baseline_second_total_s"] = core::fixed(
            after.t.assemble_s + after.t.analyze_s + after.t.factor_s + after.t.solve_s, 3);
      }
      if (!plain.ok || !first.ok) {
        std::fprintf(stderr, "peritwin-bench: the baseline's CHOLMOD solve failed\n");
        return 1;
      }
      const double plain_s =
          plain.t.assemble_s + plain.t.analyze_s + plain.t.factor_s + plain.t.solve_s;
      const double plain_opening = opening(plain.u);
      line["baseline_assemble_s"] = core::fixed(plain.t.assemble_s, 3);
      line["baseline_analyze_s"] = core::fixed(plain.t.analyze_s, 3);
      line["baseline_factor_s"] = core::fixed(plain.t.factor_s, 3);
      line["baseline_solve_s"] = core::fixed(plain.t.solve_s, 3);
      line["baseline_total_s"] = core::fixed(plain_s, 3);
      line["baseline_factor_nnz"] = core::whole(plain.factor_nnz);
      line["baseline_load_line_opening_m_per_kN"] = core::significant(plain_opening, 7);
      line["opening_relative_difference"] =
          core::significant(std::abs(project_opening - plain_opening) / std::abs(plain_opening), 2);
      // assemble + analyze + factor + solve of both (the discretization is shared and not counted)
      line["solve_over_baseline"] = core::fixed(plain_s > 0.0 ? project_s / plain_s : 0.0, 3);
      peaks.mark(line, "baseline");
    }
  }
  line["peak_rss_reset_ok"] = peaks.reset_ok();
  line["peak_rss_mb"] = core::fixed(peaks.peak_mb(), 1);
  core::print_line(line);
  return 0;
}

struct KernelComparison {
  int groups = 0;
  double flops = 0.0;
  double one_at_a_time_s = 0.0;
  double interleaved_s = 0.0;
  bool identical = false;
};

/// The first `count` groups of breaks re-solved on a fresh incremental solver of the specimen,
/// once with the sweeps one entry at a time (the oracle) and once interleaved: sweep seconds of
/// each, and whether the displacements after the last group are the same bits.
KernelComparison compare_update_kernels(
    const peritwin::statics::Specimen& s,
    const std::vector<std::vector<peritwin::mesh::BondIndex>>& groups, int count) {
  using namespace peritwin;
  KernelComparison out;
  std::vector<double> u[2];
  for (const bool interleaved : {false, true}) {
    linalg::SparseCholesky::set_interleaved_update(interleaved);
    statics::StaticSolver solver(s.disc, s.model, s.supports, s.loads);
    solver.set_incremental(true);
    if (!solver.solve().ok()) break;
    int done = 0;
    for (const auto& group : groups) {
      if (done == count) break;
      if (!solver.break_bonds(group).ok()) break;
      ++done;
    }
    out.groups = done;
    out.flops = solver.update_flops();
    (interleaved ? out.interleaved_s : out.one_at_a_time_s) = solver.sweep_seconds();
    u[interleaved ? 1 : 0] = solver.basis_displacement(statics::basis_constant);
  }
  linalg::SparseCholesky::set_interleaved_update(true);
  out.identical = !u[0].empty() && u[0] == u[1];
  return out;
}

/// Read bandwidth of this machine now: the best of three sums over 128 MB (a triangular solve
/// reads its factor once, so solves × factor bytes / this is its floor).
double memory_read_gb_s() {
  std::vector<double> buffer(16u << 20, 1.0);
  double best = 0.0;
  volatile double sink = 0.0;
  for (int pass = 0; pass < 3; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    double sum[4] = {0.0, 0.0, 0.0, 0.0};
    for (std::size_t i = 0; i + 4 <= buffer.size(); i += 4) {
      for (int k = 0; k < 4; ++k) sum[k] += buffer[i + static_cast<std::size_t>(k)];
    }
    sink = sink + sum[0] + sum[1] + sum[2] + sum[3];
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double bytes = static_cast<double>(buffer.size() * sizeof(double));
    if (s > 0) best = std::max(best, bytes / s * 1e-9);
  }
  return best;
}

int run_fatigue(const std::string& model_name, double target_nodes, double a2_at_1mm,
                std::int64_t max_cycles, int sample_groups) {
  // B1 at 4 kN, R = 0.1, from a0 to final failure with the incremental re-solve; then the same
  // final stiffness refactorized a few times to measure the ratio in this run. Memory: the peak
  // RSS of each phase (PhasePeaks) — the specimen, the first solve (assembly, analysis,
  // supernodal factor, then packed LDLᵀ in place), the first rank update, the other blocks with
  // and without a periodic rebuild, the refactorizations.
  using namespace peritwin;
  using namespace peritwin::validation;
  model::ModelOptions options;
  options.kind = model_name == "bb" ? model::ModelKind::bond_based : model::ModelKind::state_based;
  const CompactTensionSpec spec;
  const double dx = compact_tension_spacing(spec, target_nodes);
  core::JsonLine line;
  line["bench"] = "fatigue";
  const double read_gb_s = memory_read_gb_s();  // before the phases: its buffer is no one's peak
  PhasePeaks peaks;
  const statics::Specimen s = make_compact_tension(spec, options, dx);
  peaks.mark(line, "build");
  fatigue::FatigueSettings settings;
  settings.strain = fatigue::al6061_t6_strain_params();
  // A2 calibrated at Δx = 1 mm, scaled to this horizon by 000 Eq. (29).
  settings.strain.A2 = fatigue::a2_scaled(a2_at_1mm, 3.015e-3, 3.015 * dx, settings.strain.m2);
  settings.incremental = true;
  const auto t0 = std::chrono::steady_clock::now();
  double per_update = 0.0, update_total = 0.0, basis_total = 0.0, rebuild_total = 0.0, wall = 0.0;
  double supernodal_nnz = 0.0, simplicial_nnz = 0.0, peak_updates = 0.0, peak_rebuilds = 0.0;
  double ldlt_bytes = 0.0;
  double sweep_total = 0.0, update_flops = 0.0, factorization_flops = 0.0;
  std::int64_t cycles = 0, broken = 0;
  int solves = 0, rebuilds = 0, updates = 0, refactorized = 0, factorizations = 0;
  bool failed = false;
  std::vector<std::vector<mesh::BondIndex>> groups;  // the re-solves' breaks, in order
  {
    fatigue::FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings);
    if (!engine.initialize()) {
      std::fprintf(stderr, "peritwin-bench: %s\n", engine.failure_reason().c_str());
      return 1;
    }
    supernodal_nnz = engine.solver().factor().supernodal_nonzeros();
    simplicial_nnz = engine.solver().factor().factor_nonzeros();
    peaks.mark(line, "initialize");
    bool first_update = true;
    for (;;) {
      const int rebuilds_before = engine.rebuilds();
      const bool more = engine.apply({4000.0, 0.1, 0.0, 1000}) == fatigue::EngineStatus::ok &&
                        engine.total_cycles() < max_cycles;
      if (first_update && engine.updates() > 0) {  // this block converted the factor
        simplicial_nnz = engine.solver().factor().factor_nonzeros();
        ldlt_bytes = engine.solver().factor().factor_bytes();
        peaks.mark(line, "first_update");
        first_update = false;
      } else {
        const double peak = peritwin::core::proc_status_mb("VmHWM");
        double& slot = engine.rebuilds() != rebuilds_before ? peak_rebuilds : peak_updates;
        slot = std::max(slot, peak);
        peaks.reset();
      }
      if (!more) break;
    }
    wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    // Engine totals: they include the solvers replaced by the periodic rebuilds.
    per_update = engine.updates() > 0 ? engine.update_seconds() / engine.updates() : 0;
    update_total = engine.update_seconds();
    basis_total = engine.basis_solve_seconds();
    rebuild_total = engine.rebuild_seconds();
    cycles = engine.total_cycles();
    broken = static_cast<std::int64_t>(engine.broken_bonds());
    solves = engine.solves();
    rebuilds = engine.rebuilds();
    updates = engine.updates();
    failed = engine.failed();
    sweep_total = engine.sweep_seconds();
    update_flops = engine.update_flops();
    refactorized = engine.refactorized_groups();
    factorizations = engine.factorizations();
    factorization_flops = engine.solver().factor().factorization_flops();
    const fatigue::EngineState state = engine.export_state();
    std::size_t e = 0;
    for (const std::int64_t size : state.resolve_groups) {
      std::vector<mesh::BondIndex> group;
      for (std::int64_t k = 0; k < size && e < state.events.size(); ++k, ++e) {
        group.push_back(state.events[e].bond);
      }
      groups.push_back(std::move(group));
    }
  }  // the engine's factor goes before the refactorizing solver is built
  line["rss_peak_later_updates_mb"] = core::fixed(peak_updates, 1);
  line["rss_peak_rebuild_blocks_mb"] = core::fixed(peak_rebuilds, 1);
  peaks.note("later_updates", peak_updates);
  peaks.note("rebuild_blocks", peak_rebuilds);
  peaks.mark(line, "engine_freed");
  // Refactorizing path on the same model: assemble + numeric factorization + solve.
  double per_refactor = 0.0;
  {  // freed before the kernel comparison's solvers: one factor at a time
    statics::StaticSolver refactor(s.disc, s.model, s.supports, s.loads);
    if (!refactor.solve().ok()) return 1;
    const auto t1 = std::chrono::steady_clock::now();
    const int repeats = 3;
    for (int i = 0; i < repeats; ++i) {
      const mesh::BondIndex b = 0;
      if (!refactor.break_bonds(std::span(&b, 1)).ok()) return 1;
    }
    per_refactor =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count() / repeats;
  }
  peaks.mark(line, "refactor");
  // The slow path beside the fast one, in this run: the first re-solves' groups again on a fresh
  // incremental solver, the sweeps one entry at a time, then four side by side (the default);
  // the same displacements bit for bit, and each's sweep seconds.
  const KernelComparison kernels = compare_update_kernels(s, groups, sample_groups);
  peaks.mark(line, "kernels");
  line["nodes"] = s.disc.num_nodes();
  line["bonds"] = s.disc.num_bonds();
  line["cycles"] = static_cast<long long>(cycles);
  line["broken_bonds"] = static_cast<long long>(broken);
  line["solves"] = solves;
  line["updates"] = updates;
  line["wall_s"] = core::fixed(wall, 2);
  line["update_total_s"] = core::fixed(update_total, 2);
  line["basis_solve_total_s"] = core::fixed(basis_total, 2);
  line["update_s_mean"] = core::fixed(per_update, 5);
  line["refactor_s_mean"] = core::fixed(per_refactor, 4);
  line["incremental_over_refactor"] =
      core::fixed(per_update > 0 ? per_refactor / per_update : 0.0, 1);
  line["rebuilds"] = rebuilds;
  line["rebuild_total_s"] = core::fixed(rebuild_total, 2);
  // Where a re-solve's time goes (issue 37): the sweeps against their flop count (4 per entry of
  // L on each update column's elimination-tree path), the basis solves against the factor's
  // bytes read once per solve at the memory bandwidth measured in this run.
  line["sweep_total_s"] = core::fixed(sweep_total, 2);
  line["update_gflop"] = core::fixed(update_flops * 1e-9, 1);
  line["sweep_gflop_per_s"] =
      core::fixed(sweep_total > 0 ? update_flops * 1e-9 / sweep_total : 0, 2);
  line["factorization_gflop"] = core::fixed(factorization_flops * 1e-9, 1);
  line["refactorized_groups"] = refactorized;
  line["factorizations"] = factorizations;
  line["memory_read_gb_per_s"] = core::fixed(read_gb_s, 1);
  line["basis_solve_floor_s"] =
      core::fixed(read_gb_s > 0 ? solves * ldlt_bytes / (read_gb_s * 1e9) : 0.0, 2);
  line["other_s"] = core::fixed(wall - update_total - rebuild_total, 2);
  line["kernel_sample_groups"] = kernels.groups;
  line["kernel_sample_gflop"] = core::fixed(kernels.flops * 1e-9, 2);
  line["kernel_one_at_a_time_s"] = core::fixed(kernels.one_at_a_time_s, 3);
  line["kernel_interleaved_s"] = core::fixed(kernels.interleaved_s, 3);
  line["kernel_speedup"] = core::fixed(
      kernels.interleaved_s > 0 ? kernels.one_at_a_time_s / kernels.interleaved_s : 0.0, 2);
  line["kernel_identical"] = kernels.identical;
  line["final_failure"] = failed;
  line["factor_nnz_supernodal"] = core::whole(supernodal_nnz);
  line["factor_nnz_simplicial"] = core::whole(simplicial_nnz);  // the LDLᵀ factor's entries
  // The factor's bytes: the supernodal LLᵀ's values (8 B per entry, briefly, at each
  // factorization) and the LDLᵀ factor kept between updates (values, rows, pointers).
  line["factor_mb_supernodal_values"] =
      core::fixed(supernodal_nnz * sizeof(double) / (1024.0 * 1024.0), 1);
  line["factor_mb_ldlt"] = core::fixed(ldlt_bytes / (1024.0 * 1024.0), 1);
  line["peak_rss_reset_ok"] = peaks.reset_ok();
  line["peak_rss_mb"] = core::fixed(peaks.peak_mb(), 1);
  line["peak_rss_phase"] = peaks.peak_phase();
  core::print_line(line);
  return 0;
}

struct BilinearRun {
  double wall_s = 0.0;          ///< increments only (initialize excluded)
  double first_k_s = 0.0;       ///< the first `k` increments
  std::int64_t increments = 0;  ///< integrated
  int secant_iterations = 0;    ///< re-solves in increments
  int refactorizations = 0;     ///< numeric factorizations after the first solve
  peritwin::statics::StaticSolver::PcgStats pcg;
  std::int64_t broken = 0;
  std::int64_t unconverged = 0;
  double max_damage = 0.0;
  bool failed = false;
};

BilinearRun run_bilinear_engine(const peritwin::statics::Specimen& s,
                                peritwin::fatigue::FatigueSettings settings, double load,
                                std::int64_t increments, std::int64_t k) {
  using namespace peritwin;
  using namespace peritwin::validation;
  BilinearRun run;
  fatigue::FatigueEngine engine(s.disc, s.model, s.supports, s.loads, settings);
  if (!engine.initialize()) {
    std::fprintf(stderr, "peritwin-bench: %s\n", engine.failure_reason().c_str());
    std::exit(1);
  }
  const int solves0 = engine.solves();
  const int factorizations0 = engine.solver().factorizations();
  const auto t0 = std::chrono::steady_clock::now();
  for (std::int64_t i = 0; i < increments; ++i) {
    const auto status = engine.apply({load, 0.1, 0.0, settings.cycle_increment});
    if (i + 1 == k) {
      run.first_k_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    if (status != fatigue::EngineStatus::ok) break;
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (run.first_k_s == 0.0) run.first_k_s = run.wall_s;
  run.increments = engine.increments();
  run.secant_iterations = engine.solves() - solves0;
  run.refactorizations = engine.solver().factorizations() - factorizations0;
  run.pcg = engine.solver().pcg_stats();
  run.broken = static_cast<std::int64_t>(engine.break_events().size());
  run.unconverged = engine.unconverged_increments();
  for (double d : engine.damage()) run.max_damage = std::max(run.max_damage, d);
  run.failed = engine.failed();
  return run;
}

int run_bilinear(double target_nodes, std::int64_t increments, std::int64_t oracle_increments,
                 double life, int step, double tolerance) {
  // B1 as a bond-based model at 4 kN with 003's bilinear bond and third law, parameters as in
  // tests/solver/test_bilinear.cpp: s0 = 1.3 × the largest stretch of the undamaged specimen at
  // 4 kN, sc = 3·s0, m = 4, A such that the most stretched bond would reach D = 1 at constant
  // stretch in `life` cycles (003 Eq. 27); ΔN = 500. The fast path runs `increments` increments
  // (or to final failure), the refactorizing oracle the first `oracle_increments` of them.
  using namespace peritwin;
  using namespace peritwin::validation;
  model::ModelOptions options;
  options.kind = model::ModelKind::bond_based;
  const CompactTensionSpec spec;
  const statics::Specimen s =
      make_compact_tension(spec, options, compact_tension_spacing(spec, target_nodes));
  const double load = 4000.0;
  double smax = 0.0;
  {
    statics::StaticSolver probe(s.disc, s.model, s.supports, s.loads);
    if (!probe.solve().ok()) return 1;
    std::vector<double> stretch;
    probe.stretch(load, 0.0, stretch);
    for (std::size_t b = 0; b < stretch.size(); ++b) {
      if (probe.intact()[b]) smax = std::max(smax, stretch[b]);
    }
  }
  fatigue::FatigueSettings settings;
  settings.law = fatigue::FatigueLaw::bilinear;
  settings.bilinear.s0 = 1.3 * smax;
  settings.bilinear.sc = 3.0 * settings.bilinear.s0;
  settings.bilinear.m = 4.0;
  settings.bilinear.A = 1.0 / (life * std::pow(smax / settings.bilinear.sc, settings.bilinear.m));
  settings.cycle_increment = 500;
  settings.bilinear_reference_step = step;
  settings.bilinear_solve_tolerance = tolerance;
  const std::int64_t k = std::min(oracle_increments, increments);
  const BilinearRun fast = run_bilinear_engine(s, settings, load, increments, k);
  settings.bilinear_refactor_every_iteration = true;
  const BilinearRun oracle = run_bilinear_engine(s, settings, load, k, k);
  core::JsonLine line;
  line["bench"] = "bilinear";
  line["nodes"] = s.disc.num_nodes();
  line["bonds"] = s.disc.num_bonds();
  line["increments"] = static_cast<long long>(fast.increments);
  line["secant_iterations"] = fast.secant_iterations;
  line["refactorizations"] = fast.refactorizations;
  line["pcg_iterations"] = static_cast<long long>(fast.pcg.iterations);
  line["pcg_max_iterations"] = fast.pcg.max_iterations;
  line["pcg_fallbacks"] = static_cast<long long>(fast.pcg.fallbacks);
  line["pcg_s"] = core::fixed(fast.pcg.seconds, 2);
  line["wall_s"] = core::fixed(fast.wall_s, 2);
  line["broken_bonds"] = static_cast<long long>(fast.broken);
  line["unconverged_increments"] = static_cast<long long>(fast.unconverged);
  line["max_damage"] = core::fixed(fast.max_damage, 4);
  line["final_failure"] = fast.failed;
  line["reference_step"] = step;
  line["tolerance"] = core::significant(tolerance, 1);
  line["oracle_increments"] = static_cast<long long>(k);
  line["oracle_secant_iterations"] = oracle.secant_iterations;
  line["oracle_wall_s"] = core::fixed(oracle.wall_s, 2);
  line["fast_first_s"] = core::fixed(fast.first_k_s, 2);
  line["fast_over_oracle"] =
      core::fixed(fast.first_k_s > 0 ? oracle.wall_s / fast.first_k_s : 0.0, 1);
  line["peak_rss_mb"] = core::fixed(peak_rss_mb(), 1);
  core::print_line(line);
  return 0;
}

// Samples -> hysteresis gate -> incremental rainflow -> blocks, on one core: the producer side of
// a live stream. Synthetic samples (fixed seed): a 1 kN sine of period 50 samples plus a
// mean-reverting random walk (steps N(0, 20 N)), the load angle a slow sine binned to 0.05 rad;
// or, with `noise`, white noise (N(0, 100 N) rounded to whole newtons, angle 0): a reversal at
// two samples of three, the worst case for the counting. They are generated in chunks of 2^20
// outside the timed region; only push(), add() and the vectors they append to (cleared per
// chunk, as a stream's batches would be) are timed.
int run_stream_rainflow(std::int64_t samples, double gate, bool noise) {
  namespace loads = peritwin::loads;
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  std::mt19937_64 rng(20261203);
  std::normal_distribution<double> step(0.0, 20.0);
  std::normal_distribution<double> white(0.0, 100.0);
  std::vector<double> load(kChunk), alpha(kChunk);
  std::vector<loads::CountedCycle> cycles;
  std::vector<peritwin::core::LoadBlock> blocks;
  loads::RainflowCounter counter(gate);
  loads::CycleBlocks converter({0.05, true});
  double walk = 0.0, seconds = 0.0;
  std::int64_t done = 0, n_blocks = 0;
  const double two_pi = 2.0 * std::acos(-1.0);
  while (done < samples) {
    const auto n = static_cast<std::size_t>(std::min<std::int64_t>(samples - done, kChunk));
    for (std::size_t i = 0; i < n; ++i) {
      const auto t = static_cast<double>(done + static_cast<std::int64_t>(i));
      if (noise) {
        load[i] = std::round(white(rng));
        alpha[i] = 0.0;
        continue;
      }
      walk = 0.999 * walk + step(rng);
      load[i] = 1000.0 * std::sin(two_pi * t / 50.0) + walk;
      alpha[i] = 0.3 * std::sin(two_pi * t / 1.0e6);
    }
    const auto t0 = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < n; ++i) counter.push(load[i], alpha[i], cycles);
    for (const loads::CountedCycle& c : cycles) converter.add(c, blocks);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    n_blocks += static_cast<std::int64_t>(blocks.size());
    cycles.clear();
    blocks.clear();
    done += static_cast<std::int64_t>(n);
  }
  const auto t0 = std::chrono::steady_clock::now();
  counter.finish(loads::ResidueRule::half, cycles);
  for (const loads::CountedCycle& c : cycles) converter.add(c, blocks);
  seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  n_blocks += static_cast<std::int64_t>(blocks.size());
  const auto& stats = counter.stats();
  const double rate = seconds > 0.0 ? static_cast<double>(samples) / seconds : 0.0;
  constexpr double kGoal = 5e7;  // samples/s on one core (the goal)
  peritwin::core::JsonLine line;
  line["bench"] = "stream-rainflow";
  line["samples"] = static_cast<long long>(samples);
  line["signal"] = noise ? "white-noise" : "sine-walk";
  line["gate_N"] = gate;
  line["seconds"] = peritwin::core::fixed(seconds, 3);
  line["samples_per_s"] = peritwin::core::significant(rate, 4);
  line["reversals"] = static_cast<long long>(stats.reversals);
  line["cycles"] = static_cast<long long>(stats.full_cycles + stats.half_cycles);
  line["half_cycles"] = static_cast<long long>(stats.half_cycles);
  line["blocks"] = static_cast<long long>(n_blocks);
  line["goal_samples_per_s"] = kGoal;
  line["ratio_to_goal"] = peritwin::core::fixed(rate / kGoal, 2);
  peritwin::core::print_line(line);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // `peritwin-bench ingest|soak|stream|dashboard|fleet|life|prognostics ...` runs
  // peritwin-bench-<subcommand> (they need LCM and the twin library or daemon, which this solver
  // benchmark does not link) from the same directory with the same arguments.
  if (argc >= 2 && (std::string(argv[1]) == "ingest" || std::string(argv[1]) == "soak" ||
                    std::string(argv[1]) == "stream" || std::string(argv[1]) == "dashboard" ||
                    std::string(argv[1]) == "fleet" || std::string(argv[1]) == "life" ||
                    std::string(argv[1]) == "prognostics")) {
    const auto self = std::filesystem::read_symlink("/proc/self/exe");
    const std::string program =
        (self.parent_path() / ("peritwin-bench-" + std::string(argv[1]))).string();
    std::vector<char*> args{const_cast<char*>(program.c_str())};
    for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
    args.push_back(nullptr);
    execv(program.c_str(), args.data());
    std::perror(("peritwin-bench: cannot run " + program).c_str());
    return 2;
  }
  CLI::App app{"peritwin-bench: performance figures as JSON lines"};
  app.require_subcommand(1);
  auto* stat = app.add_subcommand("static", "one cold static solve of the B1 CT specimen");
  std::string model = "osb";
  double nodes = 15000;
  stat->add_option("--model", model, "bb (bond-based) or osb (ordinary state-based)")
      ->check(CLI::IsMember({"bb", "osb"}));
  stat->add_option("--nodes", nodes, "approximate number of nodes")
      ->check(peritwin::core::finite_in(100.0, 1e7));
  bool static_baseline = false;
  stat->add_flag("--baseline", static_baseline,
                 "also the plain path (triplets, CHOLMOD defaults) in the same run (--model bb)");
  std::string static_ordering = "default";
  stat->add_option(
          "--ordering", static_ordering,
          "node-graph ordering: default (METIS or AMD, the lesser fill), nesdis, metis, amd "
          "(not the default: another factor, other rounding)")
      ->check(CLI::IsMember({"default", "nesdis", "metis", "amd"}));
  auto* fat = app.add_subcommand("fatigue", "B1 at 4 kN from a0 to final failure");
  double fatigue_nodes = 15000;
  double a2 = 1301;
  fat->add_option("--nodes", fatigue_nodes, "approximate number of nodes")
      ->check(peritwin::core::finite_in(100.0, 1e7));
  std::string fatigue_model = "osb";
  fat->add_option("--model", fatigue_model, "bb or osb")->check(CLI::IsMember({"bb", "osb"}));
  std::int64_t fatigue_max_cycles = 10'000'000;
  fat->add_option("--max-cycles", fatigue_max_cycles,
                  "stop after this many cycles (default 1e7: final failure comes first)")
      ->check(CLI::Range(std::int64_t{1000}, std::int64_t{10'000'000}));
  fat->add_option("--a2", a2, "A2 calibrated at dx = 1 mm (peritwin-validate --case B1)")
      ->check(peritwin::core::finite_positive());
  int kernel_groups = 40;
  fat->add_option(
         "--kernel-groups", kernel_groups,
         "re-solve groups replayed with each update kernel (slow path beside fast; 0 none)")
      ->check(CLI::Range(0, 100000));
  auto* bil =
      app.add_subcommand("bilinear", "B1 bond-based with 003's bilinear law, fast vs oracle");
  double bilinear_nodes = 15000;
  std::int64_t bilinear_increments = 200;
  std::int64_t oracle_increments = 20;
  double bilinear_life = 20000;
  int reference_step = peritwin::fatigue::FatigueSettings{}.bilinear_reference_step;
  double solve_tolerance = peritwin::fatigue::FatigueSettings{}.bilinear_solve_tolerance;
  bil->add_option("--nodes", bilinear_nodes, "approximate number of nodes")
      ->check(peritwin::core::finite_in(100.0, 1e7));
  bil->add_option("--increments", bilinear_increments, "increments of 500 cycles (fast path)")
      ->check(CLI::Range(1, 1000000));
  bil->add_option("--oracle-increments", oracle_increments, "increments of the oracle run")
      ->check(CLI::Range(1, 1000000));
  bil->add_option("--life", bilinear_life, "cycles of the most stretched bond at constant stretch")
      ->check(peritwin::core::finite_positive());
  bil->add_option("--step", reference_step, "reference factors are powers of 2^step")
      ->check(CLI::Range(1, 64));
  bil->add_option("--tolerance", solve_tolerance, "PCG tolerance (energy norm, relative)")
      ->check(peritwin::core::finite_positive());
  auto* stream =
      app.add_subcommand("stream-rainflow", "samples -> gate -> rainflow -> blocks, one core");
  std::int64_t stream_samples = 100'000'000;
  double stream_gate = 10.0;
  stream->add_option("--samples", stream_samples, "synthetic samples (default 1e8)")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40));
  stream->add_option("--gate", stream_gate, "hysteresis gate (N, default 10)")
      ->check(peritwin::core::finite_in(0.0, 1e9));
  bool stream_noise = false;
  stream->add_flag("--noise", stream_noise,
                   "white noise instead of sine + random walk (a reversal almost every sample)");
  auto* dyn =
      app.add_subcommand("dynamics", "explicit bond-based dynamics (001): bond evaluations/s");
  double dynamics_nodes = 15000;
  int dynamics_threads = 2;
  int dynamics_steps = 1000;
  dyn->add_option("--nodes", dynamics_nodes, "approximate number of nodes")
      ->check(peritwin::core::finite_in(100.0, 1e8));
  dyn->add_option("--threads", dynamics_threads, "bond-force threads")->check(CLI::Range(1, 256));
  dyn->add_option("--steps", dynamics_steps, "timed steps")->check(CLI::Range(1, 100000000));
  CLI11_PARSE(app, argc, argv);
  if (dyn->parsed()) {
    return peritwin::bench::run_dynamics(dynamics_nodes, dynamics_threads, dynamics_steps);
  }
  if (stat->parsed()) return run_static(model, nodes, static_baseline, static_ordering);
  if (fat->parsed()) {
    return run_fatigue(fatigue_model, fatigue_nodes, a2, fatigue_max_cycles, kernel_groups);
  }
  if (stream->parsed()) return run_stream_rainflow(stream_samples, stream_gate, stream_noise);
  if (bil->parsed()) {
    return run_bilinear(bilinear_nodes, bilinear_increments, oracle_increments, bilinear_life,
                        reference_step, solve_tolerance);
  }
  return 2;
}
