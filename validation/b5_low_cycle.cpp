// B5, paper 004's low-cycle fatigue by its own scheme; contracts in b5_low_cycle.h.
#include "validation/b5_low_cycle.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "solver/mesh/discretization.h"
#include "solver/statics/elastoplastic.h"

namespace peritwin::validation {

StrainLoading symmetric_loading(double amplitude) {
  return {"symmetric", {{amplitude, -amplitude, 1}}, 0};
}
// 004 Fig. 6 (lost), from its text: "one ±0.6 % cycle and 200 cycles of ε_a = 0.18 % at mean
// −0.42 %" (POL); the same at +0.42 % with the big cycle "starting with compression" (PUL).
StrainLoading pol_loading() { return {"pol", {{0.006, -0.006, 1}, {-0.0024, -0.006, 200}}, 1}; }
StrainLoading pul_loading() { return {"pul", {{-0.006, 0.006, 1}, {0.0024, 0.006, 200}}, 1}; }

double nureg_6909_ss_life(double strain_amplitude) {
  return std::exp(6.891 - 1.920 * std::log(100.0 * strain_amplitude - 0.112));
}

double curve_strain(const model::PowerLawCurve& curve, double stress) {
  return std::max(stress / curve.youngs_modulus,
                  std::pow((curve.sigma_inf - stress) / -curve.a, 1.0 / curve.b));
}

double loop_area_at_stress(const model::PowerLawCurve& curve, double sigma) {
  return model::masing_symmetric_loop_area(curve, curve_strain(curve, sigma));
}

core::Expected<B5Kinetics> calibrate_b5_kinetics(const model::PowerLawCurve& curve, double psi,
                                                 double k_u, std::vector<B5SegmentFit>* fits) {
  B5Kinetics k;
  k.extension.kU = k_u;
  k.extension.psi = psi;
  const double kt = fatigue::kt_thermal_energy(k.base.temperature);
  k.extension.segment_count = 3;
  for (std::size_t s = 0; s < 3; ++s) {
    const B5Segment& r = kB5Segments[s];
    std::vector<fatigue::SnPoint> points;
    for (double sa = r.from; sa <= r.to + 1.0; sa += 2e6) {
      points.push_back({sa, nureg_6909_ss_life(curve_strain(curve, sa))});
    }
    B5SegmentFit f;
    f.loop_area = loop_area_at_stress(curve, 0.5 * (r.from + r.to));
    f.theta = kt + psi * f.loop_area;
    auto fit = fatigue::kt_calibrate_segment(points, -1.0, k.base, f.theta);
    if (!fit.ok()) {
      return core::failure("B5: segment " + std::to_string(s + 1) + ": " + fit.error().reason);
    }
    f.fit = *fit;
    k.extension.segments[s] = {r.upper, fit->U, fit->gamma};
    if (fits != nullptr) fits->push_back(f);
  }
  k.base.U = k.extension.segments[0].U;
  k.base.gamma = k.extension.segments[0].gamma;
  return k;
}

statics::Specimen make_b5_specimen(const B5Specimen& spec) {
  statics::Specimen p;
  p.name = "b5";
  const double dx = spec.width / spec.points_across;
  const double delta = spec.horizon_ratio * dx;
  p.geometry.thickness = spec.thickness;
  p.geometry.outline = {mesh::Rectangle{0.0, 0.0, spec.width, spec.length}};
  const double zone = 0.5 * spec.length * (1.0 - spec.failure_zone);
  // Bonds touching the ends never break (004: failure "active only in the middle").
  p.geometry.no_fail_zones = {
      mesh::Region::of(mesh::Rectangle{-1.0, -1.0, 1.0, zone}),
      mesh::Region::of(mesh::Rectangle{-1.0, spec.length - zone, 1.0, 1.0})};
  p.disc = mesh::discretize(p.geometry, dx, delta);
  p.material = model::Material{spec.youngs_modulus, 1.0 / 3.0, 0.0};
  p.material.youngs_modulus_std = spec.youngs_modulus_std;
  p.material.youngs_modulus_seed = spec.seed;
  model::ModelOptions o;
  o.kind = model::ModelKind::bond_based;  // 004 is bond-based (its Eq. 3-4)
  p.model = model::build_model(p.disc, p.material, o, p.geometry.rigid_factor);
  const auto bottom = p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1.0, -1.0, 1.0, delta}));
  const auto top =
      p.disc.nodes_in(mesh::Region::of(mesh::Rectangle{-1.0, spec.length - delta, 1.0, 1.0}));
  p.supports.push_back({bottom, true, true});
  p.supports.push_back({top, true, false});
  // P is the nominal strain: the top layer moves by P times the distance between the layers'
  // mid-lines (their inner δ/2 are the grips' reach into the gauge).
  statics::PrescribedDisplacement grip;
  grip.nodes = top;
  grip.component = 1;
  grip.constant = spec.length - delta;
  p.prescribed.push_back(grip);
  p.initial_crack_tip = {0.0, 0.5 * spec.length};
  return p;
}

namespace {

double area_of(const statics::Specimen& strip) {
  const double w = strip.geometry.outline.front().rectangle.x_max -
                   strip.geometry.outline.front().rectangle.x_min;
  return w * strip.geometry.thickness;
}

}  // namespace

double virgin_stress(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                     double kappa, double strain) {
  statics::StaticSolver solver(strip.disc, strip.model, strip.supports, strip.loads, strip.ties,
                               strip.prescribed);
  if (!solver.solve().ok()) return std::numeric_limits<double>::quiet_NaN();
  statics::BondPlasticity law;
  law.curve = curve;
  law.stretch_per_strain = kappa;
  statics::ElastoplasticSolver plastic(solver, law);
  if (!plastic.solve_turning_point(strain, 0.0).ok())
    return std::numeric_limits<double>::quiet_NaN();
  return plastic.reaction(0) / area_of(strip);
}

double calibrate_b5_kappa(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                          double strain) {
  // σ(κ) increases with κ (a bond yields later and its plateau force is κ·σ∞·k_b·ξ/E).
  const double target = curve.stress(strain);
  double lo = 0.2, hi = 2.0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (virgin_stress(strip, curve, mid, strain) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

namespace {

/// One run of 004's scheme (see the file comment of b5_low_cycle.h).
class LowCycleRun {
 public:
  LowCycleRun(const statics::Specimen& strip, const model::PowerLawCurve& curve,
              const StrainLoading& loading, const B5Kinetics& kinetics, const B5Options& options)
      : strip_(strip),
        loading_(loading),
        kin_(kinetics),
        opt_(options),
        solver_(strip.disc, strip.model, strip.supports, strip.loads, strip.ties,
                strip.prescribed) {
    if (!solver_.solve().ok()) throw std::runtime_error("B5: the strip is singular");
    statics::BondPlasticity law;
    law.curve = curve;
    law.stretch_per_strain = options.kappa;
    law.tolerance = options.newton_tolerance;
    plastic_ = std::make_unique<statics::ElastoplasticSolver>(solver_, law);
    const mesh::Discretization& d = strip.disc;
    const auto nb = static_cast<std::size_t>(d.num_bonds());
    const double r0 = fatigue::kt_remaining_life(0.0, kin_.base.lambda, kin_.base.n0);
    life_.assign(nb, r0);
    breakable_.assign(nb, 0);
    for (std::size_t b = 0; b < nb; ++b) {
      const auto i = static_cast<std::size_t>(d.bond_i[b]);
      const auto j = static_cast<std::size_t>(d.bond_j[b]);
      breakable_[b] = solver_.intact()[b] && !d.no_fail[i] && !d.no_fail[j] ? 1 : 0;
    }
    family_.assign(static_cast<std::size_t>(d.num_nodes()), 0);
    broken_at_.assign(family_.size(), 0);
    for (std::size_t k = 0; k < family_.size(); ++k) {
      family_[k] = d.family_offset[k + 1] - d.family_offset[k];
    }
  }

  B5Result run();

 private:
  /// Both turning points of a cycle: each bond's dose into `dose`, the bonds that reached s_c
  /// into `statics`; the reaction at the upper turning point into `upper`. false on a failure.
  bool cycle(const StrainCycle& c, std::vector<double>& dose, std::vector<mesh::BondIndex>& over,
             double& upper);
  /// 004 Eq. (15)/(26): one bond's dose per cycle.
  double bond_dose(std::size_t b, double s1, double s2, double area) const;
  bool phase_two(std::size_t b) const {
    const auto& d = strip_.disc;
    const auto i = static_cast<std::size_t>(d.bond_i[b]);
    const auto j = static_cast<std::size_t>(d.bond_j[b]);
    const auto phi = [&](std::size_t k) {
      return family_[k] > 0 ? static_cast<double>(broken_at_[k]) / family_[k] : 0.0;
    };
    return phi(i) >= kin_.phase_switch || phi(j) >= kin_.phase_switch;
  }
  bool break_bonds(const std::vector<mesh::BondIndex>& bonds);
  /// Adds the breakable intact bonds whose stretch at the committed state reaches s_c (phase
  /// III) and are not listed yet.
  void add_critical(std::vector<mesh::BondIndex>& list) const;
  void trace_loop(std::int64_t at);
  void measure(double upper);

  const statics::Specimen& strip_;
  const StrainLoading& loading_;
  const B5Kinetics& kin_;
  const B5Options& opt_;
  statics::StaticSolver solver_;
  std::unique_ptr<statics::ElastoplasticSolver> plastic_;
  std::vector<double> life_;
  std::vector<std::uint8_t> breakable_;
  std::vector<std::int32_t> family_, broken_at_;
  std::int64_t cycles_ = 0;
  std::size_t next_mark_ = 0;
  double peak_reaction_ = 0.0;
  B5Result result_;
};

double LowCycleRun::bond_dose(std::size_t b, double s1, double s2, double area) const {
  const double sigma_max = std::max(s1, s2);
  if (!(sigma_max > 0.0)) return 0.0;  // 004 Eq. (15) needs σ_max > 0: a compressed bond rests
  const double ratio = std::min(s1, s2) / sigma_max;
  // 004: the S–N segment of σ_max; growth (k_U, k_γ) once φx ≥ 0.5 (step 6).
  const fatigue::KineticActivation a =
      fatigue::kt_activation(kin_.base, kin_.extension, sigma_max, phase_two(b) ? 2 : 1);
  const fatigue::KineticExtension& e = kin_.extension;
  const double theta = fatigue::kt_thermal_energy(kin_.base.temperature, e.psi, area,
                                                  e.loop_area_yield);  // 004 Eq. (26)
  return fatigue::kt_cycle_dose(sigma_max, ratio, kin_.base.frequency, a.U, a.gamma, theta);
}

bool LowCycleRun::cycle(const StrainCycle& c, std::vector<double>& dose,
                        std::vector<mesh::BondIndex>& over, double& upper) {
  const auto nb = life_.size();
  std::vector<double> stress[2], work(nb, 0.0);
  std::vector<std::array<double, 3>> point[2];
  over.clear();
  const double points[2] = {c.first, c.second};
  int up = 0;
  for (int k = 0; k < 2; ++k) {
    auto tp = plastic_->solve_turning_point(points[k], 0.0);
    ++result_.turning_points;
    if (!tp.ok()) {
      result_.reason = tp.error().reason;
      result_.lost_equilibrium = true;
      return false;
    }
    stress[k].resize(nb);
    for (std::size_t b = 0; b < nb; ++b) {
      stress[k][b] = plastic_->bond_stress(b);
      work[b] += plastic_->ramp_work()[b];
    }
    if (opt_.point_stress) point[k] = plastic_->node_stress();
    if (points[k] >= points[1 - k]) {
      upper = plastic_->reaction(0);
      up = k;
    }
    add_critical(over);
  }
  if (opt_.point_stress) {
    // 004 Eq. (14): σ_xx' = (σ_x + σ_x')/2, the stress of the bond's two points. As a scalar:
    // the normal stress on the largest principal direction n of the mean tensor at the upper
    // turning point, and on the same n at the lower one (so R = −1 in a uniaxial symmetric
    // cycle).
    const auto& d = strip_.disc;
    for (std::size_t b = 0; b < nb; ++b) {
      if (!breakable_[b] || !solver_.intact()[b]) continue;
      const auto i = static_cast<std::size_t>(d.bond_i[b]);
      const auto j = static_cast<std::size_t>(d.bond_j[b]);
      std::array<double, 3> mean[2];
      for (int k = 0; k < 2; ++k) {
        for (int q = 0; q < 3; ++q) mean[k][q] = 0.5 * (point[k][i][q] + point[k][j][q]);
      }
      const auto& m = mean[up];
      // ½·atan2(2σxy, σxx − σyy) is the direction of the algebraically largest principal stress.
      const double angle = 0.5 * std::atan2(2.0 * m[2], m[0] - m[1]);
      const double nx = std::cos(angle), ny = std::sin(angle);
      const auto normal = [&](const std::array<double, 3>& s) {
        return nx * nx * s[0] + ny * ny * s[1] + 2.0 * nx * ny * s[2];
      };
      stress[up][b] = normal(mean[up]);
      stress[1 - up][b] = normal(mean[1 - up]);
    }
  }
  std::vector<double> node_area;
  const bool own_area = kin_.extension.psi > 0.0 && kin_.own_loop_area;
  if (own_area) node_area = plastic_->node_loop_area(work);
  dose.assign(nb, 0.0);
  const auto& d = strip_.disc;
  for (std::size_t b = 0; b < nb; ++b) {
    if (!breakable_[b] || !solver_.intact()[b]) continue;
    const double area = own_area ? 0.5 * (node_area[static_cast<std::size_t>(d.bond_i[b])] +
                                          node_area[static_cast<std::size_t>(d.bond_j[b])])
                                 : kin_.extension.loop_area;
    dose[b] = bond_dose(b, stress[0][b], stress[1][b], area);
  }
  return true;
}

void LowCycleRun::add_critical(std::vector<mesh::BondIndex>& list) const {
  std::vector<double> stretch;
  model::bond_stretches(strip_.disc, plastic_->displacement(), stretch);
  for (std::size_t b = 0; b < stretch.size(); ++b) {
    const auto bond = static_cast<mesh::BondIndex>(b);
    if (breakable_[b] && solver_.intact()[b] && stretch[b] >= opt_.critical_stretch &&
        std::find(list.begin(), list.end(), bond) == list.end()) {
      list.push_back(bond);
    }
  }
}

bool LowCycleRun::break_bonds(const std::vector<mesh::BondIndex>& bonds) {
  std::vector<mesh::BondIndex> group = bonds;
  // 004: "statics … repeated for each PD bond failure": the body re-balances at the turning
  // point it is held at, and the bonds that this pulls to s_c break with the group (phase III).
  for (int round = 0; !group.empty(); ++round) {
    for (mesh::BondIndex b : group) {
      const auto bi = static_cast<std::size_t>(b);
      if (phase_two(bi)) ++result_.phase_two_breaks;
    }
    for (mesh::BondIndex b : group) {
      const auto bi = static_cast<std::size_t>(b);
      ++broken_at_[static_cast<std::size_t>(strip_.disc.bond_i[bi])];
      ++broken_at_[static_cast<std::size_t>(strip_.disc.bond_j[bi])];
      breakable_[bi] = 0;
    }
    result_.broken_bonds += static_cast<std::int64_t>(group.size());
    if (round > 0) result_.static_breaks += static_cast<std::int64_t>(group.size());
    if (auto r = plastic_->break_bonds(group); !r.ok()) {
      result_.reason = core::message_of(r);
      return false;
    }
    auto balanced = plastic_->solve_turning_point(plastic_->control(), 0.0);
    ++result_.turning_points;
    if (!balanced.ok()) {
      result_.reason = balanced.error().reason;
      result_.lost_equilibrium = true;
      return false;
    }
    group.clear();
    add_critical(group);
  }
  ++result_.break_groups;
  return true;
}

void LowCycleRun::trace_loop(std::int64_t at) {
  if (!opt_.loop) return;
  statics::StaticSolver copy(solver_);
  statics::ElastoplasticSolver trace(*plastic_, copy);
  const StrainCycle& c = loading_.block[loading_.measured];
  std::vector<double> strain, stress;
  double from = trace.control();
  strain.push_back(from);
  stress.push_back(trace.reaction(0) / area_of(strip_));
  for (const double to : {c.first, c.second}) {
    for (int k = 1; k <= opt_.loop_steps; ++k) {
      const double p = from + (to - from) * k / opt_.loop_steps;
      if (!trace.solve_turning_point(p, 0.0).ok()) return;
      strain.push_back(p);
      stress.push_back(trace.reaction(0) / area_of(strip_));
    }
    from = to;
  }
  opt_.loop(at, strain, stress);
}

void LowCycleRun::measure(double upper) {
  peak_reaction_ = std::max(peak_reaction_, upper);
  result_.final_stress = upper / area_of(strip_);
  if (result_.n25_cycles < 0 && upper <= (1.0 - opt_.stress_drop) * peak_reaction_) {
    result_.n25_cycles = cycles_ + 1;  // the cycle being measured
  }
}

B5Result LowCycleRun::run() {
  const auto t0 = std::chrono::steady_clock::now();
  result_.kappa = opt_.kappa;
  const auto nb = life_.size();
  std::int64_t block_cycles = 0;
  for (const auto& c : loading_.block) block_cycles += c.count;
  std::vector<double> block_dose(nb), previous_block, dose, previous;
  std::vector<mesh::BondIndex> over, failing;
  // Passes the marks in (cycles_, until]: the loop in force now is the loop there.
  const auto pass_marks = [&](std::int64_t until) {
    while (next_mark_ < opt_.loop_cycles.size() && opt_.loop_cycles[next_mark_] <= until) {
      trace_loop(opt_.loop_cycles[next_mark_++]);
    }
  };
  // Applies n cycles of `per_cycle` doses, or fewer if a bond fails first: returns how many.
  const auto apply = [&](const std::vector<double>& per_cycle, std::int64_t n) {
    std::int64_t first_failure = n;
    for (std::size_t b = 0; b < nb; ++b) {
      if (!breakable_[b] || !(per_cycle[b] > 0.0)) continue;
      const double need = std::ceil(life_[b] / per_cycle[b]);
      if (need < static_cast<double>(first_failure)) {
        first_failure = std::max<std::int64_t>(1, static_cast<std::int64_t>(need));
      }
    }
    failing.clear();
    for (std::size_t b = 0; b < nb; ++b) {
      if (!breakable_[b]) continue;
      life_[b] -= static_cast<double>(first_failure) * per_cycle[b];
      block_dose[b] += static_cast<double>(first_failure) * per_cycle[b];
      if (life_[b] <= 0.0) failing.push_back(static_cast<mesh::BondIndex>(b));
    }
    pass_marks(cycles_ + first_failure);
    cycles_ += first_failure;
    return first_failure;
  };
  bool ok = true;
  while (ok && result_.n25_cycles < 0 && cycles_ < opt_.max_cycles) {
    std::fill(block_dose.begin(), block_dose.end(), 0.0);
    bool broke = false;
    for (std::size_t ci = 0; ok && ci < loading_.block.size() && result_.n25_cycles < 0; ++ci) {
      const StrainCycle& c = loading_.block[ci];
      std::int64_t remaining = c.count;
      bool settled = false;
      previous.clear();
      while (ok && remaining > 0 && result_.n25_cycles < 0) {
        std::int64_t n = 1;
        if (!settled) {
          double upper = 0.0;
          ok = cycle(c, dose, over, upper);
          if (!ok) break;
          if (ci == loading_.measured) measure(upper);
          if (result_.n25_cycles >= 0) break;
          // Masing under strain control repeats from the second cycle: once two consecutive
          // cycles give the same doses, the rest of the run of cycles is that one again.
          if (!previous.empty()) {
            double worst = 0.0;
            for (std::size_t b = 0; b < nb; ++b) {
              worst = std::max(
                  worst, std::abs(dose[b] - previous[b]) / std::max(std::abs(previous[b]), 1e-300));
            }
            settled = worst <= 1e-9;
          }
          previous = dose;
          if (!over.empty()) {  // phase III at the turning point: break at once
            result_.static_breaks += static_cast<std::int64_t>(over.size());
            apply(dose, 1);
            for (mesh::BondIndex b : over) {
              if (std::find(failing.begin(), failing.end(), b) == failing.end()) {
                failing.push_back(b);
              }
            }
            --remaining;
            ok = break_bonds(failing);
            broke = true;
            settled = false;
            previous.clear();
            continue;
          }
        } else {
          n = remaining;
        }
        remaining -= apply(dose, n);
        if (!failing.empty()) {
          ok = break_bonds(failing);
          broke = true;
          settled = false;
          previous.clear();
        }
      }
    }
    if (!ok || result_.n25_cycles >= 0) break;
    if (broke) {
      previous_block.clear();
      continue;
    }
    // A block without breaks that repeats the one before: every block is this one until a bond
    // fails; jump whole blocks to the one in which the first does (004's next-break step).
    bool repeats = !previous_block.empty();
    for (std::size_t b = 0; repeats && b < nb; ++b) {
      repeats = std::abs(block_dose[b] - previous_block[b]) <=
                1e-9 * std::max(std::abs(previous_block[b]), 1e-300);
    }
    previous_block = block_dose;
    if (!repeats || !opt_.jump) continue;
    double blocks = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < nb; ++b) {
      if (breakable_[b] && block_dose[b] > 0.0) {
        blocks = std::min(blocks, std::ceil(life_[b] / block_dose[b]) - 1.0);
      }
    }
    if (!std::isfinite(blocks)) {
      result_.reason = "no bond is loaded: the life is infinite";
      break;
    }
    const double room =
        static_cast<double>(opt_.max_cycles - cycles_) / static_cast<double>(block_cycles);
    const auto k = static_cast<std::int64_t>(std::max(0.0, std::min(blocks, std::floor(room))));
    if (k > 0) {
      for (std::size_t b = 0; b < nb; ++b) {
        if (breakable_[b]) life_[b] -= static_cast<double>(k) * block_dose[b];
      }
      pass_marks(cycles_ + k * block_cycles);
      cycles_ += k * block_cycles;
    }
  }
  if (result_.reason.empty()) {
    result_.reason = result_.n25_cycles >= 0 ? "25 % stress drop" : "cycle limit";
  }
  result_.life_cycles = result_.n25_cycles >= 0                                ? result_.n25_cycles
                        : result_.lost_equilibrium && result_.broken_bonds > 0 ? cycles_ + 1
                                                                               : -1;
  result_.cycles = cycles_;
  result_.peak_stress = peak_reaction_ / area_of(strip_);
  result_.newton_iterations = plastic_->newton_iterations();
  result_.stalled_turning_points = plastic_->stalled_points();
  result_.substepped_turning_points = plastic_->substepped_points();
  for (const model::MasingState& s : plastic_->bond_states()) {
    result_.deepest_memory = std::max(result_.deepest_memory, static_cast<int>(s.depth));
    result_.dropped_reversals += s.dropped_reversals;
  }
  result_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result_;
}

}  // namespace

B5Result run_b5_loading(const statics::Specimen& strip, const model::PowerLawCurve& curve,
                        const StrainLoading& loading, const B5Kinetics& kinetics,
                        const B5Options& options) {
  B5Options o = options;
  if (!(o.kappa > 0.0)) o.kappa = calibrate_b5_kappa(strip, curve, 0.0018);
  std::sort(o.loop_cycles.begin(), o.loop_cycles.end());
  LowCycleRun run(strip, curve, loading, kinetics, o);
  return run.run();
}

}  // namespace peritwin::validation
