// The paper scene as the trajectory tests use it: its tasks, loads and initial pose.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/problem.h"
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
inline sim::LoadFunction paper_loads() { return fivebar::testing::paper_static_load_function(); }

using fivebar::testing::paper_initial;

// the problem of one paper task (its torque limit, singularity margin 0.1) on a spline of
// `control_points` per joint with `quadrature_points` Gauss-Legendre points per knot span
inline TrajectoryProblem task_problem(const TaskSpec& task, int control_points,
                                      int quadrature_points) {
  const ResolvedTask rt = resolve_task(paper_params(), task, paper_initial(), 0.1);
  if (!rt.ok()) throw std::runtime_error(task.name + ": " + rt.message);
  ProblemOptions po;
  po.torque_limit = task.torque_limit;
  po.quadrature_points = quadrature_points;
  return TrajectoryProblem(paper_params(), paper_loads(),
                           RestToRest(control_points, task.duration, rt.start, rt.goal), po);
}

// the rows at 1 ms of `task` optimized in the paper scene (no validation); a failed solve fails
// the calling test (wrap the call in ASSERT_NO_FATAL_FAILURE)
inline void optimized_rows(const TaskSpec& task, std::vector<sim::Row>* rows) {
  BatchOptions options;
  options.validate = false;
  const TaskResult r = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
  ASSERT_TRUE(r.solved()) << r.message;
  const TrajectoryProblem problem = problem_of(paper_params(), paper_loads(), r, options);
  ASSERT_TRUE(problem.rows(r.x.data(), 1e-3, rows).ok());
}

}  // namespace fivebar::trajectory::testing
