// Group actuator of identification: the layout, the torque offset and the motors'
// load-independent friction recovered with the joint friction, and the identifiability report
// when they cannot be separated.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "random_samples.h"

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

}  // namespace
}  // namespace fivebar::identification
