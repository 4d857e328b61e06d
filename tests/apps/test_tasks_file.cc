// Tasks files (apps/src/tasks_file.cc): the YAML of interfaces.md read into task structs, and
// every malformed file named by file, key and reason.
#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fivebar/io/errors.h"
#include "fivebar/io/tasks_file.h"

namespace fivebar::io {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TEST(Tasks, MalformedFilesNameFileKeyAndReason) {
  const std::string ok_task =
      "  - {name: a, duration: 0.5, start: {theta1: 1.5, theta2: 1.5}, goal: {x: 0.2, y: 0.22}}\n";
  auto parse = [](const std::string& text) { return parse_tasks(text, "t.yaml"); };
  EXPECT_THAT([&] { parse("tasks: [\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml: (yaml): line")));
  EXPECT_THAT([&] { parse("task: []\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml: task: unknown key")));
  EXPECT_THAT([&] { parse("tasks: []\n"); },
              ThrowsMessage<InputError>(HasSubstr("t.yaml: tasks: expected a non-empty")));
  EXPECT_THAT([&] { parse("tasks:\n" + ok_task + ok_task); },
              ThrowsMessage<InputError>(HasSubstr("tasks.1.name: duplicate task name 'a'")));
  EXPECT_THAT([&] { parse("tasks:\n  - {name: a, start: {x: 0, y: 0}, goal: {x: 0, y: 0}}\n"); },
              ThrowsMessage<InputError>(HasSubstr("tasks.0.duration: missing")));
  EXPECT_THAT(
      [&] {
        parse("tasks:\n  - {name: a, duration: fast, start: {x: 0, y: 0}, goal: {x: 0, y: 0}}\n");
      },
      ThrowsMessage<InputError>(HasSubstr("tasks.0.duration: expected a number, got 'fast'")));
  EXPECT_THAT(
      [&] {
        parse("tasks:\n  - {name: a, duration: 1, start: {x: 0, theta2: 0}, goal: {x: 0, y: 0}}\n");
      },
      ThrowsMessage<InputError>(HasSubstr("tasks.0.start: expected {theta1")));
  EXPECT_THAT(
      [&] {
        parse("tasks:\n  - {name: a/b, duration: 1, start: {x: 0, y: 0}, goal: {x: 0, y: 0}}\n");
      },
      ThrowsMessage<InputError>(HasSubstr("tasks.0.name: 'a/b' is not usable")));
  EXPECT_THAT(
      [&] { load_tasks("/nonexistent/tasks.yaml"); },
      ThrowsMessage<InputError>(HasSubstr("/nonexistent/tasks.yaml: --tasks: cannot open")));
  EXPECT_EQ(parse("tasks:\n" + ok_task).size(), 1u);
  // crank angles in degrees (they failed the optimization with a friction-loop message)
  EXPECT_THAT(
      [&] {
        parse("tasks:\n  - {name: a, duration: 1, start: {theta1: 1.5, theta2: 1.5}, "
              "goal: {theta1: 150, theta2: 80}}\n");
      },
      ThrowsMessage<InputError>(HasSubstr("tasks.0.goal.theta1: 150 rad is beyond two turns: degrees?")));
}

TEST(Tasks, FourBarPosesHaveOneCoordinate) {
  auto four = [](const std::string& start, const std::string& goal) {
    return parse_tasks("tasks:\n  - {name: a, duration: 0.5, start: " + start + ", goal: " + goal +
                           "}\n",
                       "t.yaml", /*four_bar=*/true);
  };
  const auto tasks = four("{theta1: 1.5}", "{y: 0.25}");
  ASSERT_EQ(tasks.size(), 1u);
  EXPECT_STREQ(tasks[0].start.single(), "theta1");
  EXPECT_EQ(tasks[0].start.value(), 1.5);
  EXPECT_STREQ(tasks[0].goal.single(), "y");
  EXPECT_EQ(tasks[0].goal.value(), 0.25);
  EXPECT_THAT([&] { four("{theta1: 1.5, theta2: 1.5}", "{x: 0.1}"); },
              ThrowsMessage<InputError>(HasSubstr(
                  "t.yaml: tasks.0.start.theta2: a five_bar key: a mechanism.type four_bar")));
  EXPECT_THAT([&] { four("{theta1: 1.5}", "{x: 0.1, y: 0.2}"); },
              ThrowsMessage<InputError>(HasSubstr("tasks.0.goal: two coordinates (x, y)")));
  EXPECT_THAT([&] { four("{theta1: 150}", "{x: 0.1}"); },
              ThrowsMessage<InputError>(HasSubstr("tasks.0.start.theta1: 150 rad is beyond")));
  // the reverse: a one-coordinate pose on a five-bar
  EXPECT_THAT(
      [&] {
        parse_tasks("tasks:\n  - {name: a, duration: 0.5, start: {theta1: 1.5}, goal: {x: 0.1, "
                    "y: 0.2}}\n",
                    "t.yaml");
      },
      ThrowsMessage<InputError>(HasSubstr(
          "tasks.0.start.theta1: one coordinate is a four_bar pose: a mechanism.type five_bar")));
  const auto shipped = load_tasks(
      std::string(FIVEBAR_SOURCE_DIR) + "/datasets/tasks/four_bar_tasks.yaml", /*four_bar=*/true);
  EXPECT_EQ(shipped.size(), 3u);
}

TEST(Tasks, ShippedFileReadsIntoStructs) {
  const auto tasks = load_tasks(std::string(FIVEBAR_SOURCE_DIR) + "/datasets/tasks/paper_tasks.yaml");
  ASSERT_EQ(tasks.size(), 5u);
  EXPECT_EQ(tasks[2].name, "reach_right");
  EXPECT_TRUE(tasks[2].goal.cartesian);
  EXPECT_EQ(tasks[2].goal.a, 0.20);
  EXPECT_EQ(tasks[2].torque_limit, 20.0);
  EXPECT_EQ(tasks[4].duration, 0.3);
  EXPECT_TRUE(tasks[4].start.cartesian);
}

}  // namespace
}  // namespace fivebar::io
