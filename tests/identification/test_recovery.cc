// Identification recovers known friction from synthetic logs, with tolerances derived from the
// noise: the estimate of a linear-in-the-coefficients least-squares fit is Gaussian around the
// truth with the reported std (residual variance times (J^T J)^-1), so each test asks for
// |error| < 4 std (two-sided probability 6e-5 per coefficient; the seeds are fixed, so the
// outcome is deterministic) plus absolute targets (1 % with rates, 5 % from angles only)
// where they apply.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "light_scene.h"
#include "paper.h"
#include "synthetic_log.h"

namespace fivebar::identification {
namespace {

constexpr double kStdBound = 4.0;      // |error| / std, see the file comment
constexpr double kTorqueNoise = 0.02;  // N m, as in datasets/logs
constexpr double kAngleNoise = 1e-5;   // rad, as in datasets/logs

using testing::paper_loads;
const sim::Initial kPaperInitial = testing::paper_initial();

TorqueLog make_log(const Params<double>& truth, double duration, bool rates, bool multisine,
                   double torque_noise = kTorqueNoise, double angle_noise = kAngleNoise,
                   std::uint64_t seed = 1) {
  SynthOptions so = testing::log_options(duration, torque_noise, angle_noise, seed);
  so.with_rates = rates;
  so.multisine = multisine;
  return testing::synthetic_paper_log(truth, so, "synthetic.csv");
}

void expect_recovered(const IdentifyResult& res, const std::vector<double>& truth, double rel_tol) {
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  ASSERT_EQ(res.parameters.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    const ParameterEstimate& p = res.parameters[i];
    EXPECT_GT(p.std, 0.0) << p.name;
    EXPECT_LT(std::abs(p.value - truth[i]), kStdBound * p.std)
        << p.name << " = " << p.value << " +- " << p.std;
    if (rel_tol > 0) {
      EXPECT_NEAR(p.value, truth[i], rel_tol * truth[i]) << p.name;
    }
  }
}

TEST(Recovery, SharedWithRatesWithinOnePercentAndFourStd) {
  const Params<double> truth = paper_params();
  const TorqueLog log = make_log(truth, 3.0, true, false);
  IdentifyOptions opt;
  const IdentifyResult res = identify(truth, paper_loads, log, opt);
  expect_recovered(res, {0.12, 0.02}, 0.01);
  // the residual is the torque noise: its sample std over 6000 residuals is within ~1 %
  EXPECT_NEAR(res.residual_sigma, kTorqueNoise, 0.03 * kTorqueNoise);
  EXPECT_NEAR(res.residual_noise_floor[0], kTorqueNoise, 0.05 * kTorqueNoise);
}

TEST(Recovery, ExactDataGivesTheTruth) {
  const Params<double> truth = paper_params();
  const TorqueLog log = make_log(truth, 1.0, true, false, 0.0, 0.0);
  const IdentifyResult res = identify(truth, paper_loads, log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok());
  // limited by the simulator's tolerances (1e-10) through the logged accelerations
  EXPECT_NEAR(res.parameters[0].value, 0.12, 1e-6);
  EXPECT_NEAR(res.parameters[1].value, 0.02, 1e-7);
}

TEST(Recovery, PerJointDistinctCoefficients) {
  Params<double> truth = paper_params();
  truth.friction.coulomb = {0.08, 0.10, 0.12, 0.14, 0.16};
  truth.friction.viscous = {0.010, 0.015, 0.020, 0.025, 0.030};
  const TorqueLog log = make_log(truth, 2.0, true, true);
  IdentifyOptions opt;
  opt.layout.per_joint = true;
  const IdentifyResult res = identify(truth, paper_loads, log, opt);
  std::vector<double> x(truth.friction.coulomb.begin(), truth.friction.coulomb.end());
  x.insert(x.end(), truth.friction.viscous.begin(), truth.friction.viscous.end());
  expect_recovered(res, x, 0.0);
}

TEST(Recovery, AnglesOnlyWithinFivePercent) {
  // rates and accelerations by Savitzky-Golay: bias from the smoothing dominates, so only the
  // 5 % target is asserted (the reported std does not cover filter bias)
  const Params<double> truth = paper_params();
  const TorqueLog log = make_log(truth, 3.0, false, false);
  const IdentifyResult res = identify(truth, paper_loads, log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok());
  EXPECT_TRUE(res.rates_estimated);
  EXPECT_NEAR(res.parameters[0].value, 0.12, 0.05 * 0.12);
  EXPECT_NEAR(res.parameters[1].value, 0.02, 0.05 * 0.02);
}

TEST(Recovery, StribeckLogFittedWithCoulombViscousReportsTheMismatch) {
  const Params<double> truth = testing::stribeck_truth();
  // 6 s: the multisine's slowest tone (0.31 Hz) needs a few periods to reverse every joint often
  const TorqueLog log = make_log(truth, 6.0, true, true);
  const IdentifyResult res = identify(paper_params(), paper_loads, log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok());
  EXPECT_GT(std::max(res.rms_torque_residual[0] / res.residual_noise_floor[0],
                     res.rms_torque_residual[1] / res.residual_noise_floor[1]),
            1.1);
  EXPECT_THAT(res.warnings, ::testing::Contains(::testing::HasSubstr("times the noise floor")));
  // the matching law finds the Stribeck parameters
  IdentifyOptions st;
  st.layout.law = FrictionLaw::kStribeck;
  const IdentifyResult good = identify(paper_params(), paper_loads, log, st);
  expect_recovered(good, {0.12, 0.02, 0.2, 0.5}, 0.0);
}

/// A Stribeck log (static 0.2, Stribeck velocity 0.5 rad/s) at 500 Hz on the multisine, angles
/// only, as `coverage-angles --case stribeck` makes it.
TorqueLog stribeck_angles_log(double torque_noise, double angle_noise,
                              std::uint64_t seed = 1) {
  SynthOptions so;
  so.rate_hz = 500;
  so.duration = 6.0;
  so.torque_noise = torque_noise;
  so.angle_noise = angle_noise;
  so.multisine = true;
  so.seed = seed;
  return testing::synthetic_paper_log(testing::stribeck_truth(), so, "stribeck.csv");
}

IdentifyOptions stribeck_options() {
  IdentifyOptions opt;
  opt.layout.law = FrictionLaw::kStribeck;
  opt.estimate_delay = false;
  return opt;
}

TEST(Recovery, StribeckStartsFromSeveralVelocities) {
  // noise-free angles through the smallest window: from the neutral start (0.2 rad/s) alone the
  // fit ends at the velocity's bound (static_coulomb 0.191 undetermined); the least cost over
  // the starts finds the peak
  const TorqueLog log = stribeck_angles_log(0, 0);
  IdentifyOptions opt = stribeck_options();
  opt.auto_window = false;
  opt.sg.half_window_s = 0.006;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, opt);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_NEAR(res.parameters[2].value, 0.2, 0.01);
  EXPECT_NEAR(res.parameters[3].value, 0.5, 0.025);
  EXPECT_FALSE(res.parameters[3].at_bound);
}

TEST(Recovery, StribeckKeepsOutReversalsAndTheSecondWindow) {
  // noise-free: every window shows the filter's bias, so the order is raised; the samples near
  // reversals still go (kept, the smeared peak read as static_coulomb 0.130)
  IdentifyResult res = identify(paper_params(), paper_loads, stribeck_angles_log(0, 0),
                                stribeck_options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_EQ(res.sg_order, 7);
  EXPECT_GT(res.samples_near_reversals, 0);
  EXPECT_NEAR(res.parameters[2].value, 0.2, 0.004);
  // noisy angles: the second window (4 samples) is unbiased; backing off to the smallest would
  // raise the order (noisier accelerations); order 5 over 4 samples
  res = identify(paper_params(), paper_loads, stribeck_angles_log(kTorqueNoise, kAngleNoise),
                 stribeck_options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_EQ(res.sg_order, 5);
  EXPECT_EQ(res.sg_half_window, 4);
  EXPECT_GT(res.samples_near_reversals, 0);
  expect_recovered(res, {0.12, 0.02, 0.2, 0.5}, 0.0);
}

TEST(Recovery, StribeckProfileIntervalCoversWhereTheWaldIntervalDoesNot) {
  // seed 25 of `coverage-angles --case stribeck`: the fit is a wide, low peak (static 0.125 +-
  // 0.005, velocity 2.7 rad/s) for the true 0.2 and 0.5: the Wald interval of static_coulomb
  // misses the truth by 14 std. The cost barely rises along the trade-off between the peak's
  // height and width: the profile interval holds the truth (and is open above: the log cannot
  // rule out a taller, narrower peak), with a warning saying so
  const TorqueLog log = stribeck_angles_log(kTorqueNoise, kAngleNoise, 25);
  const IdentifyResult res = identify(paper_params(), paper_loads, log, stribeck_options());
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  const ParameterEstimate& st = res.parameters[2];
  ASSERT_EQ(st.name, "static_coulomb");
  EXPECT_GT(std::abs(st.value - 0.2), 1.96 * st.std);  // Wald misses
  EXPECT_EQ(st.ci_method, "profile-likelihood");
  EXPECT_LE(st.ci_low, 0.2);
  EXPECT_GE(st.ci_high, 0.2);
  // static >= kinetic holds in every re-fit: the interval stays above any plausible coulomb
  EXPECT_GT(st.ci_low, 0.11);
  EXPECT_EQ(res.parameters[3].ci_method, "profile-likelihood");
  EXPECT_LE(res.parameters[3].ci_low, 0.5);
  EXPECT_GE(res.parameters[3].ci_high, 0.5);
  EXPECT_THAT(res.warnings, ::testing::Contains(::testing::HasSubstr("does not bound")));
  // the linear coefficients keep their Wald interval, value +- 1.96 std
  EXPECT_EQ(res.parameters[0].ci_method, "wald");
  EXPECT_NEAR(res.parameters[0].ci_high - res.parameters[0].value, 1.96 * res.parameters[0].std,
              1e-3 * res.parameters[0].std);
}

TEST(Recovery, OutputErrorOnAShortLog) {
  // numeric derivatives through the simulator; the std come from the window sandwich
  // (covariance.h, its formula checked in test_covariance.cc). By default a 1 s log gets 20
  // windows of 0.05 s (output_error_window); 5 windows of 0.2 s are few enough for the warning
  // that these std are themselves uncertain
  const Params<double> truth = paper_params();
  const TorqueLog log = make_log(truth, 1.0, true, false);
  IdentifyOptions opt;
  opt.method = Method::kOutputError;
  const IdentifyResult res = identify(truth, paper_loads, log, opt);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_EQ(res.std_method, "window-sandwich");
  EXPECT_DOUBLE_EQ(res.window_s, 0.05);
  EXPECT_THAT(res.std_detail, ::testing::HasSubstr("20 windows"));
  // Student's t with 19 degrees of freedom for the 95 % intervals of the window sandwich
  EXPECT_EQ(res.ci_dof, 19);
  EXPECT_NEAR(res.ci_quantile, 2.093, 1e-3);
  EXPECT_NEAR(res.parameters[0].ci_high - res.parameters[0].value,
              res.ci_quantile * res.parameters[0].std, 1e-9);
  EXPECT_THAT(res.warnings, ::testing::Not(::testing::Contains(::testing::HasSubstr("windows"))));
  expect_recovered(res, {0.12, 0.02}, 0.01);
  opt.window_s = 0.2;
  const IdentifyResult few = identify(truth, paper_loads, log, opt);
  ASSERT_TRUE(few.status.ok()) << few.status.message;
  EXPECT_THAT(few.std_detail, ::testing::HasSubstr("5 windows"));
  EXPECT_THAT(few.warnings, ::testing::Contains(::testing::HasSubstr("only 5 windows")));
  expect_recovered(few, {0.12, 0.02}, 0.01);
}

// the fitted scene of a law without static friction must not keep the nominal scene's static
// coefficient (its holding bound), 0.2 against a fitted Coulomb of 0.12
TEST(Recovery, FittedSceneStaticCoulombFollowsTheFittedCoulomb) {
  const TorqueLog log = make_log(paper_params(), 1.0, true, false);
  Params<double> nominal = paper_params();
  nominal.friction.coulomb.fill(0.2);
  nominal.friction.static_coulomb.fill(0.2);  // the default: follows coulomb
  nominal.friction.static_coulomb[4] = 0.5;   // set apart from it: kept
  const IdentifyResult res = identify(nominal, paper_loads, log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  const FrictionParams<double>& fp = res.fitted.friction;
  for (int k = 0; k < 4; ++k) EXPECT_EQ(fp.static_coulomb[k], fp.coulomb[k]) << k;
  EXPECT_EQ(fp.static_coulomb[4], 0.5);
  EXPECT_NEAR(fp.coulomb[0], 0.12, 0.01);
}

TEST(Recovery, NoisyLoggedRatesGiveWayToTheAngles) {
  // rates logged with 0.05 rad/s of noise: the angles (1e-5 rad) give better rates, so the fit
  // estimates them from the angles and says so
  SynthOptions so;
  so.duration = 1.0;
  so.torque_noise = kTorqueNoise;
  so.angle_noise = kAngleNoise;
  so.rate_noise = 0.05;
  so.with_rates = true;
  so.seed = 2;
  SynthResult r = synthesize_log(paper_params(), paper_loads, kPaperInitial, so);
  ASSERT_TRUE(r.status.ok());
  const IdentifyResult res = identify(paper_params(), paper_loads, r.log, IdentifyOptions{});
  EXPECT_TRUE(res.rates_estimated);
  EXPECT_THAT(res.notes, ::testing::Contains(::testing::HasSubstr("the logged rates not used")));
  expect_recovered(res, {0.12, 0.02}, 0.02);
  // exact logged rates are kept
  so.rate_noise = 0;
  r = synthesize_log(paper_params(), paper_loads, kPaperInitial, so);
  EXPECT_FALSE(identify(paper_params(), paper_loads, r.log, IdentifyOptions{}).rates_estimated);
}

TEST(Identifiability, ShortLogWarnsNamingTheInseparableCoefficients) {
  // 0.3 s of the paper scene: the cranks barely turn, joints D and D0 load alike
  const Params<double> truth = paper_params();
  const TorqueLog log = make_log(truth, 0.3, true, false);
  IdentifyOptions opt;
  opt.layout.per_joint = true;
  const IdentifyResult res = identify(truth, paper_loads, log, opt);
  ASSERT_TRUE(res.status.ok());
  EXPECT_THAT(res.warnings,
              ::testing::Contains(::testing::AllOf(::testing::HasSubstr("cannot separate"),
                                                   ::testing::HasSubstr("coulomb_4"),
                                                   ::testing::HasSubstr("coulomb_5"))));
  EXPECT_GT(res.singular_values.front() / res.singular_values.back(), 100.0);
}

TEST(Synth, SameSeedSameLogOtherSeedOtherLog) {
  const Params<double> truth = paper_params();
  const TorqueLog a = make_log(truth, 0.2, false, false, kTorqueNoise, kAngleNoise, 5);
  const TorqueLog b = make_log(truth, 0.2, false, false, kTorqueNoise, kAngleNoise, 5);
  const TorqueLog c = make_log(truth, 0.2, false, false, kTorqueNoise, kAngleNoise, 6);
  EXPECT_EQ(a.tau1, b.tau1);
  EXPECT_EQ(a.theta2, b.theta2);
  EXPECT_NE(a.tau1, c.tau1);
}

TEST(Synth, QuantizationRoundsAngles) {
  SynthOptions so;
  so.duration = 0.1;
  so.quantization = 1e-3;
  const SynthResult r = synthesize_log(paper_params(), paper_loads, kPaperInitial, so);
  ASSERT_TRUE(r.status.ok());
  for (double th : r.log.theta1) EXPECT_NEAR(th / 1e-3, std::round(th / 1e-3), 1e-6);
}

// A coefficient at its bound keeps the direction it holds uncertain in the others' std: with
// viscous nearly 0 in truth (1e-5), the 2 s log of seed 2 ends at viscous = 0, and its coulomb
// std is that of the seeds where viscous stays free (it was a quarter of it, the bound taken as
// known).
TEST(Recovery, AStdKeepsTheUncertaintyOfACoefficientAtItsBound) {
  Params<double> truth = paper_params();
  truth.friction.viscous.fill(1e-5);
  const IdentifyResult at_bound =
      identify(truth, paper_loads, make_log(truth, 2.0, false, false, kTorqueNoise, kAngleNoise, 2),
               IdentifyOptions{});
  const IdentifyResult free =
      identify(truth, paper_loads, make_log(truth, 2.0, false, false, kTorqueNoise, kAngleNoise, 3),
               IdentifyOptions{});
  ASSERT_TRUE(at_bound.status.ok() && free.status.ok());
  ASSERT_TRUE(at_bound.parameters[1].at_bound) << at_bound.parameters[1].value;
  ASSERT_FALSE(free.parameters[1].at_bound);
  EXPECT_GT(at_bound.parameters[0].std, 0.7 * free.parameters[0].std);
  EXPECT_LT(std::abs(at_bound.parameters[0].value - 0.12), 3 * at_bound.parameters[0].std);
}

// A light, slow five-bar (links of 2-3 kg, loads of 0.4 N m, gravity 0.49 m/s^2) whose clean
// angles-only logs have a torque residual 40 times the torque noise: the angle noise through the
// estimated accelerations dominates it, and the smoothing bias predicted from those angles is as
// noisy as the estimates. Over seeds 1-6 (3 s at 1 kHz, torque noise 9.4e-4 N m, angle noise
// 1e-5 rad) each coefficient's 95 % interval holds the truth at least 5 times, and none is
// beyond 3 std without a warning (with the prediction read over the rule's span at every window
// and its own noise left out of the std, coulomb held it 3 times of 6 and viscous 4, seed 1's
// viscous +3.4 std unwarned; read over the candidate's span, 5 and 5, within 2.03 std).
TEST(Recovery, LightSlowFiveBarCleanLogsCoverTheTruth) {
  const Params<double> truth = testing::slow_light_params();
  const sim::LoadFunction loads = testing::slow_light_loads;
  const double truths[2] = {0.2, 0.05};
  int covered[2] = {0, 0};
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SynthOptions so = testing::log_options(3.0, 9.375e-4, kAngleNoise, seed);
    const SynthResult r = synthesize_log(truth, loads, testing::slow_light_start(), so);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    const IdentifyResult res = identify(truth, loads, r.log, IdentifyOptions{});
    ASSERT_TRUE(res.status.ok()) << res.status.message;
    for (int p = 0; p < 2; ++p) {
      const ParameterEstimate& e = res.parameters[p];
      const double z = (e.value - truths[p]) / e.std;
      covered[p] += e.ci_low <= truths[p] && truths[p] <= e.ci_high;
      EXPECT_TRUE(std::abs(z) <= 3 || !res.warnings.empty())
          << "seed " << seed << ": " << e.name << " " << z << " std off, no warning";
    }
  }
  EXPECT_GE(covered[0], 5);
  EXPECT_GE(covered[1], 5);
}

// The slow light five-bar under the multi-sine with coarse encoders (angle noise 1e-4 rad, torque
// noise 0.02 N m, 6 s at 1 kHz): the angle noise through the estimated accelerations is most of
// the residual, and the friction regressors (the reactions' norms) carry the same noise, so the
// fit at the residual rule's window reads coulomb near 0 and viscous 2-5 std high. That bias is
// predicted (errors in variables through the reactions) and the window moved up until it is
// small: each coefficient's 95 % interval holds its truth (with that bias unpredicted, coulomb
// read 0.053 +- 0.049 and viscous 0.067 +- 0.0077, 2.2 std high).
TEST(Recovery, LightSlowFiveBarNoisyEncodersCoverTheTruth) {
  const Params<double> truth = testing::slow_light_params();
  const double truths[2] = {0.2, 0.05};
  SynthOptions so = testing::log_options(6.0, kTorqueNoise, 1e-4, 3);
  so.multisine = true;
  const SynthResult r =
      synthesize_log(truth, testing::slow_light_loads, testing::slow_light_start(), so);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const IdentifyResult res = identify(truth, testing::slow_light_loads, r.log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  for (int p = 0; p < 2; ++p) {
    const ParameterEstimate& e = res.parameters[p];
    EXPECT_TRUE(e.ci_low <= truths[p] && truths[p] <= e.ci_high)
        << e.name << " " << e.value << " +- " << e.std << " [" << e.ci_low << ", " << e.ci_high
        << "]";
  }
}

// The slow light five-bar under its own slow loads for 3 s with coarse encoders (angle noise
// 1e-4 rad, torque noise 0.02 N m): the window walk stopped at a half-window of 33 samples,
// where the angle noise's bias it predicted was 0.17 std, and the fit exited 0 with coulomb 3.3
// std low and viscous 3 std high (seed 1; seed 5: 3.2, 3.1). The bias predicted again from that
// window's own rates is 1.4-1.8 std and the friction refitted at 50 samples moves against it,
// so the window moves up: the fit is either not to be used or within 2.5 std of the truth.
TEST(Window, CoarseEncodersOnASlowMotionMoveTheWindowUp) {
  const Params<double> truth = testing::slow_light_params();
  const double truths[2] = {0.2, 0.05};
  for (std::uint64_t seed : {1, 5}) {
    const SynthOptions so = testing::log_options(3.0, kTorqueNoise, 1e-4, seed);
    const SynthResult r =
        synthesize_log(truth, testing::slow_light_loads, testing::slow_light_start(), so);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    const IdentifyResult res = identify(truth, testing::slow_light_loads, r.log, IdentifyOptions{});
    ASSERT_TRUE(res.status.ok()) << res.status.message;
    if (!res.unusable.empty()) continue;
    for (int p = 0; p < 2; ++p) {
      const ParameterEstimate& e = res.parameters[p];
      EXPECT_LE(std::abs(e.value - truths[p]), 2.5 * e.std)
          << "seed " << seed << ": " << e.name << " " << e.value << " +- " << e.std
          << ", half-window " << res.sg_half_window << " samples";
    }
  }
}

// The same mechanism with a lighter crank under slower loads (3 s, angle noise 3e-4 rad): the
// window stays at 27 samples, where the bias predicted from its own rates is 2.6-2.7 std but the
// refit at 41 samples does not confirm it (it moves 0.07-1.4 std), and the walk's own
// prediction had taken off a fifth of it: coulomb 3.9 and 3.7 std low, viscous 3.4 std high,
// exit 0 (seeds 15, 25). The bias predicted at the window's own rates is taken off there.
TEST(Window, ABiasTheWalkUnderstatesIsTakenOffAtTheChosenWindow) {
  Params<double> truth = testing::slow_light_params();
  truth.links[0].inertia = 0.012;
  const auto loads = [](double t) -> Loads<double> {
    return {0.05 + 0.4 * std::sin(1.5 * t), -0.05 + 0.4 * std::cos(1.1 * t), 0.025, 1.0, 1.0};
  };
  const double truths[2] = {0.2, 0.05};
  for (std::uint64_t seed : {15, 25}) {
    const SynthOptions so = testing::log_options(3.0, kTorqueNoise, 3e-4, seed);
    const SynthResult r = synthesize_log(truth, loads, testing::slow_light_start(), so);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    const IdentifyResult res = identify(truth, loads, r.log, IdentifyOptions{});
    ASSERT_TRUE(res.status.ok()) << res.status.message;
    ASSERT_TRUE(res.unusable.empty()) << "seed " << seed << ": " << res.unusable;
    for (int p = 0; p < 2; ++p) {
      const ParameterEstimate& e = res.parameters[p];
      EXPECT_LE(std::abs(e.value - truths[p]), 2 * e.std)
          << "seed " << seed << ": " << e.name << " " << e.value << " +- " << e.std
          << ", half-window " << res.sg_half_window << " samples";
    }
  }
}

}  // namespace
}  // namespace fivebar::identification
