// Kinetic and potential energy of the mechanism.
#pragma once

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// Kinetic energy sum (m_i |v_ci|^2 + J_i thd_i^2) / 2 = thd^T A thd / 2 [J].
template <typename T>
T kinetic_energy(const Params<T>& p, const Kinematics<T>& k, const T& w1, const T& w2) {
  const Vec2<T> thd(w1, w2);
  const T w3 = k.G3.dot(thd), w4 = k.G4.dot(thd);
  T ke = p.links[0].inertia * w1 * w1 + p.links[1].inertia * w2 * w2 +
         p.links[2].inertia * w3 * w3 + p.links[3].inertia * w4 * w4;
  for (int i = 0; i < kLinks; ++i) ke += p.links[i].mass * (k.Gc[i] * thd).squaredNorm();
  return T(0.5) * ke;
}

/// Potential energy U = g sum m_i y_ci [J] (eq. 8).
template <typename T>
T potential_energy(const Params<T>& p, const Kinematics<T>& k) {
  T u = T(0);
  for (int i = 0; i < kLinks; ++i) u += p.links[i].mass * k.c[i].y();
  return p.gravity * u;
}

}  // namespace fivebar
