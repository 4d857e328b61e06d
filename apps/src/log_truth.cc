#include "fivebar/io/log_truth.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "fivebar/io/format.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/inertial.h"

namespace fivebar::io {
namespace id = fivebar::identification;
namespace {

// the first n values of v, comma-separated
template <size_t N>
std::string joined(const std::array<double, N>& v, size_t n = N) {
  std::string s;
  for (size_t k = 0; k < n; ++k) s += (k ? "," : "") + format_double(v[k]);
  return s;
}

// the law, pin radii, coulomb and viscous of `joints` joints
std::vector<std::string> friction_truth(const FrictionParams<double>& fp, size_t joints) {
  return {" true.law = " + std::string(id::law_name(fp.law)),
          " true.pin_radius = " + joined(fp.pin_radius, joints),
          " true.coulomb = " + joined(fp.coulomb, joints),
          " true.viscous = " + joined(fp.viscous, joints)};
}

// the law's other coefficients of `joints` joints, appended to out
void law_truth(const FrictionParams<double>& fp, size_t joints, std::vector<std::string>* out) {
  const LawDescriptor& law = law_descriptor(fp.law);
  for (int i = 0; i < law.count; ++i) {
    const Coefficient c = law.coefficients[i].id;
    if (c == Coefficient::kCoulomb || c == Coefficient::kViscous) continue;
    out->push_back(" true." + std::string(coefficient_info(c).key) + " = " +
                   joined(coefficient(fp, c), joints));
  }
}

// true.offset, true.actuator_coulomb, true.actuator_viscous of the first `actuators` actuators,
// appended to out
void actuator_truth(const ActuatorParams<double>& act, size_t actuators,
                    std::vector<std::string>* out) {
  const std::array<double, kActuators>* terms[] = {&act.offset, &act.coulomb, &act.viscous};
  for (int g = 0; g < 3; ++g) {
    const std::string name = id::actuator_term_name(g * kActuators);
    out->push_back(" true." + name.substr(0, name.size() - 2) + " = " +
                   joined(*terms[g], actuators));
  }
}

}  // namespace

std::vector<std::string> truth_lines(const FourBarParams& params) {
  std::vector<std::string> out = friction_truth(params.friction, kFourBarJoints);
  std::array<double, kInertialPerLink * kFourBarLinks> pi{};
  standard_inertial_links(params.links.data(), kFourBarLinks, pi.data());
  out.push_back(" true.inertial = " + joined(pi));
  actuator_truth(params.actuators, 1, &out);
  law_truth(params.friction, kFourBarJoints, &out);
  return out;
}

std::vector<std::string> truth_lines(const Params<double>& params) {
  std::vector<std::string> out = friction_truth(params.friction, kJoints);
  out.push_back(" true.inertial = " + joined(standard_inertial(params)));
  actuator_truth(params.actuators, kActuators, &out);
  law_truth(params.friction, kJoints, &out);
  return out;
}

namespace {

// the values of one `true.<key> = v1,v2,...` line; empty with *reason set when they do not read
std::vector<double> truth_values(const std::string& text, std::string* reason) {
  std::stringstream ss(text);
  std::string cell;
  std::vector<double> v;
  while (std::getline(ss, cell, ',')) {
    double x = 0;
    if (!parse_finite(cell, &x)) {
      *reason = "'" + trim(cell) + "' is not a finite number";
      return {};
    }
    v.push_back(x);
  }
  if (!text.empty() && text.back() == ',') *reason = "a trailing comma";
  const size_t n = v.size();
  if (reason->empty() && !(n == kJoints || n == kFourBarJoints || n == kInertialParams ||
                           n == kInertialPerLink * kFourBarLinks || n == kActuators || n == 1)) {
    *reason = std::to_string(n) + " values (1, 2, 4, 5, 12 or 16 are read)";
  }
  return reason->empty() ? v : std::vector<double>{};
}

}  // namespace

LogTruth read_truth(const std::vector<std::string>& comments, std::vector<std::string>* unread) {
  LogTruth truth;
  for (const std::string& c : comments) {
    const std::string line = trim(c);
    if (line.rfind("true.", 0) != 0) continue;
    const size_t eq = line.find('=');
    const std::string key = trim(line.substr(0, eq));
    std::string reason = eq == std::string::npos ? "no '='" : "";
    const std::vector<double> v =
        reason.empty() ? truth_values(trim(line.substr(eq + 1)), &reason) : std::vector<double>{};
    if (!reason.empty()) {
      if (unread && key != "true.law") unread->push_back(key + ": " + reason);
      continue;
    }
    if (!truth.emplace(key.substr(5), v).second && unread) {
      unread->push_back(key + ": given again (the first line is read)");
    }
  }
  return truth;
}

std::vector<std::string> truth_not_compared(const LogTruth& truth,
                                            const identification::ParameterLayout& layout) {
  std::map<std::string, int> counts = {{"pin_radius", layout.joints},
                                       {"inertial", layout.inertial_size()},
                                       {"offset", layout.actuators},
                                       {"actuator_coulomb", layout.actuators},
                                       {"actuator_viscous", layout.actuators}};
  for (int c = 0; c < kCoefficients; ++c) {
    counts[coefficient_info(static_cast<Coefficient>(c)).key] = layout.joints;
  }
  std::vector<std::string> out;
  for (const auto& [key, v] : truth) {
    auto it = counts.find(key);
    if (it == counts.end()) {
      out.push_back("true." + key + ": no such parameter");
    } else if (v.size() != size_t(it->second)) {
      out.push_back("true." + key + ": " + std::to_string(v.size()) +
                    (v.size() == 1 ? " value" : " values") + ", where this " +
                    (layout.joints == kFourBarJoints ? "four_bar" : "five-bar") + " has " +
                    std::to_string(it->second));
    }
  }
  return out;
}

bool true_value(const LogTruth& truth, const id::ParameterLayout& layout, int i,
                const std::string& name, double* value) {
  if (layout.is_actuator(i)) {  // true.offset = A,B (a four-bar's: A); true.actuator_coulomb = ...
    const size_t cut = name.rfind('_');
    auto it = truth.find(name.substr(0, cut));
    if (it == truth.end() || it->second.size() != size_t(layout.actuators)) return false;
    *value = it->second[std::stoi(name.substr(cut + 1)) - 1];
    return true;
  }
  if (layout.is_inertial(i)) {
    auto it = truth.find("inertial");
    if (it == truth.end() || it->second.size() != size_t(layout.inertial_size())) return false;
    *value = it->second[i - layout.inertia_offset()];
    return true;
  }
  const size_t us = name.rfind('_');
  const bool indexed = layout.per_joint && us != std::string::npos;
  auto it = truth.find(indexed ? name.substr(0, us) : name);
  if (it == truth.end() || it->second.size() != size_t(layout.joints)) return false;
  if (indexed) {
    *value = it->second[std::stoi(name.substr(us + 1)) - 1];
    return true;
  }
  // a shared coefficient has a truth only when the joints share it (the mean of differing
  // values is no value the fit should reach: a shared fit of a per-joint log read 50 std off it)
  const auto [lo, hi] = std::minmax_element(it->second.begin(), it->second.end());
  if (*hi - *lo > 1e-12 * std::max(std::abs(*hi), std::abs(*lo))) return false;
  *value = *lo;
  return true;
}

}  // namespace fivebar::io
