// Task specifications (interfaces.md, "Tasks file"; the YAML is read by the command line,
// fivebar/io/tasks_file.h) and their resolution into joint-space rest-to-rest motions for one
// design.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::trajectory {

/// A start or goal: the five-bar's joint angles {theta1, theta2} [rad] or point C {x, y} [m];
/// the four-bar's one coordinate, {theta1} [rad] or {x} or {y} of its point P [m], with the
/// coordinate it does not give NaN ({theta1}: b NaN; {x}: cartesian, b NaN; {y}: cartesian,
/// a NaN).
struct Pose {
  bool cartesian = false;
  double a = 0, b = 0;  ///< theta1, theta2 or x, y

  /// "theta1", "x" or "y" for a one-coordinate pose, nullptr for a two-coordinate one
  const char* single() const {
    if (std::isnan(b) && !std::isnan(a)) return cartesian ? "x" : "theta1";
    if (std::isnan(a) && !std::isnan(b) && cartesian) return "y";
    return nullptr;
  }
  /// the coordinate of a one-coordinate pose
  double value() const { return std::isnan(a) ? b : a; }
};

/// One task as written in the file. Values are not range-checked here: a non-positive duration
/// or torque limit becomes the task's status in the batch (resolve_task), not a file error.
/// Longest task [s]: the dense checks and the validation grow with the duration.
inline constexpr double kMaxTaskDuration = 100.0;
/// Largest |coordinate| of a start or goal [rad, or m for a Cartesian one].
inline constexpr double kMaxTaskAngle = 1000.0;

struct TaskSpec {
  std::string name;
  double duration = 0;  ///< [s], rest to rest
  Pose start, goal;
  /// [N m] on every motor's |M_a| (the five-bar's M1, M2; the four-bar's M1); infinity when the
  /// file gives none
  double torque_limit = std::numeric_limits<double>::infinity();
};

/// The checks of a task's own values (duration, torque limit) that come before its poses: false
/// with the task's status (invalid_duration, invalid_torque_limit) and message when one fails.
bool task_values_ok(const TaskSpec& task, std::string* status, std::string* message);

/// A task resolved for one design: joint angles at both ends, or why it cannot be done.
struct ResolvedTask {
  /// "ok" or: invalid_duration, invalid_torque_limit, start_cannot_assemble,
  /// start_out_of_workspace, start_near_singular, goal_cannot_assemble, goal_out_of_workspace,
  /// goal_near_singular
  std::string status = "ok";
  std::string message;
  std::array<double, 2> start{}, goal{};  ///< (theta1, theta2) [rad]
  bool ok() const { return status == "ok"; }
};

/// Resolves `task` for `params`. A Cartesian start is solved in the working mode (the sides of
/// both legs) of the scene's `initial` pose, a Cartesian goal in that of the task's start; the
/// goal angles are taken within pi of the start angles. Poses closer than `singular_margin` to
/// a singular configuration are refused.
ResolvedTask resolve_task(const Params<double>& params, const TaskSpec& task,
                          const sim::Initial& initial, double singular_margin);

/// Point C [m] at joint angles (theta1, theta2); false when the mechanism cannot close there.
bool point_c(const Params<double>& params, double theta1, double theta2,
             std::array<double, 2>* c);

}  // namespace fivebar::trajectory
