// Four-bar scenes (mechanism.type four_bar): the shipped reference scenes read as the tests'
// parameters, and every mix-up with the five-bar's schema fails naming the key and the type.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fivebar/io/errors.h"
#include "fivebar/io/scene.h"

namespace fivebar::io {
namespace {

using ::testing::HasSubstr;

const std::string kCrankRocker =
    std::string(FIVEBAR_SOURCE_DIR) + "/datasets/reference/four_bar/crank_rocker.yaml";

const std::string kFourBar = R"yaml(mechanism:
  type: four_bar
  ground_length: 0.30
  links:
    - {length: 0.08, mass: 0.5, inertia: 0.0003, com_offset: 0.04}
    - {length: 0.28, mass: 1.0, inertia: 0.0065, com_offset: 0.14}
    - {length: 0.20, mass: 0.8, inertia: 0.0027, com_offset: 0.10}
  point_p: 0.18
friction: {model: coulomb_viscous, pin_radius: 0.01, coulomb: [0.1, 0.2, 0.3, 0.4], viscous: 0.02}
loads: {M1: "0.9", M3: "0.2", F: "5"}
initial: {theta1: 1.5707963267948966}
)yaml";

std::string with(const std::string& from, const std::string& to, std::string text = kFourBar) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

void expect_error(const std::string& yaml, const std::vector<std::string>& sets,
                  const std::string& key, const std::string& reason, bool four_bar_ok = true) {
  try {
    parse_scene(yaml, "bad.yaml", sets, four_bar_ok);
    ADD_FAILURE() << "no InputError; expected " << key << ": " << reason;
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_THAT(e.reason(), HasSubstr(reason)) << e.what();
  }
}

TEST(FourBarScene, TheShippedReferenceSceneReadsAsItsParameters) {
  const Scene s = load_scene(kCrankRocker, {}, true);
  EXPECT_EQ(s.type, MechanismType::kFourBar);
  EXPECT_EQ(s.four_bar.ground_length, 0.30);
  EXPECT_EQ(s.four_bar.links[1].com_angle, 0.1);
  EXPECT_EQ(s.four_bar.point_p, 0.18);
  EXPECT_EQ(s.four_bar.friction.law, FrictionLaw::kCoulombViscous);
  for (int k = 0; k < 4; ++k) EXPECT_EQ(s.four_bar.friction.coulomb[k], 0.12) << k;
  EXPECT_EQ(s.four_bar.friction.coulomb[4], 0.0);  // no fifth joint
  EXPECT_EQ(friction_of(s).pin_radius[4], 0.0);
  EXPECT_EQ(s.initial.theta1, 1.5707963267948966);
  EXPECT_EQ(s.M1, "0.9 + 0.6*sin(4*pi*t)");
}

TEST(FourBarScene, PerJointListsHaveFourEntries) {
  const Scene s = parse_scene(kFourBar, "ok.yaml", {"friction.coulomb.3=0.5"}, true);
  EXPECT_EQ(s.four_bar.friction.coulomb[2], 0.3);
  EXPECT_EQ(s.four_bar.friction.coulomb[3], 0.5);
  expect_error(with("coulomb: [0.1, 0.2, 0.3, 0.4]", "coulomb: [0.1, 0.2, 0.3, 0.4, 0.5]"), {},
               "friction.coulomb", "expected 1 or 4 numbers (O, B, C, D0), got 5");
  expect_error(kFourBar, {"friction.coulomb.4=0.1"}, "friction.coulomb.4",
               "no such joint in --set friction.coulomb.4=0.1 (joints are numbered 0 to 3");
}

TEST(FourBarScene, FiveBarKeysFailNamingTheKeyAndTheType) {
  expect_error(with("M3: \"0.2\"", "M2: \"1\", M3: \"0.2\""), {}, "loads.M2",
               "is a five-bar key, not one of mechanism.type four_bar");
  expect_error(with("{theta1: 1.5707963267948966}", "{theta1: 1.57, theta2: 1.0}"), {},
               "initial.theta2", "mechanism.type four_bar");
  expect_error(kFourBar + "actuators: {M2: {winding_resistance: 1}}\n", {},
               "actuators.M2", "mechanism.type four_bar");
  expect_error(kFourBar, {"actuators.M2.coulomb=0.1"}, "actuators.M2.coulomb",
               "is a five-bar key, not one of mechanism.type four_bar");
  // the crank's motor M1 is the four-bar's: its friction and sensor offset (entry 0 of the
  // actuators), written back by scene_to_yaml
  const Scene m = parse_scene(
      kFourBar, "ok.yaml",
      {"actuators.M1.coulomb=0.04", "actuators.M1.viscous=0.005", "actuators.M1.offset=0.03"},
      /*four_bar_ok=*/true);
  EXPECT_EQ(m.four_bar.actuators.coulomb[0], 0.04);
  EXPECT_EQ(m.four_bar.actuators.viscous[0], 0.005);
  EXPECT_EQ(m.four_bar.actuators.offset[0], 0.03);
  EXPECT_EQ(m.four_bar.actuators.coulomb[1], 0.0);
  const Scene back = parse_scene(scene_to_yaml(m), "back.yaml", {}, /*four_bar_ok=*/true);
  EXPECT_EQ(back.four_bar.actuators.coulomb[0], 0.04);
  EXPECT_EQ(back.four_bar.actuators.offset[0], 0.03);
  // the one motor's winding data is the four-bar's (the optimizer's winding heat)
  const Scene s = parse_scene(kFourBar, "ok.yaml",
                              {"actuators.M1.winding_resistance=2",
                               "actuators.M1.torque_constant=0.5"},
                              /*four_bar_ok=*/true);
  EXPECT_TRUE(s.windings.present(1));
  EXPECT_DOUBLE_EQ(s.windings.heat_coefficient(0), 8.0);
  expect_error(kFourBar, {"actuators.M1.winding_resistance=2"}, "actuators.M1.torque_constant",
               "");
  expect_error(kFourBar, {"mechanism.links.3.mass=1"}, "mechanism.links.3",
               "no such link in --set mechanism.links.3.mass=1 (links are numbered 0 to 2)");
  expect_error(with("  type: four_bar\n", ""), {}, "mechanism.links",
               "; mechanism.type five_bar has 4 (five_bar 4, four_bar 3)");
  expect_error(with("four_bar", "six_bar"), {}, "mechanism.type",
               "expected five_bar or four_bar, got 'six_bar'");
}

TEST(FourBarScene, CommandsThatRunFiveBarsOnlySaySo) {
  expect_error(kFourBar, {}, "mechanism.type", "this command runs five-bars only so far", false);
}

TEST(FourBarScene, AStartThatCannotAssembleOrIsSingularFailsOnInitial) {
  expect_error(with("{length: 0.20, mass: 0.8", "{length: 0.02, mass: 0.8"), {}, "initial",
               "four-bar cannot assemble at theta1=1.5708");
  // coupler and rocker aligned: |BD0| = l2 + l3
  const std::string toggle = with("ground_length: 0.30", "ground_length: 0.5599");
  expect_error(toggle, {"initial.theta1=0", "simulation.singular_margin=0.1"}, "initial",
               "too close to a singular configuration (coupler and rocker aligned)");
}

}  // namespace
}  // namespace fivebar::io
