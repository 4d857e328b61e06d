// Wrong answers must not be given with confidence. A mass mismatch and an
// encoder zero offset must be told, each by its name (identify.cc, model_check); a breakaway from
// rest, whose stuck inner joint keeps a relative rate of ~1e-10 rad/s in synth-log's exact log,
// must fit (identify.cc, rest_rule and held_sample).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"

#include "paper.h"
#include "synthetic_log.h"

namespace fivebar::identification {
namespace {

using testing::paper_loads;

bool has_warning(const IdentifyResult& res, const std::string& text) {
  for (const std::string& w : res.warnings) {
    if (w.find(text) != std::string::npos) return true;
  }
  return false;
}

IdentifyOptions options() {
  IdentifyOptions opt;
  opt.estimate_delay = false;
  return opt;
}

// the paper scene's 2 s log (torque noise 0.02 N m, angle noise 1e-5 rad) of `truth`
TorqueLog paper_log(const Params<double>& truth, std::uint64_t seed) {
  return testing::synthetic_paper_log(truth, testing::log_options(2.0, 0.02, 1e-5, seed),
                                      "model_check.csv");
}

constexpr const char* kOffsetWarning = "an encoder's zero may be off";
constexpr const char* kMassWarning = "masses or inertias may not match";

// theta1 + 0.005 rad gives Coulomb -8 % (14 std), and must not be blamed on the masses
TEST(ModelCheck, AnEncoderZeroOffsetIsNamed) {
  TorqueLog log = paper_log(paper_params(), 1);
  for (double& th : log.theta1) th += 0.005;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(has_warning(res, kOffsetWarning));
  EXPECT_FALSE(has_warning(res, kMassWarning));
}

// crank 1's inertia 10 % over the scene's puts coulomb at its bound 0 and viscous 23 std off;
// besides the bound's warning, the evidenced cause is named
TEST(ModelCheck, AnInertiaOffTheSceneIsNamedWhenACoefficientIsAtItsBound) {
  Params<double> truth = paper_params();
  truth.links[0].inertia *= 1.1;
  const IdentifyResult res = identify(paper_params(), paper_loads, paper_log(truth, 1), options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  ASSERT_TRUE(res.parameters[0].at_bound) << res.parameters[0].value;
  EXPECT_TRUE(has_warning(res, kMassWarning));
  EXPECT_TRUE(has_warning(res, "at its bound, so the fit cannot say"));
}

// link masses +-5 % give Coulomb +5 % (10 std), which must not pass without a word
TEST(ModelCheck, MassesOffTheSceneAreNamed) {
  Params<double> truth = paper_params();
  for (int i = 0; i < 4; ++i) truth.links[i].mass *= i % 2 == 0 ? 1.05 : 0.95;
  const IdentifyResult res = identify(paper_params(), paper_loads, paper_log(truth, 1), options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(has_warning(res, kMassWarning));
  EXPECT_FALSE(has_warning(res, kOffsetWarning));
}

// a torque sensor's offset must not be blamed on the masses, nor a 3 % gain error (read at +13
// to +18 std) pass in silence. With logged rates, each is named as the torque
// readings' (the offset and the gain read back within their std)
TorqueLog paper_log_with_rates(std::uint64_t seed) {
  SynthOptions so = testing::log_options(2.0, 0.02, 1e-5, seed);
  so.with_rates = true;
  return testing::synthetic_paper_log(paper_params(), so, "model_check_rates.csv");
}

constexpr const char* kTorqueZero = "a torque sensor's zero may be off";
constexpr const char* kTorqueGain = "a torque sensor's gain may be off";
constexpr const char* kUnresolved = "the friction estimates absorbed a model error the log cannot attribute";

TEST(ModelCheck, ATorqueSensorOffsetIsNamed) {
  TorqueLog log = paper_log_with_rates(2);
  for (double& tau : log.tau1) tau += 0.1;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(has_warning(res, kTorqueZero));
  EXPECT_FALSE(has_warning(res, kTorqueGain));
  EXPECT_FALSE(has_warning(res, kOffsetWarning));
}

TEST(ModelCheck, ATorqueGainErrorIsNamed) {
  TorqueLog log = paper_log_with_rates(1);
  for (double& tau : log.tau1) tau *= 1.03;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(has_warning(res, kTorqueGain));
  EXPECT_FALSE(has_warning(res, kTorqueZero));
  EXPECT_FALSE(has_warning(res, kMassWarning));
}

// on a 2 s angles-only log the same gain is, at the smallest windows' noise (4 samples), nearly
// a change of the links' inertial parameters: no cause stood out. Its excess over the noise
// level is flat in the window (a misfit, not smoothing bias), so the window is the largest where
// it stays flat (22 samples), and there the gain is named, read 2.99 +- 0.04 %: it would move
// coulomb by 12 std, so the fit is not to be used
TEST(ModelCheck, ATorqueGainOnAShortAnglesOnlyLogIsNamedWhereTheWindowShowsIt) {
  TorqueLog log = paper_log(paper_params(), 1);
  for (double& tau : log.tau1) tau *= 1.03;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_THAT(res.window_choice, ::testing::HasSubstr("misfit"));
  EXPECT_TRUE(has_warning(res, kTorqueGain));
  EXPECT_FALSE(has_warning(res, kMassWarning));
  EXPECT_THAT(res.unusable, ::testing::HasSubstr("tau1 reads 1.03 times the model"));
  // inertia, angle_offsets, torque_readings, motor_friction, any
  ASSERT_EQ(res.model_check.size(), 5u);
  EXPECT_EQ(res.model_check.back().name, "any");
}

// per-joint Coulomb friction fitted with the shared law leaves the residual 4 to 5 times its
// floor; every cause reduces it by thousands of std, yet the torque sensors must not be blamed.
// None of them explains half the misfit beyond the others
TEST(ModelCheck, AMisfitOfTheLawIsNotBlamedOnTheSensors) {
  Params<double> truth = paper_params();
  truth.friction.coulomb = {0.1, 0.2, 0.15, 0.12, 0.18};
  SynthOptions so = testing::log_options(2.0, 0.02, 1e-5, 1);
  so.with_rates = true;
  const TorqueLog log = testing::synthetic_paper_log(truth, so, "model_check_law.csv");
  const IdentifyResult res = identify(paper_params(), paper_loads, log, options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_FALSE(has_warning(res, kTorqueZero));
  EXPECT_FALSE(has_warning(res, kTorqueGain));
  EXPECT_FALSE(has_warning(res, kOffsetWarning));
  EXPECT_FALSE(has_warning(res, kMassWarning));
}

// on a 0.05 s log (25 samples against 22 freed columns) the check would read offsets of 43 N m;
// below 10 residuals per column it does not run
TEST(ModelCheck, DoesNotRunOnAFewSamples) {
  const IdentifyResult res = identify(
      paper_params(), paper_loads,
      testing::synthetic_paper_log(paper_params(), testing::log_options(0.05, 0.02, 1e-5, 1),
                                   "model_check_short.csv"),
      options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(res.model_check.empty());
  EXPECT_FALSE(has_warning(res, kTorqueZero));
  EXPECT_FALSE(has_warning(res, kTorqueGain));
}

TEST(ModelCheck, LogsOfTheSceneAreQuiet) {
  for (std::uint64_t seed : {1, 2}) {
    const IdentifyResult res =
        identify(paper_params(), paper_loads, paper_log(paper_params(), seed), options());
    ASSERT_TRUE(res.status.ok()) << res.status.message;
    EXPECT_FALSE(has_warning(res, kOffsetWarning)) << seed;
    EXPECT_FALSE(has_warning(res, kMassWarning)) << seed;
    EXPECT_FALSE(has_warning(res, kTorqueZero)) << seed;
    EXPECT_FALSE(has_warning(res, kTorqueGain)) << seed;
    EXPECT_FALSE(has_warning(res, kUnresolved)) << seed;
  }
}

// clean angles-only logs of 6 s and more must not warn of the masses (synth-log seed 1, 6 s:
// with the inertias free the cost falls by 56 against 14 +- 5.2 from noise alone):
// the noise of the Savitzky-Golay accelerations is both in the residual and in the inertial
// columns, so the score is not centred and its excess grows with the log's length (errors in
// variables). Fails without score_bias.
TEST(ModelCheck, ALongAnglesOnlyLogOfTheSceneIsQuiet) {
  const IdentifyResult res = identify(
      paper_params(), paper_loads,
      testing::synthetic_paper_log(paper_params(), testing::log_options(6.0, 0.02, 1e-5, 1),
                                   "model_check_long.csv"),
      options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_FALSE(has_warning(res, kMassWarning));
  EXPECT_FALSE(has_warning(res, kOffsetWarning));
}

// datasets/scenes/stick_below_breakaway.yaml with M1 rising by 0.5 N m/s from 0.01 N m above
// the equilibrium: the mechanism breaks away from rest, and joint D stays stuck for most of the
// log (synth-log's exact rates give it ~1e-10 rad/s, above the 2.6e-12 that their rounding sets)
Loads<double> breakaway_loads(double t) {
  return {-1.31570913923345 + 0.01 + 0.5 * t, -1.04791037143488 - 0.01, 0.0, 50.0, M_PI / 2};
}

/// The fit of a 2 s breakaway log with exact logged rates and the given sensor noise.
IdentifyResult breakaway_fit(double torque_noise, double angle_noise, double rate_noise = 0) {
  Params<double> truth = paper_params();
  truth.gravity = 0.0;
  SynthOptions so = testing::log_options(2.0, torque_noise, angle_noise, 1);
  so.with_rates = true;
  so.rate_noise = rate_noise;
  SynthResult syn = synthesize_log(truth, breakaway_loads, testing::paper_initial(), so);
  if (!syn.status.ok()) {
    IdentifyResult failed;
    failed.status = syn.status;
    return failed;
  }
  syn.log.path = "breakaway.csv";
  return identify(truth, breakaway_loads, syn.log, options());
}

TEST(RestSamples, ANoiseFreeBreakawayLogFitsExactly) {
  const IdentifyResult res = breakaway_fit(0.0, 0.0);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_NEAR(res.parameters[0].value, 0.12, 1e-6);  // was 0.074
  EXPECT_NEAR(res.parameters[1].value, 0.02, 1e-6);  // was 0.126
  EXPECT_GT(res.samples_at_rest, 500);               // joint D held (was 193)
}

// the same with torque noise 0.02 N m and angle noise 1e-5 rad (rates exact): the angle noise
// through the kinematics gives the stuck joint D ~1e-5 rad/s (was coulomb 0.073 +- 0.0017)
TEST(RestSamples, ANoisyBreakawayLogFitsWithinItsStd) {
  const IdentifyResult res = breakaway_fit(0.02, 1e-5);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_LT(std::abs(res.parameters[0].value - 0.12), 3 * res.parameters[0].std);
  EXPECT_LT(std::abs(res.parameters[1].value - 0.02), 3 * res.parameters[1].std);
}

// logged rates 0.001 rad/s noisy, accelerations exact (327 samples held): a joint within its
// rate threshold is left out, not kept with the direction of its acceleration (a stuck joint's
// reads the rates' noise through the velocity products; a slowly turning joint's opposes its
// motion when it decelerates), which would give coulomb -25 std
TEST(RestSamples, NoisyLoggedRatesHoldTheStuckJoint) {
  const IdentifyResult exact = breakaway_fit(0.02, 1e-5);
  const IdentifyResult res = breakaway_fit(0.02, 1e-5, 1e-3);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_GE(res.samples_at_rest, exact.samples_at_rest);
  for (int i = 0; i < 2; ++i) {
    const double truth = i == 0 ? 0.12 : 0.02;
    EXPECT_LT(std::abs(res.parameters[i].value - truth), 3 * res.parameters[i].std)
        << res.parameters[i].name << " = " << res.parameters[i].value << " +- "
        << res.parameters[i].std;
  }
}

}  // namespace
}  // namespace fivebar::identification
