// The truth header of synthetic logs: what synth-log writes, identify reads back under the
// identification's parameter names.
#include <gtest/gtest.h>

#include "fivebar/io/log_truth.h"
#include "fivebar/model/inertial.h"

namespace fivebar::io {
namespace {

TEST(LogTruth, EveryWrittenValueReadsBackUnderItsParameterName) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kStribeck;
  p.friction.coulomb = {0.11, 0.12, 0.13, 0.14, 0.15};
  p.friction.static_coulomb.fill(0.2);
  p.friction.stribeck_velocity.fill(0.5);
  p.actuators.offset = {0.05, -0.01};
  p.actuators.coulomb = {0.03, 0.02};
  std::vector<std::string> comments = {" command: fivebar synth-log ...", " true.broken = a,b"};
  for (const std::string& line : truth_lines(p)) comments.push_back(line);
  std::vector<std::string> unread;
  const LogTruth truth = read_truth(comments, &unread);
  EXPECT_EQ(truth.count("broken"), 0u);
  EXPECT_EQ(unread, std::vector<std::string>{"true.broken: 'a' is not a finite number"});
  EXPECT_TRUE(truth_not_compared(truth, identification::ParameterLayout()).empty());
  ASSERT_EQ(truth.at("coulomb").size(), size_t(kJoints));
  EXPECT_EQ(truth.at("coulomb")[3], 0.14);
  EXPECT_EQ(truth.at("static_coulomb")[0], 0.2);
  EXPECT_EQ(truth.at("inertial")[5], standard_inertial(p)[5]);

  identification::ParameterLayout layout;
  layout.law = FrictionLaw::kStribeck;
  layout.per_joint = true;
  layout.inertia = true;
  layout.actuator = true;
  int checked = 0;
  const std::vector<std::string> names = layout.names();
  for (int i = 0; i < layout.size(); ++i) {
    double v = 0;
    const std::string& name = names[i];
    ASSERT_TRUE(true_value(truth, layout, i, name, &v)) << name;
    if (name == "coulomb_4") {
      EXPECT_EQ(v, 0.14);
    }
    if (name == "offset_2") {
      EXPECT_EQ(v, -0.01);
    }
    if (name == "actuator_coulomb_1") {
      EXPECT_EQ(v, 0.03);
    }
    ++checked;
  }
  EXPECT_GT(checked, 30);
  // shared: no truth when the joints' values differ (their mean is no value a fit should reach)
  layout.per_joint = false;
  double shared = 0;
  EXPECT_FALSE(true_value(truth, layout, 0, "coulomb", &shared));
  ASSERT_TRUE(true_value(truth, layout, 2, "static_coulomb", &shared));  // 0.2 at every joint
  EXPECT_EQ(shared, 0.2);
}

TEST(LogTruth, AFourBarsTruthReadsBackWhole) {
  FourBarParams p;
  p.friction.law = FrictionLaw::kStribeck;
  p.actuators.offset[0] = 0.03;
  std::vector<std::string> unread;
  const LogTruth truth = read_truth(truth_lines(p), &unread);
  EXPECT_TRUE(unread.empty()) << unread.front();
  identification::ParameterLayout layout;
  layout.set_four_bar();
  EXPECT_TRUE(truth_not_compared(truth, layout).empty());
  EXPECT_EQ(truth.at("inertial").size(), size_t(kInertialPerLink * kFourBarLinks));
  EXPECT_EQ(truth.at("offset"), std::vector<double>{0.03});
}

TEST(LogTruth, LinesThatDoNotReadAreNamedWithTheirReason) {
  const std::vector<std::string> comments = {" true.law = coulomb_viscous",
                                             " true.coulomb = 0.1,0.1,0.12x,0.1,0.1",
                                             " true.viscous = 0.02,0.02,0.02,0.02,",
                                             " true.pin_radius = 0.01,0.01,0.01",
                                             " true.offset",
                                             " true.actuator_viscous = 0.001,0.002"};
  std::vector<std::string> unread;
  const LogTruth truth = read_truth(comments, &unread);
  EXPECT_EQ(truth.size(), 1u);
  EXPECT_EQ(truth.at("actuator_viscous")[1], 0.002);
  const std::vector<std::string> expected = {
      "true.coulomb: '0.12x' is not a finite number", "true.viscous: a trailing comma",
      "true.pin_radius: 3 values (1, 2, 4, 5, 12 or 16 are read)", "true.offset: no '='"};
  EXPECT_EQ(unread, expected);
}

TEST(LogTruth, ValuesNoParameterCanBeComparedWithAreNamed) {
  const std::vector<std::string> comments = {
      " true.coulomb = 0.1,0.1,0.1,0.1", " true.cowlomb = 0.3",
      " true.viscous = 0.02,0.02,0.02,0.02,0.02", " true.viscous = 0.9,0.9,0.9,0.9,0.9",
      " true.offset = 0.01,0.02"};
  std::vector<std::string> unread;
  const LogTruth truth = read_truth(comments, &unread);
  EXPECT_EQ(unread, std::vector<std::string>{"true.viscous: given again (the first line is read)"});
  EXPECT_EQ(truth.at("viscous")[0], 0.02);
  identification::ParameterLayout five;
  const std::vector<std::string> expected = {"true.coulomb: 4 values, where this five-bar has 5",
                                             "true.cowlomb: no such parameter"};
  EXPECT_EQ(truth_not_compared(truth, five), expected);
  identification::ParameterLayout four;
  four.set_four_bar();
  const std::vector<std::string> expected4 = {"true.cowlomb: no such parameter",
                                              "true.offset: 2 values, where this four_bar has 1",
                                              "true.viscous: 5 values, where this four_bar has 4"};
  EXPECT_EQ(truth_not_compared(truth, four), expected4);
}

}  // namespace
}  // namespace fivebar::io
