// Tasks files (interfaces.md, "Tasks file"): YAML in, trajectory::TaskSpec out. The library
// takes the structs; reading the file is the command line's business.
#include "fivebar/io/tasks_file.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "fivebar/identification/degrees.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"

namespace fivebar::io {
namespace {

std::string join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "." + b; }

double number(const YAML::Node& node, const std::string& path, const std::string& key) {
  if (!node.IsScalar()) throw InputError(path, key, "expected a number");
  double v = 0;
  try {
    v = node.as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(path, key, "expected a number, got '" + node.Scalar() + "'");
  }
  if (!std::isfinite(v)) throw InputError(path, key, "expected a finite number");
  return v;
}

// a four-bar's pose: exactly one of theta1, x, y (P's coordinate); theta2 is named as the
// five-bar's key it is
trajectory::Pose four_bar_pose(const YAML::Node& node, const std::string& path,
                               const std::string& key) {
  const std::string expected =
      "expected one of {theta1: ...}, {x: ...}, {y: ...} (x, y: the coupler point P) for a "
      "mechanism.type four_bar scene";
  if (!node.IsMap()) throw InputError(path, key, expected);
  trajectory::Pose p{false, NAN, NAN};
  std::string single;
  for (const auto& kv : node) {
    const std::string k = kv.first.as<std::string>();
    if (k == "theta2") {
      throw InputError(path, join(key, k),
                       "a five_bar key: a mechanism.type four_bar scene has one degree of "
                       "freedom (" + expected + ")");
    }
    if (k != "theta1" && k != "x" && k != "y") {
      throw InputError(path, join(key, k), "unknown key (" + expected + ")");
    }
    if (!single.empty()) {
      throw InputError(path, key, "two coordinates (" + single + ", " + k + "): " + expected);
    }
    single = k;
    p.cartesian = k != "theta1";
    (k == "y" ? p.b : p.a) = number(kv.second, path, join(key, k));
  }
  if (single.empty()) throw InputError(path, key, expected);
  if (single == "theta1" && std::abs(p.a) > identification::kDegreesBeyond) {
    throw InputError(path, join(key, "theta1"),
                     format_double(p.a) + " rad is beyond two turns: degrees? (crank angles "
                     "are in radians, " + format_double(p.a) + " degrees = " +
                     format_significant(p.a * M_PI / 180, 4) + " rad)");
  }
  return p;
}

trajectory::Pose pose(const YAML::Node& node, const std::string& path, const std::string& key,
                      bool four_bar) {
  if (four_bar) return four_bar_pose(node, path, key);
  const std::string expected = "expected {theta1: ..., theta2: ...} or {x: ..., y: ...}";
  if (!node.IsMap()) throw InputError(path, key, expected);
  std::set<std::string> keys;
  for (const auto& kv : node) {
    const std::string k = kv.first.as<std::string>();
    if (k != "theta1" && k != "theta2" && k != "x" && k != "y") {
      throw InputError(path, join(key, k), "unknown key (" + expected + ")");
    }
    keys.insert(k);
  }
  trajectory::Pose p;
  if (keys == std::set<std::string>{"theta1", "theta2"}) {
    p.a = number(node["theta1"], path, join(key, "theta1"));
    p.b = number(node["theta2"], path, join(key, "theta2"));
    // crank angles beyond two turns are degrees, not a pose (goal {theta1: 150, theta2: 80}
    // read as radians failed the optimization with a friction-loop message)
    for (const auto& [name, v] : {std::pair{"theta1", p.a}, std::pair{"theta2", p.b}}) {
      if (std::abs(v) > identification::kDegreesBeyond) {
        throw InputError(path, join(key, name),
                         format_double(v) + " rad is beyond two turns: degrees? (crank angles "
                         "are in radians, " + format_double(v) + " degrees = " +
                         format_significant(v * M_PI / 180, 4) + " rad)");
      }
    }
  } else if (keys == std::set<std::string>{"x", "y"}) {
    p.cartesian = true;
    p.a = number(node["x"], path, join(key, "x"));
    p.b = number(node["y"], path, join(key, "y"));
  } else if (keys.size() == 1) {
    throw InputError(path, join(key, *keys.begin()),
                     "one coordinate is a four_bar pose: a mechanism.type five_bar scene "
                     "needs two (" + expected + ")");
  } else {
    throw InputError(path, key, expected);
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

}  // namespace

std::vector<trajectory::TaskSpec> parse_tasks(const std::string& text, const std::string& path,
                                              bool four_bar) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "(yaml)",
                        "line " + std::to_string(e.mark.line + 1) + ", column " +
                            std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (!root.IsMap()) throw InputError(path, "tasks", "expected a map with a 'tasks' list");
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    if (k != "tasks") throw InputError(path, k, "unknown key (expected 'tasks')");
  }
  const YAML::Node list = root["tasks"];
  if (!list || !list.IsSequence() || list.size() == 0) {
    throw InputError(path, "tasks", "expected a non-empty list of tasks");
  }
  std::vector<trajectory::TaskSpec> tasks;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string key = "tasks." + std::to_string(i);
    const YAML::Node t = list[i];
    if (!t.IsMap()) throw InputError(path, key, "expected a map {name, duration, start, goal}");
    for (const auto& kv : t) {
      const std::string k = kv.first.as<std::string>();
      if (k != "name" && k != "duration" && k != "start" && k != "goal" && k != "torque_limit") {
        throw InputError(path, join(key, k),
                            "unknown key (expected name, duration, start, goal, torque_limit)");
      }
    }
    for (const char* required : {"name", "duration", "start", "goal"}) {
      if (!t[required]) throw InputError(path, join(key, required), "missing");
    }
    trajectory::TaskSpec spec;
    if (!t["name"].IsScalar()) throw InputError(path, join(key, "name"), "expected a string");
    spec.name = t["name"].Scalar();
    if (!valid_name(spec.name)) {
      throw InputError(path, join(key, "name"),
                          "'" + spec.name + "' is not usable as a directory name (letters, "
                          "digits, '_', '-', '.'; not starting with '.')");
    }
    if (!names.insert(spec.name).second) {
      throw InputError(path, join(key, "name"), "duplicate task name '" + spec.name + "'");
    }
    spec.duration = number(t["duration"], path, join(key, "duration"));
    spec.start = pose(t["start"], path, join(key, "start"), four_bar);
    spec.goal = pose(t["goal"], path, join(key, "goal"), four_bar);
    if (t["torque_limit"]) {
      spec.torque_limit = number(t["torque_limit"], path, join(key, "torque_limit"));
    }
    tasks.push_back(spec);
  }
  return tasks;
}

std::vector<trajectory::TaskSpec> load_tasks(const std::string& path, bool four_bar) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "--tasks", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return parse_tasks(text.str(), path, four_bar);
}

}  // namespace fivebar::io
