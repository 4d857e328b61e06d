// The friction coefficients that identification estimates, and how they map onto the model.
#pragma once

#include <string>
#include <vector>

#include "fivebar/model/params.h"

namespace fivebar::identification {

/// Which coefficients are free. Groups, in order: coulomb, viscous, and for kStribeck also
/// static_coulomb, stribeck_velocity (the exponent stays at the scene's value). Shared: one
/// value per group for all five joints (names `coulomb`, `viscous`, ...); per joint: five per
/// group (`coulomb_1`..`coulomb_5` in joint order O, B, C, D, D0).
struct ParameterLayout {
  FrictionLaw law = FrictionLaw::kCoulombViscous;
  bool per_joint = false;
  /// Stribeck: the static_coulomb entries of the vector hold the excess static_coulomb - coulomb
  /// (>= 0 by its bound), so that a fit cannot return static friction below kinetic friction.
  /// identify() solves in this form and reports static_coulomb itself.
  bool static_as_excess = false;

  int groups() const { return law == FrictionLaw::kStribeck ? 4 : 2; }
  int per_group() const { return per_joint ? kJoints : 1; }
  int size() const { return groups() * per_group(); }

  /// Names of the parameters (interfaces.md: coulomb, viscous; coulomb_1..5, viscous_1..5).
  std::vector<std::string> names() const {
    static const char* const kGroups[] = {"coulomb", "viscous", "static_coulomb",
                                          "stribeck_velocity"};
    std::vector<std::string> out;
    for (int g = 0; g < groups(); ++g) {
      for (int j = 0; j < per_group(); ++j) {
        out.push_back(per_joint ? std::string(kGroups[g]) + "_" + std::to_string(j + 1)
                                : std::string(kGroups[g]));
      }
    }
    return out;
  }

  /// Lower bound of each parameter: 0 for the coefficients, a small positive Stribeck velocity.
  double lower_bound(int i) const { return i / per_group() == 3 ? 1e-4 : 0.0; }

  /// Writes the parameter vector x into the friction of `fp` (law set to `law`).
  template <typename T>
  void apply(const T* x, FrictionParams<T>* fp) const {
    fp->law = law;
    const std::array<std::array<T, kJoints>*, 4> dst = {
        &fp->coulomb, &fp->viscous, &fp->static_coulomb, &fp->stribeck_velocity};
    const int n = size();
    for (int i = 0; i < n; ++i) {
      // parameter i sets group i / per_group() at one joint (per joint) or at all five
      std::array<T, kJoints>& d = *dst[i / per_group()];
      // static_as_excess: static_coulomb = coulomb (same joint) + excess
      const T v = static_as_excess && i / per_group() == 2 ? x[i] + x[i - 2 * per_group()] : x[i];
      if (per_joint) {
        d[i % kJoints] = v;
      } else {
        d.fill(v);
      }
    }
  }

  /// The parameter vector of `fp` (shared: the mean over the joints).
  std::vector<double> extract(const FrictionParams<double>& fp) const {
    std::vector<double> x(size(), 0.0);
    const std::array<const std::array<double, kJoints>*, 4> src = {
        &fp.coulomb, &fp.viscous, &fp.static_coulomb, &fp.stribeck_velocity};
    for (int g = 0; g < groups(); ++g) {
      for (int k = 0; k < kJoints; ++k) {
        x[g * per_group() + (per_joint ? k : 0)] += (*src[g])[k] / (per_joint ? 1.0 : kJoints);
      }
    }
    if (static_as_excess && groups() > 2) {
      for (int j = 0; j < per_group(); ++j) x[2 * per_group() + j] -= x[j];
    }
    return x;
  }
};

/// Parses `coulomb_viscous` or `stribeck`; false otherwise.
inline bool parse_law(const std::string& name, FrictionLaw* law) {
  if (name == "coulomb_viscous")
    *law = FrictionLaw::kCoulombViscous;
  else if (name == "stribeck")
    *law = FrictionLaw::kStribeck;
  else
    return false;
  return true;
}
inline const char* law_name(FrictionLaw law) {
  switch (law) {
    case FrictionLaw::kNone:
      return "none";
    case FrictionLaw::kCoulombViscous:
      return "coulomb_viscous";
    case FrictionLaw::kStribeck:
      return "stribeck";
    case FrictionLaw::kLuGre:
      return "lugre";  // simulated by synth-log; not a law identify fits
  }
  return "unknown";
}

}  // namespace fivebar::identification
