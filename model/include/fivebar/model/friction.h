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

/// f_k(w) of joint k (0-based, order O, B, C, D, D0). `slip` is the sign that the Coulomb part
/// takes: the caller passes sign(w) or, inside an integration segment, the segment's slip
/// direction (so that sign(w) never jumps inside a step). With smoothing_velocity w_s > 0 the
/// Coulomb part is mu_c tanh(w / w_s) and `slip` is ignored.
template <typename T>
T friction_law(const FrictionParams<T>& fp, int k, const T& w, int slip) {
  using std::tanh;
  switch (fp.law) {
    case FrictionLaw::kNone:
      return T(0);
    case FrictionLaw::kCoulombViscous: {
      const T coulomb_sign =
          value_of(fp.smoothing_velocity) > 0.0 ? T(tanh(w / fp.smoothing_velocity)) : T(double(slip));
      return fp.coulomb[k] * coulomb_sign + fp.viscous[k] * w;
    }
    case FrictionLaw::kStribeck: {
      using std::abs;
      using std::exp;
      using std::pow;
      const T coulomb_sign =
          value_of(fp.smoothing_velocity) > 0.0 ? T(tanh(w / fp.smoothing_velocity)) : T(double(slip));
      // |w / w_st|^delta, written so that w = 0 has a finite derivative for delta >= 1
      const T x = abs(w / fp.stribeck_velocity[k]);
      const T decay = value_of(x) == 0.0 ? T(1) : exp(-pow(x, fp.stribeck_exponent[k]));
      const T level = fp.coulomb[k] + (fp.static_coulomb[k] - fp.coulomb[k]) * decay;
      return level * coulomb_sign + fp.viscous[k] * w;
    }
  }
  return T(0);
}

/// mu_s,k r_k: a stuck joint holds while |holding torque| <= mu_s,k r_k N_k. The static
/// coefficient falls back to the Coulomb one when it is not set (zero).
template <typename T>
T holding_bound(const FrictionParams<T>& fp, int k) {
  const T& mu_s = value_of(fp.static_coulomb[k]) > 0.0 ? fp.static_coulomb[k] : fp.coulomb[k];
  return mu_s * fp.pin_radius[k];
}

}  // namespace fivebar
