#include "fivebar/trajectory/tasks.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fivebar/model/kinematics.h"

namespace fivebar::trajectory {
namespace {

// the sides of both legs at a closed pose: sign((B - O) x (C - B)), sign((D - D0) x (C - D))
std::array<int, 2> leg_modes(const Kinematics<double>& k, const Params<double>& p) {
  const Vec2<double> D0(p.ground_length, 0.0);
  const double s1 = cross(Vec2<double>(k.B), Vec2<double>(k.C - k.B));
  const double s2 = cross(Vec2<double>(k.D - D0), Vec2<double>(k.C - k.D));
  return {s1 >= 0 ? 1 : -1, s2 >= 0 ? 1 : -1};
}

// crank angle th with |base + l e(th) - C| = r on the side `mode` of the leg; false if none
bool leg_angle(const Vec2<double>& base, double l, const Vec2<double>& C, double r, int mode,
               double* th) {
  const Vec2<double> d = C - base;
  const double L = d.norm();
  if (!(L > 0) || L > l + r || L < std::abs(l - r)) return false;
  const double phi = std::atan2(d.y(), d.x());
  const double beta = std::acos(std::clamp((l * l + L * L - r * r) / (2 * l * L), -1.0, 1.0));
  for (double cand : {phi + beta, phi - beta}) {
    const Vec2<double> K = base + l * unit(cand);
    const int side = cross(Vec2<double>(K - base), Vec2<double>(C - K)) >= 0 ? 1 : -1;
    if (side == mode) {
      *th = cand;
      return true;
    }
  }
  return false;
}

// the angle equal to `a` modulo 2 pi that is nearest to `ref`
double nearest(double a, double ref) { return ref + std::remainder(a - ref, 2 * M_PI); }

std::string str(double x) {
  std::ostringstream s;
  s.precision(6);
  s << x;
  return s.str();
}

}  // namespace

bool point_c(const Params<double>& params, double theta1, double theta2,
             std::array<double, 2>* c) {
  Kinematics<double> k;
  if (!solve_kinematics(params, theta1, theta2, &k).ok()) return false;
  *c = {k.C.x(), k.C.y()};
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
  if (!(task.duration > 0)) {
    return fail("invalid_duration", "duration " + str(task.duration) + " s is not positive");
  }
  if (task.duration > kMaxTaskDuration) {
    return fail("invalid_duration", "duration " + str(task.duration) + " s is beyond the " +
                                        str(kMaxTaskDuration) +
                                        " s a rest-to-rest task may take (the dense checks and "
                                        "the validation grow with it)");
  }
  if (!(task.torque_limit > 0)) {
    return fail("invalid_torque_limit",
                "torque_limit " + str(task.torque_limit) + " N m is not positive");
  }
  const double l1 = params.links[0].length, l2 = params.links[1].length;
  const double l3 = params.links[2].length, l4 = params.links[3].length;
  const Vec2<double> O(0, 0), D0(params.ground_length, 0);

  // joint angles of a pose, Cartesian ones in the working mode of the reference angles
  auto solve = [&](const Pose& pose, std::array<double, 2> ref, const char* which,
                   std::array<double, 2>* out) -> bool {
    Kinematics<double> k;
    const std::string w = which;
    if (!(std::abs(pose.a) <= kMaxTaskAngle && std::abs(pose.b) <= kMaxTaskAngle)) {
      return fail(w + "_invalid", w + ": (" + str(pose.a) + ", " + str(pose.b) +
                                      ") is beyond |" + str(kMaxTaskAngle) + "| (rad or m)"),
             false;
    }
    if (!pose.cartesian) {
      const Status st = solve_kinematics(params, pose.a, pose.b, &k);
      if (!st.ok()) return fail(w + "_cannot_assemble", w + ": " + st.message), false;
      *out = {pose.a, pose.b};
    } else {
      const Status st = solve_kinematics(params, ref[0], ref[1], &k);
      if (!st.ok()) return fail(w + "_cannot_assemble", w + " reference: " + st.message), false;
      const std::array<int, 2> mode = leg_modes(k, params);
      const Vec2<double> C(pose.a, pose.b);
      double th1 = 0, th2 = 0;
      const std::string where = w + " C = (" + str(pose.a) + ", " + str(pose.b) + ") m";
      if (!leg_angle(O, l1, C, l3, mode[0], &th1) || !leg_angle(D0, l2, C, l4, mode[1], &th2)) {
        return fail(w + "_out_of_workspace", where + " is out of reach of the legs"), false;
      }
      th1 = nearest(th1, ref[0]);
      th2 = nearest(th2, ref[1]);
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
