// The daemon's configuration: one TOML file (toml++), SI units (m, N, Pa, s, rad), one
// [[detail]] table per monitored structural detail, parsed into plain validated value structs.
// examples/b1-ct-al6061.toml and examples/b2-cts-al6061.toml are complete, commented examples.
//
// Schema (R = required, otherwise the default is given; "region" is an inline table that is
// a rectangle {x_min, y_min, x_max, y_max}, a circle {centre = [x, y], radius} or a polygon
// {polygon = [vertex, ...]}; points and vectors are arrays [x, y]). A polygon
// (solver/mesh/polygon.h) has >= 3 vertices, each [x, y], {at = [x, y], fillet = r} (the corner
// rounded by an arc of radius r tangent to both edges, which must be straight and long enough for
// it) or {to = [x, y], arc_centre = [x, y], direction = "ccw" | "cw"} (the edge arriving at it is a
// circular arc about arc_centre, counterclockwise or clockwise; both ends equidistant from it to
// 1e-6); the boundary closes from the last vertex to the first and may not cross itself. Every
// shape is closed: a node exactly on an edge or arc is inside it (so on an outline it is material,
// on a hole it is not).
//
//   [[detail]]           id R (1-32 chars [A-Za-z0-9_-], unique after upper-casing and '-'->'_'),
//                        description ""
//   [detail.geometry] R  thickness R (m, > 0), rigid_model "constraint" | "stiff_material"
//                          (how rigid_regions are modelled, mesh::RigidModel: "constraint" ties
//                          each region to one rigid motion, any ν; "stiff_material" is 000 Sec.
//                          6.1's E_rigid = rigid_factor·E, refused where it is indefinite, e.g.
//                          ν < 0.3266 in plane stress at 200), rigid_factor 200 (E_rigid/E, >= 1,
//                          stiff_material), rigid_penalty 1000 (>= 1, constraint: a tie's
//                          stiffness over its bond's),
//                        outline R [region, ...] (m, at least one; the body is their union,
//                          e.g. rectangles, or a polygon with arcs and fillets),
//                        holes [] [region, ...] (circles or polygons), notches [] [{from, to} |
//                          {path = [[x, y], ...]} (a polyline of >= 2 points from the mouth to the
//                          tip; every bond crossing any segment is cut), name "notch <index>"],
//                        rigid_regions [] [region, ...], no_fail_zones [] [region, ...]
//   [detail.grid] R      dx R (m, > 0, <= the smaller side of the body's bounding box; see
//                        "Resource bounds" below), horizon_ratio 3.015 (δ/Δx, 1 <= ratio <= 10:
//                        peridynamic fatigue calibrations use 3-4; a family holds ~π·ratio² bonds)
//   [detail.model]       kind "state_based" | "bond_based", kernel "constant" | "conical" |
//                        "gaussian" (state-based: constant only), plane "plane_stress" |
//                        "plane_strain", surface_correction true
//   [detail.material] R  E R (Pa, > 0), nu R (-1 < ν < 0.5), K_c 0 (Pa·√m, >= 0; 0 = not given),
//                        E_std 0 (Pa, 0 <= E_std < E/5; > 0: E drawn per node from N(E, E_std²),
//                          clamped to E ± 4·E_std, where a crack starts in a uniform specimen is
//                          decided by the scatter, 004; docs/solver.md "Material scatter (004)"),
//                        E_seed 0 (integer >= 0: the draw's seed, same seed same moduli)
//   [detail.fatigue] R   law R "strain_range" | "energy" | "bilinear" | "kinetic",
//                        phi0 (phase-switch / crack damage index, 0 < φ0 < 1; default the
//                          damage along a straight split at horizon_ratio, 0.398 at 3.015);
//                        strain_range, energy: A1 R, m1 R, A2 R, m2 R (> 0), eps_inf 0,
//                          eps_inf_prop 0 (>= 0)                 (fatigue::StrainLawParams),
//                          compressed_bonds_fatigue true (false: only bonds in tension at P_max
//                          lose life; FatigueSettings::compressed_bonds_fatigue)
//                        strain_range, energy: compression "full_range" (000 Eq. 15 as written:
//                          the papers' and welded details' rule) | "contact" (strain_range only:
//                          crack faces touch at P_min < 0, statics::CrackFaceContact) |
//                          "closure" (Newman's opening function, fatigue::NewmanClosure, with
//                          closure_constraint 2 (α in [1, 3]) and closure_smax_over_flow_stress
//                          0.3 (in (0, 1))); docs/compression.md
//                        bilinear (model.kind = "bond_based" only): s0 R (> 0), sc R (> s0),
//                          A R (> 0), m 4 (> 0) (fatigue::BilinearParams), cycle_increment 1000
//                          (ΔN, >= 1), softening_tolerance 1e-6 (> 0),
//                          softening_max_iterations 100 (>= 1)
//                        strain_range, energy, kinetic: static_failure "critical_stretch"
//                          (000 Eq. 7-8) | "critical_bond_energy" (000 Eq. 9-12, g_c = G_c/N_c)
//                        kinetic: U R (J, > 0), gamma R (m^3, > 0), lambda 9 (> 0), n0 1.771
//                          (> 1), temperature 293 (K, > 0), frequency 0.56 (Hz, > 0)
//                                                                (fatigue::KineticParams)
//   [[detail.load]] R    name "", exactly one of point [x, y] (the nearest node) | region;
//   (at least one)       constant, per_cos, per_sin [Fx, Fy] (N per N of P, default [0, 0], not
//                        all zero): the total force P·(constant + cos α·per_cos + sin α·per_sin)
//                        shared equally by the selected nodes
//   [[detail.support]] R name "", exactly one of point | region, fix_x true, fix_y true (not
//   (at least one)       both false)
//   [detail.output]      directory "results/<id>" (relative to the config file's directory; made
//                        absolute, as [auth] key_file),
//                        field_every_batches 10 (>= 0, 0 = never), png false
//   [detail.life]        criterion "phase3" | "crack_length" | "connectivity",
//                        critical_crack_length (m, > 0: the length along the crack path of the
//                        longest crack — from a notch tip, from the surface a crack started on,
//                        tip to tip inside; R with and only with "crack_length"), crack_origin
//                        ("" = any crack; else only cracks from this origin: a notch's name,
//                        "hole <index>", "outline"; only with "crack_length"),
//                        reference_spectrum "empirical" (the rolling spectrum of the received
//                        cycles) | [{p_max (N, > 0), r (< 1), alpha (rad, default 0), count
//                        (>= 1)}, ...] (repeated until the criterion is met), band "none" |
//                        "a2_scatter", a2_relative_scatter (0 < s < 1, the life band from
//                        A2·(1 ± s), for the bilinear law A·(1 ± s); R with and only with
//                        "a2_scatter"), every_batches 10 (>= 0, 0 = never: in deterministic mode an
//                        estimate is computed synchronously whenever state_seq is a multiple of it,
//                        state 0 included), every_cycles 0 (>= 0, 0 = never: in deterministic
//                        mode also at every state whose batch passed a multiple of it in cycles;
//                        either schedule > 0 turns the daemon's life worker on), dx (m, > the
//                        grid's dx, default: none; laws strain_range and energy only): estimate
//                        on a coarser grid of the same detail, the fine crack mapped onto it and
//                        its A2 calibrated to the fine model's recent da/dN (docs/design.md,
//                        "Remaining life on a coarser grid")
//   [detail.uncertainty] (optional; issue 32, docs/prognostics.md) particles 64 (2-4096), seed 1
//                        (>= 0), a2 {median (default: [detail.fatigue] A2), cov 0 (0-3)} and
//                        load_scale {median 1, cov 0}: lognormal priors (laws strain_range and
//                        energy for a2), percentiles [5, 50, 95] (increasing, in (0, 100)),
//                        horizon_cycles 0 (>= 0: P(end of life within it) published; 0 = not),
//                        resample_ess_fraction 0.5 (in (0, 1]), dx (m, > the grid's dx; default
//                        [detail.life] dx, else the grid's: the particles' grid, A2 rescaled by
//                        000 Eq. 29), every_batches 0 (>= 0: the particles' ends of life simulated
//                        again every so many batches; 0 = at the start, at each observation and
//                        at the end of life only)
//   [detail.stress_intensity]
//                        method "extrapolation" (001 Eq. 60-63 from the displacement jump at δ
//                        and 2δ behind the main tip) | "compact_tension" (000 Eq. A2, ASTM E647,
//                        for a CT detail: K_I from P_max and the crack length from the load line,
//                        K_II = 0), width (W, m, > 0) and load_line [x, y] (m; a point on the load
//                        line, the crack length is measured from it along the notch) R with and
//                        only with "compact_tension"
//   [detail.checkpoint]  every_batches 100 (>= 0, 0 = off), every_seconds 300 (s, >= 0, 0 = off;
//                        wall clock: it decides when a checkpoint is written, never a number)
//   [detail.limits]      max_p (N, > 0; default: 10× the load at which the virgin detail's peak
//                        bond stretch reaches the critical stretch, see twin/model; derived by the
//                        daemon when absent), max_batch_seconds 60 (s, > 0: STATUS health turns
//                        "degraded" while one batch takes longer), max_sources 16 (integer >= 1:
//                        distinct load sources per detail; a batch from a new source beyond it is
//                        rejected), max_rejects_per_second 10 (> 0: health turns "degraded" while
//                        the rejects, duplicates not counted, exceed this rate averaged over the
//                        last 10 s), release_idle_factor false (true: the detail holds no
//                        Cholesky factor from a factorization until its next bond break, which
//                        factorizes again first, bit-identically: about a third of the memory of
//                        a detail that idles, for one factorization at its first break; for
//                        fleets, docs/benchmarks.md "Fleet")
//   [[detail.gauge]]     (optional, issue 33, docs/gauges.md) strain gauges on the detail: id R (1
//   to
//                        32 characters from [A-Za-z0-9_-], unique in the detail), at R ([x, y] in
//                        m, in the material: not in a hole or notch), angle 0 (rad, finite: the
//                        measuring direction from +x), length 0 (m, >= 0: the strain is averaged
//                        over the nodes within dx/2 of the segment of this length centred at `at`;
//                        0 = the node nearest `at`), noise 0 (strain, >= 0: the gauge's standard
//                        deviation; weights of the load identification, the compliance residual's
//                        alarm and the likelihood of gauge observations), identify true (false:
//                        peritwin-stream does not identify the loads from it, compares it only)
//   [detail.sensor]      for peritwin-stream (raw samples -> cycles; the daemon ignores it):
//                        scale 1 (finite, != 0) and offset 0 (N, finite): the load is
//                        P = scale * measured + offset (strain or volts to newtons), gate 0 (N,
//                        >= 0: the rainflow hysteresis gate, load ranges up to it are no
//                        reversals), alpha_bin 0 (rad, >= 0: each cycle's angle rounded to its
//                        multiples; 0 = none)
//
//   [auth]               top level, at most once, optional (without it the daemon runs
//                        unauthenticated): key_file R (path of the key file, resolved against the
//                        config file's directory when relative; read by the messages' auth
//                        module, not here), sources [] (allowed source ids; empty = every source
//                        that has a key in the key file), daemon_key "peritwin" (the key id the
//                        daemon signs its STATE and REJECT messages with). Source ids and key ids
//                        are 1 to 64 printable ASCII characters without blanks (the rule of
//                        messages/batch.h, kMaxSourceIdLength); a source may be listed once.
//
// Resource bounds: after parsing, estimate_resources (config/resources.h) estimates each
// detail's nodes, bonds and memory from its area, dx and horizon_ratio, without discretizing
// anything (docs/limits.md). A config whose details, each or all together, exceed
// ConfigLimits::max_memory_bytes (the daemon's --max-memory, default 75 % of physical memory), or
// one of whose details would overflow the solver's 32-bit indices, is refused with the error at
// detail[i].grid.dx (the largest detail's for the total).
//
// Integers are accepted where a real number is expected, not the other way round; every real
// must be finite. Unknown keys, wrong types, missing required keys and impossible values are
// errors, each reported with file, line, column and key path (e.g. detail[0].material.E); all of
// them are collected, not only the first. Two details may share neither a channel token nor an
// output directory. No exception escapes this API.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/load_block.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/laws/bilinear.h"
#include "solver/fatigue/laws/kinetic.h"
#include "solver/fatigue/laws/strain_range.h"
#include "solver/mesh/discretization.h"
#include "solver/mesh/geometry.h"
#include "solver/model/pd_model.h"
#include "solver/statics/static_solver.h"

namespace peritwin::config {

/// [detail.grid] horizon_ratio's bounds (δ/Δx): δ may not be smaller than Δx; above 10 a node's
/// family (~π·ratio² bonds) and the factor grow for no use (fatigue calibrations use 3 to 4).
inline constexpr double kMinHorizonRatio = 1.0;
inline constexpr double kMaxHorizonRatio = 10.0;

/// One configuration error. line/column are 1-based; 0 = not known (e.g. the file is unreadable).
struct ConfigError {
  std::string file;
  std::uint32_t line = 0;
  std::uint32_t column = 0;
  std::string path;  ///< key path, e.g. "detail[0].material.E"; empty for TOML syntax errors
  std::string reason;
  /// "file:line:column: path: reason" (parts that are unknown or empty are left out), one line:
  /// control characters are escaped (\n, \t, \x01).
  [[nodiscard]] std::string message() const;
};

/// Where a load or support spec was written, so that resolve() can name it.
struct SourceRef {
  std::string file;
  std::uint32_t line = 0;
  std::uint32_t column = 0;
  std::string path;  ///< e.g. "detail[0].load[1]"
};

/// What a load or support acts on: the node nearest to a point, or every node inside a region.
struct NodeSelector {
  enum class Kind { point, region } kind = Kind::point;
  mesh::Point point;
  mesh::Region region;
};

/// A load term before it is bound to nodes (see LoadTerm in solver/statics/static_solver.h).
struct LoadSpec {
  std::string name;
  NodeSelector target;
  mesh::Point constant;  ///< N per N of P
  mesh::Point per_cos;   ///< N per N of P, times cos α
  mesh::Point per_sin;   ///< N per N of P, times sin α
  SourceRef where;
};

/// A support before it is bound to nodes (see Support in solver/statics/static_solver.h).
struct SupportSpec {
  std::string name;
  NodeSelector target;
  bool fix_x = true;
  bool fix_y = true;
  SourceRef where;
};

struct OutputConfig {
  std::string directory;                  ///< default "results/<id>"
  std::int64_t field_every_batches = 10;  ///< damage-field snapshot period, 0 = never
  bool png = false;                       ///< damage-map PNG and crack-length plot
};

enum class LifeCriterion { crack_length, phase3, connectivity };
enum class BandSource { none, a2_scatter };

struct LifeConfig {
  LifeCriterion criterion = LifeCriterion::phase3;
  double critical_crack_length = 0.0;  ///< m, crack_length only
  /// crack_length only: "" = the longest crack; else the longest crack whose origin is this.
  std::string crack_origin;
  /// Empty = the rolling empirical spectrum of the received cycles ("empirical").
  std::vector<core::LoadBlock> reference_spectrum;  ///< each valid by check_load_block
  BandSource band = BandSource::none;
  double a2_relative_scatter = 0.0;  ///< a2_scatter only
  /// Deterministic mode: estimate at every state_seq that is a multiple of this (0 = never).
  std::int64_t every_batches = 10;
  /// Deterministic mode: also estimate at every state whose batch took the cycle count past a
  /// multiple of this (0 = never): a schedule in load, not in messages, so that a producer's
  /// batch size (a stream's 100 ms batches, 1-cycle batches) does not set how often it runs.
  std::int64_t every_cycles = 0;
  /// Grid spacing (m) of the coarser estimate model; 0 = estimate on the detail's own model.
  double dx = 0.0;
  /// Whether remaining life is estimated at all (either schedule on).
  [[nodiscard]] bool estimates() const { return every_batches > 0 || every_cycles > 0; }
  [[nodiscard]] bool empirical_spectrum() const { return reference_spectrum.empty(); }
};

/// A lognormal prior given as its median and coefficient of variation (prognostics/).
struct LognormalPrior {
  double median = 1.0;
  double cov = 0.0;  ///< 0: the parameter is known (no spread)
};

/// [detail.uncertainty] (issue 32): the uncertain parameters' priors and the particle ensemble
/// that updates them from observations (twin/ensemble.h, docs/prognostics.md).
struct UncertaintyConfig {
  bool enabled = false;  ///< the table is present
  std::int64_t particles = 64;
  std::uint64_t seed = 1;
  /// A2 (phase II coefficient, 000 Eq. 15) in the law's units; median default: the calibrated
  /// [detail.fatigue] A2.
  LognormalPrior a2;
  /// Factor on every received P_max (the sensors' or the spectrum's bias).
  LognormalPrior load_scale;
  /// Percentiles of the end-of-life cycle published (in (0, 100), increasing).
  std::vector<double> percentiles{5.0, 50.0, 95.0};
  /// P(end of life within the next horizon_cycles) is published; 0 = not.
  double horizon_cycles = 0.0;
  /// Resample when the effective sample size falls below this fraction of the particles.
  double resample_ess_fraction = 0.5;
  /// Grid spacing of the particles' models (m): 0 = [detail.life] dx when set, else the detail's
  /// own. A coarser grid is the same detail with A2 rescaled by 000 Eq. (29) (twin/coarse_life.h
  /// coarse_model); the filter learns A2 as a factor on that.
  double dx = 0.0;
  /// The particles' ends of life are simulated again every this many batches (besides the start,
  /// every observation and the end of life); 0 = only then. In between, the remaining-cycle
  /// percentiles follow the cycle count from the last simulated ends of life.
  std::int64_t every_batches = 0;
  /// The particles' grid spacing in force (m): dx, or [detail.life] dx, or 0 (the detail's own).
  [[nodiscard]] double particle_dx(double life_dx) const { return dx > 0 ? dx : life_dx; }
};

enum class StressIntensityMethod { extrapolation, compact_tension };

/// How K_I and K_II at the main crack tip are reported (STATE, results).
struct StressIntensityConfig {
  StressIntensityMethod method = StressIntensityMethod::extrapolation;
  double width = 0.0;     ///< W (m), compact_tension only
  mesh::Point load_line;  ///< a point on the load line (m), compact_tension only
};

struct CheckpointConfig {
  std::int64_t every_batches = 100;  ///< 0 = off
  double every_seconds = 300.0;      ///< wall-clock period, 0 = off
};

/// [detail.limits]: the bounds the daemon enforces per detail (see the schema above).
struct LimitsConfig {
  /// Largest accepted P_max (N); absent: the daemon derives it from the model (twin/model).
  std::optional<double> max_p;
  double max_batch_seconds = 60.0;       ///< s; health "degraded" while one batch takes longer
  std::int64_t max_sources = 16;         ///< distinct load sources of the detail
  double max_rejects_per_second = 10.0;  ///< over the last 10 s, duplicates not counted
  /// Free the factor while the detail breaks no bond (FatigueSettings::release_idle_factor).
  bool release_idle_factor = false;
};

/// [[detail.gauge]]: a strain gauge on the detail (issue 33, docs/gauges.md).
struct GaugeConfig {
  std::string id;
  mesh::Point at;       ///< centre of the measuring grid (m)
  double angle = 0.0;   ///< measuring direction from +x (rad)
  double length = 0.0;  ///< gauge length (m); 0 = the node nearest `at`
  double noise = 0.0;   ///< standard deviation of a reading (strain)
  /// peritwin-stream --format gauges identifies the loads from it (default); false: its
  /// compliance is compared only (a gauge near the crack, docs/gauges.md).
  bool identify = true;
  SourceRef where;
};

/// [detail.sensor]: how peritwin-stream turns a sensor's samples into loads and cycles.
struct SensorConfig {
  double scale = 1.0;      ///< N per unit measured; finite, != 0
  double offset = 0.0;     ///< N; P = scale * measured + offset
  double gate = 0.0;       ///< N, rainflow hysteresis gate, >= 0
  double alpha_bin = 0.0;  ///< rad, >= 0, 0 = no binning
};

struct DetailConfig {
  std::string id;     ///< as written, e.g. "b1-ct"
  std::string token;  ///< channel token: upper case, '-' -> '_', e.g. "B1_CT"
  std::string description;
  mesh::DetailGeometry geometry;
  double dx = 0.0;               ///< grid spacing Δx (m)
  double horizon_ratio = 3.015;  ///< δ/Δx
  model::Material material;
  model::ModelOptions model;
  /// [detail.fatigue]: the engine's own settings (law, parameters, φ0, phase III); the daemon
  /// keeps the engine defaults for the keys the schema does not expose.
  fatigue::FatigueSettings fatigue;
  std::vector<LoadSpec> loads;
  std::vector<SupportSpec> supports;
  OutputConfig output;
  LifeConfig life;
  UncertaintyConfig uncertainty;
  StressIntensityConfig stress_intensity;
  CheckpointConfig checkpoint;
  LimitsConfig limits;
  SensorConfig sensor;
  std::vector<GaugeConfig> gauges;  ///< [[detail.gauge]], in the config's order
  SourceRef where;                  ///< the [[detail]] table

  [[nodiscard]] double horizon() const { return horizon_ratio * dx; }
};

/// [auth]: authenticated load and state messages (the key file is read by messages' auth module).
struct AuthConfig {
  /// As resolved: a relative key_file is joined to the config file's directory (made absolute).
  std::string key_file;
  /// Allowed source ids, each valid by is_valid_source_id; empty = every source with a key.
  std::vector<std::string> sources;
  /// Key id of the daemon's own STATE and REJECT signatures.
  std::string daemon_key = "peritwin";
  SourceRef where;  ///< the [auth] table
};

struct TwinConfig {
  std::vector<DetailConfig> details;
  std::optional<AuthConfig> auth;  ///< absent: unauthenticated
};

/// The detail a producer's --detail names: the one with id `id`, the first when `id` is empty,
/// nullptr when no detail has that id (the tools' "no detail \"X\" in FILE").
[[nodiscard]] const DetailConfig* select_detail(const TwinConfig& config, std::string_view id);

/// A source id (or key id): 1 to kMaxSourceIdLength (64) printable ASCII characters without
/// blanks — the rule check_batch applies to load_batch_t.source_id (messages/batch.cpp, where it is
/// not exported; keep the two in step).
[[nodiscard]] bool is_valid_source_id(std::string_view id);

/// What parse_config and load_config refuse besides schema errors.
struct ConfigLimits {
  /// The most memory all details together may need by estimate_resources (bytes); 0 = the
  /// default, default_memory_limit(); UINT64_MAX = no memory bound (a tool that builds no model,
  /// e.g. peritwin-replay over LCM; the 32-bit index bound still applies).
  std::uint64_t max_memory_bytes = 0;
  /// The ids of the details this process serves (the daemon's --details, a fleet sharing one
  /// config): the whole file is still checked, but only these details are returned and counted
  /// against max_memory_bytes; an id the file does not have is an error. Empty: every detail.
  std::vector<std::string> served_details{};
  /// Remaining-life estimates this process runs at once (the daemon's --life-threads, or its
  /// worker threads in deterministic mode): all details together are counted with the life
  /// engines of only this many, the largest. 0 = every detail's at once.
  int concurrent_life_estimates = 0;
};

/// 75 % of the machine's physical memory (sysconf(_SC_PHYS_PAGES) · sysconf(_SC_PAGE_SIZE)); 8 GiB
/// when sysconf cannot tell.
[[nodiscard]] std::uint64_t default_memory_limit();

/// A byte count as given on a command line: digits with an optional suffix K, M, G or T (powers of
/// 1024, upper or lower case, an optional trailing "B" or "iB"), e.g. "8G", "512M", "1048576";
/// nothing unless it is such a number > 0 that fits in 64 bits.
[[nodiscard]] std::optional<std::uint64_t> parse_byte_size(std::string_view text);

/// A byte count for people, 3 digits in binary units: "512 B", "3.4 KiB", "1.5 GiB", "2.2 PiB".
[[nodiscard]] std::string format_bytes(double bytes);

/// Either a config (errors empty) or every error found (config empty).
struct ConfigResult {
  std::optional<TwinConfig> config;
  std::vector<ConfigError> errors;
  [[nodiscard]] bool ok() const { return config.has_value(); }
  /// One message() per line.
  [[nodiscard]] std::string error_text() const;
};

/// Reads and parses a file; errors name it as given. Refuses what `limits` bounds.
[[nodiscard]] ConfigResult load_config(const std::string& file, const ConfigLimits& limits = {});
/// Parses TOML text; errors name `file_name` (need not exist; [auth] key_file is resolved against
/// its directory). Refuses what `limits` bounds.
[[nodiscard]] ConfigResult parse_config(std::string_view text, std::string_view file_name,
                                        const ConfigLimits& limits = {});

/// The supports and load terms of a detail bound to the nodes of its discretization. A point
/// selects its nearest node, a region every node inside it; a selection without nodes is an error
/// (named with the spec's file, line and path) and its entry is left out.
struct ResolvedBoundary {
  std::vector<statics::Support> supports;
  std::vector<statics::LoadTerm> loads;
  std::vector<ConfigError> errors;
  [[nodiscard]] bool ok() const { return errors.empty(); }
};
[[nodiscard]] ResolvedBoundary resolve(const DetailConfig& detail,
                                       const mesh::Discretization& disc);

/// discretize(detail.geometry, detail.dx, detail.horizon()).
[[nodiscard]] mesh::Discretization discretize(const DetailConfig& detail);

}  // namespace peritwin::config
