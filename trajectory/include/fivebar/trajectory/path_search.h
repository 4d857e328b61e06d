// A feasible joint-space path between two poses of one design: when the straight
// (minimum-jerk) path leaves the workspace or crosses a singular pose, a shortest path on a grid
// of assemblable, non-singular poses in (theta1, theta2), and a rest-to-rest initial guess along
// it. Every pose test is the model's own closure (solve_kinematics) in the scene's assembly.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/trajectory/bspline.h"

namespace fivebar::trajectory {

struct PathSearchOptions {
  /// grid step in both angles [rad]; larger when the box would hold more than 1e6 poses
  double step = 0.05;
  /// every pose of the path keeps |sin(th4 - th3)| >= margin
  double margin = kMotionSingularMargin;
  /// the search first asks for margin + cushion, to leave the spline fit room to cut corners;
  /// the bare margin is the fallback
  double cushion = 0.1;
  /// the grid box, per joint: [min(start, goal) - reach, max(start, goal) + reach] [rad]
  /// (the optimizer's bounds on the control points); angles are continuous, not wrapped
  double reach = M_PI;
};

/// A polyline in (theta1, theta2) from start to goal, or why there is none.
struct JointPath {
  /// "ok", or "unreachable" (no path in the box at the margin; message says why)
  std::string status = "ok";
  std::string message;
  std::vector<std::array<double, 2>> waypoints;  ///< start, via points, goal [rad]
  double margin = 0;      ///< the coupler-sine margin every segment keeps
  double length = 0;      ///< Euclidean length in (theta1, theta2) [rad]
  int grid_poses = 0;     ///< poses of the grid
  int feasible_poses = 0; ///< of which assemblable and beyond the margin
  bool ok() const { return status == "ok"; }
};

/// |sin(th4 - th3)| at (th1, th2) by the model's closure, or -1 when the mechanism cannot
/// close there.
double coupler_sine(const Params<double>& params, double th1, double th2);

/// True when every pose of the segment a -> b, sampled at most `spacing` apart (ends
/// included), closes with |sin(th4 - th3)| >= margin.
bool segment_clear(const Params<double>& params, const std::array<double, 2>& a,
                   const std::array<double, 2>& b, double margin, double spacing);

/// Shortest path (A* with the Euclidean heuristic on the 8-connected grid) from start to goal
/// through poses with |sin(th4 - th3)| >= margin (+ cushion first), then shortened by dropping
/// every via point whose neighbours see each other. Start and goal must themselves be beyond
/// the margin. Deterministic.
JointPath find_joint_path(const Params<double>& params, const std::array<double, 2>& start,
                          const std::array<double, 2>& goal, const PathSearchOptions& options);

/// The free variables of `motion` that follow `path` (its ends must be motion's start and
/// goal) with the minimum-jerk time law along the arc length: a rest-to-rest guess.
std::vector<double> follow_path(const RestToRest& motion, const JointPath& path);

/// Minimum |sin(th4 - th3)| of the spline x of `motion` over `points` uniform instants; -1 when
/// some pose cannot close.
double min_coupler_sine(const Params<double>& params, const RestToRest& motion,
                        const std::vector<double>& x, int points);

}  // namespace fivebar::trajectory
