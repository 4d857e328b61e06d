// The four-bar's tasks (a pose is the crank angle th1 or one coordinate of the coupler point P)
// and one task's run, as run_task does it for the five-bar. Light: it does not include the
// four-bar's model (four_bar.h); its problem is in four_bar_problem.h.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fivebar/model/four_bar_params.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/tasks.h"

namespace fivebar::trajectory {

/// A four-bar task resolved for one design: the crank angle at both ends, or why it cannot be
/// done (statuses as ResolvedTask's).
struct ResolvedFourBarTask {
  std::string status = "ok";
  std::string message;
  double start = 0, goal = 0;  ///< theta1 [rad]
  bool ok() const { return status == "ok"; }
};

/// Resolves a four-bar task: a pose is theta1 or one coordinate of P (x or y; Pose::single) in
/// the scene's assembly. A coordinate of P is
/// reached at several crank angles in general; the one taken is the nearest (modulo 2 pi) to the
/// reference: the scene's initial theta1 for the start, the start's for the goal. Poses closer
/// than `singular_margin` to a singular one (|sin(th3 - th2)|) are refused.
ResolvedFourBarTask resolve_four_bar_task(const FourBarParams& params, const TaskSpec& task,
                                          double initial_theta1, double singular_margin);

/// Point P [m] at crank angle theta1; false when the four-bar cannot close there.
bool four_bar_point_p(const FourBarParams& params, double theta1, std::array<double, 2>* p);

/// Optimizes one four-bar task, as run_task does for the five-bar: the minimum-jerk baseline,
/// the solve on options.problem.control_points control points under the smoothed law, then the
/// refinement levels (options.refine.control_points, the smoothed law of the first solve), the
/// checks on the dense grid, and the validation (the optimal torques simulated forward, the miss
/// of P at the end). The result's start and goal hold theta1 in [0] (and NaN in [1]).
/// `loads` gives M3, F, F_angle (M1 ignored).
TaskResult run_four_bar_task(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                             const TaskSpec& task, double initial_theta1,
                             const BatchOptions& options);

/// The rows of trajectory.csv (TrajectoryProblemT::rows) of a solved four-bar result's motion,
/// or with `baseline` of its minimum-jerk motion, on a grid of step `step` [s].
Status four_bar_rows(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                     const TaskResult& result, const BatchOptions& options, bool baseline,
                     double step, std::vector<sim::Row>* out);

}  // namespace fivebar::trajectory
