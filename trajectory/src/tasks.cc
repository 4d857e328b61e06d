#include "fivebar/trajectory/tasks.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "fivebar/model/format.h"
#include "fivebar/model/kinematics.h"

namespace fivebar::trajectory {
namespace {

// the angle equal to `a` modulo 2 pi that is nearest to `ref`
double nearest(double a, double ref) { return ref + std::remainder(a - ref, 2 * M_PI); }

}  // namespace

bool point_c(const Params<double>& params, double theta1, double theta2,
             std::array<double, 2>* c) {
  Kinematics<double> k;
  if (!solve_kinematics(params, theta1, theta2, &k).ok()) return false;
  *c = {k.C.x(), k.C.y()};
  return true;
}

bool task_values_ok(const TaskSpec& task, std::string* status, std::string* message) {
  auto fail = [&](const std::string& st, const std::string& msg) {
    *status = st;
    *message = msg;
    return false;
  };
  if (!(task.duration > 0)) {
    return fail("invalid_duration",
                "duration " + format_significant(task.duration, 6) + " s is not positive");
  }
  if (task.duration > kMaxTaskDuration) {
    return fail("invalid_duration", "duration " + format_significant(task.duration, 6) +
                                        " s is beyond the " +
                                        format_significant(kMaxTaskDuration, 6) +
                                        " s a rest-to-rest task may take (the dense checks and "
                                        "the validation grow with it)");
  }
  if (!(task.torque_limit > 0)) {
    return fail("invalid_torque_limit", "torque_limit " + format_significant(task.torque_limit, 6) +
                                            " N m is not positive");
  }
  return true;
}

ResolvedTask resolve_task(const Params<double>& params, const TaskSpec& task,
                          const sim::Initial& initial, double singular_margin) {
  ResolvedTask r;
  auto fail = [&](const std::string& status, const std::string& message) {
    r.status = status;
    r.message = message;
    return r;
  };
  if (!task_values_ok(task, &r.status, &r.message)) return r;
  // joint angles of a pose, Cartesian ones in the working mode of the reference angles
  auto solve = [&](const Pose& pose, std::array<double, 2> ref, const char* which,
                   std::array<double, 2>* out) -> bool {
    Kinematics<double> k;
    const std::string w = which;
    if (!(std::abs(pose.a) <= kMaxTaskAngle && std::abs(pose.b) <= kMaxTaskAngle)) {
      return fail(w + "_invalid", w + ": (" + format_significant(pose.a, 6) + ", " +
                                      format_significant(pose.b, 6) + ") is beyond |" +
                                      format_significant(kMaxTaskAngle, 6) + "| (rad or m)"),
             false;
    }
    if (!pose.cartesian) {
      const Status st = solve_kinematics(params, pose.a, pose.b, &k);
      if (!st.ok()) return fail(w + "_cannot_assemble", w + ": " + st.message), false;
      *out = {pose.a, pose.b};
    } else {
      const Status st = solve_kinematics(params, ref[0], ref[1], &k);
      if (!st.ok()) return fail(w + "_cannot_assemble", w + " reference: " + st.message), false;
      std::array<double, 2> th{};
      const std::string where = w + " C = (" + format_significant(pose.a, 6) + ", " +
                                format_significant(pose.b, 6) + ") m";
      if (!crank_angles(params, Vec2<double>(pose.a, pose.b), leg_modes(params, k), &th)) {
        return fail(w + "_out_of_workspace", where + " is out of reach of the legs"), false;
      }
      const double th1 = nearest(th[0], ref[0]), th2 = nearest(th[1], ref[1]);
      // the closure of the scene's assembly must give back the same C
      std::array<double, 2> c{};
      if (!point_c(params, th1, th2, &c) || std::hypot(c[0] - pose.a, c[1] - pose.b) > 1e-9) {
        return fail(w + "_out_of_workspace",
                    where + " is reachable only in the other assembly or working mode"),
               false;
      }
      *out = {th1, th2};
    }
    Kinematics<double> kk;
    const Status st = solve_kinematics(params, (*out)[0], (*out)[1], &kk, singular_margin);
    if (!st.ok()) return fail(w + "_near_singular", w + ": " + st.message), false;
    return true;
  };
  if (!solve(task.start, {initial.theta1, initial.theta2}, "start", &r.start)) return r;
  if (!solve(task.goal, r.start, "goal", &r.goal)) return r;
  return r;
}

}  // namespace fivebar::trajectory
