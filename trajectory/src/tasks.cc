#include "fivebar/trajectory/tasks.h"

#include <cerrno>
#include <cstring>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "fivebar/model/kinematics.h"

namespace fivebar::trajectory {
namespace {

std::string join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "." + b; }

double number(const YAML::Node& node, const std::string& path, const std::string& key) {
  if (!node.IsScalar()) throw TaskFileError(path, key, "expected a number");
  double v = 0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    throw TaskFileError(path, key, "expected a number, got '" + node.Scalar() + "'");
  }
  if (!std::isfinite(v)) throw TaskFileError(path, key, "expected a finite number");
  return v;
}

Pose pose(const YAML::Node& node, const std::string& path, const std::string& key) {
  const std::string expected = "expected {theta1: ..., theta2: ...} or {x: ..., y: ...}";
  if (!node.IsMap()) throw TaskFileError(path, key, expected);
  std::set<std::string> keys;
  for (const auto& kv : node) {
    const std::string k = kv.first.as<std::string>();
    if (k != "theta1" && k != "theta2" && k != "x" && k != "y") {
      throw TaskFileError(path, join(key, k), "unknown key (" + expected + ")");
    }
    keys.insert(k);
  }
  Pose p;
  if (keys == std::set<std::string>{"theta1", "theta2"}) {
    p.a = number(node["theta1"], path, join(key, "theta1"));
    p.b = number(node["theta2"], path, join(key, "theta2"));
  } else if (keys == std::set<std::string>{"x", "y"}) {
    p.cartesian = true;
    p.a = number(node["x"], path, join(key, "x"));
    p.b = number(node["y"], path, join(key, "y"));
  } else {
    throw TaskFileError(path, key, expected);
  }
  return p;
}

bool valid_name(const std::string& s) {
  if (s.empty() || s[0] == '.') return false;
  for (char c : s) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) {
      return false;
    }
  }
  return true;
}

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

std::vector<TaskSpec> parse_tasks(const std::string& text, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw TaskFileError(path, "(yaml)",
                        "line " + std::to_string(e.mark.line + 1) + ", column " +
                            std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw TaskFileError(path, "tasks", "expected a map with a 'tasks' list");
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    if (k != "tasks") throw TaskFileError(path, k, "unknown key (expected 'tasks')");
  }
  const YAML::Node list = root["tasks"];
  if (!list || !list.IsSequence() || list.size() == 0) {
    throw TaskFileError(path, "tasks", "expected a non-empty list of tasks");
  }
  std::vector<TaskSpec> tasks;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string key = "tasks." + std::to_string(i);
    const YAML::Node t = list[i];
    if (!t.IsMap()) throw TaskFileError(path, key, "expected a map {name, duration, start, goal}");
    for (const auto& kv : t) {
      const std::string k = kv.first.as<std::string>();
      if (k != "name" && k != "duration" && k != "start" && k != "goal" && k != "torque_limit") {
        throw TaskFileError(path, join(key, k),
                            "unknown key (expected name, duration, start, goal, torque_limit)");
      }
    }
    for (const char* required : {"name", "duration", "start", "goal"}) {
      if (!t[required]) throw TaskFileError(path, join(key, required), "missing");
    }
    TaskSpec spec;
    if (!t["name"].IsScalar()) throw TaskFileError(path, join(key, "name"), "expected a string");
    spec.name = t["name"].Scalar();
    if (!valid_name(spec.name)) {
      throw TaskFileError(path, join(key, "name"),
                          "'" + spec.name + "' is not usable as a directory name (letters, "
                          "digits, '_', '-', '.'; not starting with '.')");
    }
    if (!names.insert(spec.name).second) {
      throw TaskFileError(path, join(key, "name"), "duplicate task name '" + spec.name + "'");
    }
    spec.duration = number(t["duration"], path, join(key, "duration"));
    spec.start = pose(t["start"], path, join(key, "start"));
    spec.goal = pose(t["goal"], path, join(key, "goal"));
    if (t["torque_limit"]) {
      spec.torque_limit = number(t["torque_limit"], path, join(key, "torque_limit"));
    }
    tasks.push_back(spec);
  }
  return tasks;
}

std::vector<TaskSpec> load_tasks(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw TaskFileError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return parse_tasks(text.str(), path);
}

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
