// Joint friction laws f_k(w) (eq. 3): Mf_k = r_k N_k f_k(w_k).
#pragma once

#include <cmath>

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

/// f_k(w) of joint k (0-based, order O, B, C, D, D0). `slip` is the sign that the Coulomb part
/// takes: the caller passes sign(w) or, inside an integration segment, the segment's slip
/// direction (so that sign(w) never jumps inside a step). With smoothing_velocity w_s > 0 the
/// Coulomb part is mu_c tanh(w / w_s) and `slip` is ignored.
template <typename T>
T friction_law(const FrictionParams<T>& fp, int k, const T& w, int slip) {
  using std::tanh;
  if (fp.law != FrictionLaw::kCoulombViscous && fp.law != FrictionLaw::kStribeck) {
    return T(0);  // none; LuGre needs the bristle state: see lugre_law
  }
  const T coulomb_sign =
      value_of(fp.smoothing_velocity) > 0.0 ? T(tanh(w / fp.smoothing_velocity)) : T(double(slip));
  const T level = fp.law == FrictionLaw::kStribeck ? stribeck_level(fp, k, w) : fp.coulomb[k];
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

}  // namespace fivebar
