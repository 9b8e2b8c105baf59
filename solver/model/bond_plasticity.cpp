// The Masing bond of 004 (issue 35): the skeleton curve and the memory rules; contracts and the
// equations in bond_plasticity.h.
#include "solver/model/bond_plasticity.h"

#include <cassert>
#include <cmath>
#include <string>

namespace peritwin::model {

namespace {

/// E·ε − (a·ε^b + σ∞): positive where the elastic line lies above the power law.
double join_gap(const PowerLawCurve& c, double strain) {
  return c.youngs_modulus * strain - (c.a * std::pow(strain, c.b) + c.sigma_inf);
}

// ---- one Masing branch from the reversal (ε_r, σ_r) (bond_plasticity.h)
double branch_stress(const MasingSkeleton& sk, double er, double sr, double strain) {
  return sr + 2.0 * sk.stress(0.5 * (strain - er));
}
double branch_tangent(const MasingSkeleton& sk, double er, double strain) {
  return sk.tangent(0.5 * (strain - er));
}
/// ∫σ dε from `from` to `to` along the branch, both on the same side of ε_r.
double branch_work(const MasingSkeleton& sk, double er, double sr, double from, double to) {
  return sr * (to - from) + 4.0 * (sk.energy(0.5 * (to - er)) - sk.energy(0.5 * (from - er)));
}

/// Removes entry i of the stack (shifting the newer ones down) and zeroes the freed slot.
void erase_reversal(MasingState& s, int i) {
  for (int j = i; j + 1 < s.depth; ++j) {
    s.reversal_strain[j] = s.reversal_strain[j + 1];
    s.reversal_stress[j] = s.reversal_stress[j + 1];
  }
  --s.depth;
  s.reversal_strain[s.depth] = 0.0;
  s.reversal_stress[s.depth] = 0.0;
}

/// Pushes the current point as the newest reversal; a full stack first drops R_2 and R_3.
void push_reversal(MasingState& s) {
  static_assert(kMasingMemory >= 3, "the overflow rule drops R_2 and R_3 and keeps R_1");
  if (s.depth == kMasingMemory) {
    erase_reversal(s, 2);
    erase_reversal(s, 1);
    s.dropped_reversals += 2;
  }
  s.reversal_strain[s.depth] = s.strain;
  s.reversal_stress[s.depth] = s.stress;
  ++s.depth;
}

/// +1, −1, or 0.
int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

/// The direction of the branch the state is on: away from 0 on the skeleton (0 for a virgin
/// state), away from the newest reversal otherwise.
int branch_direction(const MasingState& s) {
  if (s.depth == 0) return sign_of(s.strain);
  const int d = sign_of(s.strain - s.reversal_strain[s.depth - 1]);
  assert(d != 0 && "a committed state never sits on its newest reversal");
  return d;
}

/// The tangent of the state's own branch at its strain.
double current_tangent(const MasingSkeleton& sk, const MasingState& s) {
  if (s.depth == 0) return sk.tangent(s.strain);
  return branch_tangent(sk, s.reversal_strain[s.depth - 1], s.strain);
}

struct Walk {
  MasingState state;
  double tangent = 0.0;
  double work = 0.0;
};

/// Follows the monotone path from s.strain to `trial` through the Masing rules.
Walk walk(const MasingSkeleton& sk, MasingState s, double trial) {
  Walk w;
  if (trial == s.strain) {
    w.tangent = current_tangent(sk, s);
    w.state = s;
    return w;
  }
  const int d = trial > s.strain ? 1 : -1;
  const int current = branch_direction(s);
  if (current != 0 && current != d) push_reversal(s);
  for (;;) {
    if (s.depth == 0) {  // the skeleton, moving away from 0
      w.work += sk.energy(trial) - sk.energy(s.strain);
      s.strain = trial;
      s.stress = sk.stress(trial);
      w.tangent = sk.tangent(trial);
      break;
    }
    const int k = s.depth - 1;  // index of the newest reversal R_k
    const double er = s.reversal_strain[k];
    const double sr = s.reversal_stress[k];
    // Closure point: R_{k−1}, or the mirror of R_1 on the skeleton.
    const double ec = k >= 1 ? s.reversal_strain[k - 1] : -er;
    const double sc = k >= 1 ? s.reversal_stress[k - 1] : -sr;
    const double tol = sk.snap_tolerance() * std::fmax(std::fabs(ec), std::fabs(ec - er));
    const double overshoot = d * (trial - ec);
    if (overshoot < -tol) {  // stays on the branch from R_k
      w.work += branch_work(sk, er, sr, s.strain, trial);
      s.strain = trial;
      s.stress = branch_stress(sk, er, sr, trial);
      w.tangent = branch_tangent(sk, er, trial);
      break;
    }
    // The loop closes: snap to the stored point, pop, continue on the older branch.
    w.work += branch_work(sk, er, sr, s.strain, ec);
    w.tangent = branch_tangent(sk, er, ec);
    s.strain = ec;
    s.stress = sc;
    erase_reversal(s, k);
    if (k >= 1) erase_reversal(s, k - 1);
    if (overshoot <= 0.0) break;  // ended on the stored point (within tol)
  }
  w.state = s;
  return w;
}

}  // namespace

MasingSkeleton::MasingSkeleton(const PowerLawCurve& curve, double snap_tolerance)
    : curve_(curve),
      yield_strain_(curve.yield_strain()),
      yield_energy_(0.5 * curve.youngs_modulus * yield_strain_ * yield_strain_),
      yield_antiderivative_(antiderivative(yield_strain_)),
      snap_tolerance_(snap_tolerance) {}

double MasingSkeleton::antiderivative(double x) const {
  return curve_.a / (curve_.b + 1.0) * std::pow(x, curve_.b + 1.0) + curve_.sigma_inf * x;
}

double MasingSkeleton::stress(double strain) const {
  const double x = std::fabs(strain);
  const double g = x <= yield_strain_ ? curve_.youngs_modulus * x
                                      : curve_.a * std::pow(x, curve_.b) + curve_.sigma_inf;
  return strain < 0.0 ? -g : g;
}

double MasingSkeleton::tangent(double strain) const {
  const double x = std::fabs(strain);
  return x <= yield_strain_ ? curve_.youngs_modulus
                            : curve_.a * curve_.b * std::pow(x, curve_.b - 1.0);
}

double MasingSkeleton::energy(double strain) const {
  const double x = std::fabs(strain);
  if (x <= yield_strain_) return 0.5 * curve_.youngs_modulus * x * x;
  return yield_energy_ + (antiderivative(x) - yield_antiderivative_);
}

double PowerLawCurve::stress(double strain) const { return MasingSkeleton(*this).stress(strain); }

double PowerLawCurve::tangent(double strain) const { return MasingSkeleton(*this).tangent(strain); }

double PowerLawCurve::energy(double strain) const { return MasingSkeleton(*this).energy(strain); }

double PowerLawCurve::yield_strain() const {
  // h(ε) = E·ε − a·ε^b − σ∞ is convex (a·b > 0, b − 1 < 0) and h(σ∞/E) = −a·(σ∞/E)^b > 0, and
  // σ∞/E lies right of h's minimum when the join exists (validate). Newton from there decreases
  // monotonically to the larger root (8 steps for the defaults); stop when a step no longer
  // decreases ε (round-off).
  double strain = sigma_inf / youngs_modulus;
  for (int i = 0; i < 200; ++i) {
    const double power = a * std::pow(strain, b);  // a·ε^b
    const double gap = youngs_modulus * strain - (power + sigma_inf);
    const double slope = youngs_modulus - b * power / strain;
    const double next = strain - gap / slope;
    if (!(next < strain)) break;
    strain = next;
  }
  return strain;
}

core::Status validate(const PowerLawCurve& c) {
  const auto fail = [](const char* field, const std::string& reason) {
    return core::Status{core::Error{field, reason}};
  };
  if (!(std::isfinite(c.youngs_modulus) && c.youngs_modulus > 0.0)) {
    return fail("youngs_modulus", "must be finite and > 0");
  }
  if (!(std::isfinite(c.sigma_inf) && c.sigma_inf > 0.0)) {
    return fail("sigma_inf", "must be finite and > 0");
  }
  if (!(std::isfinite(c.a) && c.a < 0.0)) {
    return fail("a", "must be finite and < 0 (the power law increases; 004: −0.242 MPa)");
  }
  if (!(std::isfinite(c.b) && c.b < 0.0 && c.b != -1.0)) {
    return fail("b", "must be finite, < 0 and ≠ −1 (004: −0.891)");
  }
  // The minimum of h(ε) = E·ε − a·ε^b − σ∞ (h'(ε_m) = 0) must be below 0, else the power law never
  // reaches the elastic line (004-design.md (a) check 2).
  const double strain_min = std::pow(c.youngs_modulus / (c.a * c.b), 1.0 / (c.b - 1.0));
  if (!(join_gap(c, strain_min) < 0.0)) {
    return fail("a", "the power law a·ε^b + σ∞ never meets the elastic line E·ε (no yield point)");
  }
  return {};
}

MasingResponse masing_evaluate(const MasingSkeleton& skeleton, const MasingState& committed,
                               double trial_strain) {
  const Walk w = walk(skeleton, committed, trial_strain);
  return {w.state.stress, w.tangent, w.work};
}

MasingState masing_commit(const MasingSkeleton& skeleton, const MasingState& committed,
                          double trial_strain) {
  return walk(skeleton, committed, trial_strain).state;
}

MasingResponse masing_evaluate(const PowerLawCurve& curve, const MasingState& committed,
                               double trial_strain) {
  return masing_evaluate(MasingSkeleton(curve), committed, trial_strain);
}

MasingState masing_commit(const PowerLawCurve& curve, const MasingState& committed,
                          double trial_strain) {
  return masing_commit(MasingSkeleton(curve), committed, trial_strain);
}

double masing_symmetric_loop_area(const PowerLawCurve& curve, double strain_amplitude) {
  const MasingSkeleton sk(curve);
  const double a = std::fabs(strain_amplitude);
  return 8.0 * sk.energy(a) - 4.0 * a * sk.stress(a);
}

}  // namespace peritwin::model
