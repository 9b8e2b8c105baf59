// peritwin-calibrate (validation/peritwin_calibrate.cpp): the binary run as a user runs it.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "config/config.h"
#include "validation/ct_calibration.h"

namespace {

using nlohmann::json;

struct Outcome {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Runs build/bin/peritwin-calibrate with `args` (shell words).
Outcome calibrate(const std::string& args) {
  const std::string dir = testing::TempDir();
  const std::string out = dir + "calibrate_out.txt", err = dir + "calibrate_err.txt";
  const std::string command =
      std::string(PERITWIN_BIN_DIR) + "/peritwin-calibrate " + args + " >" + out + " 2>" + err;
  const int status = std::system(command.c_str());
  Outcome o;
  o.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = slurp(out);
  o.err = slurp(err);
  return o;
}

/// B1's material and Paris law (000 Sec. 6, Eq. A4) on B1's grid.
/// Its pins as 000 Sec. 6.1 and docs/validation.md have them (stiff material), so that B1's
/// documented A2 holds.
const std::string kB1 =
    "-E 68e9 --nu 0.33 --K-c 48.7e6 --paris-c 4.34e-7 --paris-m 2.6183 --dx 0.001 "
    "--rigid-model stiff_material";

/// The B1 example with its [detail.fatigue] table replaced by `snippet`.
std::string b1_example_with(const std::string& snippet) {
  std::string text = slurp(std::string(PERITWIN_EXAMPLES_DIR) + "/b1-ct-al6061.toml");
  const auto begin = text.find("[detail.fatigue]");
  const auto end = text.find("\n[", begin + 1);
  if (begin == std::string::npos || end == std::string::npos) return {};
  return text.substr(0, begin) + snippet + text.substr(end);
}

// B1 (docs/validation.md): A2 = 1301 at Δx = 1 mm, δ = 3.015Δx. The tool's first A2 is B1's scaled
// to the inputs, so with B1's inputs one PD run must land within its 0.5 % tolerance (docs: 1301
// gives -0.06 %). 1 % on A2: a stopping point within 0.5 % of the life lies within ~0.7 % of the
// exact A2, since the life moves by ~0.7 % per 1 % of A2 (30 % of it is phase I, which A2 does not
// change). The iteration from the paper's trial 1055 (3 runs, 33-63 s on 2 loaded cores, too slow
// for the suite) is in docs/validation.md; its step rule is tested below on its measured lives.
TEST(Calibration, B1InputsReproduceB1sA2AndTheSnippetParses) {
  const Outcome o = calibrate(kB1 + " --no-check --json");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const json line = json::parse(o.out);
  EXPECT_TRUE(line["converged"].get<bool>());
  const double a2 = line["a2"].get<double>();
  EXPECT_NEAR(a2 / 1301.0 - 1.0, 0.0, 0.01) << "A2 " << a2;
  EXPECT_LE(std::abs(line["fit"]["rel_error"].get<double>()), 0.005);
  EXPECT_EQ(line["fit"]["paris_life"].get<double>(), 47567);  // docs/validation.md, B1 at 4 kN

  const std::string config = b1_example_with(line["fatigue_toml"].get<std::string>());
  ASSERT_FALSE(config.empty());
  const auto parsed = peritwin::config::parse_config(config, "b1-calibrated.toml");
  ASSERT_TRUE(parsed.ok()) << parsed.error_text() << "\n" << config;
  const auto& fatigue = parsed.config->details.at(0).fatigue;
  EXPECT_EQ(fatigue.law, peritwin::fatigue::FatigueLaw::strain_range);
  EXPECT_NEAR(fatigue.strain.A2, a2, 1e-6 * a2);  // printed with 7 significant digits
  EXPECT_DOUBLE_EQ(fatigue.strain.A1, 103.7465);  // B1's, no strain-life data given
  EXPECT_DOUBLE_EQ(fatigue.strain.m1, 2.29153);
  EXPECT_DOUBLE_EQ(fatigue.strain.m2, 2.6183);
  EXPECT_DOUBLE_EQ(fatigue.phase_switch_damage, 0.398);
  EXPECT_EQ(fatigue.static_failure, peritwin::fatigue::StaticFailure::critical_stretch);
}

// Issue 31: a structural steel (ν = 0.3) in plane stress, where the stiff pins were indefinite
// ("stiffness is not positive definite (pivot 2234)"), calibrates with the default rigid-body
// pins: the fit within 2 % of its Paris life (the tool stops within 0.5 %), the checks at 1.25 and
// 1.5 × P_max within 5 %. Measured: +5.88 %, +0.33 % (A2 35 620), checks +0.83 %, +0.64 %; 43 s.
// The stiff pins are refused with exit 2 and the reason.
TEST(Calibration, StructuralSteelInPlaneStressWithRigidBodyPins) {
  const std::string steel =
      "-E 210e9 --nu 0.3 --K-c 100e6 --paris-c 1.65e-11 --paris-units m-MPa --paris-m 3 "
      "--dx 0.001";
  const Outcome o = calibrate(steel + " --json");
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const json line = json::parse(o.out);
  EXPECT_TRUE(line["converged"].get<bool>());
  EXPECT_LE(std::abs(line["fit"]["rel_error"].get<double>()), 0.02);
  ASSERT_EQ(line["checks"].size(), 2u);
  for (const auto& check : line["checks"]) {
    EXPECT_LE(std::abs(check["rel_error"].get<double>()), 0.05) << check.dump();
  }
  const Outcome stiff = calibrate(steel + " --rigid-model stiff_material --dry-run");
  EXPECT_EQ(stiff.exit_code, 2);
  EXPECT_NE(stiff.err.find("nu >= 0.3266"), std::string::npos) << stiff.err;
}

// The step rule on B1's measured runs from the trial 1055 (docs/validation.md): Eq. (26b) gives
// peritwin-validate's 1282.13 after the first; the two-point model N = N1 + k/A2 through both gives
// 1302.5, the A2 whose run is within 0.1 % of the Paris life (Eq. 26b alone: 1300.86).
TEST(Calibration, StepRulesOnB1sMeasuredRuns) {
  using namespace peritwin::validation;
  CalibrationSetup setup;  // B1's Paris law
  auto run = [](double a2, double pd) {
    CalibrationRun r;
    r.a2 = a2;
    r.life.pd_life = pd;
    r.life.paris_life = 47567;
    return r;
  };
  std::vector<CalibrationRun> runs{run(1055, 57808)};
  EXPECT_NEAR(next_a2(setup, runs), 1282.13, 0.5);
  runs.push_back(run(1282.13, 48262));
  EXPECT_NEAR(next_a2(setup, runs), 1302.5, 0.5);
  setup.step = A2Step::eq26b;
  EXPECT_NEAR(next_a2(setup, runs), 1300.86, 0.5);
  // Two runs that define no model (longer life at the larger A2): Eq. (26b).
  setup.step = A2Step::two_point;
  runs[1].life.pd_life = 60000;
  EXPECT_NEAR(next_a2(setup, runs), 1282.13 * 60000 / 47567, 0.5);
}

TEST(Calibration, BadInputIsRefusedWithExitTwo) {
  const std::string paris = " --paris-c 4.34e-7 --paris-m 2.6183";
  struct Case {
    std::string args, says;
  };
  for (const Case& c : {
           Case{"-E -68e9 --nu 0.33 --K-c 48.7e6 --dx 0.001" + paris, "youngs-modulus"},
           Case{"-E 68e9 --nu 0.5 --K-c 48.7e6 --dx 0.001" + paris, "(-1, 0.5)"},
           Case{"-E 68e9 --nu 0.33 --K-c 48.7e6 --dx 0.001", "--paris-c is required"},
           Case{kB1 + " --horizon-ratio 11", "not in range 1 to 10"},
           Case{kB1 + " --horizon-ratio 0.5", "not in range 1 to 10"},
           Case{kB1 + " --paris-units m-Pa", "check --paris-c and --paris-units"},
           Case{"-E 68e9 --nu 0.33 --K-c 48.7e6 --dx 0.0007" + paris,
                "midway between two node rows"},
           Case{kB1 + " --kernel conical", "constant kernel"},
           Case{kB1 + " --sn-curve 0.01:1000", "000 Eq. (23)"},
           Case{kB1 + " --a1 100", "need --m1"},
       }) {
    const Outcome o = calibrate(c.args + " --dry-run");
    EXPECT_EQ(o.exit_code, 2) << c.args;
    EXPECT_NE(o.err.find(c.says), std::string::npos) << c.args << "\n" << o.err;
  }
}

// Phase I without PD runs (--dry-run): 000 Eq. (48b)'s inputs give 000 Eq. (48c); strain-life
// points on the line of Eq. (23a) with B1's A1, m1 give them back; SI Paris units convert.
TEST(Calibration, PhaseOneAndParisUnitsFromTheCommandLine) {
  {
    const Outcome o = calibrate(kB1 + " --m1 2.29153 --sn-intercept -0.87975 --dry-run --json");
    ASSERT_EQ(o.exit_code, 0) << o.err;
    EXPECT_NEAR(json::parse(o.out)["a1"].get<double>(), 103.7465, 0.01);
  }
  {
    std::string points;
    for (const double n : {1e3, 1e4, 1e5, 1e6}) {
      const double eps = std::pow(103.7465 * n, -1.0 / 2.29153);  // 000 Eq. (21)
      char point[80];
      std::snprintf(point, sizeof point, " --sn-curve %.17g:%.17g", eps, n);
      points += point;
    }
    const Outcome o = calibrate(kB1 + points + " --dry-run --json");
    ASSERT_EQ(o.exit_code, 0) << o.err;
    const json line = json::parse(o.out);
    EXPECT_NEAR(line["m1"].get<double>(), 2.29153, 1e-4);
    EXPECT_NEAR(line["a1"].get<double>() / 103.7465, 1.0, 1e-3);
  }
  {
    // 4.34e-7 mm/cycle (MPa√m) = 4.34e-10 m/cycle (MPa√m) = 4.34e-10/1e6^M m/cycle (Pa√m).
    const double si = 4.34e-10 / std::pow(1e6, 2.6183);
    char c[64];
    std::snprintf(c, sizeof c, "%.17g", si);
    const Outcome o = calibrate(
        "-E 68e9 --nu 0.33 --K-c 48.7e6 --paris-m 2.6183 --dx 0.001 "
        "--paris-units m-Pa --dry-run --json --paris-c " +
        std::string(c));
    ASSERT_EQ(o.exit_code, 0) << o.err;
    const json line = json::parse(o.out);
    EXPECT_NEAR(line["paris_c_mm_mpa"].get<double>() / 4.34e-7, 1.0, 1e-12);
    EXPECT_EQ(line["paris_life"].get<double>(), 47567);
    EXPECT_NEAR(line["p_max"].get<double>(), 4000, 1e-9);  // B1's load: the default for B1's coupon
    EXPECT_NEAR(line["first_a2"].get<double>(), 1301, 0.01);
  }
}

}  // namespace
