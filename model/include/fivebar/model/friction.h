// Joint friction laws f_k(w) (eq. 3): Mf_k = r_k N_k f_k(w_k).
#pragma once

#include <cmath>
#include <string>

#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// Sign of the value part: +1, -1, or 0 at exactly zero (model.md: sign(0) = 0).
template <typename T>
int sign_of(const T& x) {
  const double v = value_of(x);
  return (v > 0.0) - (v < 0.0);
}

/// Stribeck level mu_c + (mu_s - mu_c) exp(-|w / w_st|^delta) (mu_c where w_st is unset).
template <typename T>
T stribeck_level(const FrictionParams<T>& fp, int k, const T& w) {
  using std::abs;
  using std::exp;
  using std::pow;
  if (!(value_of(fp.stribeck_velocity[k]) > 0.0)) return fp.coulomb[k];
  const T x = abs(w / fp.stribeck_velocity[k]);
  // exp(-x^delta) with a finite derivative at x = 0 for delta >= 1
  const T decay = value_of(x) == 0.0 ? T(1) : exp(-pow(x, fp.stribeck_exponent[k]));
  const T& mu_s = value_of(fp.static_coulomb[k]) > 0.0 ? fp.static_coulomb[k] : fp.coulomb[k];
  return fp.coulomb[k] + (mu_s - fp.coulomb[k]) * decay;
}

/// The direction the Coulomb part takes: `slip` (a coulomb_sign), or tanh(w / w_s) when the
/// smoothing velocity w_s > 0 (then `slip` is ignored). Shared by the joint laws and the
/// actuators' friction (actuator.h).
template <typename T>
T coulomb_direction(const FrictionParams<T>& fp, const T& w, int slip) {
  using std::tanh;
  return value_of(fp.smoothing_velocity) > 0.0 ? T(tanh(w / fp.smoothing_velocity))
                                               : T(double(slip));
}

/// The Coulomb-viscous law with the Coulomb part's direction s given: mu_c s + mu_v w (the
/// kCoulombViscous case of friction_law, for callers that decide the law once for all joints).
template <typename T>
T coulomb_viscous_law(const FrictionParams<T>& fp, int k, const T& w, const T& s) {
  return fp.coulomb[k] * s + fp.viscous[k] * w;
}

/// friction_law below reduces to coulomb_viscous_law with s = `slip` for every joint.
template <typename T>
bool plain_coulomb_viscous(const FrictionParams<T>& fp) {
  return fp.law == FrictionLaw::kCoulombViscous && !(value_of(fp.smoothing_velocity) > 0.0);
}

/// f_k(w) of joint k (0-based, order O, B, C, D, D0). `slip` is the sign that the Coulomb part
/// takes: the caller passes sign(w) or, inside an integration segment, the segment's slip
/// direction (so that sign(w) never jumps inside a step). With smoothing_velocity w_s > 0 the
/// Coulomb part is mu_c tanh(w / w_s) and `slip` is ignored.
template <typename T>
T friction_law(const FrictionParams<T>& fp, int k, const T& w, int slip) {
  using std::abs;
  using std::pow;
  if (fp.law == FrictionLaw::kNone || fp.law == FrictionLaw::kLuGre) {
    return T(0);  // none; LuGre needs the bristle state: see lugre_law
  }
  const T coulomb_sign = coulomb_direction(fp, w, slip);
  const T level = fp.law == FrictionLaw::kStribeck ? stribeck_level(fp, k, w) : fp.coulomb[k];
  if (fp.law == FrictionLaw::kPowerViscous) {
    // |w|^n sign(w); at w = 0 exactly the term is 0 (pow's derivative there is not finite)
    const T viscous =
        value_of(w) == 0.0 ? T(0) : pow(abs(w), fp.viscous_exponent[k]) * (w / abs(w));
    return level * coulomb_sign + fp.viscous[k] * viscous;
  }
  return level * coulomb_sign + fp.viscous[k] * w;
}

/// LuGre friction coefficient f = sigma0 z + sigma1 zdot + sigma2 w and the bristle rate zdot
/// of joint k at relative rate w and bristle deflection z.
template <typename T>
T lugre_law(const FrictionParams<T>& fp, int k, const T& w, const T& z, T* zdot) {
  using std::abs;
  const T g = stribeck_level(fp, k, w);
  *zdot = w - fp.sigma0[k] * abs(w) * z / g;
  return fp.sigma0[k] * z + fp.sigma1[k] * (*zdot) + fp.sigma2[k] * w;
}

/// mu_s,k r_k: a stuck joint holds while |holding torque| <= mu_s,k r_k N_k. The static
/// coefficient falls back to the Coulomb one when it is not set (zero).
template <typename T>
T holding_bound(const FrictionParams<T>& fp, int k) {
  const T& mu_s = value_of(fp.static_coulomb[k]) > 0.0 ? fp.static_coulomb[k] : fp.coulomb[k];
  return mu_s * fp.pin_radius[k];
}

// ---------------------------------------------------------------------------------------------
// Friction laws as descriptors: everything the scene schema and writer, identification and the
// synthetic-log header need to know about a law and its coefficients comes from here. A new law
// adds its enum value and coefficient arrays (params.h), its entry below and its f(w) in this file.

/// The per-joint coefficient arrays of FrictionParams, by id (order: scene writer order).
enum class Coefficient : int {
  kCoulomb = 0,
  kViscous,
  kStaticCoulomb,
  kStribeckVelocity,
  kStribeckExponent,
  kSigma0,
  kSigma1,
  kSigma2,
  kViscousExponent,
};
inline constexpr int kCoefficients = 9;

/// The array of coefficient `c` in `fp`.
template <typename T>
std::array<T, kJoints>& coefficient(FrictionParams<T>& fp, Coefficient c) {
  switch (c) {
    case Coefficient::kCoulomb: return fp.coulomb;
    case Coefficient::kViscous: return fp.viscous;
    case Coefficient::kStaticCoulomb: return fp.static_coulomb;
    case Coefficient::kStribeckVelocity: return fp.stribeck_velocity;
    case Coefficient::kStribeckExponent: return fp.stribeck_exponent;
    case Coefficient::kSigma0: return fp.sigma0;
    case Coefficient::kSigma1: return fp.sigma1;
    case Coefficient::kSigma2: return fp.sigma2;
    case Coefficient::kViscousExponent: return fp.viscous_exponent;
  }
  return fp.coulomb;  // unreachable
}
template <typename T>
const std::array<T, kJoints>& coefficient(const FrictionParams<T>& fp, Coefficient c) {
  return coefficient(const_cast<FrictionParams<T>&>(fp), c);
}

/// One coefficient: its scene key (`friction.<key>`, also the identification name stem), symbol,
/// unit and meaning, its value when a scene omits it (also FrictionParams' default), and where
/// identification starts it when it is fitted.
struct CoefficientInfo {
  Coefficient id;
  const char* key;
  const char* symbol;
  const char* unit;
  const char* meaning;
  double default_value;  ///< when omitted (and not `same_as`)
  /// when omitted, the value of this coefficient instead (mu_s defaults to mu_c); or itself
  Coefficient same_as;
  double start;  ///< identification's neutral start, independent of the scene
};

inline constexpr CoefficientInfo kCoefficientInfo[kCoefficients] = {
    {Coefficient::kCoulomb, "coulomb", "mu_c", "-", "kinetic (Coulomb) coefficient", 0.0,
     Coefficient::kCoulomb, 0.1},
    {Coefficient::kViscous, "viscous", "mu_v", "s/rad", "viscous coefficient", 0.0,
     Coefficient::kViscous, 0.01},
    {Coefficient::kStaticCoulomb, "static_coulomb", "mu_s", "-",
     "static coefficient: Stribeck peak and holding bound of a stuck joint", 0.0,
     Coefficient::kCoulomb, 0.15},
    {Coefficient::kStribeckVelocity, "stribeck_velocity", "w_st", "rad/s", "Stribeck velocity",
     0.0, Coefficient::kStribeckVelocity, 0.2},
    {Coefficient::kStribeckExponent, "stribeck_exponent", "delta", "-", "Stribeck exponent",
     kDefaultStribeckExponent, Coefficient::kStribeckExponent, kDefaultStribeckExponent},
    {Coefficient::kSigma0, "sigma0", "sigma0", "1/rad", "LuGre bristle stiffness", 0.0,
     Coefficient::kSigma0, 0.0},
    {Coefficient::kSigma1, "sigma1", "sigma1", "s/rad", "LuGre bristle damping", 0.0,
     Coefficient::kSigma1, 0.0},
    {Coefficient::kSigma2, "sigma2", "sigma2", "s/rad", "LuGre viscous coefficient", 0.0,
     Coefficient::kSigma2, 0.0},
    {Coefficient::kViscousExponent, "viscous_exponent", "n", "-", "exponent of the viscous rate",
     kDefaultViscousExponent, Coefficient::kViscousExponent, kDefaultViscousExponent},
};

inline const CoefficientInfo& coefficient_info(Coefficient c) {
  return kCoefficientInfo[static_cast<int>(c)];
}

/// How a law uses one coefficient.
struct LawCoefficient {
  Coefficient id;
  bool required;      ///< the scene must give it when the law is on
  bool positive;      ///< must be > 0 (else >= 0)
  bool identifiable;  ///< `identify` estimates it for this law
  /// `identify` gives it a profile-likelihood interval, not only a Wald one: the cost is far
  /// from quadratic in it (the Stribeck peak's height and width trade off)
  bool profiled;
};

/// A friction law f(w, z) of Mf_k = r_k N_k f_k(w_k).
struct LawDescriptor {
  FrictionLaw law;
  const char* name;     ///< scene name (friction.model) and identify --law name
  const char* formula;  ///< f(w) in the notation of docs/model.md
  const LawCoefficient* coefficients;
  int count;
  int states_per_joint;  ///< extra ODE states per joint (LuGre: the bristle deflection z)
  /// has a sign(w) jump (no internal state decides the friction's direction): with the exact
  /// sign, switches are located and joints stick
  bool coulomb_sign;
};

// {id, required, positive, identifiable, profiled}
inline constexpr LawCoefficient kCoulombViscousCoefficients[] = {
    {Coefficient::kCoulomb, true, false, true, false},
    {Coefficient::kViscous, true, false, true, false},
    {Coefficient::kStaticCoulomb, false, false, false, false},
};
inline constexpr LawCoefficient kStribeckCoefficients[] = {
    {Coefficient::kCoulomb, true, false, true, false},
    {Coefficient::kViscous, true, false, true, false},
    {Coefficient::kStaticCoulomb, false, false, true, true},
    {Coefficient::kStribeckVelocity, true, true, true, true},
    {Coefficient::kStribeckExponent, false, true, false, false},
};
inline constexpr LawCoefficient kLuGreCoefficients[] = {
    {Coefficient::kCoulomb, true, false, false, false},
    {Coefficient::kStaticCoulomb, false, false, false, false},
    {Coefficient::kStribeckVelocity, false, false, false, false},
    {Coefficient::kStribeckExponent, false, true, false, false},
    {Coefficient::kSigma0, true, true, false, false},
    {Coefficient::kSigma1, false, false, false, false},
    {Coefficient::kSigma2, false, false, false, false},
};

inline constexpr LawCoefficient kPowerViscousCoefficients[] = {
    {Coefficient::kCoulomb, true, false, true, false},
    {Coefficient::kViscous, true, false, true, false},
    {Coefficient::kStaticCoulomb, false, false, false, false},
    {Coefficient::kViscousExponent, true, true, false, false},
};

inline constexpr LawDescriptor kLaws[] = {
    {FrictionLaw::kNone, "none", "0", nullptr, 0, 0, false},
    {FrictionLaw::kCoulombViscous, "coulomb_viscous", "mu_c sign(w) + mu_v w",
     kCoulombViscousCoefficients, 3, 0, true},
    {FrictionLaw::kStribeck, "stribeck",
     "(mu_c + (mu_s - mu_c) exp(-|w / w_st|^delta)) sign(w) + mu_v w", kStribeckCoefficients, 5,
     0, true},
    {FrictionLaw::kLuGre, "lugre",
     "sigma0 z + sigma1 dz/dt + sigma2 w, dz/dt = w - sigma0 |w| z / g(w)", kLuGreCoefficients, 7,
     1, false},
    {FrictionLaw::kPowerViscous, "power_viscous", "mu_c sign(w) + mu_v |w|^n sign(w)",
     kPowerViscousCoefficients, 4, 0, true},
};

inline constexpr const LawDescriptor& law_descriptor(FrictionLaw law) {
  for (const LawDescriptor& d : kLaws) {
    if (d.law == law) return d;
  }
  return kLaws[0];
}

/// The most ODE states any law adds per joint (the simulator's state array holds kJoints times
/// as many after the mechanism's).
constexpr int max_states_per_joint() {
  int n = 0;
  for (const LawDescriptor& d : kLaws) n = d.states_per_joint > n ? d.states_per_joint : n;
  return n;
}
inline constexpr int kMaxStatesPerJoint = max_states_per_joint();

/// The exact Coulomb sign(w) is used, with switch functions on the joints' rates: a law with a
/// sign jump (LawDescriptor::coulomb_sign) and smoothing_velocity = 0 (no tanh).
inline bool exact_sign(const FrictionParams<double>& friction) {
  return law_descriptor(friction.law).coulomb_sign && friction.smoothing_velocity == 0.0;
}

/// The law named `name` (scene / command-line name), or nullptr.
inline const LawDescriptor* find_law(const std::string& name) {
  for (const LawDescriptor& d : kLaws) {
    if (name == d.name) return &d;
  }
  return nullptr;
}

/// "none, coulomb_viscous, stribeck, lugre": for "expected one of" messages.
inline std::string law_names() {
  std::string out;
  for (const LawDescriptor& d : kLaws) out += (out.empty() ? "" : ", ") + std::string(d.name);
  return out;
}

/// How `law` uses coefficient `c`, or nullptr when it does not.
inline const LawCoefficient* law_coefficient(const LawDescriptor& law, Coefficient c) {
  for (int i = 0; i < law.count; ++i) {
    if (law.coefficients[i].id == c) return &law.coefficients[i];
  }
  return nullptr;
}

/// Whether `law` identifies coefficient c (`identify` estimates it).
inline bool identifies(const LawDescriptor& law, Coefficient c) {
  const LawCoefficient* use = law_coefficient(law, c);
  return use && use->identifiable;
}

}  // namespace fivebar
