// Strain gauges -> P and α (stream/gauge_identification.h). Where the numbers come from:
// - Exact recovery: strains made from the model itself, ε_g = P·(c0 + c1 cos α + c2 sin α), give
//   back P to 1e-10 relative and α to 1e-10 rad, in each of the three forms of the load.
// - Noise: 10,000 samples with independent normal noise of known σ_g (std::mt19937_64, fixed
//   seed). The weighted least-squares estimate's standard error is computed analytically from the
//   coefficients: σ_P = (Σ w c0²)^−½ for P alone; the covariance (JᵀWJ)⁻¹ of the linearized model
//   (J = ∂ε/∂(P, α)) for two unknowns. The measured RMS error must lie within ±5 % of it: the RMS
//   of 10,000 normal deviates has a relative standard deviation of 1/√20000 = 0.7 %, and the
//   linearization error is of order (σ_P/P)² ~ 1e-6 here. The mean of residual_rms² must be
//   (n − unknowns)/Σw (the expected χ² of a least-squares fit), within ±5 % too.
// - Refusals: the reason texts a user reads.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "stream/gauge_identification.h"

namespace peritwin::stream {
namespace {

constexpr double kPi = std::numbers::pi;

/// An angle difference brought into (−π, π].
double angle_difference(double a, double b) {
  double d = std::fmod(a - b, 2.0 * kPi);
  if (d > kPi) d -= 2.0 * kPi;
  if (d <= -kPi) d += 2.0 * kPi;
  return d;
}

/// Eight gauges of a rosette-like layout (strain per N ~ 1e-7: 400 µε at 4 kN), with a constant
/// part when `constant`, an angle part when `angle`; noise σ_g = 1e-6·(1 + 0.25 g) (1 to 2.75 µε).
std::vector<GaugeInfluence> rosette(bool constant, bool angle, int n = 8) {
  std::vector<GaugeInfluence> gauges;
  for (int g = 0; g < n; ++g) {
    const double theta = 0.3 + 0.7 * g;
    GaugeInfluence gi;
    gi.id = std::to_string(g + 1);
    gi.id.insert(0, 1, 'g');  // not "g" + ...: GCC 12's -Wrestrict false positive (PR 105329)
    gi.per_basis[0] = constant ? 1e-7 * (0.8 - 0.2 * g + 0.03 * g * g) : 0.0;
    gi.per_basis[1] = angle ? 1e-7 * std::cos(2.0 * theta) * (1.0 + 0.1 * g) : 0.0;
    gi.per_basis[2] = angle ? 1e-7 * std::sin(2.0 * theta + 0.4) : 0.0;
    gi.noise = 1e-6 * (1.0 + 0.25 * g);
    gauges.push_back(gi);
  }
  return gauges;
}

std::vector<std::string> ids(const std::vector<GaugeInfluence>& gauges) {
  std::vector<std::string> out;
  for (const auto& g : gauges) out.push_back(g.id);
  return out;
}

/// The model's strains of `gauges` for (p, alpha).
std::vector<double> strains_of(const std::vector<GaugeInfluence>& gauges, double p, double alpha) {
  std::vector<double> e;
  for (const auto& g : gauges) {
    e.push_back(
        p * (g.per_basis[0] + g.per_basis[1] * std::cos(alpha) + g.per_basis[2] * std::sin(alpha)));
  }
  return e;
}

LoadIdentifier make(const std::vector<GaugeInfluence>& gauges) {
  auto made = LoadIdentifier::create(ids(gauges), gauges);
  EXPECT_TRUE(made.ok()) << (made.ok() ? "" : made.error());
  return std::move(made).value();
}

std::string refusal(std::vector<std::string> columns, const std::vector<GaugeInfluence>& gauges) {
  const auto made = LoadIdentifier::create(std::move(columns), gauges);
  return made.ok() ? std::string("(accepted)") : made.error();
}

// --- exact recovery -------------------------------------------------------------------------

TEST(GaugeIdentification, POnlyRecoversPExactlyAndReportsAlphaZero) {
  const auto gauges = rosette(true, false);
  const LoadIdentifier id = make(gauges);
  EXPECT_EQ(id.form(), LoadForm::p_only);
  EXPECT_EQ(id.unknowns(), 1);
  for (const double p : {-3000.0, 0.5, 4000.0, 1e6}) {
    // α does not change the strains of this model; any α is the same sample.
    const IdentifiedLoad l = id.identify(strains_of(gauges, p, 0.7));
    EXPECT_NEAR(l.p, p, 1e-10 * std::abs(p)) << p;
    EXPECT_EQ(l.alpha, 0.0);
    EXPECT_LE(l.residual_rms, 1e-14 * std::abs(p) * 1e-7);
  }
}

TEST(GaugeIdentification, LinearPairRecoversPAndAlphaExactly) {
  const auto gauges = rosette(false, true);
  const LoadIdentifier id = make(gauges);
  EXPECT_EQ(id.form(), LoadForm::linear_pair);
  EXPECT_EQ(id.unknowns(), 2);
  for (int i = 0; i < 50; ++i) {
    const double alpha = -0.5 * kPi + (i + 0.5) * kPi / 50.0;  // inside (−π/2, π/2)
    for (const double p : {-5000.0, -120.0, 35.0, 4000.0}) {
      const IdentifiedLoad l = id.identify(strains_of(gauges, p, alpha));
      EXPECT_NEAR(l.p, p, 1e-10 * std::abs(p)) << p << " " << alpha;
      EXPECT_NEAR(l.alpha, alpha, 1e-10) << p << " " << alpha;
      // (p, α + π) is the same load as (−p, α): reported as (−p, α) in (−π/2, π/2].
      const IdentifiedLoad flipped = id.identify(strains_of(gauges, p, alpha + kPi));
      EXPECT_NEAR(flipped.p, -p, 1e-10 * std::abs(p)) << p << " " << alpha;
      EXPECT_NEAR(flipped.alpha, alpha, 1e-10) << p << " " << alpha;
    }
  }
  // The end of the range: π/2 stays π/2 (−π/2 would be (−P, π/2)).
  const IdentifiedLoad end = id.identify(strains_of(gauges, 900.0, 0.5 * kPi));
  EXPECT_NEAR(end.p, 900.0, 1e-10 * 900.0);
  EXPECT_NEAR(end.alpha, 0.5 * kPi, 1e-10);
  // A load reversing through zero keeps its angle.
  EXPECT_NEAR(id.identify(strains_of(gauges, -1.0, 0.3)).alpha, 0.3, 1e-12);
  EXPECT_NEAR(id.identify(strains_of(gauges, 1.0, 0.3)).alpha, 0.3, 1e-12);
}

TEST(GaugeIdentification, ConstantAndAngleRecoversPAndAlphaExactly) {
  const auto gauges = rosette(true, true);
  const LoadIdentifier id = make(gauges);
  EXPECT_EQ(id.form(), LoadForm::constant_and_angle);
  EXPECT_EQ(id.unknowns(), 2);
  std::vector<double> angles;
  for (int i = 0; i < 360; ++i) angles.push_back(-kPi + (i + 1) * 2.0 * kPi / 360.0);  // scan's too
  for (const double a : {kPi, -kPi + 1e-9, 1e-13, -0.0, 2.0 * kPi / 72 * 0.5}) angles.push_back(a);
  for (const double alpha : angles) {
    for (const double p : {-4000.0, -1.0, 2.5, 4000.0}) {
      const IdentifiedLoad l = id.identify(strains_of(gauges, p, alpha));
      EXPECT_NEAR(l.p, p, 1e-10 * std::abs(p)) << p << " " << alpha;
      EXPECT_NEAR(angle_difference(l.alpha, alpha), 0.0, 1e-10) << p << " " << alpha;
      EXPECT_GT(l.alpha, -kPi);
      EXPECT_LE(l.alpha, kPi);
      EXPECT_LE(l.residual_rms, 1e-9 * std::abs(p) * 1e-7) << p << " " << alpha;
    }
  }
}

TEST(GaugeIdentification, ConstantAndAngleWithThreeGaugesAndUnweighted) {
  // The fewest gauges that identify both unknowns; one noise not given: unweighted.
  auto gauges = rosette(true, true, 3);
  gauges[1].noise = 0.0;
  const LoadIdentifier id = make(gauges);
  for (const double alpha : {-2.9, -1.0, 0.0, 0.4, 3.1}) {
    const IdentifiedLoad l = id.identify(strains_of(gauges, 3000.0, alpha));
    EXPECT_NEAR(l.p, 3000.0, 3e-7) << alpha;
    EXPECT_NEAR(angle_difference(l.alpha, alpha), 0.0, 1e-10) << alpha;
  }
}

TEST(GaugeIdentification, ColumnsPickAndOrderTheModelsGauges) {
  // The model has 10 gauges; the samples give 5 of them in another order.
  const auto model = rosette(true, true, 10);
  const std::vector<std::string> columns{"g7", "g2", "g10", "g4", "g1"};
  auto made = LoadIdentifier::create(columns, model);
  ASSERT_TRUE(made.ok()) << made.error();
  std::vector<double> e;
  for (const auto& c : columns) {
    const auto& g =
        *std::find_if(model.begin(), model.end(), [&](const auto& m) { return m.id == c; });
    e.push_back(1500.0 * (g.per_basis[0] + g.per_basis[1] * std::cos(-0.8) +
                          g.per_basis[2] * std::sin(-0.8)));
  }
  const IdentifiedLoad l = made->identify(e);
  EXPECT_NEAR(l.p, 1500.0, 1e-10 * 1500.0);
  EXPECT_NEAR(l.alpha, -0.8, 1e-10);
  EXPECT_EQ(made->columns(), columns);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    EXPECT_NEAR(made->model_strain(i, 1500.0, -0.8), e[i], 1e-15 * 1500.0 * 1e-7);
  }
}

TEST(GaugeIdentification, ResidualsAreStrainMinusModelStrain) {
  const auto gauges = rosette(true, true);
  const LoadIdentifier id = make(gauges);
  std::vector<double> e = strains_of(gauges, 2000.0, 1.1);
  e[3] += 5e-6;  // one gauge off by 5 µε
  std::vector<double> r;
  const IdentifiedLoad l = id.identify(e, &r);
  ASSERT_EQ(r.size(), e.size());
  double sum_w = 0.0, sum_wr2 = 0.0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    EXPECT_NEAR(r[i], e[i] - id.model_strain(i, l.p, l.alpha), 1e-18);
    const double w = 1.0 / (gauges[i].noise * gauges[i].noise);
    sum_w += w;
    sum_wr2 += w * r[i] * r[i];
  }
  EXPECT_NEAR(l.residual_rms, std::sqrt(sum_wr2 / sum_w), 1e-12 * l.residual_rms);
  EXPECT_GT(l.residual_rms, 1e-7);
}

TEST(GaugeIdentification, BadSamplesGiveNaNAndZeroStrainsGiveZero) {
  for (const bool constant : {true, false}) {
    for (const bool angle : {true, false}) {
      if (!constant && !angle) continue;
      const auto gauges = rosette(constant, angle);
      const LoadIdentifier id = make(gauges);
      const std::vector<double> zeros(gauges.size(), 0.0);
      const IdentifiedLoad zero = id.identify(zeros);
      EXPECT_EQ(zero.p, 0.0);
      EXPECT_EQ(zero.alpha, 0.0);
      EXPECT_EQ(zero.residual_rms, 0.0);
      std::vector<double> r;
      EXPECT_TRUE(std::isnan(id.identify(std::vector<double>(3, 1e-6), &r).p));
      EXPECT_EQ(r.size(), gauges.size());
      std::vector<double> nan_sample = strains_of(gauges, 100.0, 0.2);
      nan_sample[2] = std::nan("");
      const IdentifiedLoad bad = id.identify(nan_sample);
      EXPECT_TRUE(std::isnan(bad.p) && std::isnan(bad.alpha) && std::isnan(bad.residual_rms));
    }
  }
}

TEST(GaugeIdentification, ConstantAndAngleNearlyDegenerateGaugesRecoverExactly) {
  // Three gauges (found by a randomized search) where v'(α) is nearly parallel to v(α) at the
  // truth: the misfit has a second local minimum 0.019 rad away, 1.5e-9 × εᵀWε above zero. A
  // refinement bracketing one-sidedly from the (exact) linear candidate went there.
  std::vector<GaugeInfluence> gauges(3);
  gauges[0] = {
      "a", {-2.5696437307468234e-07, -7.3664663481803603e-08, 4.6344115773058412e-08}, 2.3702e-06};
  gauges[1] = {
      "b", {-1.5011995354005175e-07, 3.0391084570531968e-09, 4.3516805987187696e-08}, 1.70257e-06};
  gauges[2] = {
      "c", {-1.2369674308846823e-09, 9.9326593851351207e-08, 3.4121200312538603e-08}, 8.132e-07};
  const LoadIdentifier id = make(gauges);
  const IdentifiedLoad l = id.identify(strains_of(gauges, 1470.7146735179676, 0.60764288120097476));
  EXPECT_NEAR(l.p, 1470.7146735179676, 1e-10 * 1470.7);
  EXPECT_NEAR(l.alpha, 0.60764288120097476, 1e-10);
}

/// A double in [-1, 1) from the generator's top 53 bits (the same on every standard library,
/// unlike std::uniform_real_distribution).
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-52 - 1.0; }

TEST(GaugeIdentification, ConstantAndAngleFindsTheGlobalMinimumOfNoisySamples) {
  // Random gauges (3 to 10, constant parts 0.01 to 100 times the angle parts: condition
  // numbers up to ~1e3) and one set made so that v(α) nearly vanishes at α = 1 (a misfit
  // minimum ~1e-3 rad wide, which a 72-angle scan would step over); noisy samples. The misfit at
  // the reported α must be no larger than at the best of a 20,000-angle scan polished by golden
  // section (1e-12 × εᵀWε of rounding allowed).
  std::mt19937_64 rng(3301);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<GaugeInfluence>> sets;
  for (int set = 0; set < 24; ++set) {
    std::vector<GaugeInfluence> gauges(static_cast<std::size_t>(3 + set % 8));
    for (std::size_t g = 0; g < gauges.size(); ++g) {
      const double constant = std::pow(10.0, 2.0 * uniform(rng));
      gauges[g].id = std::to_string(g);
      gauges[g].per_basis = {constant * 1e-7 * uniform(rng), 1e-7 * uniform(rng),
                             1e-7 * uniform(rng)};
      gauges[g].noise = 1e-6 * (1.5 + uniform(rng));
    }
    sets.push_back(gauges);
  }
  auto narrow = rosette(true, true);
  for (std::size_t g = 0; g < narrow.size(); ++g) {
    auto& c = narrow[g].per_basis;
    c[0] = -(c[1] * std::cos(1.0) + c[2] * std::sin(1.0)) +
           3e-10 * std::cos(1.0 + 2.0 * static_cast<double>(g));
  }
  sets.push_back(narrow);
  int wider_scans = 0;
  for (std::size_t set = 0; set < sets.size(); ++set) {
    const auto& gauges = sets[set];
    auto made = LoadIdentifier::create(ids(gauges), gauges);
    ASSERT_TRUE(made.ok()) << set << ": " << made.error();
    ASSERT_EQ(made->form(), LoadForm::constant_and_angle);
    wider_scans += made->scan_angles() > LoadIdentifier::kMinScanAngles ? 1 : 0;
    for (int s = 0; s < 8; ++s) {
      const bool at_narrow = set + 1 == sets.size() && s % 2 == 0;
      const double alpha = at_narrow ? 1.0 + 1e-3 * uniform(rng) : kPi * uniform(rng);
      std::vector<double> e = strains_of(gauges, 5000.0 * uniform(rng), alpha);
      for (std::size_t i = 0; i < e.size(); ++i) e[i] += gauges[i].noise * unit(rng);
      // The weighted misfit at α with the best P, relative to εᵀWε.
      const auto misfit = [&](double a) {
        double ve = 0.0, vv = 0.0, ee = 0.0;
        for (std::size_t i = 0; i < e.size(); ++i) {
          const auto& c = gauges[i].per_basis;
          const double w = 1.0 / (gauges[i].noise * gauges[i].noise);
          const double v = c[0] + c[1] * std::cos(a) + c[2] * std::sin(a);
          ve += w * v * e[i];
          vv += w * v * v;
          ee += w * e[i] * e[i];
        }
        return (ee - ve * ve / vv) / ee;
      };
      double best_alpha = 0.0, best = 2.0;
      for (int k = 0; k < 20000; ++k) {
        const double a = -kPi + (k + 1) * 2.0 * kPi / 20000;
        if (const double m = misfit(a); m < best) {
          best = m;
          best_alpha = a;
        }
      }
      double lo = best_alpha - 2.0 * kPi / 20000, hi = best_alpha + 2.0 * kPi / 20000;
      while (hi - lo > 1e-12) {
        const double m1 = lo + 0.381966 * (hi - lo), m2 = hi - 0.381966 * (hi - lo);
        if (misfit(m1) < misfit(m2)) {
          hi = m2;
        } else {
          lo = m1;
        }
      }
      best = std::min(best, misfit(0.5 * (lo + hi)));
      const IdentifiedLoad l = made->identify(e);
      EXPECT_LE(misfit(l.alpha), best + 1e-12) << "set " << set << " sample " << s;
    }
  }
  EXPECT_GE(wider_scans, 1);  // the narrow set at least
}

// --- noise ------------------------------------------------------------------------------------

struct NoiseRun {
  double rms_p = 0.0, rms_alpha = 0.0, mean_residual2 = 0.0;
};

/// 10,000 samples of (p, alpha) with normal noise σ_g on each gauge.
NoiseRun run_noise(const LoadIdentifier& id, const std::vector<GaugeInfluence>& gauges, double p,
                   double alpha) {
  std::mt19937_64 rng(33);
  std::normal_distribution<double> unit(0.0, 1.0);
  const std::vector<double> clean = strains_of(gauges, p, alpha);
  constexpr int kSamples = 10000;
  NoiseRun run;
  std::vector<double> e(clean.size());
  for (int s = 0; s < kSamples; ++s) {
    for (std::size_t i = 0; i < e.size(); ++i) e[i] = clean[i] + gauges[i].noise * unit(rng);
    const IdentifiedLoad l = id.identify(e);
    run.rms_p += (l.p - p) * (l.p - p);
    const double da = angle_difference(l.alpha, alpha);
    run.rms_alpha += da * da;
    run.mean_residual2 += l.residual_rms * l.residual_rms;
  }
  run.rms_p = std::sqrt(run.rms_p / kSamples);
  run.rms_alpha = std::sqrt(run.rms_alpha / kSamples);
  run.mean_residual2 /= kSamples;
  return run;
}

double weight_sum(const std::vector<GaugeInfluence>& gauges) {
  double s = 0.0;
  for (const auto& g : gauges) s += 1.0 / (g.noise * g.noise);
  return s;
}

/// Standard errors of (P, α) from the linearized model: Cov = (JᵀWJ)⁻¹, J = [v(α), P v'(α)].
Eigen::Vector2d standard_errors(const std::vector<GaugeInfluence>& gauges, double p, double alpha) {
  Eigen::Matrix2d info = Eigen::Matrix2d::Zero();
  for (const auto& g : gauges) {
    const double v =
        g.per_basis[0] + g.per_basis[1] * std::cos(alpha) + g.per_basis[2] * std::sin(alpha);
    const double dv = -g.per_basis[1] * std::sin(alpha) + g.per_basis[2] * std::cos(alpha);
    const Eigen::Vector2d j(v, p * dv);
    info += j * j.transpose() / (g.noise * g.noise);
  }
  const Eigen::Matrix2d cov = info.inverse();
  return {std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1))};
}

TEST(GaugeIdentification, POnlyNoiseErrorIsTheWeightedLeastSquaresStandardError) {
  const auto gauges = rosette(true, false);
  const LoadIdentifier id = make(gauges);
  double info = 0.0;
  for (const auto& g : gauges) info += g.per_basis[0] * g.per_basis[0] / (g.noise * g.noise);
  const double sigma_p = 1.0 / std::sqrt(info);  // (Σ w c0²)^−½
  const NoiseRun run = run_noise(id, gauges, 4000.0, 0.0);
  EXPECT_NEAR(run.rms_p / sigma_p, 1.0, 0.05) << "σ_P " << sigma_p << " N";
  EXPECT_NEAR(run.mean_residual2 * weight_sum(gauges) / (8 - 1), 1.0, 0.05);

  // One gauge without a noise figure: unweighted; the error is then the ordinary least-squares
  // one, σ_P² = Σ c0² σ² / (Σ c0²)², larger than the weighted one.
  auto unweighted = gauges;
  unweighted[0].noise = 0.0;
  const LoadIdentifier plain = make(unweighted);
  double cc = 0.0, ccs = 0.0;
  for (const auto& g : gauges) {
    cc += g.per_basis[0] * g.per_basis[0];
    ccs += g.per_basis[0] * g.per_basis[0] * g.noise * g.noise;
  }
  const double sigma_plain = std::sqrt(ccs) / cc;
  ASSERT_GT(sigma_plain, 1.05 * sigma_p);
  EXPECT_NEAR(run_noise(plain, gauges, 4000.0, 0.0).rms_p / sigma_plain, 1.0, 0.05);
}

TEST(GaugeIdentification, LinearPairNoiseErrorIsTheLinearizedStandardError) {
  const auto gauges = rosette(false, true);
  const LoadIdentifier id = make(gauges);
  const Eigen::Vector2d sigma = standard_errors(gauges, 4000.0, 0.6);
  const NoiseRun run = run_noise(id, gauges, 4000.0, 0.6);
  EXPECT_LT(sigma[0] / 4000.0, 1e-2);  // the linearization holds
  EXPECT_NEAR(run.rms_p / sigma[0], 1.0, 0.05) << "σ_P " << sigma[0] << " N";
  EXPECT_NEAR(run.rms_alpha / sigma[1], 1.0, 0.05) << "σ_α " << sigma[1] << " rad";
  EXPECT_NEAR(run.mean_residual2 * weight_sum(gauges) / (8 - 2), 1.0, 0.05);
}

TEST(GaugeIdentification, ConstantAndAngleNoiseErrorIsTheLinearizedStandardError) {
  const auto gauges = rosette(true, true);
  const LoadIdentifier id = make(gauges);
  for (const double alpha : {-2.5, 0.6}) {
    const Eigen::Vector2d sigma = standard_errors(gauges, 4000.0, alpha);
    const NoiseRun run = run_noise(id, gauges, 4000.0, alpha);
    EXPECT_LT(sigma[0] / 4000.0, 1e-2);
    EXPECT_NEAR(run.rms_p / sigma[0], 1.0, 0.05) << alpha << ": σ_P " << sigma[0] << " N";
    EXPECT_NEAR(run.rms_alpha / sigma[1], 1.0, 0.05) << alpha << ": σ_α " << sigma[1] << " rad";
    EXPECT_NEAR(run.mean_residual2 * weight_sum(gauges) / (8 - 2), 1.0, 0.05) << alpha;
  }
}

// --- the form and the refusals ----------------------------------------------------------------

TEST(GaugeIdentification, NegligibleCoefficientsAreZero) {
  auto gauges = rosette(true, false);
  gauges[2].per_basis[1] = 1e-10 * 1e-7;  // <= 1e-9 × the largest |c|: 0
  EXPECT_EQ(make(gauges).form(), LoadForm::p_only);
  EXPECT_EQ(make(gauges).model_strain(2, 1000.0, 0.0), 1000.0 * gauges[2].per_basis[0]);
  gauges[2].per_basis[1] = 1e-8 * 1e-7;  // not negligible: an angle part (but too few gauges)
  EXPECT_NE(refusal(ids(gauges), gauges).find("2 unknowns (P, α)"), std::string::npos);
}

TEST(GaugeIdentification, RefusesTooFewIndependentGauges) {
  // One gauge, two unknowns.
  const auto one = rosette(false, true, 1);
  EXPECT_EQ(refusal({"g1"}, one),
            "2 unknowns (P, α) but the gauge g1 gives only 1 independent equation (their cos α "
            "and sin α coefficients are in proportion: add a gauge that reads another direction "
            "of the load)");
  // Two collinear gauges (the second reads twice the first).
  auto two = rosette(false, true, 2);
  two[1].per_basis = {0.0, 2.0 * two[0].per_basis[1], 2.0 * two[0].per_basis[2]};
  EXPECT_EQ(refusal({"g1", "g2"}, two),
            "2 unknowns (P, α) but the gauges g1, g2 give only 1 independent equation (their cos "
            "α and sin α coefficients are in proportion: add a gauge that reads another "
            "direction of the load)");
  // Collinear within the 1e-8 threshold: refused; 1e-6 apart: taken.
  two[1].per_basis[2] *= 1.0 + 1e-10;
  EXPECT_NE(refusal({"g1", "g2"}, two).find("only 1 independent equation"), std::string::npos);
  two[1].per_basis[2] *= 1.0 + 1e-6;
  EXPECT_EQ(refusal({"g1", "g2"}, two), "(accepted)");
  // A constant and an angle part: 3 independent gauges needed; the third the sum of two.
  auto three = rosette(true, true, 3);
  for (std::size_t j = 0; j < 3; ++j) {
    three[2].per_basis[j] = three[0].per_basis[j] + three[1].per_basis[j];
  }
  EXPECT_EQ(refusal({"g1", "g2", "g3"}, three),
            "2 unknowns (P, α) of a load with a constant and an angle part need 3 independent "
            "gauges (with fewer, two different (P, α) give the same strains) but the gauges g1, "
            "g2, g3 give only 2 independent equations (add a gauge whose constant, cos α and sin "
            "α coefficients are no combination of theirs)");
  // Two gauges with a constant and an angle part: refused although 2 equations for 2 unknowns
  // (α and −α fit alike when the sin α coefficients are 0).
  auto symmetric = rosette(true, true, 2);
  symmetric[0].per_basis[2] = symmetric[1].per_basis[2] = 0.0;
  EXPECT_NE(refusal({"g1", "g2"}, symmetric).find("only 2 independent equations"),
            std::string::npos);
  const auto made = rosette(true, true, 2);
  EXPECT_NE(refusal({"g1", "g2"}, made).find("only 2 independent equations"), std::string::npos);
}

TEST(GaugeIdentification, RefusesBadColumnsAndModels) {
  const auto gauges = rosette(true, true, 4);
  EXPECT_EQ(refusal({"g1", "g9", "g2", "g3"}, gauges),
            "column 'g9' is no gauge of the model (its gauges: g1, g2, g3, g4)");
  EXPECT_EQ(refusal({"g1", "g2", "g1", "g3"}, gauges),
            "gauge 'g1' is given twice (gauge columns 1 and 3)");
  EXPECT_EQ(refusal({}, gauges), "no gauge columns");
  auto zero = gauges;
  for (auto& g : zero) g.per_basis = {0.0, 0.0, 0.0};
  EXPECT_EQ(refusal({"g1", "g2"}, zero),
            "every coefficient of the gauges g1, g2 is 0: they do not see the load");
  auto twice = gauges;
  twice.push_back(gauges[1]);
  EXPECT_EQ(refusal({"g1", "g3", "g4"}, twice), "the model gives gauge 'g2' twice");
  auto nan = gauges;
  nan[2].per_basis[1] = std::nan("");
  EXPECT_EQ(refusal(ids(nan), nan), "gauge 'g3': its coefficient per_basis[1] is not finite");
  auto negative = gauges;
  negative[0].noise = -1e-6;
  EXPECT_EQ(refusal(ids(negative), negative), "gauge 'g1': its noise must be a finite number >= 0");
  // A gauge the columns do not use may be anything.
  EXPECT_EQ(refusal({"g1", "g2", "g4"}, nan), "(accepted)");
}

TEST(GaugeIdentification, UpdateTakesNewCoefficientsAndKeepsTheOldOnRefusal) {
  auto gauges = rosette(true, true);
  LoadIdentifier id = make(gauges);
  const std::vector<double> e = strains_of(gauges, 4000.0, 0.5);

  // Refused: a column missing from the new model; then all coefficients 0.
  auto missing = gauges;
  missing.erase(missing.begin() + 4);
  const core::Status no = id.update(missing);
  ASSERT_FALSE(no.ok());
  EXPECT_EQ(no.error().reason,
            "column 'g5' is no gauge of the model (its gauges: g1, g2, g3, g4, g6, g7, g8)");
  auto zero = gauges;
  for (auto& g : zero) g.per_basis = {0.0, 0.0, 0.0};
  EXPECT_FALSE(id.update(zero).ok());
  IdentifiedLoad l = id.identify(e);
  EXPECT_NEAR(l.p, 4000.0, 1e-10 * 4000.0);
  EXPECT_NEAR(l.alpha, 0.5, 1e-10);

  // Bonds broke: the gauges read 25 % more per N. The same strains are then a smaller load.
  for (auto& g : gauges) {
    for (double& c : g.per_basis) c *= 1.25;
  }
  ASSERT_TRUE(id.update(gauges).ok());
  l = id.identify(e);
  EXPECT_NEAR(l.p, 3200.0, 1e-10 * 3200.0);
  EXPECT_NEAR(l.alpha, 0.5, 1e-10);

  // The form may change with the coefficients.
  const auto linear = rosette(false, true);
  ASSERT_TRUE(id.update(linear).ok());
  EXPECT_EQ(id.form(), LoadForm::linear_pair);
  EXPECT_NEAR(id.identify(strains_of(linear, -700.0, 1.2)).p, -700.0, 1e-10 * 700.0);
}

// --- parsing ----------------------------------------------------------------------------------

TEST(GaugeParsing, Header) {
  const auto ok = parse_gauge_header("\xEF\xBB\xBFtime_s, g1 ,rosette A/x,g3\r\n");
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(*ok, (std::vector<std::string>{"g1", "rosette A/x", "g3"}));
  EXPECT_EQ(parse_gauge_header("t,g1,g2").error(),
            "the header must begin with time_s (\"time_s,<gauge id>,...\"), not 't'");
  EXPECT_EQ(parse_gauge_header("time_s").error(),
            "the header names no gauge (\"time_s,<gauge id>,...\")");
  EXPECT_EQ(parse_gauge_header("time_s,g1,,g2").error(), "gauge column 2 has an empty id");
  EXPECT_EQ(parse_gauge_header("time_s,g1,").error(), "gauge column 2 has an empty id");
  EXPECT_EQ(parse_gauge_header("time_s,g1,g2,g1").error(),
            "gauge 'g1' is given twice (gauge columns 1 and 3)");
  EXPECT_EQ(parse_gauge_header("").error(),
            "the header must begin with time_s (\"time_s,<gauge id>,...\"), not ''");
}

TEST(GaugeParsing, DataLines) {
  const auto ok = parse_gauge_line(" 0.25, 1.5e-6,-2e-6 ,+3E-7\r\n", 3);
  ASSERT_TRUE(ok.ok()) << ok.error();
  ASSERT_TRUE(ok->has_value());
  EXPECT_EQ((*ok)->t, 0.25);
  EXPECT_EQ((*ok)->strains, (std::vector<double>{1.5e-6, -2e-6, 3e-7}));
  // Nothing: blank lines and comments.
  for (const char* nothing : {"", "   \r\n", "# a comment", "  #1,2,3"}) {
    const auto n = parse_gauge_line(nothing, 3);
    ASSERT_TRUE(n.ok()) << nothing;
    EXPECT_FALSE(n->has_value()) << nothing;
  }
  const auto why = [](std::string_view line, std::size_t gauges) {
    const auto r = parse_gauge_line(line, gauges);
    return r.ok() ? std::string("(accepted)") : r.error();
  };
  EXPECT_EQ(why("1,2e-6", 3), "expected 4 fields (t and 3 strains), not 2");
  EXPECT_EQ(why("1,2e-6,3e-6,4e-6,5e-6", 3), "expected 4 fields (t and 3 strains), not 5");
  EXPECT_EQ(why("1;2e-6", 1), "expected 2 fields (t and 1 strain), not 1");
  EXPECT_EQ(why("1,0,5", 1), "expected 2 fields (t and 1 strain), not 3");  // a decimal comma
  EXPECT_EQ(why("1,2e-6,abc", 2),
            "the strain of gauge column 2 ('abc') is no number (or out of a double's range)");
  EXPECT_EQ(why("1,2e-6,", 2),
            "the strain of gauge column 2 ('') is no number (or out of a double's range)");
  EXPECT_EQ(why("1,1e999", 1),
            "the strain of gauge column 1 ('1e999') is no number (or out of a double's range)");
  EXPECT_EQ(why("1,nan,2", 2), "the strain of gauge column 1 is not finite");
  EXPECT_EQ(why("1,2,-inf", 2), "the strain of gauge column 2 is not finite");
  EXPECT_EQ(why("x,1", 1), "the time 'x' is no number (or out of a double's range)");
  EXPECT_EQ(why("inf,1", 1), "the time is not finite");
  EXPECT_EQ(why("0x1p3,1", 1), "the time '0x1p3' is no number (or out of a double's range)");
  EXPECT_EQ(why("++1,1", 1), "the time '++1' is no number (or out of a double's range)");
  EXPECT_EQ(why("time_s,g1", 1),
            "a header line inside the data (the first header fixes the columns)");
}

}  // namespace
}  // namespace peritwin::stream
