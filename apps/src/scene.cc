// Scene loading: the YAML tree is first flattened into dotted keys checked against the schema,
// the --set overrides are applied to that flat map (so they work for keys the file omits), and
// the Scene is then built and validated key by key.
#include "fivebar/io/scene.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "fivebar/io/command.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/loads.h"
#include "fivebar/model/actuator.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/motor.h"

namespace fivebar::io {
namespace {

// ---------------------------------------------------------------------------------------------
// Schema

enum class Kind {
  kSection,     // a map of keys
  kLinkList,    // mechanism.links: a list of kLinks maps
  kNumber,      // a finite double
  kNumberOr5,   // one number for all joints, or a list of 5 (O, B, C, D, D0)
  kInteger,     // an integral number
  kBool,        // true / false
  kName,        // one of a fixed set of names
  kExpression,  // a muParser expression of t
};

struct Field {
  std::string key;  // dotted; "#" stands for a link index
  Kind kind;
  SceneLimit limit{};  // the plausible magnitudes of a number (none when high is 0)
};

// Plausibility limits: a nonzero magnitude outside [low, high] describes no machine (a 100 m crane
// link, a 1e-4 m MEMS link and 1e5 kg are all well inside). Zero and the sign are left to each
// key's own domain check. docs/scene.md states the same table.
constexpr double kNoUpperLimit = std::numeric_limits<double>::max();
constexpr SceneLimit kLength{1e-7, 1e3, "m"};
constexpr SceneLimit kOffset{0, 1e3, "m"};
constexpr SceneLimit kAngle{0, 1e3, "rad"};
constexpr SceneLimit kRate{0, 1e5, "rad/s"};
constexpr SceneLimit kTorque{0, 1e9, "N m"};
// a motor's (actuators.M1, actuators.M2)
constexpr SceneLimit kMotorViscous{0, 1e9, "N m s/rad"};
constexpr SceneLimit kWinding{1e-6, 1e6, "ohm"};
constexpr SceneLimit kTorqueConstant{1e-6, 1e4, "N m/A"};
constexpr SceneLimit kGearRatio{1e-3, 1e6, "-"};

// every key a scene may contain (interfaces.md, scene.h), except the friction coefficients,
// which come from the friction-law descriptors (friction.h): see schema()
const Field kBaseSchema[] = {
    {"mechanism", Kind::kSection},
    {"mechanism.type", Kind::kName},
    {"mechanism.ground_length", Kind::kNumber, kLength},
    {"mechanism.links", Kind::kLinkList},
    {"mechanism.links.#", Kind::kSection},
    {"mechanism.links.#.length", Kind::kNumber, kLength},
    {"mechanism.links.#.mass", Kind::kNumber, {1e-15, 1e7, "kg"}},
    {"mechanism.links.#.inertia", Kind::kNumber, {1e-30, 1e13, "kg m^2"}},
    {"mechanism.links.#.com_offset", Kind::kNumber, kOffset},
    {"mechanism.links.#.com_angle", Kind::kNumber, kAngle},
    {"mechanism.point_p", Kind::kNumber, kOffset},
    {"mechanism.assembly", Kind::kName},
    {"gravity", Kind::kNumber, {0, 1e4, "m/s^2"}},
    {"friction", Kind::kSection},
    {"friction.model", Kind::kName},
    {"friction.pin_radius", Kind::kNumberOr5, {1e-8, 10, "m"}},
    {"friction.smoothing_velocity", Kind::kNumber, {1e-9, 1e4, "rad/s"}},
    {"actuators", Kind::kSection},
    {"actuators.M1", Kind::kSection},
    {"actuators.M1.offset", Kind::kNumber, kTorque},
    {"actuators.M1.coulomb", Kind::kNumber, kTorque},
    {"actuators.M1.viscous", Kind::kNumber, kMotorViscous},
    {"actuators.M1.winding_resistance", Kind::kNumber, kWinding},
    {"actuators.M1.torque_constant", Kind::kNumber, kTorqueConstant},
    {"actuators.M1.gear_ratio", Kind::kNumber, kGearRatio},
    {"actuators.M2", Kind::kSection},
    {"actuators.M2.offset", Kind::kNumber, kTorque},
    {"actuators.M2.coulomb", Kind::kNumber, kTorque},
    {"actuators.M2.viscous", Kind::kNumber, kMotorViscous},
    {"actuators.M2.winding_resistance", Kind::kNumber, kWinding},
    {"actuators.M2.torque_constant", Kind::kNumber, kTorqueConstant},
    {"actuators.M2.gear_ratio", Kind::kNumber, kGearRatio},
    {"loads", Kind::kSection},
    {"loads.M1", Kind::kExpression, kTorque},
    {"loads.M2", Kind::kExpression, kTorque},
    {"loads.M3", Kind::kExpression, kTorque},
    {"loads.F", Kind::kExpression, {0, 1e10, "N"}},
    {"loads.F_angle", Kind::kNumber, kAngle},
    {"initial", Kind::kSection},
    {"initial.theta1", Kind::kNumber},
    {"initial.theta2", Kind::kNumber},
    {"initial.omega1", Kind::kNumber, kRate},
    {"initial.omega2", Kind::kNumber, kRate},
    {"simulation", Kind::kSection},
    // the longest duration is the output rows' limit (rows_beyond_limit) at output_step's
    {"simulation.duration", Kind::kNumber, {1e-6, kNoUpperLimit, "s"}},
    {"simulation.output_step", Kind::kNumber, {1e-9, 1e6, "s"}},
    {"simulation.integrator", Kind::kName},
    {"simulation.rtol", Kind::kNumber, {1e-16, 1, "-"}},
    {"simulation.atol", Kind::kNumber, {1e-20, 1, "rad, rad/s"}},
    {"simulation.target_error", Kind::kNumber, {1e-15, 1, "rad"}},
    {"simulation.locate_switches", Kind::kBool},
    {"simulation.stick", Kind::kBool},
    {"simulation.max_steps", Kind::kInteger},
    {"simulation.singular_margin", Kind::kNumber},
    {"simulation.friction_tol", Kind::kNumber, {1e-16, 1, "-"}},
    {"simulation.friction_max_iter", Kind::kInteger},
    {"simulation.rest_rate_threshold", Kind::kNumber, kRate},
    {"simulation.rest_acceleration_threshold", Kind::kNumber, {0, 1e9, "rad/s^2"}},
};

// the friction coefficients' limits (kCoefficientInfo order: coulomb, viscous, static_coulomb,
// stribeck_velocity, stribeck_exponent, sigma0, sigma1, sigma2, viscous_exponent)
constexpr SceneLimit kCoefficientLimits[kCoefficients] = {
    {0, 10, "-"},         {0, 1e4, "s/rad"}, {0, 10, "-"},
    {1e-6, 1e4, "rad/s"}, {1e-2, 100, "-"},  {1e-6, 1e12, "1/rad"},
    {0, 1e6, "s/rad"},    {0, 1e4, "s/rad"}, {1e-2, 10, "-"},
};

// the whole schema: the base keys with the laws' coefficients after friction.pin_radius
const std::vector<Field>& schema() {
  static const std::vector<Field> fields = [] {
    std::vector<Field> out;
    for (const Field& f : kBaseSchema) {
      out.push_back(f);
      if (f.key != "friction.pin_radius") continue;
      for (const CoefficientInfo& c : kCoefficientInfo) {
        out.push_back({std::string("friction.") + c.key, Kind::kNumberOr5,
                       kCoefficientLimits[static_cast<int>(c.id)]});
      }
    }
    return out;
  }();
  return fields;
}

const Field* find_field(const std::string& schema_key) {
  for (const Field& f : schema()) {
    if (schema_key == f.key) return &f;
  }
  return nullptr;
}

// the keys directly below a section ("" is the top level), for "expected one of" hints
std::string children_of(const std::string& schema_section) {
  std::string out;
  const std::string prefix = schema_section.empty() ? "" : schema_section + ".";
  for (const Field& f : schema()) {
    const std::string& key = f.key;
    if (key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = key.substr(prefix.size());
    if (rest.empty() || rest.find('.') != std::string::npos || rest == "#") continue;
    out += (out.empty() ? "" : ", ") + rest;
  }
  return out;
}


// ---------------------------------------------------------------------------------------------
// Small string helpers

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::string::size_type start = 0;
  while (true) {
    const auto pos = s.find(sep, start);
    parts.push_back(s.substr(start, pos - start));
    if (pos == std::string::npos) break;
    start = pos + 1;
  }
  return parts;
}

std::string join(const std::vector<std::string>& parts, size_t n, char sep) {
  std::string out;
  for (size_t i = 0; i < n && i < parts.size(); ++i) {
    out += (i ? std::string(1, sep) : "") + parts[i];
  }
  return out;
}

// a non-negative decimal index such as "2", or -1
int parse_index(const std::string& s) {
  if (s.empty() || s.size() > 6) return -1;
  for (char c : s) {
    if (c < '0' || c > '9') return -1;
  }
  return std::atoi(s.c_str());
}

// a YAML number: decimal or exponent form, or one of YAML's .inf / .nan spellings
bool parse_double(const std::string& text, double* out) {
  const std::string s = trim(text);
  std::string lower(s);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == ".nan") {
    *out = std::nan("");
    return true;
  }
  if (lower == ".inf" || lower == "+.inf" || lower == "-.inf") {
    *out = lower[0] == '-' ? -HUGE_VAL : HUGE_VAL;
    return true;
  }
  if (s.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size();
}

// ---------------------------------------------------------------------------------------------
// The scene as a flat map of dotted keys

struct Value {
  std::vector<std::string> items;  // one scalar, or the elements of a list
  bool list = false;
  std::string origin;  // " (line 12)" or " (from --set)": appended to messages about the value
};

class SceneReader {
 public:
  explicit SceneReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    throw InputError(path_, key, reason);
  }

  // --- the file ---

  void read_root(const YAML::Node& root) {
    if (root.IsNull()) return;  // an empty file: every required key will be reported missing
    if (!root.IsMap()) {
      fail("(top level)", "expected a map of sections (" + children_of("") + "), got " +
                              type_name(root) + line_of(root));
    }
    read_section(root, "", "");
  }

  // --- the --set overrides ---

  void apply_set(const std::string& assignment) {
    const auto eq = assignment.find('=');
    if (eq == std::string::npos || trim(assignment.substr(0, eq)).empty()) {
      fail("--set", "expected KEY=VALUE, got '" + assignment + "'");
    }
    std::string key = trim(assignment.substr(0, eq));
    const std::string text = trim(assignment.substr(eq + 1));
    std::vector<std::string> parts = split(key, '.');
    for (const auto& p : parts) {
      if (p.empty()) fail(key, "malformed key in --set " + assignment);
    }
    const std::string in_set = " in --set " + assignment;
    int element = -1;
    const Field* field = resolve_set_key(in_set, &parts, &key, &element);
    if (element >= 0) {
      set_element(key, element, text, in_set);
    } else {
      set_value(key, *field, text, in_set);
    }
  }

  // the schema field of a --set key; friction.coulomb.3 names element 3 of a per-joint list
  // (*element, and *parts / *key lose the index)
  const Field* resolve_set_key(const std::string& in_set, std::vector<std::string>* parts_io,
                               std::string* key_io, int* element) const {
    std::vector<std::string>& parts = *parts_io;
    std::string& key = *key_io;
    // a link index must name one of the mechanism's links
    if (parts.size() >= 3 && parts[0] == "mechanism" && parts[1] == "links") {
      const int i = parse_index(parts[2]);
      if (i < 0 || i >= links()) {
        fail(join(parts, 3, '.'), "no such link" + in_set + " (links are numbered 0 to " +
                                      std::to_string(links() - 1) + ")");
      }
    }
    const Field* field = find_field(schema_key(parts));
    if (field == nullptr && parts.size() >= 2 && parse_index(parts.back()) >= 0) {
      std::vector<std::string> parent(parts.begin(), parts.end() - 1);
      const Field* pf = find_field(schema_key(parent));
      if (pf != nullptr && pf->kind == Kind::kNumberOr5) {
        *element = parse_index(parts.back());
        if (*element >= joints()) {
          fail(key, "no such joint" + in_set + " (joints are numbered 0 to " +
                        std::to_string(joints() - 1) + ": " + joint_names() + ")");
        }
        field = pf;
        parts = parent;
        key = join(parts, parts.size(), '.');
      }
    }
    if (field == nullptr) fail(key, "unknown key" + in_set + unknown_hint(parts));
    if (field->kind == Kind::kSection || field->kind == Kind::kLinkList) {
      fail(key, "is a section, not a value" + in_set);
    }
    return field;
  }

  // one element of a per-joint list, starting from the file's value or the key's default
  void set_element(const std::string& key, int element, const std::string& text,
                   const std::string& in_set) {
    auto it = flat_.find(key);
    if (it == flat_.end()) {
      const std::vector<std::string> fallback = per_joint_default(key);
      if (fallback.empty()) {
        fail(key, "the scene has no value to take element " + std::to_string(element) + " of" +
                      in_set + "; set the whole key, e.g. " + key + "=[a,b,c,d,e]");
      }
      it = flat_.emplace(key, Value{fallback, fallback.size() > 1, ""}).first;
    }
    Value& v = it->second;
    if (!v.list || v.items.size() == 1) v.items.assign(joints(), v.items.front());
    if (v.items.size() != static_cast<size_t>(joints())) {
      fail(key, "expected 1 or " + std::to_string(joints()) + " numbers" + joint_hint() +
                    ", got " + std::to_string(v.items.size()) + v.origin);
    }
    v.list = true;
    v.items[element] = text;
    v.origin = " (from --set)";
  }

  // a whole value: a scalar, or a flow list such as [0.1, 0.1, 0.12, 0.1, 0.1]
  void set_value(const std::string& key, const Field& field, const std::string& text,
                 const std::string& in_set) {
    Value v;
    v.origin = " (from --set)";
    if (field.kind == Kind::kNumberOr5 && !text.empty() && text.front() == '[') {
      YAML::Node node;
      try {
        node = YAML::Load(text);
      } catch (const YAML::Exception& e) {
        fail(key, "malformed list" + in_set + ": " + e.msg);
      }
      if (!node.IsSequence()) fail(key, "malformed list" + in_set);
      v.list = true;
      for (const auto& item : node) {
        if (!item.IsScalar()) fail(key, "expected a list of numbers" + in_set);
        v.items.push_back(item.Scalar());
      }
    } else {
      v.items = {text};
    }
    flat_[key] = std::move(v);
  }


  // --- typed access to the flat map, with the value's origin in every message ---

  bool has(const std::string& key) const { return flat_.count(key) != 0; }

  std::string origin(const std::string& key) const {
    auto it = flat_.find(key);
    return it == flat_.end() ? "" : it->second.origin;
  }

  // the single scalar under `key`; fails when it is a list
  const std::string& scalar(const std::string& key) const {
    const Value& v = flat_.at(key);
    if (v.list) fail(key, "expected a single value, got a list" + v.origin);
    return v.items.front();
  }

  double number(const std::string& key, std::optional<double> fallback) const {
    if (!has(key)) {
      if (!fallback) fail(key, "missing (required)");
      return *fallback;
    }
    return to_number(key, scalar(key), origin(key));
  }

  double to_number(const std::string& key, const std::string& text,
                   const std::string& where) const {
    double x = 0;
    if (!parse_double(text, &x)) fail(key, "expected a number, got '" + text + "'" + where);
    if (!std::isfinite(x)) fail(key, "must be a finite number, got " + text + where);
    const std::string implausible = limit_problem(limit_key(key), x);
    if (!implausible.empty()) fail(key, implausible + where);
    return x;
  }

  long integer(const std::string& key, long fallback) const {
    if (!has(key)) return fallback;
    const double x = number(key, std::nullopt);
    if (x != std::floor(x) || std::fabs(x) > 9e15) {
      fail(key, "expected an integer, got " + scalar(key) + origin(key));
    }
    return static_cast<long>(x);
  }

  bool boolean(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    std::string s = scalar(key);
    std::transform(s.begin(), s.end(), s.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (s == "true" || s == "yes" || s == "on") return true;
    if (s == "false" || s == "no" || s == "off") return false;
    fail(key, "expected true or false, got '" + scalar(key) + "'" + origin(key));
  }

  std::string text(const std::string& key, const std::string& fallback) const {
    return has(key) ? trim(scalar(key)) : fallback;
  }

  // one number for all joints or a list of one per joint (5 for the five-bar, 4 for the
  // four-bar, whose fifth slot stays 0), each checked by `check` (named in `domain`)
  std::array<double, kJoints> per_joint(const std::string& key, std::optional<double> fallback,
                                        bool (*check)(double), const char* domain) const {
    std::array<double, kJoints> out{};
    const int n = joints();
    if (!has(key)) {
      if (!fallback) {
        fail(key, "missing (required by friction.model " + text("friction.model", "none") +
                      "): one number or a list of " + std::to_string(n) + " (" + joint_names() +
                      ")");
      }
      std::fill(out.begin(), out.begin() + n, *fallback);
      return out;
    }
    const Value& v = flat_.at(key);
    if (v.items.size() != 1 && v.items.size() != static_cast<size_t>(n)) {
      fail(key, "expected 1 or " + std::to_string(n) + " numbers" + joint_hint() + ", got " +
                    std::to_string(v.items.size()) + v.origin);
    }
    for (int k = 0; k < n; ++k) {
      const bool single = v.items.size() == 1;
      const std::string item_key = single ? key : key + "." + std::to_string(k);
      const std::string& item = v.items[single ? 0 : k];
      out[k] = to_number(item_key, item, v.origin);
      if (!check(out[k]))
        fail(item_key, std::string("must be ") + domain + ", got " + item + v.origin);
    }
    return out;
  }

  /// mechanism.type four_bar (the file's or a --set's value; anything else is checked later)
  bool four_bar() const { return has("mechanism.type") && trim(scalar("mechanism.type")) == "four_bar"; }
  int joints() const { return four_bar() ? kFourBarJoints : kJoints; }
  int links() const { return four_bar() ? kFourBarLinks : kLinks; }
  std::string joint_names() const { return four_bar() ? "O, B, C, D0" : "O, B, C, D, D0"; }
  /// the four-bar's joints named in list-length messages (the five-bar's as they always read)
  std::string joint_hint() const { return four_bar() ? " (" + joint_names() + ")" : ""; }
  /// every key the scene gives a value (dotted), and every section it names, even empty
  std::vector<std::string> keys() const {
    std::vector<std::string> out(sections_.begin(), sections_.end());
    for (const auto& kv : flat_) out.push_back(kv.first);
    return out;
  }

  int link_count() const { return link_count_; }
  const std::string& link_line() const { return link_line_; }
  const std::string& path() const { return path_; }

 private:
  static std::string type_name(const YAML::Node& n) {
    if (n.IsMap()) return "a map";
    if (n.IsSequence()) return "a list";
    if (n.IsNull()) return "nothing";
    return "'" + n.Scalar() + "'";
  }

  static std::string line_of(const YAML::Node& n) {
    const int line = n.Mark().line;
    return line >= 0 ? " (line " + std::to_string(line + 1) + ")" : "";
  }

  // the scene_keys() name of a value's key: link indices become "N", a per-joint item's index
  // is dropped (friction.coulomb.2 -> friction.coulomb)
  static std::string limit_key(const std::string& key) {
    std::vector<std::string> p = split(key, '.');
    if (p.size() >= 3 && p[0] == "mechanism" && p[1] == "links") p[2] = "N";
    if (p.size() == 3 && p[0] == "friction") p.pop_back();
    return join(p, p.size(), '.');
  }

  // the schema key of a dotted key: link indices become "#"
  static std::string schema_key(const std::vector<std::string>& parts) {
    std::vector<std::string> p = parts;
    if (p.size() >= 3 && p[0] == "mechanism" && p[1] == "links") p[2] = "#";
    return join(p, p.size(), '.');
  }

  // the default of a per-joint friction coefficient as scene text (see read_coefficients), or
  // nothing when the scene's law requires the key or it has no default
  std::vector<std::string> per_joint_default(const std::string& key) const {
    const LawDescriptor* law = find_law(text("friction.model", "none"));
    for (const CoefficientInfo& c : kCoefficientInfo) {
      if (key != std::string("friction.") + c.key) continue;
      const LawCoefficient* use = law ? law_coefficient(*law, c.id) : nullptr;
      if (use && use->required) return {};
      if (c.same_as != c.id) {  // mu_s defaults to mu_c
        auto it = flat_.find(std::string("friction.") + coefficient_info(c.same_as).key);
        return it == flat_.end() ? std::vector<std::string>{} : it->second.items;
      }
      return {format_double(c.default_value)};
    }
    return {};
  }

  // "; expected one of ..." for the deepest known section on the way to an unknown key
  static std::string unknown_hint(const std::vector<std::string>& parts) {
    for (size_t n = parts.size() - 1; n > 0; --n) {
      std::vector<std::string> head(parts.begin(), parts.begin() + n);
      const Field* f = find_field(schema_key(head));
      if (f == nullptr) continue;
      if (f->kind == Kind::kSection) {
        return "; keys of " + join(head, n, '.') + ": " + children_of(schema_key(head));
      }
      if (f->kind == Kind::kLinkList) return "; links are numbered 0 to 3";
      return "";
    }
    return "; top-level keys: " + children_of("");
  }

  // a YAML map under `key` (dotted) whose schema key is `skey`
  void read_section(const YAML::Node& node, const std::string& key, const std::string& skey) {
    if (!key.empty()) sections_.insert(key);
    if (node.IsNull()) return;  // `friction:` with nothing below
    if (!node.IsMap()) {
      fail(key, "expected a map of keys (" + children_of(skey) + "), got " + type_name(node) +
                    line_of(node));
    }
    std::set<std::string> seen;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) fail(key, "a key must be a name" + line_of(kv.first));
      const std::string name = kv.first.Scalar();
      const std::string child = key.empty() ? name : key + "." + name;
      const std::string schild = skey.empty() ? name : skey + "." + name;
      if (!seen.insert(name).second) fail(child, "duplicate key" + line_of(kv.first));
      const Field* field = find_field(schild);
      if (field == nullptr) {
        fail(child, "unknown key" + line_of(kv.first) + "; " +
                        (key.empty() ? "top-level keys" : "keys of " + key) + ": " +
                        children_of(skey));
      }
      read_value(kv.second, child, *field);
    }
  }

  void read_value(const YAML::Node& node, const std::string& key, const Field& field) {
    switch (field.kind) {
      case Kind::kSection:
        read_section(node, key, field.key);
        return;
      case Kind::kLinkList:
        if (!node.IsSequence()) {
          fail(key, "expected a list of " + std::to_string(links()) + " links, got " +
                        type_name(node) + line_of(node));
        }
        link_count_ = static_cast<int>(node.size());
        link_line_ = line_of(node);
        for (size_t i = 0; i < node.size() && i < static_cast<size_t>(kLinks); ++i) {
          read_section(node[i], key + "." + std::to_string(i), "mechanism.links.#");
        }
        return;
      default:
        break;
    }
    Value v;
    v.origin = line_of(node);
    if (node.IsScalar()) {
      v.items = {node.Scalar()};
    } else if (node.IsSequence() && field.kind == Kind::kNumberOr5) {
      v.list = true;
      for (const auto& item : node) {
        if (!item.IsScalar()) fail(key, "expected a list of numbers" + v.origin);
        v.items.push_back(item.Scalar());
      }
    } else if (node.IsNull()) {
      fail(key, "no value given" + v.origin);
    } else {
      fail(key, "expected a single value, got " + type_name(node) + v.origin);
    }
    flat_[key] = std::move(v);
  }

  std::string path_;
  std::map<std::string, Value> flat_;
  std::set<std::string> sections_;  // the sections the file names (dotted)
  int link_count_ = 0;
  std::string link_line_;
};

bool positive(double x) { return x > 0; }
bool non_negative(double x) { return x >= 0; }

std::string num(double x) { return format_double(x); }

// builds and validates the Scene from the flat map

/// One warning line for each value that is valid but likely a unit mistake (degrees for
/// radians, millimetres or grams for SI): |theta| > 2 pi, lengths outside 1e-4..10 m, masses
/// outside 1e-6..1e4 kg.
template <class P>
void plausibility_warnings(const P& p, Scene* s) {
  auto say = [&](const std::string& key, double v, const std::string& why) {
    s->warnings.push_back(s->path + ": " + key + ": " + num(v) + " " + why);
  };
  const bool four = s->type == MechanismType::kFourBar;
  for (const char* key : {"theta1", "theta2"}) {
    if (four && std::string(key) == "theta2") continue;
    const double v = std::string(key) == "theta1" ? s->initial.theta1 : s->initial.theta2;
    if (std::abs(v) > 2 * M_PI) say(std::string("initial.") + key, v, "rad is beyond 2 pi: degrees?");
  }
  auto length = [&](const std::string& key, double v) {
    if (v > 10) say(key, v, "m is outside 1e-4..10 m: millimetres?");
    if (v < 1e-4) say(key, v, "m is outside 1e-4..10 m: a microscale mechanism, or another unit?");
  };
  length("mechanism.ground_length", p.ground_length);
  if (p.point_p != 0.0) length("mechanism.point_p", std::abs(p.point_p));
  for (size_t i = 0; i < p.links.size(); ++i) {
    const std::string link = "mechanism.links." + std::to_string(i);
    length(link + ".length", p.links[i].length);
    const double m = p.links[i].mass;
    if (m > 1e4) say(link + ".mass", m, "kg is outside 1e-6..1e4 kg: grams?");
    if (m < 1e-6) {
      say(link + ".mass", m,
          "kg is outside 1e-6..1e4 kg: a microscale mechanism, or another unit?");
    }
  }
}

// The coefficients of every law (a scene may carry those of other laws too): required when the
// scene's law requires them, else their default; > 0 where the law needs it, or where the
// default itself is positive (the Stribeck exponent), else >= 0.
void read_coefficients(const SceneReader& r, const LawDescriptor& law, FrictionParams<double>* f) {
  for (const CoefficientInfo& c : kCoefficientInfo) {  // mu_c before mu_s, which defaults to it
    const std::string key = std::string("friction.") + c.key;
    std::array<double, kJoints>& dst = coefficient(*f, c.id);
    if (!r.has(key) && c.same_as != c.id) {
      dst = coefficient(*f, c.same_as);
      continue;
    }
    const LawCoefficient* use = law_coefficient(law, c.id);
    const bool required = use && use->required;
    const bool pos = use ? use->positive : c.default_value > 0;
    dst = r.per_joint(key, required ? std::nullopt : std::optional<double>(c.default_value),
                      pos ? positive : non_negative, pos ? "> 0" : ">= 0");
  }
}

// check: a value with a domain, failing with the key, the domain and the offending value
void require(const SceneReader& r, const std::string& key, double x, bool ok,
             const std::string& domain) {
  if (!ok) r.fail(key, "must be " + domain + ", got " + num(x) + r.origin(key));
}

// the geometry of either mechanism (Params or FourBarParams: the same keys, P::links links)
template <class P>
void read_mechanism(const SceneReader& r, P* out) {
  P& p = *out;
  const int n = static_cast<int>(p.links.size());
  p.ground_length = r.number("mechanism.ground_length", std::nullopt);
  require(r, "mechanism.ground_length", p.ground_length, p.ground_length > 0, "> 0");
  if (r.link_count() != n) {
    r.fail("mechanism.links",
           "expected " + std::to_string(n) + " links, got " + std::to_string(r.link_count()) +
               r.link_line() + "; mechanism.type " + (r.four_bar() ? "four_bar" : "five_bar") +
               " has " + std::to_string(n) + " (five_bar 4, four_bar 3)");
  }
  for (int i = 0; i < n; ++i) {
    const std::string k = "mechanism.links." + std::to_string(i) + ".";
    Link<double>& link = p.links[i];
    link.length = r.number(k + "length", std::nullopt);
    require(r, k + "length", link.length, link.length > 0, "> 0");
    link.mass = r.number(k + "mass", std::nullopt);
    require(r, k + "mass", link.mass, link.mass > 0, "> 0");
    link.inertia = r.number(k + "inertia", std::nullopt);
    require(r, k + "inertia", link.inertia, link.inertia > 0, "> 0");
    link.com_offset = r.number(k + "com_offset", std::nullopt);
    require(r, k + "com_offset", link.com_offset, link.com_offset >= 0, ">= 0");
    link.com_angle = r.number(k + "com_angle", 0.0);
  }
  p.point_p = r.number("mechanism.point_p", std::nullopt);
  const std::string assembly = r.text("mechanism.assembly", "elbow_up");
  if (assembly == "elbow_up") {
    p.assembly = kElbowUp;
  } else if (assembly == "elbow_down") {
    p.assembly = kElbowDown;
  } else {
    r.fail("mechanism.assembly", "expected elbow_up or elbow_down, got '" + assembly + "'" +
                                     r.origin("mechanism.assembly"));
  }
  p.gravity = r.number("gravity", 9.81);

}

// friction: each law's coefficients are required only when that law is on
void read_friction(const SceneReader& r, FrictionParams<double>* out) {
  FrictionParams<double>& f = *out;
  const std::string model = r.text("friction.model", "none");
  const LawDescriptor* law = find_law(model);
  if (!law) {
    r.fail("friction.model", "expected one of " + law_names() + ", got '" + model + "'" +
                                 r.origin("friction.model"));
  }
  f.law = law->law;
  const bool on = f.active();
  f.pin_radius = r.per_joint("friction.pin_radius", on ? std::nullopt : std::optional<double>(0.0),
                             on ? positive : non_negative, on ? "> 0" : ">= 0");
  read_coefficients(r, *law, &f);
  f.smoothing_velocity = r.number("friction.smoothing_velocity", 0.0);
  require(r, "friction.smoothing_velocity", f.smoothing_velocity, f.smoothing_velocity >= 0, ">= 0");

}

// the motors' winding data (winding heat R (M / (k_t G))^2, docs/model.md): each value > 0; a
// scene gives R and k_t of all its `motors` motors or of none
void read_windings(const SceneReader& r, int motors, MotorWindings* out) {
  bool any = false;
  for (int a = 0; a < motors; ++a) {
    const std::string k = std::string("actuators.M") + std::to_string(a + 1) + ".";
    for (const char* key : {"winding_resistance", "torque_constant"}) any |= r.has(k + key);
  }
  for (int a = 0; a < motors; ++a) {
    const std::string k = std::string("actuators.M") + std::to_string(a + 1) + ".";
    const std::optional<double> none = any ? std::nullopt : std::optional<double>(0.0);
    out->resistance[a] = r.number(k + "winding_resistance", none);
    out->torque_constant[a] = r.number(k + "torque_constant", none);
    out->gear_ratio[a] = r.number(k + "gear_ratio", 1.0);
    if (any) {
      require(r, k + "winding_resistance", out->resistance[a], out->resistance[a] > 0, "> 0");
      require(r, k + "torque_constant", out->torque_constant[a], out->torque_constant[a] > 0,
              "> 0");
    }
    require(r, k + "gear_ratio", out->gear_ratio[a], out->gear_ratio[a] > 0, "> 0");
  }
}

// actuators: per motor (the five-bar's M1 at O, M2 at D0; the four-bar's M1 at O: `motors` of
// them) a sensor offset and a load-independent friction, which needs a joint friction law with a
// Coulomb sign (the stick-slip logic is the joint's)
void read_actuators(const SceneReader& r, FrictionLaw law, int motors,
                    ActuatorParams<double>* out) {
  for (int a = 0; a < motors; ++a) {
    const std::string k = std::string("actuators.M") + std::to_string(a + 1) + ".";
    out->offset[a] = r.number(k + "offset", 0.0);
    out->coulomb[a] = r.number(k + "coulomb", 0.0);
    out->viscous[a] = r.number(k + "viscous", 0.0);
    require(r, k + "coulomb", out->coulomb[a], out->coulomb[a] >= 0, ">= 0");
    require(r, k + "viscous", out->viscous[a], out->viscous[a] >= 0, ">= 0");
  }
  if (!actuator_friction_active(*out) || law_descriptor(law).coulomb_sign) return;
  const int a = out->coulomb[0] > 0 || out->viscous[0] > 0 ? 0 : 1;
  const std::string key = std::string("actuators.M") + std::to_string(a + 1) +
                          (out->coulomb[a] > 0 ? ".coulomb" : ".viscous");
  r.fail(key, std::string("actuator friction needs a friction.model with a Coulomb sign (") +
                  "coulomb_viscous, stribeck, power_viscous), got '" + law_descriptor(law).name +
                  "'" + r.origin(key));
}

// loads (compiled once here so that a bad expression is reported at load time), initial state
void read_loads_and_initial(const SceneReader& r, Scene* out) {
  Scene& s = *out;
  const bool five = s.type == MechanismType::kFiveBar;
  s.M1 = r.text("loads.M1", "0");
  s.M2 = r.text("loads.M2", "0");
  s.M3 = r.text("loads.M3", "0");
  s.F = r.text("loads.F", "0");
  s.F_angle = r.number("loads.F_angle", 0.0);
  static_cast<void>(LoadExpressions(s));

  // initial state (the four-bar's crank alone)
  s.initial.theta1 = r.number("initial.theta1", std::nullopt);
  s.initial.theta2 = five ? r.number("initial.theta2", std::nullopt) : 0.0;
  s.initial.omega1 = r.number("initial.omega1", 0.0);
  s.initial.omega2 = r.number("initial.omega2", 0.0);
  // beyond this an angle has lost its precision (at 1e20 rad one ulp is many turns)
  constexpr double kMaxAngle = 1e3;
  require(r, "initial.theta1", s.initial.theta1, std::abs(s.initial.theta1) <= kMaxAngle,
          "|theta| <= 1000 rad");
  require(r, "initial.theta2", s.initial.theta2, std::abs(s.initial.theta2) <= kMaxAngle,
          "|theta| <= 1000 rad");

}

// solver settings, defaults from sim::Options: tolerances and integrator
void read_integration(const SceneReader& r, FrictionLaw law, sim::Options* out) {
  sim::Options& o = *out;
  const sim::Options d;
  o.duration = r.number("simulation.duration", d.duration);
  require(r, "simulation.duration", o.duration, o.duration > 0, "> 0");
  o.output_step = r.number("simulation.output_step", d.output_step);
  require(r, "simulation.output_step", o.output_step, o.output_step > 0, "> 0");
  if (o.output_step > o.duration) {
    r.fail("simulation.output_step", "must not exceed simulation.duration = " + num(o.duration) +
                                         ", got " + num(o.output_step) +
                                         r.origin("simulation.output_step"));
  }
  // the default integrator is the friction law's (sim::default_method): stated in the scene, so
  // that a run with another law from these options (the frictionless twin) keeps it
  const std::string integrator =
      r.text("simulation.integrator", integrator_name(sim::default_method(law)));
  sim::Method method{};
  if (!parse_integrator(integrator, &method)) {
    std::string names;
    for (sim::Method m : sim::kAllMethods) {
      names += (names.empty() ? "" : ", ") + std::string(sim::method_name(m));
    }
    r.fail("simulation.integrator", "unknown integrator '" + integrator + "' (known: " + names +
                                        ")" + r.origin("simulation.integrator"));
  }
  o.method = method;
  o.rtol = r.number("simulation.rtol", d.rtol);
  require(r, "simulation.rtol", o.rtol, o.rtol > 0 && o.rtol < 1, "in (0, 1)");
  o.atol = r.number("simulation.atol", d.atol);
  require(r, "simulation.atol", o.atol, o.atol > 0 && o.atol < 1, "in (0, 1)");
  // neither tolerance given: `simulate` chooses them to meet target_error (sim::estimate.h)
  o.auto_tolerance = !r.has("simulation.rtol") && !r.has("simulation.atol");
  o.target_error = r.number("simulation.target_error", d.target_error);
  require(r, "simulation.target_error", o.target_error, o.target_error > 0 && o.target_error < 1,
          "in (0, 1)");
  const std::string rows = rows_beyond_limit(o.duration, o.output_step);
  if (!rows.empty()) {
    r.fail("simulation.duration, simulation.output_step",
           "duration " + num(o.duration) + " s at output_step " + num(o.output_step) + " s " +
               rows + " (shorten simulation.duration or raise simulation.output_step)");
  }
}

// solver settings: switches, limits, the friction loop and the rest rule
void read_solver_limits(const SceneReader& r, Scene* out) {
  Scene& s = *out;
  sim::Options& o = s.options;
  const sim::Options d;
  o.locate_switches = r.boolean("simulation.locate_switches", d.locate_switches);
  o.stick = r.boolean("simulation.stick", d.stick);
  o.max_steps = r.integer("simulation.max_steps", d.max_steps);
  require(r, "simulation.max_steps", o.max_steps, o.max_steps >= 1, ">= 1");
  o.singular_margin = r.number("simulation.singular_margin", d.singular_margin);
  require(r, "simulation.singular_margin", o.singular_margin,
          o.singular_margin >= 0 && o.singular_margin < 1, "in [0, 1)");
  o.friction_tol = r.number("simulation.friction_tol", d.friction_tol);
  require(r, "simulation.friction_tol", o.friction_tol, o.friction_tol > 0 && o.friction_tol < 1,
          "in (0, 1)");
  const long max_iter = r.integer("simulation.friction_max_iter", d.friction_max_iter);
  require(r, "simulation.friction_max_iter", max_iter, max_iter >= 1 && max_iter <= 1000000,
          "in [1, 1000000]");
  o.friction_max_iter = static_cast<int>(max_iter);
  // rest rule of inverse dynamics (rest.h): absent means derived from the rates' noise
  s.rest_rate_threshold = r.number("simulation.rest_rate_threshold", -1.0);
  s.rest_acceleration_threshold = r.number("simulation.rest_acceleration_threshold", -1.0);
  for (const char* key : {"simulation.rest_rate_threshold", "simulation.rest_acceleration_threshold"}) {
    if (r.has(key)) require(r, key, r.number(key, -1.0), r.number(key, -1.0) >= 0, ">= 0");
  }

}

// the initial pose must close, away from the coupler singularity (the model's closure)
void check_initial_pose(const SceneReader& r, const Scene& s) {
  const Params<double>& p = s.params;
  Kinematics<double> k;
  if (!solve_kinematics(p, s.initial.theta1, s.initial.theta2, &k, 0.0, false).ok()) {
    const double l3 = p.links[2].length, l4 = p.links[3].length;
    r.fail("initial", "the mechanism cannot assemble at theta1 = " + num(s.initial.theta1) +
                          ", theta2 = " + num(s.initial.theta2) +
                          ": |BD| = " + num((k.D - k.B).norm()) +
                          " m is outside [|l3 - l4|, l3 + l4] = [" + num(std::fabs(l3 - l4)) +
                          ", " + num(l3 + l4) + "] m");
  }
  const double sine = std::abs(k.sin43);
  if (sine < s.options.singular_margin) {
    r.fail("initial",
           "too close to a singular configuration (couplers aligned): |sin(th4 - th3)| "
           "= " +
               num(sine) + " < simulation.singular_margin = " + num(s.options.singular_margin));
  }
}

// the four-bar's initial crank angle must close, away from the toggle (coupler and rocker
// aligned, where the reactions grow as 1 / sin(th3 - th2))
void check_four_bar_pose(const SceneReader& r, const Scene& s) {
  FourBarKinematics k;
  const Status closed = four_bar_kinematics(s.four_bar, s.initial.theta1, &k);
  if (!closed.ok()) r.fail("initial", closed.message);
  const double sine = std::abs(k.sin32);
  if (sine < s.options.singular_margin) {
    r.fail("initial", "too close to a singular configuration (coupler and rocker aligned): "
                      "|sin(th3 - th2)| = " + num(sine) + " < simulation.singular_margin = " +
                          num(s.options.singular_margin));
  }
}

// mechanism.type, checked against the caller's mechanisms and the keys the scene gives: a
// five-bar key in a four-bar scene fails naming both
MechanismType read_type(const SceneReader& r, bool four_bar_ok) {
  const std::string type = r.text("mechanism.type", "five_bar");
  if (type != "five_bar" && type != "four_bar") {
    r.fail("mechanism.type", "expected five_bar or four_bar, got '" + type + "'" +
                                 r.origin("mechanism.type"));
  }
  if (type == "five_bar") return MechanismType::kFiveBar;
  if (!four_bar_ok) {
    r.fail("mechanism.type",
           "four_bar: this command runs five-bars only so far (simulate, "
           "inverse, synth-log, hold, animate, identify, excite, optimize, study, "
           "design and accuracy run four-bars)" +
               r.origin("mechanism.type"));
  }
  for (const std::string& key : r.keys()) {
    // the four-bar has one motor, M1 at O (the crank)
    const bool five_bar_key = key == "loads.M2" || key == "initial.theta2" ||
                              key == "initial.omega2" || key.rfind("actuators.M2", 0) == 0;
    if (five_bar_key) {
      r.fail(key,
             "is a five-bar key, not one of mechanism.type four_bar (one crank: loads M1, M3, "
             "F, F_angle; initial theta1, omega1; actuators.M1 only)" +
                 r.origin(key));
    }
  }
  return MechanismType::kFourBar;
}

Scene build_scene(const SceneReader& r, bool four_bar_ok) {
  Scene s;
  s.path = r.path();
  s.type = read_type(r, four_bar_ok);
  const bool five = s.type == MechanismType::kFiveBar;
  FrictionParams<double>& friction = five ? s.params.friction : s.four_bar.friction;
  if (five) {
    read_mechanism(r, &s.params);
  } else {
    read_mechanism(r, &s.four_bar);
  }
  read_friction(r, &friction);
  read_actuators(r, friction.law, five ? kActuators : 1,
                 five ? &s.params.actuators : &s.four_bar.actuators);
  read_windings(r, five ? kActuators : 1, &s.windings);
  read_loads_and_initial(r, &s);
  read_integration(r, friction.law, &s.options);
  read_solver_limits(r, &s);
  if (five) {
    check_initial_pose(r, s);
    plausibility_warnings(s.params, &s);
  } else {
    check_four_bar_pose(r, s);
    plausibility_warnings(s.four_bar, &s);
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
// Writing

// a YAML double-quoted scalar
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// the first `joints` values of v: one number when they are equal, else a list
std::string per_joint_yaml(const std::array<double, kJoints>& v, int joints) {
  if (std::all_of(v.begin(), v.begin() + joints, [&](double x) { return x == v[0]; })) {
    return num(v[0]);
  }
  std::string out = "[";
  for (int k = 0; k < joints; ++k) out += (k ? ", " : "") + num(v[k]);
  return out + "]";
}

}  // namespace

const char* integrator_name(sim::Method method) { return sim::method_name(method); }

bool parse_integrator(const std::string& name, sim::Method* out) {
  return sim::parse_method(name, out);
}

const char* friction_law_name(FrictionLaw law) { return law_descriptor(law).name; }

double coupler_sine(const Params<double>& p, double theta1, double theta2) {
  Kinematics<double> k;
  if (!solve_kinematics(p, theta1, theta2, &k, 0.0, false).ok()) return -1;
  return std::abs(k.sin43);
}

std::string rows_beyond_limit(double duration, double step) {
  sim::Options grid;
  grid.duration = duration;
  grid.output_step = step;
  const long rows = sim::output_row_count(grid);
  if (rows <= sim::kMaxOutputRows) return "";
  // exact where the count is (the grid's tolerance of 1e-12 steps is below a row)
  const std::string count =
      rows < 1e9 ? std::to_string(rows) : format_significant(duration / step, 3);
  return "needs " + count + " rows, more than the limit of " + std::to_string(sim::kMaxOutputRows);
}

std::string log_rows_problem(double duration, double rate_hz) {
  const std::string rows = rows_beyond_limit(duration, 1.0 / rate_hz);
  if (!rows.empty()) return rows;
  const double samples = std::floor(duration * rate_hz * (1 + 1e-12)) + 1;
  if (samples >= kMinLogSamples) return "";
  return "gives " + format_significant(samples, 3) + " sample" + (samples == 1 ? "" : "s") +
         ", fewer than the " + std::to_string(kMinLogSamples) + " of a torque log";
}

double four_bar_sine(const FourBarParams& p, double theta1) {
  FourBarKinematics k;
  return four_bar_kinematics(p, theta1, &k).ok() ? std::abs(k.sin32) : -1.0;
}

const char* mechanism_type_name(MechanismType type) {
  return type == MechanismType::kFourBar ? "four_bar" : "five_bar";
}

Scene parse_scene(const std::string& yaml_text, const std::string& path,
                  const std::vector<std::string>& sets, bool four_bar_ok) {
  SceneReader reader(path);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw InputError(
        path,
        "line " + std::to_string(e.mark.line + 1) + ", column " + std::to_string(e.mark.column + 1),
        "malformed YAML: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "(file)", std::string("malformed YAML: ") + e.what());
  }
  reader.read_root(root);
  for (const std::string& set : sets) reader.apply_set(set);
  return build_scene(reader, four_bar_ok);
}

std::vector<std::string> scene_keys(bool sections) {
  std::vector<std::string> keys;
  for (const Field& f : schema()) {
    if (!sections && (f.kind == Kind::kSection || f.kind == Kind::kLinkList)) continue;
    std::string key = f.key;
    const size_t hash = key.find('#');
    if (hash != std::string::npos) key[hash] = 'N';
    keys.push_back(key);
  }
  return keys;
}

const SceneLimit* scene_limit(const std::string& key) {
  std::string skey = key;
  const size_t n = skey.find(".N.");
  if (n != std::string::npos) skey[n + 1] = '#';
  const Field* f = find_field(skey);
  return f != nullptr && f->limit.high > 0 ? &f->limit : nullptr;
}

std::string limit_problem(const std::string& key, double value) {
  const SceneLimit* l = scene_limit(key);
  const double a = std::abs(value);
  if (l == nullptr || value == 0 || (a >= l->low && a <= l->high)) return "";
  const std::string unit = std::string(l->unit) == "-" ? "" : std::string(" ") + l->unit;
  std::string range =
      l->low > 0 ? "within [" + format_double(l->low) + ", " + format_double(l->high) + "]" + unit
                 : "at most " + format_double(l->high) + unit;
  if (l->high == std::numeric_limits<double>::max())
    range = "at least " + format_double(l->low) + unit;
  return "must be " + range + " in magnitude (the plausible range of a machine, " +
         "docs/scene.md), got " + format_double(value);
}

Scene read_scene(const std::string& path, const std::vector<std::string>& sets, bool four_bar_ok) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "(file)", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    throw InputError(path, "(file)", std::string("cannot read: ") + std::strerror(errno));
  return parse_scene(text.str(), path, sets, four_bar_ok);
}

Scene load_scene(const std::string& path, const std::vector<std::string>& sets, bool four_bar_ok) {
  Scene scene = read_scene(path, sets, four_bar_ok);
  for (const std::string& w : scene.warnings) warn(w);
  return scene;
}

namespace {

// mechanism: the type (four-bars only: five_bar is the default) and the links of either
template <class P>
void mechanism_yaml(const Scene& s, const P& p, std::ostringstream& y) {
  y << "mechanism:\n";
  if (s.type == MechanismType::kFourBar) y << "  type: four_bar\n";
  y << "  ground_length: " << num(p.ground_length) << "\n"
    << "  links:\n";
  for (const Link<double>& l : p.links) {
    y << "    - {length: " << num(l.length) << ", mass: " << num(l.mass)
      << ", inertia: " << num(l.inertia) << ", com_offset: " << num(l.com_offset)
      << ", com_angle: " << num(l.com_angle) << "}\n";
  }
  y << "  point_p: " << num(p.point_p) << "\n"
    << "  assembly: " << (p.assembly == kElbowDown ? "elbow_down" : "elbow_up") << "\n"
    << "gravity: " << num(p.gravity) << "\n";
}

// friction: the law and every coefficient of the mechanism's joints
void friction_yaml(const FrictionParams<double>& f, int joints, std::ostringstream& y) {
  y << "friction:\n"
    << "  model: " << friction_law_name(f.law) << "\n"
    << "  pin_radius: " << per_joint_yaml(f.pin_radius, joints) << "\n"
    << "  coulomb: " << per_joint_yaml(f.coulomb, joints) << "\n"
    << "  viscous: " << per_joint_yaml(f.viscous, joints) << "\n";
  // the other coefficients, where they differ from their defaults
  for (const CoefficientInfo& c : kCoefficientInfo) {
    if (c.id == Coefficient::kCoulomb || c.id == Coefficient::kViscous) continue;
    std::array<double, kJoints> fallback;
    fallback.fill(c.default_value);
    if (c.same_as != c.id) fallback = coefficient(f, c.same_as);
    const std::array<double, kJoints>& v = coefficient(f, c.id);
    if (!std::equal(v.begin(), v.begin() + joints, fallback.begin())) {
      y << "  " << c.key << ": " << per_joint_yaml(v, joints) << "\n";
    }
  }
  y << "  smoothing_velocity: " << num(f.smoothing_velocity) << "\n";
}

// actuators: the five-bar's motor terms, when any differs from the defaults
void actuators_yaml(const Scene& s, std::ostringstream& y) {
  const ActuatorParams<double>& act = s.params.actuators;
  const MotorWindings& wd = s.windings;
  const bool geared = wd.gear_ratio != MotorWindings().gear_ratio;
  if (act.offset == ActuatorParams<double>().offset && !actuator_friction_active(act) &&
      !wd.present() && !geared) {
    return;
  }
  y << "actuators:\n";
  for (int a = 0; a < kActuators; ++a) {
    y << "  M" << a + 1 << ": {offset: " << num(act.offset[a]) << ", coulomb: "
      << num(act.coulomb[a]) << ", viscous: " << num(act.viscous[a]);
    if (wd.present()) {
      y << ", winding_resistance: " << num(wd.resistance[a])
        << ", torque_constant: " << num(wd.torque_constant[a]);
    }
    if (wd.present() || geared) y << ", gear_ratio: " << num(wd.gear_ratio[a]);
    y << "}\n";
  }
}

// actuators: the four-bar's one motor's terms and winding data, when any is given
void four_bar_actuators_yaml(const ActuatorParams<double>& act, const MotorWindings& wd,
                             std::ostringstream& y) {
  const bool geared = wd.gear_ratio[0] != MotorWindings().gear_ratio[0];
  const bool terms = act.offset[0] != 0.0 || actuator_friction_active(act);
  if (!terms && !wd.present(1) && !geared) return;
  y << "actuators:\n  M1: {";
  const char* sep = "";
  if (terms) {
    y << "offset: " << num(act.offset[0]) << ", coulomb: " << num(act.coulomb[0])
      << ", viscous: " << num(act.viscous[0]);
    sep = ", ";
  }
  if (wd.present(1)) {
    y << sep << "winding_resistance: " << num(wd.resistance[0])
      << ", torque_constant: " << num(wd.torque_constant[0]);
    sep = ", ";
  }
  if (wd.present(1) || geared) y << sep << "gear_ratio: " << num(wd.gear_ratio[0]);
  y << "}\n";
}

}  // namespace

std::string scene_to_yaml(const Scene& s) {
  const bool four_bar = s.type == MechanismType::kFourBar;
  const sim::Options& o = s.options;
  std::ostringstream y;
  if (four_bar) {
    mechanism_yaml(s, s.four_bar, y);
    friction_yaml(s.four_bar.friction, kFourBarJoints, y);
    four_bar_actuators_yaml(s.four_bar.actuators, s.windings, y);
  } else {
    mechanism_yaml(s, s.params, y);
    friction_yaml(s.params.friction, kJoints, y);
    actuators_yaml(s, y);
  }
  y << "loads:\n"
    << "  M1: " << quoted(s.M1) << "\n";
  if (!four_bar) y << "  M2: " << quoted(s.M2) << "\n";
  y << "  M3: " << quoted(s.M3) << "\n"
    << "  F: " << quoted(s.F) << "\n"
    << "  F_angle: " << num(s.F_angle) << "\n";
  if (four_bar) {
    y << "initial: {theta1: " << num(s.initial.theta1) << ", omega1: " << num(s.initial.omega1)
      << "}\n";
  } else {
    y << "initial: {theta1: " << num(s.initial.theta1) << ", theta2: " << num(s.initial.theta2)
      << ", omega1: " << num(s.initial.omega1) << ", omega2: " << num(s.initial.omega2) << "}\n";
  }
  y << "simulation:\n"
    << "  duration: " << num(o.duration) << "\n"
    << "  output_step: " << num(o.output_step) << "\n"
    << "  integrator: " << integrator_name(sim::method_of(o, friction_of(s).law)) << "\n"
    << "  rtol: " << num(o.rtol) << "\n"
    << "  atol: " << num(o.atol) << "\n"
    << "  target_error: " << num(o.target_error) << "\n"
    << "  locate_switches: " << (o.locate_switches ? "true" : "false") << "\n"
    << "  stick: " << (o.stick ? "true" : "false") << "\n"
    << "  max_steps: " << o.max_steps << "\n"
    << "  singular_margin: " << num(o.singular_margin) << "\n"
    << "  friction_tol: " << num(o.friction_tol) << "\n"
    << "  friction_max_iter: " << o.friction_max_iter << "\n";
  if (s.rest_rate_threshold >= 0) y << "  rest_rate_threshold: " << num(s.rest_rate_threshold) << "\n";
  if (s.rest_acceleration_threshold >= 0) {
    y << "  rest_acceleration_threshold: " << num(s.rest_acceleration_threshold) << "\n";
  }
  return y.str();
}

}  // namespace fivebar::io
