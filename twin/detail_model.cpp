#include "twin/detail_model.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

#include "core/fnv1a.h"
#include "solver/statics/rigid_regions.h"

namespace peritwin::twin {

namespace {

/// The model signature's hash: byte-wise FNV-1a 64 over values and vectors (with their sizes).
struct SignatureHash {
  core::Fnv1a64 h;
  template <class T>
  void value(const T& v) {
    h.bytes(&v, sizeof v);
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    value(v.size());
    if (!v.empty()) h.bytes(v.data(), v.size() * sizeof(T));
  }
};

}  // namespace

void use_single_threaded_blas() {
  static std::once_flag once;
  std::call_once(once, [] {
    // OpenBLAS (Debian's libblas.so.3 alternative) threads fight the twin's own threads on small
    // machines (2x slower with 3 forward simulations on 2 cores) and make round-off depend on
    // the core count. Looked up at run time: any other BLAS simply lacks the symbol.
    using SetThreads = void (*)(int);
    if (void* f = dlsym(RTLD_DEFAULT, "openblas_set_num_threads")) {
      reinterpret_cast<SetThreads>(f)(1);
    }
  });
}

core::Expected<fatigue::FatigueSettings> solver_settings(const config::DetailConfig& detail) {
  fatigue::FatigueSettings s = detail.fatigue;
  if (s.law == fatigue::FatigueLaw::bilinear) {
    if (const core::Status valid = fatigue::validate(s.bilinear); !valid) {
      return core::failure(detail.where.file + ": " + detail.where.path +
                           ".fatigue: " + valid.error().reason);
    }
  }
  s.incremental = true;
  return s;
}

core::Expected<std::shared_ptr<const DetailModel>> DetailModel::build(
    const config::DetailConfig& config) {
  const auto settings = solver_settings(config);
  if (!settings) return settings.error();
  use_single_threaded_blas();
  std::shared_ptr<DetailModel> m(new DetailModel());
  m->config_ = config;
  m->settings_ = *settings;
  statics::Specimen& sp = m->specimen_;
  sp.name = config.id;
  sp.geometry = config.geometry;
  sp.material = config.material;
  sp.disc = discretize(config);
  if (sp.disc.num_nodes() == 0)
    return core::failure("detail " + config.id + ": the discretization has no nodes");
  const config::ResolvedBoundary boundary = config::resolve(config, sp.disc);
  if (!boundary.ok()) {
    std::string reasons;
    for (const auto& e : boundary.errors) reasons += e.message() + "\n";
    return core::failure(reasons);
  }
  sp.supports = boundary.supports;
  sp.loads = boundary.loads;
  sp.model = model::build_model(sp.disc, config.material, config.model,
                                statics::material_rigid_factor(config.geometry));
  sp.ties = statics::rigid_region_ties(sp.disc, sp.model, config.geometry);
  crack::CrackTrackerOptions tracker_options;
  tracker_options.phase_switch_damage = config.fatigue.phase_switch_damage;
  m->tracker_ =
      std::make_unique<crack::CrackTracker>(sp.disc, config.geometry.notches, tracker_options);
  std::vector<std::vector<mesh::Point>> notch_paths;
  for (const auto& n : config.geometry.notches) notch_paths.push_back(n.path);
  m->finder_ = std::make_unique<crack::CrackFinder>(sp.disc, *m->tracker_, std::move(notch_paths),
                                                    config.fatigue.phase_switch_damage);
  for (auto c : sp.disc.bond_precut) m->precut_bonds_ += c ? 1 : 0;
  // Gauges read the model, they do not change it: not in the signature (a checkpoint resumes
  // after a gauge is added or moved).
  m->gauges_ = model_gauges(config.gauges, sp.disc);

  SignatureHash h;
  const auto& d = sp.disc;
  h.value(d.dx);
  h.value(d.horizon);
  h.value(d.thickness);
  h.vec(d.position);
  h.vec(d.volume);
  h.vec(d.rigid);
  h.vec(d.no_fail);
  h.vec(d.bond_i);
  h.vec(d.bond_j);
  h.vec(d.bond_precut);
  h.vec(sp.model.bond_stiffness);
  h.vec(sp.model.dilatation_stiffness);
  // Rigid-region ties (issue 31). Only when there are some, so that the signature of a detail
  // without them (every detail before) is unchanged and its checkpoints still resume.
  if (!sp.ties.empty()) {
    h.value(sp.ties.size());
    for (const auto& tie : sp.ties) {
      h.vec(tie.terms);
      h.value(tie.stiffness);
    }
  }
  for (const auto& s : sp.supports) {
    h.vec(s.nodes);
    h.value(s.fix_x);
    h.value(s.fix_y);
  }
  for (const auto& l : sp.loads) {
    h.vec(l.nodes);
    h.value(l.constant);
    h.value(l.per_cos);
    h.value(l.per_sin);
  }
  h.value(m->settings_.law);
  h.value(m->settings_.strain);
  h.value(m->settings_.kinetic);
  h.value(m->settings_.phase_switch_damage);
  h.value(m->settings_.critical_stretch);
  // The bilinear bond's four original fields as before (the same bytes: existing signatures and
  // checkpoints are unchanged); 003's first and second laws (issue 36) add their own.
  const fatigue::BilinearParams& bl = m->settings_.bilinear;
  for (const double v : {bl.s0, bl.sc, bl.A, bl.m}) h.value(v);
  if (bl.law != 3) {
    h.value(bl.law);
    for (const double v : {bl.C, bl.beta, bl.lambda, bl.mu, bl.B, bl.n}) h.value(v);
  }
  h.value(m->settings_.cycle_increment);
  h.value(m->settings_.softening_tolerance);
  h.value(m->settings_.softening_max_iterations);
  h.value(m->settings_.static_failure);
  h.value(m->settings_.critical_bond_energy);
  h.value(m->settings_.crack_interactions);
  h.value(m->settings_.refactor_every_resolves);
  h.value(config.material.fracture_toughness);
  h.value(m->settings_.compressed_bonds_fatigue);
  // Issue 34: hashed only when not the default, so that existing details keep their signatures.
  if (m->settings_.compression != fatigue::CompressionRule::full_range) {
    h.value(m->settings_.compression);
    if (m->settings_.compression == fatigue::CompressionRule::closure) {
      h.value(m->settings_.closure.constraint);
      h.value(m->settings_.closure.smax_over_flow_stress);
    }
  }
  // Material scatter (004): hashed only when drawn, so that uniform details keep their
  // signatures (the drawn moduli are in bond_stiffness already; these name the draw).
  if (config.material.youngs_modulus_std > 0.0) {
    h.value(config.material.youngs_modulus_std);
    h.value(config.material.youngs_modulus_seed);
  }
  // Issue 35, the kinetic law's segments, k_U, k_γ and Eq. (26): hashed only when not the
  // default (a single U, γ; 1, 1; ψ = 0), so that existing details keep their signatures. Field
  // by field (the struct has padding).
  if (const fatigue::KineticExtension& e = m->settings_.kinetic_extension;
      e.segment_count != 0 || e.kU != 1.0 || e.kgamma != 1.0 || e.psi != 0.0) {
    h.value(e.segment_count);
    for (const auto& s : e.segments) {
      h.value(s.sigma_upper);
      h.value(s.U);
      h.value(s.gamma);
    }
    h.value(e.kU);
    h.value(e.kgamma);
    h.value(e.psi);
    h.value(e.loop_area);
    h.value(e.loop_area_yield);
  }
  m->signature_ = h.h.get();
  return std::shared_ptr<const DetailModel>(std::move(m));
}

fatigue::FatigueSettings DetailModel::engine_settings(double a2_factor, bool live) const {
  fatigue::FatigueSettings s = settings_;
  // Only the live twin idles between breaks; a remaining-life simulation breaks bonds from its
  // first blocks, so it keeps its factor.
  s.release_idle_factor = live && config_.limits.release_idle_factor;
  s.strain.A2 *= a2_factor;
  s.bilinear.A *= a2_factor;  // the bilinear law's growth coefficient (003 Eq. 27) plays A2's role
  return s;
}

std::unique_ptr<fatigue::FatigueEngine> DetailModel::make_engine(double a2_factor,
                                                                 bool live) const {
  const fatigue::FatigueSettings s = engine_settings(a2_factor, live);
  return std::make_unique<fatigue::FatigueEngine>(
      specimen_.disc, specimen_.model, specimen_.supports, specimen_.loads, s, specimen_.ties);
}

std::string DetailModel::surface_name(mesh::Point p) const {
  // The nearest piece of the free surface (geometry.h nearest_surface): a hole's rim, else the
  // outline. A notch's faces count as the outline here: a crack that starts on them is not the
  // notch's (that one starts at its tip).
  const mesh::SurfacePlace place = config_.geometry.nearest_surface(p);
  if (place.kind == mesh::SurfacePlace::Kind::hole) return "hole " + std::to_string(place.index);
  return "outline";
}

const ReportedCrack* CrackReport::criterion_crack(const std::string& origin) const {
  for (const auto& c : cracks) {
    if (origin.empty() || c.origin == origin) return &c;  // longest first
  }
  return nullptr;
}

namespace {

std::string origin_name(const DetailModel& model, const crack::FoundCrack& c) {
  switch (c.origin) {
    case crack::CrackOrigin::notch:  // "notch <index>" unless the config names it
      return model.config().geometry.notches[static_cast<std::size_t>(c.notch)].name;
    case crack::CrackOrigin::surface:
      return model.surface_name(c.origin_point);
    case crack::CrackOrigin::interior:
      return "interior";
  }
  return "interior";
}

/// Longest first along the path; ties by id (then the snapshot order).
void sort_longest_first(std::vector<ReportedCrack>& cracks) {
  std::stable_sort(cracks.begin(), cracks.end(), [](const auto& a, const auto& b) {
    if (a.crack.length != b.crack.length) return a.crack.length > b.crack.length;
    return a.crack.id < b.crack.id;
  });
}

double path_length(const std::vector<mesh::Point>& path) {
  double l = 0.0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    l += std::hypot(path[i + 1].x - path[i].x, path[i + 1].y - path[i].y);
  }
  return l;
}

/// Whether the displacement extrapolation (001 Eq. 62-63 at r = δ and 2δ behind the tip, the node
/// pairs of stress_intensity_by_extrapolation) is meaningful at this tip; why not otherwise.
KStatus extrapolation_status(const DetailModel& model, const std::vector<std::uint8_t>& intact,
                             const crack::CrackTipState& tip, double face_length) {
  const mesh::Discretization& disc = model.disc();
  const double delta = disc.horizon;
  if (face_length < 2 * delta) return KStatus::short_crack;
  const auto tip_node = static_cast<std::size_t>(disc.nearest_node(tip.position));
  if (model.finder().surface_distance()[tip_node] < delta) return KStatus::near_surface;
  if (std::hypot(tip.direction.x, tip.direction.y) < 0.5) return KStatus::short_crack;
  for (const double r : {delta, 2 * delta}) {
    const auto pair = crack::extrapolation_face_nodes(disc, tip.position, tip.direction, r);
    for (const auto& [node, target] :
         {std::pair{pair.upper, pair.upper_target}, std::pair{pair.lower, pair.lower_target}}) {
      const mesh::Point q = disc.position[static_cast<std::size_t>(node)];
      // A node more than a cell from its fit point: the point lies outside the body.
      if (std::hypot(q.x - target.x, q.y - target.y) > disc.dx) return KStatus::near_surface;
    }
    if (pair.upper == pair.lower ||
        !crack::separated_by_crack(disc, intact, pair.upper, pair.lower)) {
      return KStatus::no_faces;
    }
  }
  return KStatus::ok;
}

}  // namespace

CrackReport measure_cracks(const DetailModel& model, const fatigue::FatigueEngine& engine,
                           const core::LoadBlock* last_block) {
  CrackReport report;
  const auto& damage = engine.node_damage();
  for (double phi : damage) report.max_damage = std::max(report.max_damage, phi);
  const auto& intact = engine.solver().intact();
  crack::CrackFindings found = model.finder().find_with_history(damage, engine.break_events());
  report.merges = std::move(found.merges);
  for (auto& c : found.cracks) {
    ReportedCrack r;
    r.origin = origin_name(model, c);
    r.crack = std::move(c);
    r.k.assign(r.crack.tips.size(), TipStressIntensity{});
    report.cracks.push_back(std::move(r));
  }
  sort_longest_first(report.cracks);
  if (report.cracks.empty()) return report;
  const KStatus common = engine.failed()         ? KStatus::failed
                         : last_block == nullptr ? KStatus::no_load
                                                 : KStatus::ok;
  if (common != KStatus::ok) {
    for (auto& c : report.cracks) {
      for (auto& k : c.k) k.status = common;
    }
    return report;
  }
  const config::StressIntensityConfig& method = model.config().stress_intensity;
  const auto& pd = model.pd();
  const double nu = model::effective_poisson_ratio(pd.material, pd.options);
  const double mu = pd.material.youngs_modulus / (2 * (1 + nu));
  const double kappa = crack::kolosov_kappa(nu, pd.options.plane);
  const double delta = model.disc().horizon;
  std::vector<double> u;
  for (std::size_t i = 0; i < report.cracks.size(); ++i) {
    ReportedCrack& rc = report.cracks[i];
    const crack::FoundCrack& c = rc.crack;
    if (method.method == config::StressIntensityMethod::compact_tension &&
        c.origin == crack::CrackOrigin::notch) {
      // 000 Eq. (A2) at P_max for a notch crack: crack length from the load line along the notch,
      // K_II = 0. ASTM E647 gives the formula for 0.2 <= a/W < 1; outside it: out of range.
      const mesh::Point d =
          model.config().geometry.notches[static_cast<std::size_t>(c.notch)].direction();
      const double nx = d.x, ny = d.y;
      const mesh::Point tip = c.tips[0].position;
      const double q = (tip.x - method.load_line.x) * nx + (tip.y - method.load_line.y) * ny;
      const double ratio = q / method.width;
      if (ratio >= 0.2 && ratio < 1.0) {
        rc.k[0] = {crack::compact_tension_delta_k(
                       last_block->p_max, model.config().geometry.thickness, method.width, q),
                   0.0, KStatus::ok};
      } else {
        rc.k[0].status = KStatus::out_of_range;
      }
      continue;
    }
    // Behind a notch crack's tip its faces are the grown crack and the notch.
    double faces = c.length;
    if (c.origin == crack::CrackOrigin::notch) {
      const auto& n = model.config().geometry.notches[static_cast<std::size_t>(c.notch)];
      faces += path_length(n.path);
    }
    for (std::size_t t = 0; t < c.tips.size(); ++t) {
      TipStressIntensity& k = rc.k[t];
      k.status = extrapolation_status(model, intact, c.tips[t], faces);
      if (k.status != KStatus::ok) continue;
      if (u.empty()) engine.solver().displacement(last_block->p_max, last_block->alpha, u);
      const auto sif = crack::stress_intensity_by_extrapolation(
          model.disc(), u, c.tips[t].position, c.tips[t].direction, delta, 2 * delta, mu, kappa);
      k.k_i = sif.k_i;
      k.k_ii = sif.k_ii;
    }
  }
  report.k_i = report.cracks[0].k[0].k_i;
  report.k_ii = report.cracks[0].k[0].k_ii;
  return report;
}

double criterion_crack_length(const DetailModel& model, const std::vector<double>& node_damage,
                              const std::vector<std::uint8_t>& intact) {
  const std::string& origin = model.config().life.crack_origin;
  double longest = 0.0;
  for (const auto& c : model.finder().find(node_damage, intact).cracks) {
    if (origin.empty() || origin_name(model, c) == origin) longest = std::max(longest, c.length);
  }
  return longest;
}

double observed_crack_length(const DetailModel& model, const std::vector<double>& node_damage,
                             const std::vector<std::uint8_t>& intact, const std::string& origin) {
  const bool any = origin.empty() || origin == "longest";
  double longest = 0.0;
  for (const auto& c : model.finder().find(node_damage, intact).cracks) {
    if (any || origin_name(model, c) == origin) longest = std::max(longest, c.length);
  }
  return longest;
}

double observed_crack_length(const DetailModel& model, const fatigue::FatigueEngine& engine,
                             const std::string& origin) {
  return observed_crack_length(model, engine.node_damage(), engine.solver().intact(), origin);
}

bool is_crack_origin(const DetailModel& model, const std::string& origin) {
  if (origin == "longest" || origin == "outline" || origin == "interior") return true;
  const mesh::DetailGeometry& g = model.config().geometry;
  for (const auto& n : g.notches) {
    if (n.name == origin) return true;
  }
  for (std::size_t h = 0; h < g.holes.size(); ++h) {
    if (origin == "hole " + std::to_string(h)) return true;
  }
  return false;
}

Failure end_of_life(const DetailModel& model, const fatigue::FatigueEngine& engine) {
  if (engine.failed()) return Failure::singular;
  const config::LifeConfig& life = model.config().life;
  switch (life.criterion) {
    case config::LifeCriterion::crack_length:
      return criterion_crack_length(model, engine.node_damage(), engine.solver().intact()) >=
                     life.critical_crack_length
                 ? Failure::end_criterion
                 : Failure::none;
    case config::LifeCriterion::phase3:
      for (const auto& e : engine.break_events()) {
        if (e.cause == fatigue::BreakCause::overload) return Failure::end_criterion;
      }
      return Failure::none;
    case config::LifeCriterion::connectivity:
      return Failure::none;
  }
  return Failure::none;
}

fatigue::FatigueEngine::StopCheck end_of_life_check(const DetailModel& model) {
  return [&model](const fatigue::FatigueEngine& engine) {
    return end_of_life(model, engine) != Failure::none;
  };
}

}  // namespace peritwin::twin
