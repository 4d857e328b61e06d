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

trajectory::Pose pose(const YAML::Node& node, const std::string& path, const std::string& key) {
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

std::vector<trajectory::TaskSpec> parse_tasks(const std::string& text, const std::string& path) {
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
    spec.start = pose(t["start"], path, join(key, "start"));
    spec.goal = pose(t["goal"], path, join(key, "goal"));
    if (t["torque_limit"]) {
      spec.torque_limit = number(t["torque_limit"], path, join(key, "torque_limit"));
    }
    tasks.push_back(spec);
  }
  return tasks;
}

std::vector<trajectory::TaskSpec> load_tasks(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  return parse_tasks(text.str(), path);
}

}  // namespace fivebar::io
