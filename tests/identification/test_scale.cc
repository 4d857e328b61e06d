// identify() at any scale of the mechanism: a MEMS-sized five-bar and four-bar (lengths 1e-3
// times, masses 1e-9 times the reference scenes', torques of 1e-15 N m) identify their friction
// as the reference scenes do. The solver's cost is weighted by the logged torques' mean square
// (torque_cost_weight); unweighted, a cost of 1e-27 left the fit at its start values.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "../model/four_bar_scenes.h"
#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "paper.h"
#include "synthetic_log.h"

namespace fivebar::identification {
namespace {

/// The lengths' and masses' factors of the micro-scale scenes
constexpr double kLength = 1e-3, kMass = 1e-9;
/// the torques' factor: at kLength and kMass (gravity times kLength) the motion under torques
/// times kTorque and forces times kMass * kLength is the reference scene's
constexpr double kTorque = kMass * kLength * kLength;

/// A five-bar's or four-bar's parameters with every length (the pins' radii too) and gravity
/// times kLength, masses times kMass, inertias times kTorque.
template <class P>
P micro(P p) {
  p.ground_length *= kLength;
  p.point_p *= kLength;
  p.gravity *= kLength;
  for (Link<double>& l : p.links) {
    l.length *= kLength;
    l.com_offset *= kLength;
    l.mass *= kMass;
    l.inertia *= kTorque;
  }
  for (double& r : p.friction.pin_radius) r *= kLength;
  return p;
}

/// A four-bar scene's loads at micro scale: torques times kTorque, the force times kMass *
/// kLength.
std::function<FourBarLoads(double)> micro_four_bar_loads(const testing::ReferenceScene& scene) {
  return [loads = scene.loads](double t) {
    FourBarLoads l = loads(t);
    l.M1 *= kTorque, l.M3 *= kTorque, l.F *= kMass * kLength;
    return l;
  };
}

/// Every estimate within 3 std of the truth and within 0.1 std of the reference scene's.
void expect_same_fit(const IdentifyResult& ref, const IdentifyResult& res,
                     const std::vector<double>& truth) {
  ASSERT_TRUE(ref.status.ok()) << ref.status.message;
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_TRUE(res.converged);
  ASSERT_EQ(res.parameters.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    const ParameterEstimate &e = res.parameters[i], &r = ref.parameters[i];
    ASSERT_TRUE(std::isfinite(e.std)) << e.name;
    EXPECT_LT(std::abs(e.value - truth[i]), 3 * e.std) << e.name << " " << e.value;
    EXPECT_LT(std::abs(e.value - r.value), 0.1 * r.std)
        << e.name << " " << e.value << " " << r.value;
    EXPECT_NEAR(e.std / r.std, 1.0, 0.05) << e.name;
  }
}

TEST(IdentifyScale, MicroFiveBarIdentifiesAsThePaperScene) {
  const Params<double> truth = paper_params();
  const auto micro_loads = [](double t) {
    Loads<double> l = paper_loads(t);
    l.M1 *= kTorque, l.M2 *= kTorque, l.M3 *= kTorque, l.F *= kMass * kLength;
    return l;
  };
  const SynthResult ref_log = synthesize_log(truth, paper_loads, testing::paper_initial(),
                                             testing::log_options(2.0, 0.02, 1e-5, 3));
  const SynthResult log = synthesize_log(micro(truth), micro_loads, testing::paper_initial(),
                                         testing::log_options(2.0, 0.02 * kTorque, 1e-5, 3));
  ASSERT_TRUE(ref_log.status.ok() && log.status.ok());
  const IdentifyResult ref = identify(truth, paper_loads, ref_log.log, IdentifyOptions{});
  const IdentifyResult res = identify(micro(truth), micro_loads, log.log, IdentifyOptions{});
  expect_same_fit(ref, res, {0.12, 0.02});
}

TEST(IdentifyScale, MicroCrankRockerIdentifiesAsTheCrankRocker) {
  const testing::ReferenceScene cr = testing::reference_scenes()[0];
  const auto micro_loads = micro_four_bar_loads(cr);
  SynthOptions so = testing::log_options(3.0, 0.02, 1e-5, 1);
  sim::Initial init;
  init.theta1 = cr.th0;
  const SynthResult ref_log = synthesize_log(cr.p, cr.loads, init, so);
  so.torque_noise *= kTorque;
  const SynthResult log = synthesize_log(micro(cr.p), micro_loads, init, so);
  ASSERT_TRUE(ref_log.status.ok() && log.status.ok());
  IdentifyOptions opt;
  opt.layout.joints = kFourBarJoints;
  const IdentifyResult ref = identify(cr.p, cr.loads, ref_log.log, opt);
  const IdentifyResult res = identify(micro(cr.p), micro_loads, log.log, opt);
  expect_same_fit(ref, res, {0.12, 0.02});
}

// The model check at micro scale: a crank-rocker's torque offset (a tenth of the rms torque)
// names the torque sensors as at the reference scale. Its information matrix has an offset
// column in N m beside a gain's of 1e-15 N m torques: tested unscaled, its eigenvalues' ratio
// (1e-30) read as a rank deficiency, the torque readings went unchecked and the inertias were
// named.
TEST(IdentifyScale, MicroCrankRockersTorqueOffsetIsNamed) {
  const testing::ReferenceScene cr = testing::reference_scenes()[0];
  const auto micro_loads = micro_four_bar_loads(cr);
  SynthOptions so = testing::log_options(3.0, 0.02 * kTorque, 1e-5, 1);
  sim::Initial init;
  init.theta1 = cr.th0;
  SynthResult log = synthesize_log(micro(cr.p), micro_loads, init, so);
  ASSERT_TRUE(log.status.ok());
  double rms = 0;
  for (double tau : log.log.tau1) rms += tau * tau / log.log.tau1.size();
  for (double& tau : log.log.tau1) tau += 0.1 * std::sqrt(rms);
  IdentifyOptions opt;
  opt.layout.joints = kFourBarJoints;
  const IdentifyResult res = identify(micro(cr.p), micro_loads, log.log, opt);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_NE(res.unusable.find("torque sensors"), std::string::npos) << res.unusable;
}

}  // namespace
}  // namespace fivebar::identification
