// Group actuator of identification: the layout, the torque offset and the motors'
// load-independent friction recovered with the joint friction, and the identifiability report
// when they cannot be separated.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "model_check_causes.h"
#include "random_samples.h"
#include "synthetic_log.h"

namespace fivebar::identification {
namespace {

using testing::paper_loads;

TEST(ActuatorLayout, NamesSizesBoundsAndRoundTrip) {
  ParameterLayout layout;
  std::string bad;
  ASSERT_TRUE(parse_groups("friction,inertia,actuator", &layout, &bad));
  EXPECT_TRUE(layout.inertia);
  EXPECT_TRUE(layout.actuator);
  EXPECT_EQ(layout.size(), 2 + 16 + 6);
  EXPECT_EQ(layout.names()[18], "offset_1");
  EXPECT_EQ(layout.names()[21], "actuator_coulomb_2");
  EXPECT_EQ(layout.names()[23], "actuator_viscous_2");
  EXPECT_FALSE(layout.is_inertial(18));
  EXPECT_TRUE(layout.is_inertial(17));
  EXPECT_EQ(layout.unit(18), "N m");
  EXPECT_EQ(layout.unit(22), "N m s/rad");
  EXPECT_LT(layout.lower_bound(18), -1e300);  // offsets are signed
  EXPECT_EQ(layout.lower_bound(20), 0.0);
  Params<double> truth = paper_params();
  truth.actuators.offset = {0.05, -0.03};
  truth.actuators.coulomb = {0.02, 0.04};
  truth.actuators.viscous = {0.001, 0.002};
  const std::vector<double> x = layout.extract(truth);
  Params<double> p = paper_params();
  layout.apply(x.data(), &p);
  EXPECT_EQ(p.actuators.offset, truth.actuators.offset);
  EXPECT_EQ(p.actuators.coulomb, truth.actuators.coulomb);
  EXPECT_EQ(p.actuators.viscous, truth.actuators.viscous);
  EXPECT_FALSE(parse_groups("friction,actuators", &layout, &bad));
  EXPECT_EQ(bad, "actuators");
  // identify and excite read --estimate alike: a group twice is refused, not silently merged
  EXPECT_FALSE(parse_groups("friction,friction", &layout, &bad));
  EXPECT_EQ(bad, "friction");
  EXPECT_TRUE(parse_groups("inertia", &layout, &bad));  // friction is implied for identify
  EXPECT_TRUE(layout.inertia);
}

/// A multisine log of the paper mechanism `truth` (rates logged): both cranks reverse, which
/// the paper's own loads do not do for crank 1.
TorqueLog actuator_log(const Params<double>& truth, double duration, std::uint64_t seed) {
  return testing::rated_log(truth, duration, seed, "actuator.csv", true);
}

Params<double> actuator_truth() {
  Params<double> p = paper_params();
  p.actuators.offset = {0.05, 0.0};
  p.actuators.coulomb = {0.02, 0.02};  // both cranks reverse on the multisine log (with 0.03
  p.actuators.viscous = {0.001, 0.001};  // at O or more viscous friction, crank 2 does not)
  return p;
}

TEST(ActuatorRecovery, OffsetAndMotorFrictionWithTheJointFriction) {
  const TorqueLog log = actuator_log(actuator_truth(), 4.0, 5);
  IdentifyOptions opt;
  opt.estimate_delay = false;
  // without the group, the offset and the motor friction bias the joint friction
  const IdentifyResult plain = identify(paper_params(), paper_loads, log, opt);
  ASSERT_TRUE(plain.status.ok()) << plain.status.message;
  EXPECT_GT(std::abs(plain.parameters[0].value - 0.12), 0.01 * 0.12);
  opt.layout.actuator = true;
  const IdentifyResult res = identify(paper_params(), paper_loads, log, opt);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  ASSERT_EQ(res.parameters.size(), 8u);
  const double truth[] = {0.12, 0.02, 0.05, 0.0, 0.02, 0.02, 0.001, 0.001};
  for (int i = 0; i < 8; ++i) {
    const ParameterEstimate& p = res.parameters[i];
    ASSERT_TRUE(std::isfinite(p.std)) << p.name;
    EXPECT_LT(std::abs(p.value - truth[i]), 3.5 * p.std) << p.name << " " << p.value << " +- " << p.std;
  }
  EXPECT_NEAR(res.parameters[0].value, 0.12, 0.01 * 0.12);
  EXPECT_NEAR(res.parameters[2].value, 0.05, 0.01);
  EXPECT_EQ(res.fitted.actuators.offset[0], res.parameters[2].value);
  for (int j = 0; j < 2; ++j) {
    EXPECT_LT(res.rms_torque_residual[j], 1.2 * res.residual_noise_floor[j]);
  }
}

/// True when a warning says that the log cannot separate `name` from something.
bool cannot_separate(const IdentifyResult& r, const std::string& name) {
  for (const std::string& w : r.warnings) {
    if (w.find("cannot separate") != std::string::npos && w.find(name) != std::string::npos) {
      return true;
    }
  }
  return false;
}

// The offset and the motor's Coulomb friction are separable only where the crank reverses
// (sign(w1) changes). The multisine log reverses both cranks: no warning. On the paper's own
// loads crank 1 turns one way only, and the identifiability report says that offset_1 and
// actuator_coulomb_1 are one number.
TEST(ActuatorIdentifiability, ReportedWhenTheCrankNeverReverses) {
  IdentifyOptions opt;
  opt.estimate_delay = false;
  opt.layout.actuator = true;
  const IdentifyResult good =
      identify(paper_params(), paper_loads, actuator_log(actuator_truth(), 4.0, 6), opt);
  ASSERT_TRUE(good.status.ok()) << good.status.message;
  EXPECT_FALSE(cannot_separate(good, "offset_1"));
  const TorqueLog one_way = testing::rated_log(actuator_truth(), 2.0, 6, "one_way.csv");
  ASSERT_GT(one_way.size(), 1000);
  const IdentifyResult flat = identify(paper_params(), paper_loads, one_way, opt);
  EXPECT_TRUE(cannot_separate(flat, "offset_1")) << flat.status.message;
  EXPECT_TRUE(cannot_separate(flat, "actuator_coulomb_1")) << flat.status.message;
}

// The model check's columns on the motors' friction (stages::motor_friction_columns) are the
// residual's derivatives in the motors' coefficients, which it adds to its own drive's torque
// alone, on a mechanism other than the paper's, with exact and smoothed Coulomb signs, and 0 on a
// crank held by the rest rule (no motor torque there)
TEST(MotorFrictionColumns, AreTheResidualsDerivativesInTheMotorsCoefficients) {
  Params<double> scene = paper_params();
  scene.links[1].mass *= 1.3;
  scene.links[2].length *= 0.9;
  scene.actuators.coulomb = {0.03, 0.01};
  std::vector<Sample> samples = testing::random_samples(scene, 12, 21);
  Sample held = samples.front();
  held.w1 = held.a1 = 0.0;  // crank 1 at rest
  samples.push_back(held);
  const ParameterLayout layout;
  EvalOptions eval;
  eval.rest_acceleration = 1e-9;  // the rest rule holds crank 1 of `held`
  constexpr double h = 1e-3;
  int checked = 0;
  for (double smoothing : {0.0, 0.05}) {
    scene.friction.smoothing_velocity = smoothing;
    const std::vector<double> x = layout.extract(scene);
    for (const Sample& s : samples) {
      double r0[2];
      ASSERT_TRUE(InverseDynamicsResidual(scene, layout, s, eval)(x.data(), r0));
      for (int a = 0; a < kActuators; ++a) {
        const Eigen::Vector2d d = stages::motor_friction_columns(
            scene.friction, eval, a == 0 ? s.w1 : s.w2, a == 0 ? s.a1 : s.a2);
        for (int term = 0; term < 2; ++term) {
          Params<double> moved = scene;
          (term == 0 ? moved.actuators.coulomb : moved.actuators.viscous)[a] += h;
          double r1[2];
          ASSERT_TRUE(InverseDynamicsResidual(moved, layout, s, eval)(x.data(), r1));
          for (int c = 0; c < kActuators; ++c) {
            EXPECT_NEAR((r1[c] - r0[c]) / h, c == a ? d(term) : 0.0, 1e-8)
                << "sample t " << s.t << " actuator " << a << " term " << term << " channel " << c;
          }
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 2 * 13 * 4);
  const Eigen::Vector2d at_rest = stages::motor_friction_columns(scene.friction, eval, 0.0, 0.0);
  EXPECT_EQ(at_rest, Eigen::Vector2d::Zero());
}

// A log whose motors have Coulomb friction (0.05 N m each) that the fit leaves out (--estimate
// friction alone): it was blamed on the torque sensors' zeros; the model check names the motors'
// friction, reads it, and the fit is unusable where it moves the friction. With the actuator
// group the same log fits.
TEST(MotorFriction, LeftOutOfTheFitIsNamed) {
  Params<double> truth = paper_params();
  truth.actuators.coulomb = {0.05, 0.05};
  const TorqueLog log = actuator_log(truth, 4.0, 3);
  IdentifyOptions opt;
  opt.estimate_delay = false;
  const IdentifyResult plain = identify(paper_params(), paper_loads, log, opt);
  ASSERT_TRUE(plain.status.ok()) << plain.status.message;
  bool named = false;
  for (const std::string& w : plain.warnings) {
    named = named || (w.find("with the motors' friction free") != std::string::npos &&
                      w.find("actuator_coulomb_1 0.0") != std::string::npos);
    EXPECT_EQ(w.find("a torque sensor's zero may be off"), std::string::npos) << w;
  }
  EXPECT_TRUE(named);
  EXPECT_NE(plain.unusable.find("motors'"), std::string::npos) << plain.unusable;
  opt.layout.actuator = true;
  const IdentifyResult fitted = identify(paper_params(), paper_loads, log, opt);
  ASSERT_TRUE(fitted.status.ok()) << fitted.status.message;
  EXPECT_TRUE(fitted.unusable.empty()) << fitted.unusable;
  for (const IdentifyResult::MisfitCause& c : fitted.model_check) {
    EXPECT_NE(c.name, "motor_friction");  // fitted: not a candidate cause
  }
}

// The same friction on a 6 s angles-only log fitted per joint: the model check at the fit's
// window names the motors (read 0.05 N m each), and a check at a smaller window, where the
// motors' evidence is not predicted from the model causes', does not turn it into the
// smoothing's error (it did, and the fit passed with coulomb_5 13 std off)
TEST(MotorFriction, LeftOutOfAPerJointFitFromAnglesIsNamed) {
  Params<double> truth = paper_params();
  truth.actuators.coulomb = {0.05, 0.05};
  SynthOptions so = ::fivebar::testing::log_options(6.0, 0.02, 1e-5, 3);
  so.multisine = true;
  SynthResult r = synthesize_log(truth, paper_loads, {M_PI / 2, M_PI / 2, 0, 0}, so);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  r.log.path = "motors_angles.csv";
  IdentifyOptions opt;
  opt.estimate_delay = false;
  opt.layout.per_joint = true;
  const IdentifyResult res = identify(paper_params(), paper_loads, r.log, opt);
  ASSERT_TRUE(res.status.ok()) << res.status.message;
  EXPECT_NE(res.unusable.find("motors'"), std::string::npos) << res.unusable;
}

}  // namespace
}  // namespace fivebar::identification
