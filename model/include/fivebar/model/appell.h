// Appell's equations (eq. 10 as corrected in model.md): the generalized mass matrix, the
// friction-free generalized forces, the relative joint rates and their Jacobian rows, and the
// generalized force of the friction torques.
// Conventions (model.md, joints table): joint k in order O, B, C, D, D0 joins body i to body j;
// F_k is the force body i exerts on body j; the friction torque Mf_k acts on j as -Mf_k and on
// i as +Mf_k. Link 1: F1 at O, -F2 at B. Link 3: F2 at B, -F3 at C. Link 4: F3 at C, -F4 at D.
// Link 2: F4 at D, F5 at D0.
#pragma once

#include <array>
#include <cmath>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// External force vector at P: F e(th3 + alpha_F) (model.md erratum 2).
template <typename T>
Vec2<T> force_vector(const Kinematics<T>& k, const Loads<T>& L) {
  using std::cos;
  using std::sin;
  if (is_exact_zero(L.F)) return Vec2<T>::Zero();
  return L.F * rotate(k.e3, T(cos(L.F_angle)), T(sin(L.F_angle)));
}

/// A (eq. 10) and the friction-free generalized force Q_U + M_d - b.
template <typename T>
void mass_and_forces(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b,
                     const Loads<T>& L, const Vec2<T>& Fvec, Mat2<T>* A, Vec2<T>* rhs) {
  // A = sum m_i G_ci^T G_ci + J_i G_i^T G_i, b = sum m_i G_ci^T h_ci + J_i G_i^T h_i
  A->setZero();
  (*A)(0, 0) = p.links[0].inertia;
  (*A)(1, 1) = p.links[1].inertia;
  *A += p.links[2].inertia * k.G3.transpose() * k.G3 + p.links[3].inertia * k.G4.transpose() * k.G4;
  Vec2<T> bias = p.links[2].inertia * b.h3 * k.G3.transpose() +
                 p.links[3].inertia * b.h4 * k.G4.transpose();
  for (int i = 0; i < kLinks; ++i) {
    const T& m = p.links[i].mass;
    *A += m * k.Gc[i].transpose() * k.Gc[i];
    bias += m * k.Gc[i].transpose() * b.hc[i];
  }
  // M_d = (M1, M2) + M3 G3^T + G_P^T F (eq. 9 with erratum 1), Q_U = -g sum m_i G_yci^T (eq. 8)
  *rhs = Vec2<T>(L.M1, L.M2) - bias;
  if (!is_exact_zero(L.M3)) *rhs += L.M3 * k.G3.transpose();
  if (!is_exact_zero(L.F)) *rhs += k.GP.transpose() * Fvec;
  if (!is_exact_zero(p.gravity)) {
    for (int i = 0; i < kLinks; ++i) {
      *rhs -= p.gravity * p.links[i].mass * k.Gc[i].row(1).transpose();
    }
  }
}

/// Relative joint rates w = J_w thd, order O, B, C, D, D0.
template <typename T>
std::array<T, kJoints> relative_rates(const T& w1, const T& w2, const T& w3, const T& w4) {
  return {w1, w3 - w1, w4 - w3, w2 - w4, w2};
}

/// Row k of J_w (w = J_w thd): O (1, 0), B G3 - (1, 0), C G4 - G3, D (0, 1) - G4, D0 (0, 1).
template <typename T>
Row2<T> joint_row(const Kinematics<T>& k, int j) {
  const Row2<T> e1(T(1), T(0)), e2(T(0), T(1));
  switch (j) {
    case 0: return e1;
    case 1: return k.G3 - e1;
    case 2: return k.G4 - k.G3;
    case 3: return e2 - k.G4;
    default: return e2;
  }
}

/// J_w^T Mf: the generalized force of the friction torques is Q_f = -J_w^T Mf (eq. 7).
template <typename T>
Vec2<T> friction_transpose(const Kinematics<T>& k, const std::array<T, kJoints>& Mf) {
  Vec2<T> q(Mf[0] - Mf[1], Mf[4] + Mf[3]);
  q += (Mf[1] - Mf[2]) * k.G3.transpose() + (Mf[2] - Mf[3]) * k.G4.transpose();
  return q;
}

/// One relative acceleration per joint (d/dt of w), from the link accelerations.
template <typename T>
std::array<T, kJoints> relative_accelerations(const Vec2<T>& thdd, const T& al3, const T& al4) {
  return relative_rates(thdd[0], thdd[1], al3, al4);
}

#ifdef FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM
// The command-line layer (apps/, at -O1) takes these double instances from fivebar::sim
// (model/src/double_instances.cc) rather than compiling -O1 copies the linker could keep in
// place of the libraries' optimized ones.
extern template void mass_and_forces<double>(const Params<double>&, const Kinematics<double>&,
                                             const Bias<double>&, const Loads<double>&,
                                             const Vec2<double>&, Mat2<double>*, Vec2<double>*);
#endif

}  // namespace fivebar
