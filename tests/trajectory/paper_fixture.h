// The paper scene as the trajectory tests use it: its tasks file, loads and initial pose.
#pragma once

#include <cmath>
#include <string>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::trajectory::testing {

inline const std::string kTasks =
    std::string(FIVEBAR_SOURCE_DIR) + "/datasets/tasks/paper_tasks.yaml";

// loads of the paper scene other than the motors: M3 = 6 N m, F = 50 N at pi/2 from link 3
inline sim::LoadFunction paper_loads() {
  return [](double) {
    Loads<double> L;
    L.M3 = 6.0;
    L.F = 50.0;
    L.F_angle = M_PI / 2;
    return L;
  };
}

inline sim::Initial paper_initial() { return {M_PI / 2, M_PI / 2, 0.0, 0.0}; }

}  // namespace fivebar::trajectory::testing
