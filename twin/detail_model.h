// The immutable model of one detail, built once from its config: discretization, PD model,
// supports and load terms bound to nodes, solver fatigue settings, crack tracker. Shared (const)
// by the live Twin and by the remaining-life forward simulations, which build their own
// FatigueEngine on it; it must outlive every engine made from it (hold the shared_ptr).
// Also the measurements every consumer of a state needs: crack metrics, K, end criterion.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "config/config.h"
#include "core/expected.h"
#include "solver/crack/crack_finder.h"
#include "solver/crack/crack_tracker.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/statics/specimen.h"
#include "twin/gauges.h"

namespace peritwin::twin {

/// The solver's settings for a detail's fatigue config, or why the engine cannot run the
/// configured law's parameters (fatigue::validate).
/// Re-solves are incremental (CHOLMOD rank updates); resume stays bit-identical because the
/// engine replays its recorded re-solve groups on import (EngineState::resolve_groups).
core::Expected<fatigue::FatigueSettings> solver_settings(const config::DetailConfig& detail);

/// Limits OpenBLAS (when it is the BLAS in use) to one thread, once per process. Called by
/// DetailModel::build: the twin parallelizes over forward simulations instead, and one BLAS
/// thread keeps the factorization's round-off independent of the machine's core count.
void use_single_threaded_blas();

class DetailModel {
 public:
  /// Discretizes, binds supports and loads, builds the PD model; or why it cannot.
  static core::Expected<std::shared_ptr<const DetailModel>> build(
      const config::DetailConfig& config);

  [[nodiscard]] const config::DetailConfig& config() const { return config_; }
  [[nodiscard]] const mesh::Discretization& disc() const { return specimen_.disc; }
  /// The outline, holes and notches the discretization was cut from.
  [[nodiscard]] const mesh::DetailGeometry& geometry() const { return specimen_.geometry; }
  [[nodiscard]] const model::PdModel& pd() const { return specimen_.model; }
  /// Everything a static solve is built from (the rigid regions' ties included).
  [[nodiscard]] const statics::Specimen& specimen() const { return specimen_; }
  [[nodiscard]] const fatigue::FatigueSettings& settings() const { return settings_; }
  [[nodiscard]] const crack::CrackTracker& tracker() const { return *tracker_; }
  /// Finds every crack (notch, surface, interior) from the damage; its notches are the tracker's.
  [[nodiscard]] const crack::CrackFinder& finder() const { return *finder_; }
  /// Where a crack that starts at `p` (not at a notch) comes from, for people: "hole <index>"
  /// when a hole's rim is the nearest surface, else "outline".
  [[nodiscard]] std::string surface_name(mesh::Point p) const;
  /// The [[detail.gauge]] on this model's grid (issue 33, twin/gauges.h).
  [[nodiscard]] const std::vector<ModelGauge>& gauges() const { return gauges_; }
  /// Bonds cut by notches at construction (not counted as broken in the published state).
  [[nodiscard]] std::int64_t precut_bonds() const { return precut_bonds_; }
  /// Byte-wise FNV-1a 64 (core/fnv1a.h) over everything that defines the model's numbers
  /// (nodes, bonds, boundary, material, model, fatigue settings): a checkpoint only resumes on an
  /// equal signature.
  [[nodiscard]] std::uint64_t signature() const { return signature_; }

  /// A new engine on this model (not initialized); the phase II coefficient A2 scaled by
  /// `a2_factor` (the life band). `live`: the twin's own engine, which frees its factor while it
  /// breaks no bond when the config says so ([detail.limits] release_idle_factor).
  [[nodiscard]] std::unique_ptr<fatigue::FatigueEngine> make_engine(double a2_factor = 1.0,
                                                                    bool live = false) const;
  /// The settings make_engine(a2_factor, live) builds its engine with (for FatigueEngine::fork).
  [[nodiscard]] fatigue::FatigueSettings engine_settings(double a2_factor = 1.0,
                                                         bool live = false) const;

 private:
  DetailModel() = default;
  config::DetailConfig config_;
  statics::Specimen specimen_;
  fatigue::FatigueSettings settings_;
  std::unique_ptr<crack::CrackTracker> tracker_;
  std::unique_ptr<crack::CrackFinder> finder_;
  std::int64_t precut_bonds_ = 0;
  std::uint64_t signature_ = 0;
  std::vector<ModelGauge> gauges_;
};

/// Why a tip's K is NaN (crack_tip_t.K_* codes).
enum class KStatus : std::int8_t {
  ok = 0,
  no_load = 1,       ///< no block applied yet
  short_crack = 2,   ///< faces shorter than 2δ behind the tip
  near_surface = 3,  ///< tip within δ of a free surface, or a fit point outside the body
  no_faces = 4,      ///< a node pair behind the tip is not separated by the crack
  out_of_range = 5,  ///< the configured formula does not cover this crack
  failed = 6,        ///< final failure
};

/// K at one crack tip under P_max of the last block; NaN unless status is ok.
struct TipStressIntensity {
  double k_i = std::numeric_limits<double>::quiet_NaN();
  double k_ii = std::numeric_limits<double>::quiet_NaN();
  KStatus status = KStatus::no_load;
};

/// One crack of a state: the finder's crack, where it comes from in words, K per tip.
struct ReportedCrack {
  crack::FoundCrack crack;
  std::string origin;                 ///< the notch's name, "hole <index>", "outline", "interior"
  std::vector<TipStressIntensity> k;  ///< one per crack.tips
};

/// The cracks of a state (CrackFinder with ids from the break history) and their SIFs.
struct CrackReport {
  std::vector<ReportedCrack> cracks;      ///< longest first along the path (ties: the smaller id)
  std::vector<crack::CrackMerge> merges;  ///< every join so far, in cycle order
  double max_damage = 0.0;
  /// K_I, K_II at the main crack's first tip (= cracks[0].k[0]); NaN without a crack or a block.
  double k_i = std::numeric_limits<double>::quiet_NaN();
  double k_ii = std::numeric_limits<double>::quiet_NaN();
  [[nodiscard]] double main_length() const { return cracks.empty() ? 0.0 : cracks[0].crack.length; }
  /// The crack the life criterion measures: the longest, or the longest whose origin is `origin`
  /// (nullptr when there is none).
  [[nodiscard]] const ReportedCrack* criterion_crack(const std::string& origin) const;
};

/// Measures the engine's current state. `last_block` (may be null) gives P_max and α for K.
CrackReport measure_cracks(const DetailModel& model, const fatigue::FatigueEngine& engine,
                           const core::LoadBlock* last_block);

/// The crack length the life criterion compares (the longest crack, or the longest from the
/// configured origin) for a damage field and the bond state it came from (snapshot: no ids).
double criterion_crack_length(const DetailModel& model, const std::vector<double>& node_damage,
                              const std::vector<std::uint8_t>& intact);

/// damage_state_t FAILURE_* codes.
enum class Failure : std::int8_t { none = 0, end_criterion = 1, singular = 2 };

/// The length (m, along its path) of the longest crack of the engine's state whose origin is
/// `origin` ("longest" or "": any crack; else a notch's name, "hole <index>", "outline" as STATE
/// reports it); 0 when there is none. What an inspection of that crack is compared with.
double observed_crack_length(const DetailModel& model, const fatigue::FatigueEngine& engine,
                             const std::string& origin);
/// The same for a damage field and the bond state it came from.
double observed_crack_length(const DetailModel& model, const std::vector<double>& node_damage,
                             const std::vector<std::uint8_t>& intact, const std::string& origin);
/// Whether `origin` names a place a crack of this detail can start from, as STATE reports it:
/// "longest", a notch's name, "hole <index>" of an existing hole, "outline" or "interior".
bool is_crack_origin(const DetailModel& model, const std::string& origin);

/// Whether the engine's state meets the end criterion of the detail's life config
/// (crack_length: the criterion's crack, criterion_crack_length(), >= critical; phase3: any bond
/// broken by overload; connectivity: final failure). A singular stiffness (final failure) is
/// always the end. The one rule of the live twin (checked after every group of breaks, through
/// end_of_life_check) and of the remaining-life simulation.
Failure end_of_life(const DetailModel& model, const fatigue::FatigueEngine& engine);

/// end_of_life() != none as the engine's stop check (FatigueEngine::StopCheck): an engine given it
/// stops at the exact cycle at which the criterion is met, whatever the blocks.
fatigue::FatigueEngine::StopCheck end_of_life_check(const DetailModel& model);

}  // namespace peritwin::twin
