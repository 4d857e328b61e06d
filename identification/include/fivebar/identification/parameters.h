// The parameters that identification estimates, in groups, and how they map onto the model:
// the friction coefficients, then (group `inertia`) the 16 standard inertial parameters of the
// links (model/inertial.h). `fivebar excite` designs excitations for the same groups.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/inertial.h"
#include "fivebar/model/params.h"

namespace fivebar::identification {

/// The actuator group of the five-bar: offset, Coulomb and viscous friction of each of its two
/// actuators (a four-bar's: 3, ParameterLayout::actuator_size).
inline constexpr int kActuatorTerms = 3 * kActuators;

/// Name of actuator term i of `actuators` actuators (the five-bar's two: 0..5 offset_1, offset_2,
/// actuator_coulomb_1, actuator_coulomb_2, actuator_viscous_1, actuator_viscous_2, 1: tau1 / M1 at
/// O, 2: tau2 / M2 at D0; the four-bar's one: offset_1, actuator_coulomb_1, actuator_viscous_1).
inline std::string actuator_term_name(int i, int actuators = kActuators) {
  static const char* kStem[] = {"offset_", "actuator_coulomb_", "actuator_viscous_"};
  return kStem[i / actuators] + std::to_string(i % actuators + 1);
}

/// Which coefficients are free: the identifiable coefficients of the law's descriptor
/// (friction.h), in its order: coulomb, viscous, and for kStribeck also static_coulomb,
/// stribeck_velocity (the exponent stays at the scene's value). Shared: one
/// value per group for all five joints (names `coulomb`, `viscous`, ...); per joint: five per
/// group (`coulomb_1`..`coulomb_5` in joint order O, B, C, D, D0).
///
/// Groups and vector order: friction first (always, size friction_size()), then, when `inertia`,
/// the 16 standard inertial parameters m_1, mx_1, my_1, J_1, ..., J_4 (inertial.h: per link
/// mass [kg], first moments m c_x, m c_y [kg m] in the link frame, inertia about the proximal
/// joint [kg m^2]), then, when `actuator`, the 6 actuator terms (kActuatorTerms):
/// offset_1, offset_2 [N m] (torque-sensor biases of tau1, tau2), actuator_coulomb_1, _2 [N m]
/// and actuator_viscous_1, _2 [N m s/rad] (the motors' load-independent friction at O, D0).
struct ParameterLayout {
  FrictionLaw law = FrictionLaw::kCoulombViscous;
  bool per_joint = false;
  bool inertia = false;  ///< group `inertia`: the 16 standard inertial parameters follow
  bool actuator = false;  ///< group `actuator`: the 6 actuator terms follow
  /// Stribeck: the static_coulomb entries of the vector hold the excess static_coulomb - coulomb
  /// (>= 0 by its bound), so that a fit cannot return static friction below kinetic friction.
  /// identify() solves in this form and reports static_coulomb itself.
  bool static_as_excess = false;
  /// joints with friction (the five-bar's 5, the four-bar's 4: slots 0..joints-1 of the friction
  /// arrays; per joint, one coefficient each; shared, one value written to every slot)
  int joints = kJoints;
  /// moving links of the inertia group (the five-bar's 4; the four-bar's 3: crank, coupler,
  /// rocker, whose standard parameters are m_1 .. J_3) and actuators of the actuator group (the
  /// five-bar's 2; the four-bar's 1, its crank's: offset_1, actuator_coulomb_1, actuator_viscous_1)
  int links = kLinks;
  int actuators = kActuators;

  /// The four-bar's counts: its 4 joints, 3 links and 1 actuator (the crank's motor).
  void set_four_bar() {
    joints = kFourBarJoints;
    links = kFourBarLinks;
    actuators = 1;
  }

  /// The coefficient of friction group g (0 <= g < groups()).
  Coefficient group(int g) const {
    const LawDescriptor& d = law_descriptor(law);
    for (int i = 0, n = 0; i < d.count; ++i) {
      if (d.coefficients[i].identifiable && n++ == g) return d.coefficients[i].id;
    }
    return Coefficient::kCoulomb;  // unreachable for g < groups()
  }
  int groups() const {
    const LawDescriptor& d = law_descriptor(law);
    int n = 0;
    for (int i = 0; i < d.count; ++i) n += d.coefficients[i].identifiable;
    return n;
  }
  /// The group of coefficient c, or -1.
  int group_of(Coefficient c) const {
    for (int g = 0; g < groups(); ++g) {
      if (group(g) == c) return g;
    }
    return -1;
  }
  int per_group() const { return per_joint ? joints : 1; }
  int friction_size() const { return groups() * per_group(); }
  int inertia_offset() const { return friction_size(); }
  int inertial_size() const { return kInertialPerLink * links; }
  int actuator_size() const { return 3 * actuators; }
  int actuator_offset() const { return inertia_offset() + (inertia ? inertial_size() : 0); }
  int size() const { return actuator_offset() + (actuator ? actuator_size() : 0); }
  bool is_inertial(int i) const {
    return inertia && i >= inertia_offset() && i < actuator_offset();
  }
  bool is_actuator(int i) const { return actuator && i >= actuator_offset(); }

  /// Names of the parameters (interfaces.md: coulomb, viscous; coulomb_1..5, viscous_1..5).
  std::vector<std::string> names() const {
    std::vector<std::string> out;
    for (int g = 0; g < groups(); ++g) {
      const std::string key = coefficient_info(group(g)).key;
      for (int j = 0; j < per_group(); ++j) {
        out.push_back(per_joint ? key + "_" + std::to_string(j + 1) : key);
      }
    }
    if (inertia) {
      for (int i = 0; i < inertial_size(); ++i) out.push_back(inertial_name(i));
    }
    if (actuator) {
      for (int i = 0; i < actuator_size(); ++i) out.push_back(actuator_term_name(i, actuators));
    }
    return out;
  }

  /// Unit of parameter i.
  std::string unit(int i) const {
    if (is_inertial(i)) return inertial_unit(i - inertia_offset());
    if (is_actuator(i)) return (i - actuator_offset()) / actuators == 2 ? "N m s/rad" : "N m";
    const std::string u = coefficient_info(group(i / per_group())).unit;
    // f multiplies r_k N_k: a coefficient is per N m of load torque
    return u == "rad/s" ? u : (u == "-" ? "1" : "N m " + u) + " (per N m of load)";
  }

  /// Lower bound of each parameter: 0 for the friction coefficients, a small positive Stribeck
  /// velocity, a small positive mass (m > 0); the first moments and J_O are unbounded (the
  /// inertia about the COM is kept > 0 by identify()'s consistency term).
  double lower_bound(int i) const {
    if (is_actuator(i)) {  // offsets are signed; friction coefficients >= 0
      return i - actuator_offset() < actuators ? -std::numeric_limits<double>::max() : 0.0;
    }
    if (is_inertial(i)) {
      return (i - inertia_offset()) % kInertialPerLink == 0 ? 1e-6
                                                            : -std::numeric_limits<double>::max();
    }
    const LawCoefficient* c = law_coefficient(law_descriptor(law), group(i / per_group()));
    return c && c->positive ? 1e-4 : 0.0;
  }

  /// Writes the parameter vector x into `p`: its friction (law set to `law`) and, with the
  /// inertia group, its links' mass, COM and inertia.
  template <typename T>
  void apply(const T* x, Params<T>* p) const {
    apply(x, &p->friction);
    if (inertia) set_standard_inertial(x + inertia_offset(), p);
    if (actuator) apply_actuators(x + actuator_offset(), &p->actuators);
  }

  /// Writes the parameter vector x into the four-bar `p`: its friction (law set to `law`), with
  /// the inertia group its three links' mass, COM and inertia, with the actuator group its crank
  /// motor's terms (entry 0 of its actuators).
  template <typename T>
  void apply(const T* x, FourBarParamsT<T>* p) const {
    apply(x, &p->friction);
    if (inertia) set_standard_inertial_links(x + inertia_offset(), links, p->links.data());
    if (actuator) apply_actuators(x + actuator_offset(), &p->actuators, actuators);
  }

  /// Writes the 3 count actuator terms (offsets, Coulomb, viscous, count of each; the five-bar's
  /// kActuatorTerms order) into the first `count` actuators of `a`.
  template <typename T>
  static void apply_actuators(const T* x, ActuatorParams<T>* a, int count = kActuators) {
    for (int k = 0; k < count; ++k) {
      a->offset[k] = x[k];
      a->coulomb[k] = x[count + k];
      a->viscous[k] = x[2 * count + k];
    }
  }

  /// The actuator group's part of the parameter vector: the terms of the first `actuators`
  /// actuators of `a` (offsets, Coulomb, viscous).
  std::vector<double> extract_actuators(const ActuatorParams<double>& a) const {
    std::vector<double> x;
    for (const auto* terms : {&a.offset, &a.coulomb, &a.viscous}) {
      x.insert(x.end(), terms->begin(), terms->begin() + actuators);
    }
    return x;
  }

  /// The parameter vector of `p` (friction as extract(p.friction), then its inertial parameters).
  std::vector<double> extract(const Params<double>& p) const {
    std::vector<double> x = extract(p.friction);
    if (inertia) {
      const std::array<double, kInertialParams> pi = standard_inertial(p);
      x.insert(x.end(), pi.begin(), pi.end());
    }
    if (actuator) {
      const std::vector<double> a = extract_actuators(p.actuators);
      x.insert(x.end(), a.begin(), a.end());
    }
    return x;
  }

  /// Writes the parameter vector x into the friction of `fp` (law set to `law`).
  template <typename T>
  void apply(const T* x, FrictionParams<T>* fp) const {
    fp->law = law;
    const int n = friction_size();
    const int g_static = group_of(Coefficient::kStaticCoulomb);
    const int g_coulomb = group_of(Coefficient::kCoulomb);
    for (int i = 0; i < n; ++i) {
      // parameter i sets group i / per_group() at one joint (per joint) or at all of them
      const int g = i / per_group();
      std::array<T, kJoints>& d = coefficient(*fp, group(g));
      // static_as_excess: static_coulomb = coulomb (same joint) + excess
      const T v = static_as_excess && g == g_static
                      ? x[i] + x[i - (g_static - g_coulomb) * per_group()]
                      : x[i];
      if (per_joint) {
        d[i % joints] = v;
      } else {
        d.fill(v);
      }
    }
  }

  /// The friction part of the parameter vector of `fp` (shared: the mean over the joints).
  std::vector<double> extract(const FrictionParams<double>& fp) const {
    std::vector<double> x(friction_size(), 0.0);
    for (int g = 0; g < groups(); ++g) {
      const std::array<double, kJoints>& src = coefficient(fp, group(g));
      for (int k = 0; k < joints; ++k) {
        x[g * per_group() + (per_joint ? k : 0)] += src[k] / (per_joint ? 1.0 : joints);
      }
    }
    const int g_static = group_of(Coefficient::kStaticCoulomb);
    const int g_coulomb = group_of(Coefficient::kCoulomb);
    if (static_as_excess && g_static >= 0) {
      for (int j = 0; j < per_group(); ++j) {
        x[g_static * per_group() + j] -= x[g_coulomb * per_group() + j];
      }
    }
    return x;
  }
};

/// Parses a comma-separated list of parameter groups (`friction`, `inertia`, `actuator`, each
/// at most once, any order) into the three flags (groups listed: true). False on an unknown,
/// repeated or empty group, naming it in `bad` (the whole list when it names none).
inline bool parse_group_list(const std::string& list, std::array<bool, 3>* friction_inertia_actuator,
                             std::string* bad) {
  std::array<bool, 3>& on = *friction_inertia_actuator;
  on = {false, false, false};
  static const char* const kNames[3] = {"friction", "inertia", "actuator"};
  size_t pos = 0;
  while (true) {
    const size_t comma = list.find(',', pos);
    std::string g = list.substr(pos, comma == std::string::npos ? comma : comma - pos);
    g.erase(g.find_last_not_of(" \t") + 1);  // (spaces around a name are no part of it)
    g.erase(0, std::min(g.size(), g.find_first_not_of(" \t")));
    int k = 0;
    while (k < 3 && g != kNames[k]) ++k;
    if (k == 3 || on[k]) {
      *bad = list.empty() ? list : g;
      return false;
    }
    on[k] = true;
    if (comma == std::string::npos) return true;
    pos = comma + 1;
  }
}

/// The groups of `list` (parse_group_list) into `layout`; friction is always estimated.
inline bool parse_groups(const std::string& list, ParameterLayout* layout, std::string* bad) {
  std::array<bool, 3> on{};
  if (!parse_group_list(list, &on, bad)) return false;
  layout->inertia = on[1];
  layout->actuator = on[2];
  return true;
}

/// Parses the name of a law that identify fits (one with identifiable coefficients, friction.h);
/// false otherwise.
/// True when the law has a coefficient identify can fit.
inline bool law_is_identifiable(const LawDescriptor& d) {
  for (int i = 0; i < d.count; ++i) {
    if (d.coefficients[i].identifiable) return true;
  }
  return false;
}

inline bool parse_law(const std::string& name, FrictionLaw* law) {
  const LawDescriptor* d = find_law(name);
  if (!d || !law_is_identifiable(*d)) return false;
  *law = d->law;
  return true;
}

/// "coulomb_viscous | stribeck | ...": the laws parse_law accepts, from their descriptors.
inline std::string identifiable_law_names() {
  std::string out;
  for (const LawDescriptor& d : kLaws) {
    if (law_is_identifiable(d)) out += (out.empty() ? "" : " | ") + std::string(d.name);
  }
  return out;
}
inline const char* law_name(FrictionLaw law) { return law_descriptor(law).name; }

}  // namespace fivebar::identification
