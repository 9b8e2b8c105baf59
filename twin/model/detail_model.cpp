#include "twin/model/detail_model.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

#include "solver/core/fnv1a.h"

namespace peritwin::twin {

namespace {

/// The model signature's hash: byte-wise FNV-1a 64 over values and vectors (with their sizes).
struct SignatureHash {
  Fnv1a64 h;
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

Expected<FatigueSettings> solver_settings(const DetailConfig& detail) {
  FatigueSettings s = detail.fatigue;
  if (s.law == FatigueLaw::bilinear) {
    if (const Status valid = fatigue::validate(s.bilinear); !valid) {
      return failure(detail.where.file + ": " + detail.where.path +
                     ".fatigue: " + valid.error().reason);
    }
  }
  s.incremental = true;
  return s;
}

Expected<std::shared_ptr<const DetailModel>> DetailModel::build(const DetailConfig& config) {
  const auto settings = solver_settings(config);
  if (!settings) return settings.error();
  use_single_threaded_blas();
  std::shared_ptr<DetailModel> m(new DetailModel());
  m->config_ = config;
  m->settings_ = *settings;
  Specimen& sp = m->specimen_;
  sp.name = config.id;
  sp.geometry = config.geometry;
  sp.material = config.material;
  sp.disc = discretize(config);
  if (sp.disc.num_nodes() == 0)
    return failure("detail " + config.id + ": the discretization has no nodes");
  const ResolvedBoundary boundary = resolve(config, sp.disc);
  if (!boundary.ok()) {
    std::string reasons;
    for (const auto& e : boundary.errors) reasons += e.message() + "\n";
    return failure(reasons);
  }
  sp.supports = boundary.supports;
  sp.loads = boundary.loads;
  sp.model = build_model(sp.disc, config.material, config.model, config.geometry.rigid_factor);
  CrackTrackerOptions tracker_options;
  tracker_options.phase_switch_damage = config.fatigue.phase_switch_damage;
  m->tracker_ = std::make_unique<CrackTracker>(sp.disc, config.geometry.notches, tracker_options);
  for (auto c : sp.disc.bond_precut) m->precut_bonds_ += c ? 1 : 0;

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
  h.value(m->settings_.bilinear);
  h.value(m->settings_.cycle_increment);
  h.value(m->settings_.softening_tolerance);
  h.value(m->settings_.softening_max_iterations);
  h.value(m->settings_.static_failure);
  h.value(m->settings_.critical_bond_energy);
  h.value(m->settings_.crack_interactions);
  h.value(m->settings_.refactor_every_resolves);
  h.value(config.material.fracture_toughness);
  h.value(m->settings_.compressed_bonds_fatigue);
  m->signature_ = h.h.get();
  return std::shared_ptr<const DetailModel>(std::move(m));
}

std::unique_ptr<FatigueEngine> DetailModel::make_engine(double a2_factor) const {
  FatigueSettings s = settings_;
  s.strain.A2 *= a2_factor;
  s.bilinear.A *= a2_factor;  // the bilinear law's growth coefficient (003 Eq. 27) plays A2's role
  return std::make_unique<FatigueEngine>(specimen_.disc, specimen_.model, specimen_.supports,
                                         specimen_.loads, s);
}

CrackReport measure_cracks(const DetailModel& model, const FatigueEngine& engine,
                           const LoadBlock* last_block) {
  CrackReport report;
  const auto& damage = engine.node_damage();
  for (double phi : damage) report.max_damage = std::max(report.max_damage, phi);
  report.cracks = model.tracker().measure(damage);
  std::stable_sort(
      report.cracks.begin(), report.cracks.end(),
      [](const CrackMetrics& a, const CrackMetrics& b) { return a.length > b.length; });
  const double nan = std::numeric_limits<double>::quiet_NaN();
  report.k_i = report.k_ii = nan;
  if (report.cracks.empty() || last_block == nullptr || engine.failed()) return report;
  const CrackMetrics& main = report.cracks.front();
  const Segment notch =
      model.config().geometry.notches[static_cast<std::size_t>(main.notch)].last_segment();
  const double len = std::hypot(notch.b.x - notch.a.x, notch.b.y - notch.a.y);
  if (!(len > 0)) return report;
  // Crack direction: the notch direction turned by the kink angle.
  const double c = std::cos(main.kink_angle), s = std::sin(main.kink_angle);
  const double nx = (notch.b.x - notch.a.x) / len, ny = (notch.b.y - notch.a.y) / len;
  const Point direction{c * nx - s * ny, s * nx + c * ny};
  const StressIntensityConfig& method = model.config().stress_intensity;
  if (method.method == StressIntensityMethod::compact_tension) {
    // 000 Eq. (A2) at P_max: crack length from the load line along the notch, K_II = 0. ASTM
    // E647 gives the formula for 0.2 <= a/W < 1; outside it the value is not reported (NaN).
    const double q =
        (main.tip.x - method.load_line.x) * nx + (main.tip.y - method.load_line.y) * ny;
    const double ratio = q / method.width;
    if (ratio >= 0.2 && ratio < 1.0) {
      report.k_i = compact_tension_delta_k(last_block->p_max, model.config().geometry.thickness,
                                           method.width, q);
      report.k_ii = 0.0;
    }
    return report;
  }
  std::vector<double> u;
  engine.solver().displacement(last_block->p_max, last_block->alpha, u);
  const auto& pd = model.pd();
  const double nu = effective_poisson_ratio(pd.material, pd.options);
  const double mu = pd.material.youngs_modulus / (2 * (1 + nu));
  const double kappa = kolosov_kappa(nu, pd.options.plane);
  const double delta = model.disc().horizon;
  const auto k = stress_intensity_by_extrapolation(model.disc(), u, main.tip, direction, delta,
                                                   2 * delta, mu, kappa);
  report.k_i = k.k_i;
  report.k_ii = k.k_ii;
  return report;
}

double main_crack_length(const DetailModel& model, const std::vector<double>& node_damage) {
  double longest = 0.0;
  for (const auto& c : model.tracker().measure(node_damage)) longest = std::max(longest, c.length);
  return longest;
}

Failure end_of_life(const DetailModel& model, const FatigueEngine& engine,
                    const CrackReport& report) {
  if (engine.failed()) return Failure::singular;
  const LifeConfig& life = model.config().life;
  switch (life.criterion) {
    case LifeCriterion::crack_length:
      return report.main_length() >= life.critical_crack_length ? Failure::end_criterion
                                                                : Failure::none;
    case LifeCriterion::phase3:
      for (const auto& e : engine.break_events()) {
        if (e.cause == BreakCause::overload) return Failure::end_criterion;
      }
      return Failure::none;
    case LifeCriterion::connectivity:
      return Failure::none;
  }
  return Failure::none;
}

}  // namespace peritwin::twin
