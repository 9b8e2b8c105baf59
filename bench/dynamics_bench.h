// peritwin-bench dynamics: speed of the explicit bond-based integrator (solver/dynamics).
#pragma once

namespace peritwin::bench {
/// A square plate of about `nodes` nodes (Δx = 1 mm, δ = 3Δx, Gaussian p = 2, a step traction on
/// one edge) run for `steps` central-difference steps on `threads` threads after 20 warm-up steps;
/// prints one JSON line: bond evaluations per second (each bond evaluated from both ends, the
/// integrator's unit of work) and ns per node-step.
int run_dynamics(double nodes, int threads, int steps);
}  // namespace peritwin::bench
