// Identification and samples at rest. A log that holds the start pose still before it
// moves: the held samples carry a static friction torque (anywhere within +-mu_s r N), and their
// logged rates are rounding noise of one sign (-1.5e-14 rad/s, as measured). The rest
// rule leaves them out; with the exact rule (only w = 0 at rest) their sign picks full kinetic
// friction at every joint, 0.11 N m off the held torques, and biases the Coulomb coefficient.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "fivebar/model/rest.h"

#include "paper.h"

namespace fivebar::identification {
namespace {

constexpr double kStdBound = 4.0;      // |error| / std, as in test_recovery.cc
constexpr double kTorqueNoise = 0.02;  // N m, as in datasets/logs
constexpr int kHeld = 1000;            // samples held still (1 s at 1 kHz)

using testing::paper_loads;

// 1 s held at the start pose with the frictionless equilibrium torques, then 2 s of the paper
// scene's motion (rates and accelerations logged, torque noise on both parts)
TorqueLog held_then_moving(const Params<double>& truth) {
  SynthOptions so;
  so.duration = 2.0;
  so.torque_noise = kTorqueNoise;
  so.with_rates = true;
  so.seed = 14;
  const SynthResult moving =
      synthesize_log(truth, paper_loads, testing::paper_initial(), so);
  EXPECT_TRUE(moving.status.ok()) << moving.status.message;
  Holding<double> h;
  EXPECT_TRUE(holding_torques(truth, paper_loads(0), M_PI / 2, M_PI / 2, EvalOptions{}, &h).ok());
  TorqueLog log;
  log.path = "held_then_moving.csv";
  log.has_rates = log.has_accels = true;
  std::mt19937_64 rng(14);
  std::normal_distribution<double> noise(0.0, kTorqueNoise);
  const double dt = 1e-3;
  for (int i = 0; i < kHeld; ++i) {
    for (auto* v : {&log.theta1, &log.theta2}) v->push_back(M_PI / 2);
    for (auto* v : {&log.omega1, &log.omega2}) v->push_back(-1.5e-14);
    for (auto* v : {&log.alpha1, &log.alpha2}) v->push_back(0.0);
    log.t.push_back(i * dt);
    log.tau1.push_back(h.M1 + noise(rng));
    log.tau2.push_back(h.M2 + noise(rng));
  }
  const TorqueLog& m = moving.log;
  for (int i = 0; i < m.size(); ++i) {
    log.t.push_back(kHeld * dt + m.t[i]);
    log.theta1.push_back(m.theta1[i]);
    log.theta2.push_back(m.theta2[i]);
    log.omega1.push_back(m.omega1[i]);
    log.omega2.push_back(m.omega2[i]);
    log.alpha1.push_back(m.alpha1[i]);
    log.alpha2.push_back(m.alpha2[i]);
    log.tau1.push_back(m.tau1[i]);
    log.tau2.push_back(m.tau2[i]);
  }
  log.lines.resize(log.t.size(), 0);
  return log;
}

TEST(RestSamples, HeldSamplesAreLeftOutAndDoNotBiasTheFit) {
  const Params<double> truth = paper_params();
  // the scene's loads after the hold are those of t - 1 s; M3 and F are constant, M1, M2 unused
  const TorqueLog log = held_then_moving(truth);
  const IdentifyResult res = identify(truth, paper_loads, log, IdentifyOptions{});
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  // at the breakaway the logged acceleration steps from 0, the logged rate has a kink and the
  // torques step by 0.8 N m: none of them is a glitch (24 samples were rejected as glitches
  // before the kink and step-side checks of condition.cc), and every held sample is at rest
  EXPECT_TRUE(res.glitches.empty()) << res.glitches.size() << " glitches, the first on line "
                                    << res.glitches.front().line;
  EXPECT_GE(res.samples_at_rest, kHeld);
  EXPECT_LT(res.samples_at_rest, kHeld + 20);  // the moving part is not at rest
  for (const ParameterEstimate& p : res.parameters) {
    const double t = p.name == "coulomb" ? 0.12 : 0.02;
    EXPECT_LT(std::abs(p.value - t), kStdBound * p.std) << p.name << " = " << p.value;
  }
  // the exact rule: the held samples' rounding noise picks the friction direction
  IdentifyOptions exact;
  exact.rest_rate_threshold = 0.0;
  exact.rest_acceleration_threshold = 0.0;
  const IdentifyResult biased = identify(truth, paper_loads, log, exact);
  ASSERT_TRUE(biased.status.ok()) << biased.status.message;
  EXPECT_EQ(biased.samples_at_rest, 0);
  EXPECT_GT(std::abs(biased.parameters[0].value - 0.12), kStdBound * biased.parameters[0].std)
      << "coulomb = " << biased.parameters[0].value;
}

}  // namespace
}  // namespace fivebar::identification
