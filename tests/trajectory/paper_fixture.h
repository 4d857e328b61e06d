// The paper scene as the trajectory tests use it: its tasks, loads and initial pose.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/tasks.h"
#include "paper.h"

namespace fivebar::trajectory::testing {

// the tasks of datasets/tasks/paper_tasks.yaml, as structs (the library takes structs; the file
// itself is read by the command line, tested in tests/apps/test_tasks_file.cc)
inline std::vector<TaskSpec> paper_tasks() {
  const Pose rest{false, M_PI / 2, M_PI / 2};
  return {{"swing_left", 0.5, rest, {false, 2.6, 2.2}, 30.0},
          {"swing_right", 0.5, rest, {false, 0.7, 0.6}, 30.0},
          {"reach_right", 0.5, rest, {true, 0.20, 0.22}, 20.0},
          {"reach_left", 0.5, rest, {true, 0.12, 0.24}, 25.0},
          {"lower_fast", 0.3, {true, 0.166, 0.268}, {true, 0.16, 0.21}, 20.0}};
}

// loads of the paper scene other than the motors: M3 = 6 N m, F = 50 N at pi/2 from link 3
inline sim::LoadFunction paper_loads() {
  return [](double) { return fivebar::testing::paper_static_loads(); };
}

using fivebar::testing::paper_initial;

}  // namespace fivebar::trajectory::testing
