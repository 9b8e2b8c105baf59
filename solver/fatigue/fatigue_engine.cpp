#include "solver/fatigue/fatigue_engine.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace peritwin::fatigue {

namespace {

/// k additions of `increment` to `sum`, bit-identical to the loop: repeated subtraction of the
/// negated value is exactly repeated addition under round-to-nearest (fatigue::advance_life).
double advance_sum(double sum, double increment, std::int64_t k) {
  return -fatigue::advance_life(-sum, increment, k);
}

bool same_rate_key(const core::LoadBlock& a, const core::LoadBlock& b, bool dose_mode) {
  // Dose mode: the rates are per unit load at α; the block's P_max and R are in the dose.
  if (dose_mode) return a.alpha == b.alpha;
  return a.p_max == b.p_max && a.r == b.r && a.alpha == b.alpha;
}

}  // namespace

double critical_stretch(const model::Material& material, double horizon) {
  const double e = material.youngs_modulus;
  const double nu = material.poisson_ratio;
  const double mu = e / (2 * (1 + nu));
  const double kappa = e / (2 * (1 - nu));  // 2D plane-stress bulk modulus
  const double pi = std::numbers::pi;
  const double gc = material.critical_energy_release_rate();
  return std::sqrt(gc / ((6 / pi * mu + 16 / (9 * pi * pi) * (kappa - 2 * mu)) * horizon));
}

double critical_bond_energy(const model::Material& material, double crack_interactions) {
  if (!(crack_interactions > 0.0)) return 0.0;
  return material.critical_energy_release_rate() / crack_interactions;  // 000 Eq. (12)
}

double phase_switch_damage_for_horizon(double horizon_ratio) {
  return std::floor(model::straight_crack_face_damage(horizon_ratio) * 1000.0) / 1000.0;
}

double crack_crossing_interactions(double horizon_over_dx) {
  // Family offsets (p, q) in grid units within δ (the discretization's rule, with its tolerance).
  const double r2 = horizon_over_dx * horizon_over_dx * (1 + 1e-12);
  const int reach = static_cast<int>(std::floor(horizon_over_dx)) + 1;
  double crossings = 0.0;
  for (int q = 1; q <= reach; ++q) {
    for (int p = -reach; p <= reach; ++p) {
      if (p * p + q * q <= r2) crossings += q;  // q rows apart: q crossings per Δx of the cut
    }
  }
  return 2.0 * crossings;  // 000 Eq. (10a): ḡ is half the bond's energy per Δx·h
}

FatigueEngine::FatigueEngine(const mesh::Discretization& disc, const model::PdModel& model,
                             std::vector<statics::Support> supports,
                             std::vector<statics::LoadTerm> loads, FatigueSettings settings,
                             std::vector<statics::Tie> ties,
                             std::vector<statics::PrescribedDisplacement> prescribed)
    : disc_(disc),
      model_(model),
      supports_(std::move(supports)),
      loads_(std::move(loads)),
      ties_(std::move(ties)),
      prescribed_(std::move(prescribed)),
      solver_(std::make_unique<statics::StaticSolver>(disc, model, supports_, loads_, ties_,
                                                      prescribed_)),
      settings_(settings) {
  const auto nb = static_cast<std::size_t>(disc.num_bonds());
  if (settings_.law == FatigueLaw::bilinear) {
    if (model.options.kind != model::ModelKind::bond_based) {
      throw std::invalid_argument(
          "FatigueEngine: the bilinear law (003) needs a bond-based model (its damage scales a "
          "bond's pair stiffness, 003 Eq. 45)");
    }
    if (const core::Status valid = fatigue::validate(settings_.bilinear); !valid) {
      throw std::invalid_argument("FatigueEngine: bilinear law: " + valid.error().reason);
    }
    if (settings_.cycle_increment < 1) {
      throw std::invalid_argument("FatigueEngine: cycle_increment must be >= 1");
    }
    if (!(settings_.softening_tolerance > 0.0) || settings_.softening_max_iterations < 1) {
      throw std::invalid_argument(
          "FatigueEngine: softening_tolerance must be > 0 and softening_max_iterations >= 1");
    }
    if (!(settings_.bilinear_solve_tolerance > 0.0) || settings_.bilinear_reference_step < 1 ||
        settings_.bilinear_reference_step > 64) {
      throw std::invalid_argument(
          "FatigueEngine: bilinear_solve_tolerance must be > 0 and bilinear_reference_step in "
          "[1, 64]");
    }
    settings_.incremental = false;  // see the file comment
    state_.damage.assign(nb, 0.0);
    state_.max_stretch.assign(nb, 0.0);
    solver_->set_preconditioned(!settings_.bilinear_refactor_every_iteration,
                                settings_.bilinear_solve_tolerance,
                                settings_.bilinear_reference_step);
  }
  if (settings_.compression != CompressionRule::full_range &&
      settings_.law != FatigueLaw::strain_range && settings_.law != FatigueLaw::energy) {
    throw std::invalid_argument(
        "FatigueEngine: compression \"contact\" or \"closure\" applies to the strain_range and "
        "energy laws (000 Eq. 15); the kinetic law takes R in its own dose (004 Eq. 15), the "
        "bilinear law holds the load at its peak (003 Sec. 4)");
  }
  if (settings_.compression == CompressionRule::contact) {
    if (settings_.law != FatigueLaw::strain_range) {
      throw std::invalid_argument(
          "FatigueEngine: compression \"contact\" needs the strain_range law (each bond's range "
          "from the contact solution at P_min; the energy law's ḡ range has no such form)");
    }
    if (!prescribed_.empty()) {
      throw std::invalid_argument(
          "FatigueEngine: compression \"contact\" is for force-controlled details (its "
          "active-set solve at P = -1 takes loads, not prescribed displacements)");
    }
    contact_ = std::make_unique<statics::CrackFaceContact>(disc, model, supports_, loads_, ties_);
  }
  if (settings_.compression == CompressionRule::closure) {
    if (const core::Status valid = fatigue::validate(settings_.closure); !valid) {
      throw std::invalid_argument("FatigueEngine: closure: " + valid.error().reason);
    }
  }
  solver_->set_incremental(settings_.incremental);
  state_.anchor_life.assign(nb, 1.0);  // 000 Eq. (14): λ = 1 at N = 0
  rate_.assign(nb, 0.0);
  phase_.assign(nb, 1);
  breakable_.assign(nb, 0);
  if (settings_.critical_stretch == 0.0 && model.material.fracture_toughness > 0) {
    critical_stretch_ = critical_stretch(model.material, disc.horizon);
  } else {
    critical_stretch_ = settings_.critical_stretch;
  }
  if (settings_.critical_bond_energy == 0.0 && model.material.fracture_toughness > 0) {
    const double n_c = settings_.crack_interactions > 0.0
                           ? settings_.crack_interactions
                           : crack_crossing_interactions(disc.horizon / disc.dx);
    critical_bond_energy_ = critical_bond_energy(model.material, n_c);
  } else {
    critical_bond_energy_ = settings_.critical_bond_energy;
  }
}

bool FatigueEngine::dose_mode() const {
  // Contact: a bond's range at R < 0 is |s⁺ − |R|·P_max·c_b| with c_b its own contact stretch,
  // not a bond factor times a load dose: the direct mode.
  return settings_.law == FatigueLaw::strain_range && settings_.strain.eps_inf == 0.0 &&
         settings_.strain.eps_inf_prop == 0.0 && settings_.compression != CompressionRule::contact;
}

double FatigueEngine::range_ratio(double load_ratio) const {
  if (settings_.compression == CompressionRule::closure) {
    return fatigue::newman_opening_ratio(load_ratio, settings_.closure);  // ΔK_eff = (1 − f)K_max
  }
  return load_ratio;
}

double FatigueEngine::cycle_dose(const core::LoadBlock& block, double m) const {
  return fatigue::load_dose(block.p_max, range_ratio(block.r), m);
}

bool FatigueEngine::prepare_contact(double alpha) {
  if (contact_valid_ && contact_alpha_ == alpha && contact_events_ == state_.events.size()) {
    return true;
  }
  // The canonical order of the breaks (statics/crack_contact.h): a notch cut first, then each
  // fatigue or overload break by its re-solve group (by its event when the groups do not account
  // for every event): the same numbers on an engine that resumed from this state.
  contact_rank_.assign(state_.anchor_life.size(), -1);
  std::int64_t grouped = 0;
  for (auto g : state_.resolve_groups) grouped += g;
  const bool by_group = grouped == static_cast<std::int64_t>(state_.events.size());
  std::size_t e = 0;
  if (by_group) {
    for (std::size_t g = 0; g < state_.resolve_groups.size(); ++g) {
      for (std::int64_t i = 0; i < state_.resolve_groups[g]; ++i, ++e) {
        contact_rank_[static_cast<std::size_t>(state_.events[e].bond)] =
            static_cast<std::int64_t>(g);
      }
    }
  } else {
    for (; e < state_.events.size(); ++e) {
      contact_rank_[static_cast<std::size_t>(state_.events[e].bond)] = static_cast<std::int64_t>(e);
    }
  }
  if (const core::Status r =
          contact_->compressive_stretch(solver_->intact(), contact_rank_, alpha, contact_stretch_);
      !r.ok()) {
    state_.failed = true;
    state_.failure_reason = "crack-face contact at P_min < 0: " + core::message_of(r);
    contact_valid_ = false;
    return false;
  }
  contact_valid_ = true;
  contact_alpha_ = alpha;
  contact_events_ = state_.events.size();
  return true;
}

bool FatigueEngine::initialize() {
  const core::Status r = solver_->solve();
  ++solves_;
  if (!r.ok()) {
    state_.failed = true;
    state_.failure_reason = core::message_of(r);
    return false;
  }
  const auto& intact = solver_->intact();
  for (std::size_t b = 0; b < breakable_.size(); ++b) {
    const auto i = static_cast<std::size_t>(disc_.bond_i[b]);
    const auto j = static_cast<std::size_t>(disc_.bond_j[b]);
    breakable_[b] = intact[b] && !disc_.no_fail[i] && !disc_.no_fail[j] ? 1 : 0;
  }
  update_phases();
  if (settings_.release_idle_factor) solver_->release_factor();
  return true;
}

std::int64_t FatigueEngine::broken_bonds() const {
  std::int64_t n = 0;
  for (auto v : solver_->intact()) n += v ? 0 : 1;
  return n;
}

double FatigueEngine::life(std::size_t b) const {
  if (bilinear()) return 1.0 - state_.damage[b];
  if (!dose_mode()) return state_.anchor_life[b];
  return state_.anchor_life[b] - rate_[b] * state_.dose[phase_[b] - 1];
}

std::vector<double> FatigueEngine::remaining_life() const {
  std::vector<double> lives(state_.anchor_life.size());
  for (std::size_t b = 0; b < lives.size(); ++b) lives[b] = life(b);
  return lives;
}

void FatigueEngine::materialize() {
  if (!dose_mode()) return;
  if (state_.dose[0] == 0.0 && state_.dose[1] == 0.0) return;
  for (std::size_t b = 0; b < state_.anchor_life.size(); ++b) state_.anchor_life[b] = life(b);
  state_.dose[0] = state_.dose[1] = 0.0;
}

bool FatigueEngine::prepare_rates(const core::LoadBlock& block) {
  if (state_.rates_valid && same_rate_key(state_.rate_key, block, dose_mode())) return true;
  materialize();
  return compute_rates(block);
}

bool FatigueEngine::compute_rates(const core::LoadBlock& block) {
  const bool dose = dose_mode();
  // Contact at P_min < 0: the stretches at P = −1 with the faces touching (homogeneous in P).
  const bool contact_range = contact_ && block.r < 0.0;
  if (contact_range && !prepare_contact(block.alpha)) return false;
  const double ratio = range_ratio(block.r);
  const auto& p = settings_.strain;
  const auto& intact = solver_->intact();
  if (dose) {
    solver_->stretch(1.0, block.alpha, stretch_);  // ŝ: stretch per unit load at α
  } else {
    solver_->stretch(block.p_max, block.alpha, stretch_);  // s⁺ at P_max
  }
  std::vector<double> g;
  if (settings_.law == FatigueLaw::energy) {
    std::vector<double> theta;
    model::dilatations(disc_, model_, intact, stretch_, theta);
    model::bond_energy_release_rates(disc_, model_, stretch_, theta, g);  // ḡ⁺, 000 Eq. (31)
  }
  for (std::size_t b = 0; b < rate_.size(); ++b) {
    if (!intact[b]) {
      rate_[b] = 0.0;
      continue;
    }
    const auto phase = static_cast<fatigue::Phase>(phase_[b]);
    const double s = stretch_[b];
    if (s < 0.0 && !settings_.compressed_bonds_fatigue &&
        (settings_.law == FatigueLaw::strain_range || settings_.law == FatigueLaw::energy)) {
      rate_[b] = 0.0;  // FatigueSettings::compressed_bonds_fatigue
      continue;
    }
    switch (settings_.law) {
      case FatigueLaw::strain_range:
        if (dose) {
          rate_[b] = phase_[b] == 1 ? fatigue::strain_bond_factor(p.A1, p.m1, s)
                                    : fatigue::strain_bond_factor(p.A2, p.m2, s);
        } else if (contact_range) {  // 000 Eq. (15) with s⁻ = |P_min|·c_b, the contact solution
          const double s_min = -block.r * block.p_max * contact_stretch_[b];
          rate_[b] = fatigue::strain_decrement(fatigue::strain_range(s, s_min), phase, p);
        } else {  // 000 Eq. (15), (17)-(19)
          rate_[b] =
              fatigue::strain_decrement(fatigue::strain_range_from_ratio(s, ratio), phase, p);
        }
        break;
      case FatigueLaw::energy: {  // 000 Eq. (30)-(39) with B_i, n_i from Eq. (44)-(46)
        // Eq. (34a) and (35c) take |C0|: a bond whose dilatation term makes ḡ negative (a
        // compressed bond in a dilated region, say) still fatigues, as 000 states ḡ is "always
        // positive". With B_i from the same C1 (Eq. 44b) the decrement is then A_i·ε^m_i for
        // every bond: the energy law equals the strain-range law up to rounding (tested).
        const double c0 = s != 0.0 ? g[b] / (s * s) : 0.0;
        const double range = fatigue::energy_release_rate_range_from_ratio(c0, s, ratio);
        rate_[b] = c0 != 0.0 ? fatigue::energy_decrement(range, phase,
                                                         fatigue::c1_coefficient(c0, ratio), p)
                             : 0.0;
        break;
      }
      case FatigueLaw::bilinear:  // integrated by bilinear_increment, no per-cycle rate
        rate_[b] = 0.0;
        break;
      case FatigueLaw::kinetic: {  // 004 Eq. (12)-(15): remaining life falls by Φ per cycle
        // Decision: the bond stress is E·s⁺, the stress of a bar at the bond's stretch (004 uses
        // the bond's stress; a PD bond carries no other uniaxial stress measure).
        // The bond's σ_max picks its stress segment (004 Fig. 8b), its phase k_U, k_γ (004 step
        // 6), and θ is Eq. (26)'s with the configured loop area; all off by default, and then
        // this is kt_cycle_dose(σ, R, f, U, γ, kT) bit for bit.
        const double sigma = model_.material.youngs_modulus * std::max(s, 0.0);
        rate_[b] = fatigue::kt_bond_dose(settings_.kinetic, settings_.kinetic_extension, sigma,
                                         block.r, phase_[b]);
        break;
      }
    }
  }
  if (dose) {
    dose_threshold_[0] = dose_threshold_[1] = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < rate_.size(); ++b) {
      if (!breakable_[b] || !(rate_[b] > 0.0)) continue;
      double& t = dose_threshold_[phase_[b] - 1];
      t = std::min(t, state_.anchor_life[b] / rate_[b]);
    }
  }
  state_.rates_valid = true;
  state_.rate_key = block;
  // The rates do not depend on the count; kept out of the state so that it is the same however
  // the cycles were cut into blocks (FatigueEngine::StopCheck, Twin::engine_hash).
  state_.rate_key.count = 0;
  return true;
}

std::int64_t FatigueEngine::cycles_to_next_break(const core::LoadBlock& block,
                                                 std::int64_t limit) const {
  const std::int64_t none = limit + 1;
  if (!dose_mode()) {
    // Every bond's cycle to failure lies within cycles_to_failure_bounds; only the bonds whose
    // lower bound is at most the smallest upper bound (and within the block) can fail first, and
    // only those take the exact count (cycles_to_failure, bulk subtraction per binade: the cost
    // that made a contact run 4x slower than the dose mode when it ran for every bond).
    std::int64_t smallest_hi = none;
    candidates_.clear();
    for (std::size_t b = 0; b < rate_.size(); ++b) {
      if (!breakable_[b] || !(rate_[b] > 0.0)) continue;
      const fatigue::CycleBounds bounds =
          fatigue::cycles_to_failure_bounds(state_.anchor_life[b], rate_[b]);
      if (bounds.lo > smallest_hi) continue;
      smallest_hi = std::min(smallest_hi, bounds.hi);
      candidates_.emplace_back(bounds.lo, b);
    }
    std::int64_t best = none;
    for (const auto& [lo, b] : candidates_) {
      if (lo > smallest_hi || lo > best) continue;
      best = std::min(best, fatigue::cycles_to_failure(state_.anchor_life[b], rate_[b]));
    }
    return best;
  }
  const auto& p = settings_.strain;
  const double increment[2] = {cycle_dose(block, p.m1), cycle_dose(block, p.m2)};
  // Exact predicate of the per-cycle path: bond b has failed after k cycles of this block.
  auto failed_after = [&](std::size_t b, std::int64_t k) {
    const int ph = phase_[b] - 1;
    return state_.anchor_life[b] - rate_[b] * advance_sum(state_.dose[ph], increment[ph], k) <= 0.0;
  };
  // O(1) absorption: if neither phase's dose reaches its smallest threshold within the block (with
  // a margin far above round-off), no bond can fail in it.
  bool may_break = false;
  for (int ph = 0; ph < 2; ++ph) {
    if (increment[ph] > 0.0 &&
        advance_sum(state_.dose[ph], increment[ph], limit) >= dose_threshold_[ph] * (1 - 1e-9)) {
      may_break = true;
    }
  }
  if (!may_break) return none;
  // Real-arithmetic estimate for every bond, then the exact cycle for the near-minimal ones.
  std::int64_t best = none;
  std::vector<std::pair<double, std::size_t>> estimates;
  double min_estimate = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < rate_.size(); ++b) {
    if (!breakable_[b] || !(rate_[b] > 0.0)) continue;
    const int ph = phase_[b] - 1;
    if (!(increment[ph] > 0.0)) continue;
    const double k = (state_.anchor_life[b] / rate_[b] - state_.dose[ph]) / increment[ph];
    if (k > static_cast<double>(limit) * (1 + 1e-9) + 4) continue;
    estimates.emplace_back(k, b);
    min_estimate = std::min(min_estimate, k);
  }
  for (const auto& [estimate, b] : estimates) {
    if (estimate > min_estimate * (1 + 1e-9) + 4) continue;
    // Monotone predicate in k: gallop from the estimate, then bisect.
    std::int64_t lo = 0;  // known not failed (or k = 0)
    std::int64_t hi =
        std::clamp<std::int64_t>(static_cast<std::int64_t>(std::ceil(estimate)), 1, none);
    if (failed_after(b, hi)) {
      std::int64_t step = 1;
      while (hi - step > 0 && failed_after(b, hi - step)) {
        hi -= step;
        step *= 2;
      }
      lo = std::max<std::int64_t>(0, hi - step);
    } else {
      std::int64_t step = 1;
      lo = hi;
      while (true) {
        if (lo >= none) break;
        hi = std::min(none, lo + step);
        if (failed_after(b, hi)) break;
        lo = hi;
        step *= 2;
      }
      if (lo >= none) continue;
    }
    while (hi - lo > 1) {
      const std::int64_t mid = lo + (hi - lo) / 2;
      (failed_after(b, mid) ? hi : lo) = mid;
    }
    best = std::min(best, hi);
  }
  return best;
}

void FatigueEngine::advance(const core::LoadBlock& block, std::int64_t k) {
  if (dose_mode()) {
    const auto& p = settings_.strain;
    state_.dose[0] = advance_sum(state_.dose[0], cycle_dose(block, p.m1), k);
    state_.dose[1] = advance_sum(state_.dose[1], cycle_dose(block, p.m2), k);
    return;
  }
  for (std::size_t b = 0; b < rate_.size(); ++b) {
    if (rate_[b] > 0.0)
      state_.anchor_life[b] = fatigue::advance_life(state_.anchor_life[b], rate_[b], k);
  }
}

EngineStatus FatigueEngine::apply(const core::LoadBlock& block, const StopCheck& stop) {
  if (bilinear()) return apply_bilinear(block, stop);
  // Whether the breaks since event `e0` make the caller stop.
  const auto stop_after = [&](std::size_t e0) {
    return stop && state_.events.size() > e0 && stop(*this);
  };
  const std::size_t e0 = state_.events.size();
  if (state_.failed || !static_cascade(block)) return EngineStatus::final_failure;
  if (stop_after(e0)) return EngineStatus::stopped;
  std::int64_t remaining = block.count;
  while (remaining > 0) {
    if (!prepare_rates(block)) return EngineStatus::final_failure;
    const std::int64_t k = cycles_to_next_break(block, remaining);
    if (k > remaining) {
      advance(block, remaining);
      state_.total_cycles += remaining;
      break;
    }
    advance(block, k);
    state_.total_cycles += k;
    remaining -= k;
    const std::size_t e = state_.events.size();
    if (!break_and_resolve(block)) return EngineStatus::final_failure;
    if (stop_after(e)) return EngineStatus::stopped;
  }
  return EngineStatus::ok;
}

void FatigueEngine::set_propagation_limit(double eps_inf_prop) {
  if (!std::isfinite(eps_inf_prop) || eps_inf_prop < 0.0) {
    throw std::invalid_argument("set_propagation_limit: eps_inf_prop must be finite and >= 0");
  }
  materialize();  // fold the dose while the lives are still read in the old mode (dose_mode())
  settings_.strain.eps_inf_prop = eps_inf_prop;
  state_.rates_valid = false;
}

EngineStatus FatigueEngine::apply_per_cycle(const core::LoadBlock& block) {
  if (bilinear()) {
    if (block.count < 0) throw std::invalid_argument("apply_per_cycle: count < 0");
    const std::vector<std::int64_t> ones(static_cast<std::size_t>(block.count), 1);
    return apply_increments(block, ones);
  }
  if (state_.failed || !static_cascade(block)) return EngineStatus::final_failure;
  const auto& p = settings_.strain;
  for (std::int64_t c = 0; c < block.count; ++c) {
    if (!prepare_rates(block)) return EngineStatus::final_failure;
    if (dose_mode()) {
      state_.dose[0] += cycle_dose(block, p.m1);
      state_.dose[1] += cycle_dose(block, p.m2);
    } else {
      for (std::size_t b = 0; b < rate_.size(); ++b) {
        if (rate_[b] > 0.0)
          state_.anchor_life[b] = fatigue::step_life(state_.anchor_life[b], rate_[b]);
      }
    }
    ++state_.total_cycles;
    bool any = false;
    for (std::size_t b = 0; b < rate_.size() && !any; ++b) any = breakable_[b] && life(b) <= 0.0;
    if (any && !break_and_resolve(block)) return EngineStatus::final_failure;
  }
  return EngineStatus::ok;
}

// ------------------------------------------------------------------ bilinear law (003)

namespace {
bool same_bilinear_key(const core::LoadBlock& a, const core::LoadBlock& b) {
  return a.p_max == b.p_max && a.alpha == b.alpha;  // R is not used by 003's envelope
}
}  // namespace

EngineStatus FatigueEngine::apply_bilinear(const core::LoadBlock& block, const StopCheck& stop) {
  if (state_.failed) return EngineStatus::final_failure;
  if (block.count < 1) return EngineStatus::ok;
  // One increment of dn cycles at the pending key, then the caller's stop check if it broke bonds.
  const auto increment = [&](std::int64_t dn) {
    const std::size_t e0 = state_.events.size();
    if (!bilinear_increment(state_.pending_key, dn)) return EngineStatus::final_failure;
    return stop && state_.events.size() > e0 && stop(*this) ? EngineStatus::stopped
                                                            : EngineStatus::ok;
  };
  if (state_.pending_cycles > 0 && !same_bilinear_key(state_.pending_key, block)) {
    const std::int64_t dn = state_.pending_cycles;
    state_.pending_cycles = 0;
    if (const EngineStatus s = increment(dn); s != EngineStatus::ok) return s;
  }
  state_.pending_key = block;
  state_.pending_key.count = 0;
  // The block's cycles join the pending ones increment by increment, so that total_cycles() is the
  // end of the increment when it is integrated (and when a stop leaves the rest unapplied).
  const std::int64_t dn = settings_.cycle_increment;
  std::int64_t left = block.count;
  while (state_.pending_cycles + left >= dn) {
    const std::int64_t take = std::max<std::int64_t>(0, dn - state_.pending_cycles);
    left -= take;
    state_.total_cycles += take;
    state_.pending_cycles += take - dn;
    if (const EngineStatus s = increment(dn); s != EngineStatus::ok) return s;
  }
  state_.total_cycles += left;
  state_.pending_cycles += left;
  return EngineStatus::ok;
}

EngineStatus FatigueEngine::flush() {
  if (!bilinear() || state_.pending_cycles == 0) {
    return state_.failed ? EngineStatus::final_failure : EngineStatus::ok;
  }
  if (state_.failed) return EngineStatus::final_failure;
  const std::int64_t dn = state_.pending_cycles;
  state_.pending_cycles = 0;
  return bilinear_increment(state_.pending_key, dn) ? EngineStatus::ok
                                                    : EngineStatus::final_failure;
}

EngineStatus FatigueEngine::apply_increments(const core::LoadBlock& block,
                                             std::span<const std::int64_t> increments) {
  if (!bilinear()) throw std::logic_error("apply_increments: bilinear law only");
  std::int64_t sum = 0;
  for (auto dn : increments) {
    if (dn < 1) throw std::invalid_argument("apply_increments: increments must be >= 1");
    sum += dn;
  }
  if (sum != block.count) {
    throw std::invalid_argument("apply_increments: increments must sum to the block's count");
  }
  if (flush() != EngineStatus::ok) return EngineStatus::final_failure;
  for (auto dn : increments) {
    state_.total_cycles += dn;
    if (!bilinear_increment(block, dn)) return EngineStatus::final_failure;
  }
  return EngineStatus::ok;
}

bool FatigueEngine::bilinear_increment(const core::LoadBlock& key, std::int64_t dn) {
  const auto& p = settings_.bilinear;
  const auto nb = state_.damage.size();
  const auto delta_n = static_cast<double>(dn);
  // Events carry the cycle count at the end of the increment (pending cycles are not integrated).
  const std::int64_t at_cycle = state_.total_cycles - state_.pending_cycles;
  std::vector<double> s_start, s, trial(nb);
  solver_->stretch(key.p_max, key.alpha, s_start);  // s_N: current factors, this load
  s = s_start;
  std::vector<double> iterate = state_.damage;  // D' of the factors now in the solver
  std::vector<mesh::BondIndex> changed_bonds;
  std::vector<double> changed_factors;
  bool converged = false;
  for (int it = 0; it < settings_.softening_max_iterations; ++it) {
    changed_bonds.clear();
    changed_factors.clear();
    double largest_change = 0.0;
    for (std::size_t b = 0; b < nb; ++b) {
      if (!breakable_[b]) continue;
      // 003 Eq. (50) (third law: static increment along the envelope, Eq. 46, + fatigue, Eq. 29),
      // or Eq. (47) / (49) for the first / second law (BilinearParams::law)
      double d = fatigue::bilinear_update_damage(state_.damage[b], state_.max_stretch[b],
                                                 s_start[b], s[b], delta_n, p);
      // 003 Eq. (45): f = 1 − D below sc, 0 at or beyond sc or at D = 1 (broken)
      const double f = fatigue::bilinear_force_factor(s[b], d, p.sc);
      if (f == 0.0) d = 1.0;
      trial[b] = d;
      const double old_f = solver_->bond_factor(static_cast<mesh::BondIndex>(b));
      if (f != old_f) {
        changed_bonds.push_back(static_cast<mesh::BondIndex>(b));
        changed_factors.push_back(f);
        largest_change = std::max(largest_change, std::abs(f - old_f));
      }
    }
    // Converged: the factors in the solver reproduce themselves within the tolerance (checked only
    // after the increment's damage was applied once, so that small increments are never lost).
    // A bond that would break is never left out. Bonds whose factor did not change take the new
    // damage in any case (their factor 1 − D is what the solver has), the others keep the damage
    // of the factors in the solver.
    bool breaks = false;
    for (double f : changed_factors) breaks = breaks || f == 0.0;
    if (changed_bonds.empty() ||
        (it > 0 && !breaks && largest_change <= settings_.softening_tolerance)) {
      for (std::size_t b = 0; b < nb; ++b) {
        if (breakable_[b] && fatigue::bilinear_force_factor(s[b], trial[b], p.sc) ==
                                 solver_->bond_factor(static_cast<mesh::BondIndex>(b))) {
          iterate[b] = trial[b];
        }
      }
      converged = true;
      break;
    }
    for (std::size_t b = 0; b < nb; ++b) {
      if (breakable_[b]) iterate[b] = trial[b];
    }
    for (std::size_t n = 0; n < changed_bonds.size(); ++n) {
      const auto b = static_cast<std::size_t>(changed_bonds[n]);
      if (changed_factors[n] == 0.0) {
        breakable_[b] = 0;  // broken for good: the solver refuses to revive it
        state_.events.push_back({at_cycle, changed_bonds[n],
                                 s[b] >= p.sc ? BreakCause::overload : BreakCause::fatigue});
      }
    }
    const core::Status r = solver_->set_bond_factors(changed_bonds, changed_factors);
    ++solves_;
    if (!r.ok()) {
      state_.failed = true;
      state_.failure_reason =
          "final failure at cycle " + std::to_string(at_cycle) + ": " + core::message_of(r);
      state_.damage = iterate;
      update_phases();
      return false;
    }
    solver_->stretch(key.p_max, key.alpha, s);
  }
  ++increments_;
  if (!converged) ++unconverged_increments_;

  state_.damage = iterate;
  for (std::size_t b = 0; b < nb; ++b) {
    if (solver_->intact()[b]) state_.max_stretch[b] = std::max(state_.max_stretch[b], s[b]);
  }
  update_phases();
  return true;
}

bool FatigueEngine::break_and_resolve(const core::LoadBlock& block) {
  materialize();
  std::vector<mesh::BondIndex> newly;
  for (std::size_t b = 0; b < state_.anchor_life.size(); ++b) {
    if (breakable_[b] && state_.anchor_life[b] <= 0.0) {  // 000 Eq. (20)
      newly.push_back(static_cast<mesh::BondIndex>(b));
      state_.events.push_back(
          {state_.total_cycles, static_cast<mesh::BondIndex>(b), BreakCause::fatigue});
    }
  }
  if (!newly.empty() && !resolve(newly)) return false;
  return static_cascade(block);
}

bool FatigueEngine::static_cascade(const core::LoadBlock& block) {
  const bool energy = settings_.static_failure == StaticFailure::critical_bond_energy;
  const double limit = energy ? critical_bond_energy_ : critical_stretch_;
  if (!(limit > 0.0)) return true;
  // Stretch is P times a per-α basis combination and rounding is monotone, so if no bond reached
  // s_c at (P_c, α) since the last re-solve, none reaches it at (P ≤ P_c, α): skip the O(bonds)
  // scan. The bond energy is evaluated as fl(P²)·ḡ(P = 1), which is monotone in P as well.
  if (cascade_checked_ && block.alpha == cascade_alpha_ && block.p_max <= cascade_p_max_) {
    return true;
  }
  std::vector<double> s;
  std::vector<double> theta;
  std::vector<double> g;
  const double p2 = block.p_max * block.p_max;
  while (true) {
    if (energy) {
      // 000 Eq. (31): ḡ is a quadratic form in (s, θ), and s, θ are linear in P, so ḡ(P) =
      // P²·ḡ(1) exactly in real arithmetic; ḡ(1) from the unit-load stretches and dilatations.
      solver_->stretch(1.0, block.alpha, s);
      model::dilatations(disc_, model_, solver_->intact(), s, theta);
      model::bond_energy_release_rates(disc_, model_, s, theta, g);
    } else {
      solver_->stretch(block.p_max, block.alpha, s);
    }
    std::vector<mesh::BondIndex> newly;
    for (std::size_t b = 0; b < s.size(); ++b) {
      if (!breakable_[b]) continue;
      // 000 Eq. (9) (ḡ ≥ g_c) or Eq. (7) (s ≥ s_c), then Eq. (20)
      const bool breaks = energy ? p2 * g[b] >= limit : s[b] >= limit;
      if (breaks) {
        newly.push_back(static_cast<mesh::BondIndex>(b));
        state_.events.push_back(
            {state_.total_cycles, static_cast<mesh::BondIndex>(b), BreakCause::overload});
      }
    }
    if (newly.empty()) {
      cascade_checked_ = true;
      cascade_alpha_ = block.alpha;
      cascade_p_max_ = block.p_max;
      return true;
    }
    materialize();
    if (!resolve(newly)) return false;
  }
}

bool FatigueEngine::rebuild_due(std::size_t resolves) const {
  const auto every = settings_.refactor_every_resolves;
  return settings_.incremental && every > 0 && resolves > 0 &&
         static_cast<std::int64_t>(resolves) % every == 0;
}

double FatigueEngine::update_seconds() const {
  return retired_.update_s + solver_->update_seconds();
}
int FatigueEngine::updates() const { return retired_.updates + solver_->updates(); }
double FatigueEngine::basis_solve_seconds() const {
  return retired_.basis_solve_s + solver_->basis_solve_seconds();
}
double FatigueEngine::sweep_seconds() const { return retired_.sweep_s + solver_->sweep_seconds(); }
double FatigueEngine::update_flops() const {
  return retired_.update_flops + solver_->update_flops();
}
int FatigueEngine::refactorized_groups() const {
  return retired_.refactorized_groups + solver_->refactorized_groups();
}
int FatigueEngine::factorizations() const {
  return retired_.factorizations + solver_->factorizations();
}

core::Status FatigueEngine::rebuild_solver(std::vector<std::uint8_t> intact) {
  const auto t0 = std::chrono::steady_clock::now();
  retired_.update_s += solver_->update_seconds();
  retired_.updates += solver_->updates();
  retired_.basis_solve_s += solver_->basis_solve_seconds();
  retired_.sweep_s += solver_->sweep_seconds();
  retired_.update_flops += solver_->update_flops();
  retired_.refactorized_groups += solver_->refactorized_groups();
  retired_.factorizations += solver_->factorizations();
  // The old solver (its updated simplicial factor, the largest block of memory) goes before the
  // new one factorizes: the two never coexist (the rebuild's memory peak, issue 18 item 5).
  solver_ =
      std::make_unique<statics::StaticSolver>(disc_, model_, supports_, loads_, ties_, prescribed_);
  statics::StaticSolver& fresh = *solver_;
  core::Status r = fresh.solve();
  std::vector<mesh::BondIndex> broken;
  for (std::size_t b = 0; b < intact.size(); ++b) {
    if (!intact[b] && fresh.intact()[b]) broken.push_back(static_cast<mesh::BondIndex>(b));
  }
  if (r.ok() && !broken.empty()) {
    fresh.set_incremental(false);
    r = fresh.break_bonds(broken);
  }
  fresh.set_incremental(settings_.incremental);
  if (r.ok() && settings_.release_idle_factor) fresh.release_factor();
  ++rebuilds_;
  rebuild_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

bool FatigueEngine::resolve(const std::vector<mesh::BondIndex>& newly_broken) {
  for (mesh::BondIndex b : newly_broken) {
    breakable_[static_cast<std::size_t>(b)] = 0;
    rate_[static_cast<std::size_t>(b)] = 0.0;
  }
  cascade_checked_ = false;
  core::Status r = solver_->break_bonds(newly_broken);
  ++solves_;
  state_.resolve_groups.push_back(static_cast<std::int64_t>(newly_broken.size()));
  if (r.ok() && rebuild_due(state_.resolve_groups.size())) r = rebuild_solver(solver_->intact());
  state_.rates_valid = false;
  if (!r.ok()) {
    state_.failed = true;
    state_.failure_reason = "final failure at cycle " + std::to_string(state_.total_cycles) + ": " +
                            core::message_of(r);
    return false;
  }
  update_phases_after(newly_broken);
  return true;
}

void FatigueEngine::update_phases_after(const std::vector<mesh::BondIndex>& newly_broken) {
  // update_phases() redone only where it can change (issue 37: it was an O(bonds) pass per
  // re-solve). Breaking bonds changes the damage (000 Eq. 13) of their end nodes only, and a
  // damage never falls (a broken bond stays broken), so a node at or above φ0 stays there and
  // the bonds it put in phase II stay in it. Only a node whose damage just changed can newly
  // reach φ0; it puts every bond of its own and its family members' families in phase II, as
  // update_phases() does. The same phases and damages (tested against update_phases()).
  const auto& intact = solver_->intact();
  auto grow = [&](std::size_t n) {  // node n in phase II: its bonds follow
    for (auto f = disc_.family_offset[n]; f < disc_.family_offset[n + 1]; ++f) {
      phase_[static_cast<std::size_t>(disc_.family_bonds[static_cast<std::size_t>(f)])] = 2;
    }
  };
  for (const mesh::BondIndex b : newly_broken) {
    for (const mesh::NodeIndex node :
         {disc_.bond_i[static_cast<std::size_t>(b)], disc_.bond_j[static_cast<std::size_t>(b)]}) {
      const auto k = static_cast<std::size_t>(node);
      node_damage_[k] = model::node_damage_index(disc_, intact, k);
      if (node_damage_[k] < settings_.phase_switch_damage) continue;
      grow(k);
      for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
        const auto c = disc_.family_bonds[static_cast<std::size_t>(f)];
        grow(static_cast<std::size_t>(disc_.other_end(c, node)));
      }
    }
  }
}

void FatigueEngine::update_phases() {
  model::damage_index(disc_, solver_->intact(), node_damage_);
  const auto nn = static_cast<std::size_t>(disc_.num_nodes());
  // 000 Sec. 4.4: node k is in phase II once k or any family member has φ ≥ φ0.
  std::vector<std::uint8_t> node_growth(nn, 0);
  for (std::size_t k = 0; k < nn; ++k) {
    if (node_damage_[k] < settings_.phase_switch_damage) continue;
    node_growth[k] = 1;
    for (auto f = disc_.family_offset[k]; f < disc_.family_offset[k + 1]; ++f) {
      const auto b = disc_.family_bonds[static_cast<std::size_t>(f)];
      node_growth[static_cast<std::size_t>(disc_.other_end(b, static_cast<mesh::NodeIndex>(k)))] =
          1;
    }
  }
  // Decision: a bond follows phase II when either of its nodes does (the paper states the rule
  // per material point; a bond belongs to two).
  for (std::size_t b = 0; b < phase_.size(); ++b) {
    phase_[b] = node_growth[static_cast<std::size_t>(disc_.bond_i[b])] ||
                        node_growth[static_cast<std::size_t>(disc_.bond_j[b])]
                    ? 2
                    : 1;
  }
}

FatigueEngine::FatigueEngine(const FatigueEngine& other, const FatigueSettings& settings)
    : disc_(other.disc_),
      model_(other.model_),
      supports_(other.supports_),
      loads_(other.loads_),
      ties_(other.ties_),
      prescribed_(other.prescribed_),
      solver_(std::make_unique<statics::StaticSolver>(*other.solver_)),
      retired_(other.retired_),
      rebuilds_(other.rebuilds_),
      rebuild_s_(other.rebuild_s_),
      settings_(settings),
      critical_stretch_(other.critical_stretch_),
      critical_bond_energy_(other.critical_bond_energy_),
      state_(other.state_),
      rate_(other.rate_),
      phase_(other.phase_),
      breakable_(other.breakable_),
      node_damage_(other.node_damage_),
      stretch_(other.stretch_),
      solves_(other.solves_),
      // A fresh contact solver (its virgin factor again on first use): its answer is a function
      // of the broken set and α alone (statics/crack_contact.h), so the copy continues alike.
      contact_(other.contact_
                   ? std::make_unique<statics::CrackFaceContact>(
                         other.disc_, other.model_, other.supports_, other.loads_, other.ties_)
                   : nullptr),
      increments_(other.increments_),
      unconverged_increments_(other.unconverged_increments_) {
  dose_threshold_[0] = other.dose_threshold_[0];
  dose_threshold_[1] = other.dose_threshold_[1];
}

std::unique_ptr<FatigueEngine> FatigueEngine::fork(const FatigueSettings& settings) const {
  if (bilinear() || settings.law == FatigueLaw::bilinear) {
    throw std::logic_error("FatigueEngine::fork: not for the bilinear law (see fork())");
  }
  if (settings.law != settings_.law || settings.incremental != settings_.incremental ||
      settings.refactor_every_resolves != settings_.refactor_every_resolves ||
      settings.phase_switch_damage != settings_.phase_switch_damage ||
      settings.critical_stretch != settings_.critical_stretch ||
      settings.critical_bond_energy != settings_.critical_bond_energy ||
      settings.static_failure != settings_.static_failure ||
      settings.crack_interactions != settings_.crack_interactions ||
      settings.compression != settings_.compression) {
    throw std::invalid_argument(
        "FatigueEngine::fork: only the fatigue laws' coefficients may differ");
  }
  auto copy = std::unique_ptr<FatigueEngine>(new FatigueEngine(*this, settings));
  // What import_state leaves on a fresh engine, done here on the copy: the phase III scan is
  // redone at the next block, rates without a key are zero (a fresh engine's), and rates with a
  // key are recomputed from the copied stretches' solver for the new coefficients, unfolded.
  copy->cascade_checked_ = false;
  if (copy->state_.rates_valid && !copy->state_.failed) {
    copy->compute_rates(copy->state_.rate_key);
  } else {
    std::fill(copy->rate_.begin(), copy->rate_.end(), 0.0);
    copy->state_.rates_valid = false;
  }
  return copy;
}

EngineState FatigueEngine::export_state() const {
  EngineState s = state_;
  s.intact = solver_->intact();
  // Bilinear law: the key of no pending cycles is never used; exported as {} so that states that
  // differ only there export (and hash) equal.
  if (s.pending_cycles == 0) s.pending_key = core::LoadBlock{};
  return s;
}

void FatigueEngine::restore_history(const EngineState& s) {
  state_.anchor_life = s.anchor_life;
  state_.total_cycles = s.total_cycles;
  state_.events = s.events;
  state_.resolve_groups = s.resolve_groups;
  state_.failed = s.failed;
  state_.failure_reason = s.failure_reason;
}

bool FatigueEngine::import_state(const EngineState& s) {
  if (s.anchor_life.size() != state_.anchor_life.size() ||
      s.intact.size() != state_.anchor_life.size()) {
    return false;
  }
  if (bilinear()) return import_bilinear_state(s);
  cascade_checked_ = false;
  contact_valid_ = false;
  // The re-solves to replay: on a fresh engine, the recorded groups of events when they account
  // for every event (same updates, same factor bit for bit), else one group of every bond broken
  // since now.
  std::vector<std::vector<mesh::BondIndex>> groups;
  std::int64_t grouped = 0;
  for (auto g : s.resolve_groups) grouped += g;
  if (state_.events.empty() && !s.resolve_groups.empty() &&
      grouped == static_cast<std::int64_t>(s.events.size())) {
    std::size_t e = 0;
    for (auto g : s.resolve_groups) {
      auto& group = groups.emplace_back();
      for (std::int64_t i = 0; i < g; ++i, ++e) group.push_back(s.events[e].bond);
    }
  } else {
    auto& group = groups.emplace_back();
    for (std::size_t b = 0; b < s.intact.size(); ++b) {
      if (!s.intact[b] && solver_->intact()[b]) group.push_back(static_cast<mesh::BondIndex>(b));
    }
  }
  restore_history(s);
  // With periodic rebuilds (resolve()), the factor after the last rebuild depends only on the
  // bonds broken by then: break those in one refactorization, rebuild exactly as resolve() did,
  // and replay only the groups after it.
  std::size_t first = 0;
  if (groups.size() == s.resolve_groups.size() && settings_.incremental) {
    for (std::size_t k = groups.size(); k > 0; --k) {
      if (rebuild_due(k)) {
        first = k;
        break;
      }
    }
  }
  for (std::size_t k = 0; k < groups.size(); ++k) {
    for (mesh::BondIndex b : groups[k]) {
      breakable_[static_cast<std::size_t>(b)] = 0;
      rate_[static_cast<std::size_t>(b)] = 0.0;
    }
  }
  if (first > 0 && !state_.failed) {
    std::vector<std::uint8_t> intact = solver_->intact();
    for (std::size_t k = 0; k < first; ++k) {
      for (mesh::BondIndex b : groups[k]) intact[static_cast<std::size_t>(b)] = 0;
    }
    const core::Status r = rebuild_solver(intact);
    ++solves_;
    if (!r.ok()) return false;
  }
  for (std::size_t k = first; k < groups.size(); ++k) {
    if (!groups[k].empty() && !state_.failed) {
      const core::Status r = solver_->break_bonds(groups[k]);
      ++solves_;
      if (!r.ok()) return false;
    }
  }
  if (solver_->intact() != s.intact && !state_.failed) return false;
  update_phases();
  state_.dose[0] = s.dose[0];
  state_.dose[1] = s.dose[1];
  state_.rates_valid = false;
  if (s.rates_valid && !state_.failed) {
    compute_rates(s.rate_key);
  } else {
    // Rates not valid (a failed engine, or invalidated by the last breaks): the key of the last
    // rates is still part of the state and its hash (it was at end of life: a restart after end
    // of life hashed differently, issue 30).
    state_.rate_key = s.rate_key;
  }
  return true;
}

bool FatigueEngine::import_bilinear_state(const EngineState& s) {
  const auto nb = state_.damage.size();
  if (s.damage.size() != nb || s.max_stretch.size() != nb || s.pending_cycles < 0 ||
      !state_.events.empty()) {
    return false;
  }
  // The factor of every bond, as bilinear_increment set it: a refactorization depends only on
  // them (and the broken set), so one call rebuilds the solver state bit for bit.
  std::vector<mesh::BondIndex> bonds;
  std::vector<double> factors;
  for (std::size_t b = 0; b < nb; ++b) {
    const double f = s.intact[b] ? 1.0 - s.damage[b] : 0.0;
    if (s.intact[b] && !(s.damage[b] < 1.0)) return false;
    if (f != solver_->bond_factor(static_cast<mesh::BondIndex>(b))) {
      bonds.push_back(static_cast<mesh::BondIndex>(b));
      factors.push_back(f);
    }
  }
  if (!bonds.empty() && !s.failed) {
    const core::Status r = solver_->set_bond_factors(bonds, factors);
    ++solves_;
    if (!r.ok()) return false;
  }
  for (std::size_t b = 0; b < nb; ++b) breakable_[b] = breakable_[b] && s.intact[b] ? 1 : 0;
  restore_history(s);
  state_.damage = s.damage;
  state_.max_stretch = s.max_stretch;
  state_.pending_cycles = s.pending_cycles;
  state_.pending_key = s.pending_key;
  update_phases();
  return true;
}

namespace {

/// for_each_field over the engine's own state, with export_state()'s two differences read in
/// place: the intact flags are the solver's, and a pending key with no pending cycles is {}.
template <class Hash>
void hash_engine_state(Hash& h, const EngineState& state, const std::vector<std::uint8_t>& intact) {
  for_each_field(state, [&](std::string_view key, const auto& field) {
    if (key == "intact") {
      hash_field(h, intact);
    } else if (key == "pending_key" && state.pending_cycles == 0) {
      hash_field(h, core::LoadBlock{});
    } else {
      hash_field(h, field);
    }
  });
}

}  // namespace

void FatigueEngine::hash_state(core::Fnv1a64& h) const {
  hash_engine_state(h, state_, solver_->intact());
}
void FatigueEngine::hash_state(core::Fnv1a64Pair& h) const {
  hash_engine_state(h, state_, solver_->intact());
}

std::uint64_t FatigueEngine::state_hash() const {
  core::Fnv1a64 h;
  hash_state(h);
  return h.get();
}

}  // namespace peritwin::fatigue
