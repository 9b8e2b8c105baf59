// The immutable model of one detail, built once from its config: discretization, PD model,
// supports and load terms bound to nodes, solver fatigue settings, crack tracker. Shared (const)
// by the live Twin and by the remaining-life forward simulations, which build their own
// FatigueEngine on it; it must outlive every engine made from it (hold the shared_ptr).
// Also the measurements every consumer of a state needs: crack metrics, K, end criterion.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "solver/core/expected.h"
#include "solver/crack/crack_tracker.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/static/specimen.h"
#include "twin/config/config.h"

namespace peritwin::twin {

/// The solver's settings for a detail's fatigue config, or why the engine cannot run the
/// configured law's parameters (fatigue::validate).
/// Re-solves are incremental (CHOLMOD rank updates); resume stays bit-identical because the
/// engine replays its recorded re-solve groups on import (EngineState::resolve_groups).
Expected<FatigueSettings> solver_settings(const DetailConfig& detail);

/// Limits OpenBLAS (when it is the BLAS in use) to one thread, once per process. Called by
/// DetailModel::build: the twin parallelizes over forward simulations instead, and one BLAS
/// thread keeps the factorization's round-off independent of the machine's core count.
void use_single_threaded_blas();

class DetailModel {
 public:
  /// Discretizes, binds supports and loads, builds the PD model; or why it cannot.
  static Expected<std::shared_ptr<const DetailModel>> build(const DetailConfig& config);

  [[nodiscard]] const DetailConfig& config() const { return config_; }
  [[nodiscard]] const Discretization& disc() const { return specimen_.disc; }
  [[nodiscard]] const PdModel& pd() const { return specimen_.model; }
  [[nodiscard]] const FatigueSettings& settings() const { return settings_; }
  [[nodiscard]] const CrackTracker& tracker() const { return *tracker_; }
  /// Bonds cut by notches at construction (not counted as broken in the published state).
  [[nodiscard]] std::int64_t precut_bonds() const { return precut_bonds_; }
  /// Byte-wise FNV-1a 64 (solver/core/fnv1a.h) over everything that defines the model's numbers
  /// (nodes, bonds, boundary, material, model, fatigue settings): a checkpoint only resumes on an
  /// equal signature.
  [[nodiscard]] std::uint64_t signature() const { return signature_; }

  /// A new engine on this model (not initialized); the phase II coefficient A2 scaled by
  /// `a2_factor` (the life band).
  [[nodiscard]] std::unique_ptr<FatigueEngine> make_engine(double a2_factor = 1.0) const;

 private:
  DetailModel() = default;
  DetailConfig config_;
  Specimen specimen_;
  FatigueSettings settings_;
  std::unique_ptr<CrackTracker> tracker_;
  std::int64_t precut_bonds_ = 0;
  std::uint64_t signature_ = 0;
};

/// Crack metrics of a state (the solver's CrackTracker, one crack per notch) and the SIFs.
struct CrackReport {
  std::vector<CrackMetrics> cracks;  ///< main crack (longest along the path) first
  double max_damage = 0.0;
  /// K_I, K_II at the main crack tip under P_max of the last block (displacement extrapolation,
  /// 001 Eq. 62-63, at r = δ and 2δ behind the tip); NaN without a notch or a block.
  double k_i = 0.0;
  double k_ii = 0.0;
  [[nodiscard]] double main_length() const { return cracks.empty() ? 0.0 : cracks[0].length; }
};

/// Measures the engine's current state. `last_block` (may be null) gives P_max and α for K.
CrackReport measure_cracks(const DetailModel& model, const FatigueEngine& engine,
                           const LoadBlock* last_block);

/// Crack length along the path of the main (longest) crack for a damage field.
double main_crack_length(const DetailModel& model, const std::vector<double>& node_damage);

/// damage_state_t FAILURE_* codes.
enum class Failure : std::int8_t { none = 0, end_criterion = 1, singular = 2 };

/// Whether the engine's state meets the end criterion of the detail's life config
/// (crack_length: main crack ≥ critical; phase3: any bond broken by overload; connectivity:
/// final failure). A singular stiffness (final failure) is always the end.
Failure end_of_life(const DetailModel& model, const FatigueEngine& engine,
                    const CrackReport& report);

}  // namespace peritwin::twin
