// The kinetic law's parts beyond Eq. (15) (004): stress segments, the phase II factors k_U, k_γ,
// Eq. (26)'s thermal energy, the reader's keys, and the calibration of U and γ on an S-N curve,
// down to 004's own case (the NUREG/CR-6909 curve of 316L through the printed tensile curve).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/param_reader.h"
#include "solver/fatigue/fatigue_engine.h"
#include "solver/fatigue/fatigue_settings.h"
#include "solver/fatigue/law_registry.h"
#include "solver/fatigue/laws/kinetic.h"
#include "solver/fatigue/laws/kinetic_calibration.h"
#include "tests/support/map_reader.h"
#include "tests/support/plates.h"

namespace peritwin {
namespace {

constexpr double kElectronVolt = 1.602176634e-19;  // J, exact SI 2019
constexpr double kInf = std::numeric_limits<double>::infinity();

// ------------------------------------------------------------------------------- Eq. (26)

TEST(KineticEq26, EqualsEq15BitForBitWithoutLoopEnergy) {
  // 004 Eq. (26) is Eq. (15) with kT → kT + ψA "if A ≥ A_σy": no loop (A = 0) or a loop below
  // the yield loop leaves Eq. (15)'s kT bit for bit, whatever ψ.
  for (const double t : {293.0, 77.0, 873.15}) {
    const double kt = fatigue::kt_thermal_energy(t);
    EXPECT_EQ(kt, fatigue::kBoltzmann * t);
    EXPECT_EQ(fatigue::kt_thermal_energy(t, 0.0, 0.0, 0.0), kt);
    EXPECT_EQ(fatigue::kt_thermal_energy(t, 1.9e-28, 0.0, 0.0), kt);      // A = 0
    EXPECT_EQ(fatigue::kt_thermal_energy(t, 1.9e-28, 4.0e5, 5.0e5), kt);  // A < A_σy
    EXPECT_EQ(fatigue::kt_thermal_energy(t, 0.0, 4.0e5, 0.0), kt);        // ψ = 0
    // A ≥ A_σy: kT + ψA (ψA = 1.9e-28 m³ · 5e5 J/m³ = 9.5e-23 J, 0.0235 kT at 293 K).
    EXPECT_EQ(fatigue::kt_thermal_energy(t, 1.9e-28, 5.0e5, 5.0e5), kt + 1.9e-28 * 5.0e5);
  }
}

/// 004's three segments, with U, γ in the range of the calibration below (1.5-1.8 eV, 3-6e-28 m³).
struct Law {
  fatigue::KineticParams p;
  fatigue::KineticExtension e;
};
Law three_segments() {
  Law l;
  l.p.U = 1.49 * kElectronVolt;
  l.p.gamma = 3.67e-28;
  l.e.segment_count = 3;
  l.e.segments[0] = {250e6, 1.49 * kElectronVolt, 3.67e-28};
  l.e.segments[1] = {290e6, 1.75 * kElectronVolt, 5.28e-28};
  l.e.segments[2] = {kInf, 2.0 * kElectronVolt, 6.0e-28};
  return l;
}

TEST(KineticSegments, ChosenByTheBondsMaximumStress) {
  // 004: "σ ≤ 250 MPa, 250 MPa < σ ≤ 290 MPa, and σ > 290 MPa".
  const Law l = three_segments();
  const auto& seg = l.e.segments;
  EXPECT_EQ(core::message_of(validate(l.e)), "");
  const auto at = [&](double s, int phase = 1) {
    return fatigue::kt_activation(l.p, l.e, s, phase);
  };
  EXPECT_EQ(at(1e6).U, seg[0].U);
  EXPECT_EQ(at(250e6).U, seg[0].U);
  EXPECT_EQ(at(250e6).gamma, seg[0].gamma);
  EXPECT_EQ(at(std::nextafter(250e6, kInf)).U, seg[1].U);
  EXPECT_EQ(at(290e6).gamma, seg[1].gamma);
  EXPECT_EQ(at(std::nextafter(290e6, kInf)).U, seg[2].U);
  EXPECT_EQ(at(1e9).gamma, seg[2].gamma);
  // No segments: KineticParams' single U, γ at every stress.
  const fatigue::KineticExtension none;
  EXPECT_EQ(fatigue::kt_activation(l.p, none, 1e9, 1).U, l.p.U);
  EXPECT_EQ(fatigue::kt_activation(l.p, none, 1e9, 1).gamma, l.p.gamma);
}

TEST(KineticSegments, PhaseTwoScalesUAndGamma) {
  // 004 step 6: in the growth phase U = k_U·U, γ = k_γ·γ; 004's values k_U = 1.2, k_γ = 1.
  Law l = three_segments();
  const auto& seg = l.e.segments;
  l.e.kU = 1.2;
  l.e.kgamma = 0.9;
  const auto a = fatigue::kt_activation(l.p, l.e, 270e6, 2);
  EXPECT_EQ(a.U, 1.2 * seg[1].U);
  EXPECT_EQ(a.gamma, 0.9 * seg[1].gamma);
  EXPECT_EQ(fatigue::kt_activation(l.p, l.e, 270e6, 1).U, seg[1].U);  // phase I untouched
  // The bond dose is kt_cycle_dose with those values (004 Eq. 15), computed independently here.
  const double theta = fatigue::kBoltzmann * l.p.temperature;
  EXPECT_EQ(fatigue::kt_bond_dose(l.p, l.e, 270e6, -1.0, 2),
            fatigue::kt_cycle_dose(270e6, -1.0, l.p.frequency, 1.2 * seg[1].U, 0.9 * seg[1].gamma,
                                   theta));
  l.e.kgamma = 1.0;
  // With k_U = 1.2 a phase II bond at 227.5 MPa lives e^(0.2 U/kT) longer (U ≈ 59 kT: ~1.3e5
  // times), as 004-design check 8 found: the factor slows growth.
  const double slow = fatigue::kt_bond_dose(l.p, l.e, 227.5e6, -1.0, 1) /
                      fatigue::kt_bond_dose(l.p, l.e, 227.5e6, -1.0, 2);
  EXPECT_NEAR(std::log(slow) / (0.2 * seg[0].U / theta), 1.0, 1e-12);
}

TEST(KineticSegments, DefaultsLeaveTheDoseBitIdentical) {
  // No segments, k_U = k_γ = 1, ψ = 0: the engine's dose is the former
  // kt_cycle_dose(σ, R, f, U, γ, kT) bit for bit, in both phases.
  fatigue::KineticParams p;
  p.U = 1.6e-19;
  p.gamma = 2.1e-28;
  const fatigue::KineticExtension e;
  for (const double s : {50e6, 227.5e6, 400e6}) {
    for (const double r : {-1.0, 0.1, 0.9}) {
      const double old = fatigue::kt_cycle_dose(s, r, p.frequency, p.U, p.gamma,
                                                fatigue::kt_thermal_energy(p.temperature));
      EXPECT_EQ(fatigue::kt_bond_dose(p, e, s, r, 1), old);
      EXPECT_EQ(fatigue::kt_bond_dose(p, e, s, r, 2), old);
    }
  }
  EXPECT_EQ(fatigue::kt_bond_dose(p, e, 0.0, -1.0, 1), 0.0);
  EXPECT_EQ(fatigue::kt_bond_dose(p, e, -5e6, -1.0, 1), 0.0);
}

TEST(KineticSegments, Validation) {
  EXPECT_EQ(core::message_of(validate(fatigue::KineticExtension{})), "");
  fatigue::KineticExtension e = three_segments().e;
  e.segments[1].sigma_upper = 240e6;  // not above the first
  EXPECT_NE(core::message_of(validate(e)).find("ascend"), std::string::npos);
  e = three_segments().e;
  e.segments[2].sigma_upper = 400e6;  // the last must be +inf
  EXPECT_NE(core::message_of(validate(e)).find("ascend"), std::string::npos);
  e = three_segments().e;
  e.segments[1].gamma = 0.0;
  EXPECT_NE(core::message_of(validate(e)).find("segment's U and gamma"), std::string::npos);
  e = three_segments().e;
  e.segment_count = 1;
  EXPECT_NE(core::message_of(validate(e)).find("segment_count"), std::string::npos);
  e = three_segments().e;
  e.kU = 0.0;
  EXPECT_NE(core::message_of(validate(e)).find("kU"), std::string::npos);
  e = three_segments().e;
  e.psi = -1.0;
  EXPECT_NE(core::message_of(validate(e)).find("psi"), std::string::npos);
}

// ------------------------------------------------------------------------------- reader

using testing::MapReader;

std::vector<std::string> read_errors(std::map<std::string, double> values,
                                     fatigue::FatigueSettings& f) {
  MapReader r(std::move(values));
  fatigue::law_entry(fatigue::FatigueLaw::kinetic).read(r, f);
  std::vector<std::string> out;
  for (const auto& e : r.errors) out.push_back(e.message());
  return out;
}

TEST(KineticReader, SegmentsPhaseFactorsAndLoopEnergy) {
  fatigue::FatigueSettings f;
  EXPECT_TRUE(read_errors({{"U", 2.4e-19},
                           {"gamma", 3.7e-28},
                           {"U2", 2.8e-19},
                           {"gamma2", 5.3e-28},
                           {"sigma_upper1", 250e6},
                           {"U3", 3.2e-19},
                           {"gamma3", 6e-28},
                           {"sigma_upper2", 290e6},
                           {"kU", 1.2},
                           {"kgamma", 1.0},
                           {"psi", 1.9e-28},
                           {"loop_area", 4.0e5},
                           {"loop_area_yield", 0.0}},
                          f)
                  .empty());
  const auto& k = f.kinetic_extension;
  EXPECT_EQ(core::message_of(validate(k)), "");
  EXPECT_EQ(f.kinetic.U, 2.4e-19);
  ASSERT_EQ(k.segment_count, 3);
  EXPECT_EQ(k.segments[0].U, 2.4e-19);
  EXPECT_EQ(k.segments[0].gamma, 3.7e-28);
  EXPECT_EQ(k.segments[0].sigma_upper, 250e6);
  EXPECT_EQ(k.segments[1].U, 2.8e-19);
  EXPECT_EQ(k.segments[1].sigma_upper, 290e6);
  EXPECT_EQ(k.segments[2].gamma, 6e-28);
  EXPECT_EQ(k.segments[2].sigma_upper, kInf);
  EXPECT_EQ(k.kU, 1.2);
  EXPECT_EQ(k.psi, 1.9e-28);
  EXPECT_EQ(k.loop_area, 4.0e5);

  fatigue::FatigueSettings d;  // the old keys alone: every new one off
  EXPECT_TRUE(read_errors({{"U", 2e-19}, {"gamma", 1e-28}}, d).empty());
  EXPECT_EQ(d.kinetic_extension.segment_count, 0);
  EXPECT_EQ(d.kinetic_extension.kU, 1.0);
  EXPECT_EQ(d.kinetic_extension.kgamma, 1.0);
  EXPECT_EQ(d.kinetic_extension.psi, 0.0);
  EXPECT_EQ(d.kinetic_extension.loop_area, 0.0);
}

TEST(KineticReader, ErrorsNameTheKey) {
  fatigue::FatigueSettings f;
  EXPECT_EQ(read_errors({{"U", 2e-19}, {"gamma", 1e-28}, {"U2", 3e-19}}, f),
            (std::vector<std::string>{"gamma2: missing", "sigma_upper1: missing"}));
  EXPECT_EQ(read_errors({{"U", 2e-19}, {"gamma", 1e-28}, {"sigma_upper1", 250e6}}, f),
            (std::vector<std::string>{"sigma_upper1: needs U2 and gamma2 (a second segment)"}));
  EXPECT_EQ(
      read_errors({{"U", 2e-19},
                   {"gamma", 1e-28},
                   {"U2", 3e-19},
                   {"gamma2", 2e-28},
                   {"sigma_upper1", 290e6},
                   {"U3", 3e-19},
                   {"gamma3", 2e-28},
                   {"sigma_upper2", 250e6}},
                  f),
      (std::vector<std::string>{"sigma_upper2: must be > sigma_upper1 (got 2.5e+08 <= 2.9e+08)"}));
  EXPECT_EQ(
      read_errors({{"U", 2e-19}, {"gamma", 1e-28}, {"U3", 3e-19}}, f),
      (std::vector<std::string>{"U3: needs U2 and gamma2 (segments fill in order, 004 Fig. 8b)"}));
  EXPECT_EQ(read_errors({{"U", 2e-19}, {"gamma", 1e-28}, {"kU", 0.0}, {"psi", -1.0}}, f),
            (std::vector<std::string>{"kU: must be > 0 (got 0)", "psi: must be >= 0 (got -1)"}));
}

// ------------------------------------------------------------------------------- engine

/// The notched plate's kinetic settings: the hottest bond (σ = E·s_max at P = 1000 N) lives
/// `life` cycles at R = 0.1 with γσ/θ = 10 (as the engine tests' settings_for).
fatigue::FatigueSettings plate_kinetic(const statics::Specimen& plate, double life,
                                       std::vector<double>& s, double& sigma) {
  const double smax = testing::largest_intact_stretch(plate, 1000.0, &s);
  sigma = plate.model.material.youngs_modulus * smax;
  fatigue::FatigueSettings f;
  f.law = fatigue::FatigueLaw::kinetic;
  f.critical_stretch = 4 * smax;
  f.incremental = false;
  auto& k = f.kinetic;
  const double kt = fatigue::kt_thermal_energy(k.temperature);
  k.gamma = 10 * kt / sigma;
  k.U = std::log(fatigue::kt_cycle_dose(sigma, 0.1, k.frequency, 0.0, k.gamma, kt) * life) * kt;
  return f;
}

TEST(KineticEngine, SegmentsAndLoopEnergyReachTheBondLives) {
  // The engine's kinetic rate is kt_bond_dose: (a) three equal segments give bit for bit the
  // lives of one U, γ; (b) with a loop energy ψA the hottest bond's remaining life after a block
  // is 1 − count·Φ(E·s_max, R, θ = kT + ψA), Φ by 004 Eq. (15) outside the engine.
  const auto plate = testing::make_notched_plate(model::ModelKind::bond_based);
  const double load = 1000.0;
  std::vector<double> s;
  double sigma = 0.0;
  const fatigue::FatigueSettings f = plate_kinetic(plate, 500.0, s, sigma);
  const auto& k = f.kinetic;
  const double kt = fatigue::kt_thermal_energy(k.temperature);
  const core::LoadBlock block{load, 0.1, 0.0, 120};

  fatigue::FatigueSettings seg = f;
  seg.kinetic_extension.segment_count = 3;
  seg.kinetic_extension.segments = {fatigue::KineticSegment{0.3 * sigma, k.U, k.gamma},
                                    fatigue::KineticSegment{0.7 * sigma, k.U, k.gamma},
                                    fatigue::KineticSegment{kInf, k.U, k.gamma}};
  fatigue::FatigueEngine one(plate.disc, plate.model, plate.supports, plate.loads, f);
  fatigue::FatigueEngine three(plate.disc, plate.model, plate.supports, plate.loads, seg);
  ASSERT_TRUE(one.initialize());
  ASSERT_TRUE(three.initialize());
  one.apply(block);
  three.apply(block);
  EXPECT_EQ(one.remaining_life(), three.remaining_life());

  fatigue::FatigueSettings hot = f;
  hot.kinetic_extension.psi = 1e-28;
  hot.kinetic_extension.loop_area = 0.005 * kt / hot.kinetic_extension.psi;  // ψA = 0.005 kT
  fatigue::FatigueEngine warm(plate.disc, plate.model, plate.supports, plate.loads, hot);
  ASSERT_TRUE(warm.initialize());
  warm.apply(block);
  ASSERT_EQ(warm.break_events().size(), 0u);
  std::size_t h = s.size();  // the most stretched intact bond
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (!plate.disc.bond_precut[b] && (h == s.size() || s[b] > s[h])) h = b;
  }
  ASSERT_LT(h, s.size());
  const double dose =
      fatigue::kt_cycle_dose(sigma, 0.1, k.frequency, k.U, k.gamma, kt + 0.005 * kt);
  EXPECT_NEAR(warm.remaining_life()[h], 1.0 - 120.0 * dose, 1e-12);
  EXPECT_LT(warm.remaining_life()[h], one.remaining_life()[h]);  // hotter: shorter (Eq. 26)
}

TEST(KineticEngine, PhaseTwoBondsTakeKuAndKgamma) {
  // The notch's pre-cut bonds put the nodes at its faces in phase II from the start (φ ≥ φ0 =
  // 0.398, 000 Sec. 4.4). After one block without breaks, a phase I bond's life equals the
  // k_U = 1 engine's bit for bit, and a phase II bond's is 1 − count·Φ(E·s, R, k_U·U, k_γ·γ),
  // Φ by 004 Eq. (15) outside the engine (004 step 6).
  const auto plate = testing::make_notched_plate(model::ModelKind::bond_based);
  std::vector<double> s;
  double sigma = 0.0;
  const fatigue::FatigueSettings f = plate_kinetic(plate, 500.0, s, sigma);
  fatigue::FatigueSettings g = f;
  g.kinetic_extension.kU = 1.05;
  g.kinetic_extension.kgamma = 1.1;
  fatigue::FatigueEngine base(plate.disc, plate.model, plate.supports, plate.loads, f);
  fatigue::FatigueEngine grow(plate.disc, plate.model, plate.supports, plate.loads, g);
  ASSERT_TRUE(base.initialize());
  ASSERT_TRUE(grow.initialize());
  const core::LoadBlock block{1000.0, 0.1, 0.0, 120};
  base.apply(block);
  grow.apply(block);
  ASSERT_EQ(grow.break_events().size(), 0u);
  const auto& k = f.kinetic;
  const double kt = fatigue::kt_thermal_energy(k.temperature);
  const auto lb = base.remaining_life(), lg = grow.remaining_life();
  std::size_t phase_two = 0, differ = 0;
  for (std::size_t b = 0; b < s.size(); ++b) {
    if (plate.disc.bond_precut[b]) continue;
    if (grow.bond_phase()[b] == 1) {
      ASSERT_EQ(lg[b], lb[b]) << "bond " << b;
      continue;
    }
    ++phase_two;
    const double sb = plate.model.material.youngs_modulus * std::max(s[b], 0.0);
    const double dose =
        sb > 0.0 ? fatigue::kt_cycle_dose(sb, 0.1, k.frequency, 1.05 * k.U, 1.1 * k.gamma, kt)
                 : 0.0;
    EXPECT_NEAR(lg[b], 1.0 - 120.0 * dose, 1e-12) << "bond " << b;
    if (lg[b] != lb[b]) ++differ;
  }
  EXPECT_GT(phase_two, 50u);
  EXPECT_GT(differ, 50u);  // the factors reached the lives
}

TEST(KineticEngine, BlocksEqualPerCycleWithEveryPartOn) {
  // The exact-stepping contract (next-break jumps = cycle-by-cycle integration, bit for bit)
  // with segments, k_U, k_γ and Eq. (26) all on, through breaks and phase changes.
  const auto plate = testing::make_notched_plate(model::ModelKind::bond_based);
  std::vector<double> s;
  double sigma = 0.0;
  fatigue::FatigueSettings f = plate_kinetic(plate, 150.0, s, sigma);
  const auto& k = f.kinetic;
  auto& e = f.kinetic_extension;
  e.segment_count = 2;
  e.segments = {fatigue::KineticSegment{0.8 * sigma, 1.02 * k.U, 0.9 * k.gamma},
                fatigue::KineticSegment{kInf, k.U, k.gamma}, fatigue::KineticSegment{}};
  e.kU = 1.02;
  e.kgamma = 1.05;
  e.psi = 1e-28;
  e.loop_area = 0.002 * fatigue::kt_thermal_energy(k.temperature) / e.psi;
  ASSERT_EQ(core::message_of(validate(e)), "");
  fatigue::FatigueEngine fast(plate.disc, plate.model, plate.supports, plate.loads, f);
  fatigue::FatigueEngine slow(plate.disc, plate.model, plate.supports, plate.loads, f);
  ASSERT_TRUE(fast.initialize());
  ASSERT_TRUE(slow.initialize());
  for (const core::LoadBlock& block :
       {core::LoadBlock{1000.0, 0.1, 0.0, 120}, core::LoadBlock{1100.0, -0.2, 0.2, 90},
        core::LoadBlock{1000.0, 0.1, 0.0, 300}}) {
    fast.apply(block);
    slow.apply_per_cycle(block);
    testing::expect_same_breaks(fast, slow);
    EXPECT_EQ(fast.remaining_life(), slow.remaining_life());
    EXPECT_EQ(fast.bond_phase(), slow.bond_phase());
  }
  EXPECT_GE(fast.break_events().size(), 5u);  // it must actually crack the plate
}

// ------------------------------------------------------------------------------- calibration

fatigue::KineticParams fixed_004() {
  fatigue::KineticParams p;  // λ = 9, T = 293 K, f = 0.56 Hz (004)
  p.n0 = fatigue::kt_n0_for_unit_life(p.lambda);
  return p;
}

TEST(KineticCalibration, RecoversUAndGammaFromEq15Lives) {
  // Synthetic S-N curves made by 004 Eq. (15) itself (kt_sn_life), at R = −1 and R = 0.1: the
  // fit returns the U, γ that made them to 1e-6 relative and a residual at round-off.
  const fatigue::KineticParams fixed = fixed_004();
  const double kt = fatigue::kt_thermal_energy(fixed.temperature);
  struct Case {
    double U, gamma, r, lo, hi;
  };
  for (const Case c : {Case{1.49 * kElectronVolt, 3.67e-28, -1.0, 210e6, 250e6},
                       Case{1.75 * kElectronVolt, 5.28e-28, -1.0, 250e6, 290e6},
                       Case{1.2 * kElectronVolt, 1.0e-28, 0.1, 100e6, 300e6}}) {
    std::vector<fatigue::SnPoint> pts;
    for (int i = 0; i <= 8; ++i) {
      const double sa = c.lo + (c.hi - c.lo) * i / 8.0;
      pts.push_back({sa, fatigue::kt_sn_life(sa, c.r, fixed.frequency, c.U, c.gamma, fixed.lambda,
                                             fixed.n0, kt)});
    }
    const auto fit = fatigue::kt_calibrate_segment(pts, c.r, fixed, kt);
    ASSERT_TRUE(fit.ok()) << fit.error().message();
    EXPECT_NEAR(fit->U / c.U, 1.0, 1e-6);
    EXPECT_NEAR(fit->gamma / c.gamma, 1.0, 1e-6);
    EXPECT_LT(fit->max_abs_log_error, 1e-8);
  }
}

TEST(KineticCalibration, RefusesTooFewOrNonPositivePoints) {
  const fatigue::KineticParams fixed = fixed_004();
  const double kt = fatigue::kt_thermal_energy(293.0);
  const auto message = [&](std::vector<fatigue::SnPoint> pts, double r = -1.0) {
    const auto fit = fatigue::kt_calibrate_segment(pts, r, fixed, kt);
    return fit.ok() ? std::string("ok") : fit.error().message();
  };
  EXPECT_EQ(message({{230e6, 1.4e5}}),
            "points: need at least 2 S-N points to fit U and gamma (got 1)");
  EXPECT_EQ(message({{230e6, 1.4e5}, {-250e6, 3e4}}),
            "points[1].stress_amplitude: must be finite and > 0 Pa (got -2.5e+08)");
  EXPECT_EQ(message({{230e6, 0.0}, {250e6, 3e4}}),
            "points[0].cycles: must be finite and > 0 (got 0)");
  EXPECT_EQ(message({{230e6, 1.4e5}, {230e6, 3e4}}),
            "points: need at least 2 distinct stress amplitudes (gamma is the slope)");
  EXPECT_EQ(message({{230e6, 1.4e5}, {250e6, 3e4}}, 1.0),
            "load_ratio: must be finite and < 1 (got 1)");
  // Life rising with stress: no γ > 0 fits.
  EXPECT_NE(message({{230e6, 1e4}, {250e6, 1e5}}).find("gamma -> 0"), std::string::npos);
}

// 004's case. NUREG/CR-6909 Rev. 0 (Chopra and Shack, 2007), the mean air curve of austenitic
// stainless steel, ln N = 6.891 − 1.920 ln(ε_a − 0.112), ε_a in % (†: from 004-design's memory of
// the report; it reproduces 004's S-N life 171,517 at 0.18 %, tested below).
double nureg_6909_ss_life(double strain_amplitude) {
  return std::exp(6.891 - 1.920 * std::log(100.0 * strain_amplitude - 0.112));
}

// 004 Fig. 7c's tensile curve, σ = −0.242·ε^−0.891 + 295 MPa above yield, joined to the elastic
// line by min(): the printed curve does not meet Eε at ε_y = 6.6e-4 (004-design check 2), min()
// keeps it continuous with tangent <= E. E = 193 GPa (004). The lead is adding the same curve as
// model::PowerLawCurve in solver/model/bond_plasticity.h; the two will be unified at merge.
constexpr double kE316 = 193e9;
double tensile_316l(double strain) {
  return std::min(kE316 * strain, -0.242e6 * std::pow(strain, -0.891) + 295e6);
}
/// Its inverse for 0 < σ < 295 MPa: min of two increasing branches → max of their inverses.
double strain_316l(double stress) {
  return std::max(stress / kE316, std::pow((295e6 - stress) / 0.242e6, -1.0 / 0.891));
}

std::vector<fatigue::SnPoint> nureg_points(double lo, double hi, int intervals) {
  std::vector<fatigue::SnPoint> pts;
  for (int i = 0; i <= intervals; ++i) {
    const double sa = lo + (hi - lo) * i / intervals;
    pts.push_back({sa, nureg_6909_ss_life(strain_316l(sa))});
  }
  return pts;
}

TEST(KineticCalibration, Nureg6909CurveThroughThe316lTensileCurve) {
  // 004: the S-N life at ε_a = 0.18 % is 171,517 cycles; 004-design check 1-2 give σ(0.18 %) =
  // 227.5 MPa, σ(0.6 %) = 271.9 MPa and the yield of the min() join at 161 MPa.
  EXPECT_NEAR(nureg_6909_ss_life(0.0018), 171517.0, 0.5);
  EXPECT_NEAR(tensile_316l(0.0018), 227.5e6, 0.05e6);
  EXPECT_NEAR(tensile_316l(0.006), 271.9e6, 0.05e6);
  EXPECT_NEAR(strain_316l(161e6), 161e6 / kE316, 1e-6);
  for (const double sa : {150e6, 210e6, 227.5e6, 270e6, 290e6}) {
    EXPECT_NEAR(tensile_316l(strain_316l(sa)), sa, 1e-6 * sa);
  }
}

TEST(KineticCalibration, Segments004OnTheNurergCurve) {
  // 004 Fig. 8b: three segments, 210-250, 250-290 and >290 MPa (the curve saturates at 295 MPa,
  // so the third covers 290-294 MPa, ε_a 3.3-20 %, N 104-3). Points every 2 MPa (21 per
  // segment), R = −1, θ = kT at 293 K, λ = 9, n0 for unit life, f = 0.56 Hz. Expected: the
  // independent Python fit of 004-design check 4 (same points): seg. 1 U = 59.1 kT (1.49 eV),
  // γ = 3.67e-28 m³, max |Δ ln N| = 0.19; seg. 2 U = 69.2 kT (1.75 eV), γ = 5.28e-28 m³, 0.99;
  // single-bond life at ε_a = 0.18 % (σ_a = 227.5 MPa) 185,678 cycles (S-N: 171,517).
  const fatigue::KineticParams fixed = fixed_004();
  const double kt = fatigue::kt_thermal_energy(fixed.temperature);
  struct Segment {
    double lo, hi;
  };
  std::vector<fatigue::KineticFit> fits;
  for (const Segment seg : {Segment{210e6, 250e6}, Segment{250e6, 290e6}, Segment{290e6, 294e6}}) {
    const int intervals = static_cast<int>(std::lround((seg.hi - seg.lo) / 2e6));
    const auto fit =
        fatigue::kt_calibrate_segment(nureg_points(seg.lo, seg.hi, intervals), -1.0, fixed, kt);
    ASSERT_TRUE(fit.ok()) << fit.error().message();
    std::printf(
        "segment %.0f-%.0f MPa: U = %.6e J = %.4f eV = %.2f kT, gamma = %.4e m^3, max "
        "|dlnN| = %.3f, rms %.3f\n",
        seg.lo / 1e6, seg.hi / 1e6, fit->U, fit->U / kElectronVolt, fit->U / kt, fit->gamma,
        fit->max_abs_log_error, fit->rms_log_error);
    fits.push_back(*fit);
  }
  EXPECT_NEAR(fits[0].U / kt, 59.1, 0.05);
  EXPECT_NEAR(fits[0].gamma / 3.67e-28, 1.0, 2e-3);
  EXPECT_NEAR(fits[0].max_abs_log_error, 0.19, 0.005);
  EXPECT_NEAR(fits[1].U / kt, 69.2, 0.05);
  EXPECT_NEAR(fits[1].gamma / 5.28e-28, 1.0, 2e-3);
  EXPECT_NEAR(fits[1].max_abs_log_error, 0.99, 0.005);
  const double sa = tensile_316l(0.0018);
  const double life = fatigue::kt_sn_life(sa, -1.0, fixed.frequency, fits[0].U, fits[0].gamma,
                                          fixed.lambda, fixed.n0, kt);
  std::printf(
      "single-bond life at 0.18 %% (%.2f MPa, R = -1): %.0f (S-N: %.0f); seg. 2 at 0.6 "
      "%% (%.2f MPa): %.0f (S-N: %.0f)\n",
      sa / 1e6, life, nureg_6909_ss_life(0.0018), tensile_316l(0.006) / 1e6,
      fatigue::kt_sn_life(tensile_316l(0.006), -1.0, fixed.frequency, fits[1].U, fits[1].gamma,
                          fixed.lambda, fixed.n0, kt),
      nureg_6909_ss_life(0.006));
  EXPECT_NEAR(life / 185678.0, 1.0, 2e-5);
}

}  // namespace
}  // namespace peritwin
