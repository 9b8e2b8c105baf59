#include "twin/detail_model.h"

#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>

namespace peritwin::twin {

namespace {

class Fnv {
 public:
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      h_ ^= p[i];
      h_ *= 1099511628211ULL;
    }
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    value(v.size());
    if (!v.empty()) bytes(v.data(), v.size() * sizeof(T));
  }
  [[nodiscard]] std::uint64_t get() const { return h_; }

 private:
  std::uint64_t h_ = 1469598103934665603ULL;
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

std::optional<FatigueSettings> solver_settings(const DetailConfig& detail, std::string* error) {
  FatigueSettings s;
  switch (detail.fatigue.law) {
    case FatigueLaw::strain_range:
      s.law = peritwin::FatigueLaw::strain_range;
      break;
    case FatigueLaw::energy:
      s.law = peritwin::FatigueLaw::energy;
      break;
    case FatigueLaw::kinetic:
      s.law = peritwin::FatigueLaw::kinetic;
      break;
    case FatigueLaw::bilinear:
      s.law = peritwin::FatigueLaw::bilinear;
      if (const std::string why = fatigue::validate(detail.fatigue.bilinear); !why.empty()) {
        if (error != nullptr)
          *error = detail.where.file + ": " + detail.where.path + ".fatigue: " + why;
        return std::nullopt;
      }
      break;
  }
  s.strain = detail.fatigue.strain;
  s.kinetic = detail.fatigue.kinetic;
  s.bilinear = detail.fatigue.bilinear;
  s.cycle_increment = detail.fatigue.cycle_increment;
  s.softening_tolerance = detail.fatigue.softening_tolerance;
  s.softening_max_iterations = detail.fatigue.softening_max_iterations;
  s.static_failure = detail.fatigue.static_failure;
  s.phase_switch_damage = detail.fatigue.phase_switch_damage;
  s.compressed_bonds_fatigue = detail.fatigue.compressed_bonds_fatigue;
  s.incremental = true;
  return s;
}

std::shared_ptr<const DetailModel> DetailModel::build(const DetailConfig& config,
                                                      std::string* error) {
  const auto settings = solver_settings(config, error);
  if (!settings) return nullptr;
  use_single_threaded_blas();
  std::shared_ptr<DetailModel> m(new DetailModel());
  m->config_ = config;
  m->settings_ = *settings;
  Specimen& sp = m->specimen_;
  sp.name = config.id;
  sp.geometry = config.geometry;
  sp.material = config.material;
  sp.disc = discretize(config);
  if (sp.disc.num_nodes() == 0) {
    if (error != nullptr) *error = "detail " + config.id + ": the discretization has no nodes";
    return nullptr;
  }
  const ResolvedBoundary boundary = resolve(config, sp.disc);
  if (!boundary.ok()) {
    if (error != nullptr) {
      error->clear();
      for (const auto& e : boundary.errors) *error += e.message() + "\n";
    }
    return nullptr;
  }
  sp.supports = boundary.supports;
  sp.loads = boundary.loads;
  sp.model = build_model(sp.disc, config.material, config.model, config.geometry.rigid_factor);
  CrackTrackerOptions tracker_options;
  tracker_options.phase_switch_damage = config.fatigue.phase_switch_damage;
  m->tracker_ = std::make_unique<CrackTracker>(sp.disc, config.geometry.notches, tracker_options);
  for (auto c : sp.disc.bond_precut) m->precut_bonds_ += c ? 1 : 0;

  Fnv h;
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
  // Hashed only when off, so that checkpoints written before the option existed still resume.
  if (!m->settings_.compressed_bonds_fatigue) h.value(m->settings_.compressed_bonds_fatigue);
  m->signature_ = h.get();
  return m;
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
  const auto& notch = model.config().geometry.notches[static_cast<std::size_t>(main.notch)];
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
