// Newton-Euler joint reactions for given accelerations and friction torques.
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

namespace detail {

/// The reactions from the links' accelerations: coupler angular accelerations al3, al4,
/// centre-of-mass accelerations a, gravity gvec, loads Fvec (at P) and M3, friction torques Mf.
/// Links 3 and 4: moments about C give two equations in F2 (determinant l3 l4 sin(th4 - th3));
/// then F3, F4 from the coupler force balances and F1, F5 from the cranks'. Affine in
/// (al3, al4, a, gvec, Fvec, M3, Mf) jointly: all of them zero gives zero reactions.
template <typename T>
void reactions_of_accelerations(const Params<T>& p, const Kinematics<T>& k, const T& al3,
                                const T& al4, const std::array<Vec2<T>, kLinks>& a,
                                const Vec2<T>& gvec, const Vec2<T>& Fvec, const T& M3,
                                const std::array<T, kJoints>& Mf,
                                std::array<Vec2<T>, kJoints>* F) {
  const T& m1 = p.links[0].mass;
  const T& m2 = p.links[1].mass;
  const T& m3 = p.links[2].mass;
  const T& m4 = p.links[3].mass;
  // force balances: F2 - F3 = R3, F3 - F4 = R4
  const Vec2<T> R3 = m3 * (a[2] - gvec) - Fvec;
  const Vec2<T> R4 = m4 * (a[3] - gvec);
  // link 3 about C: (B-C) x F2 + (P-C) x Fvec + (c3-C) x m3 g + M3 - Mf2 + Mf3
  //                 = J3 al3 + m3 (c3-C) x a3
  const Vec2<T> u3 = k.B - k.C, u4 = k.D - k.C;
  const Vec2<T> q3 = k.c[2] - k.C, q4 = k.c[3] - k.C;
  const T S3 = p.links[2].inertia * al3 + m3 * cross(q3, Vec2<T>(a[2] - gvec)) -
               cross(Vec2<T>(k.P - k.C), Fvec) - M3 + Mf[1] - Mf[2];
  // link 4 about C: (D-C) x (-F4) + (c4-C) x m4 g - Mf3 + Mf4 = J4 al4 + m4 (c4-C) x a4,
  // with F4 = F2 - R3 - R4
  const T S4 = -p.links[3].inertia * al4 - m4 * cross(q4, Vec2<T>(a[3] - gvec)) - Mf[2] + Mf[3] +
               cross(u4, Vec2<T>(R3 + R4));
  // solve u3 x F2 = S3, u4 x F2 = S4
  const T det = cross(u3, u4);
  Vec2<T>& F2 = (*F)[1];
  F2.x() = (S3 * u4.x() - S4 * u3.x()) / det;
  F2.y() = (S3 * u4.y() - S4 * u3.y()) / det;
  (*F)[2] = F2 - R3;
  (*F)[3] = (*F)[2] - R4;
  // cranks: F1 - F2 + m1 g = m1 a1, F4 + F5 + m2 g = m2 a2
  (*F)[0] = m1 * (a[0] - gvec) + F2;
  (*F)[4] = m2 * (a[1] - gvec) - (*F)[3];
}

}  // namespace detail

/// Newton-Euler reactions of the five joints for given accelerations thdd and friction torques.
template <typename T>
void reactions(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b, const Loads<T>& L,
               const Vec2<T>& Fvec, const Vec2<T>& thdd, const std::array<T, kJoints>& Mf,
               std::array<Vec2<T>, kJoints>* F, T* alpha3, T* alpha4) {
  *alpha3 = k.G3.dot(thdd) + b.h3;
  *alpha4 = k.G4.dot(thdd) + b.h4;
  std::array<Vec2<T>, kLinks> a;  // centre-of-mass accelerations
  for (int i = 0; i < kLinks; ++i) a[i] = k.Gc[i] * thdd + b.hc[i];
  detail::reactions_of_accelerations(p, k, *alpha3, *alpha4, a, Vec2<T>(T(0), -p.gravity), Fvec,
                                     L.M3, Mf, F);
}

/// Linear responses of the reactions: dF[j][k] is the change of F_k per unit of the input j.
template <typename T>
using ReactionResponse = std::array<std::array<Vec2<T>, kJoints>, kJoints>;

/// The change of the reactions per unit friction torque Mf_j at fixed accelerations (inverse
/// dynamics). Mf enters only the moment balances of links 3 and 4 (S3 + Mf_B - Mf_C,
/// S4 - Mf_C + Mf_D), so it moves F2, and by the force balances F1, F3, F4 with it and F5
/// against it; the cranks' torques Mf_O, Mf_D0 leave the reactions as they are.
template <typename T>
ReactionResponse<T> reaction_torque_response(const Kinematics<T>& k) {
  const Vec2<T> u3 = k.B - k.C, u4 = k.D - k.C;
  const T det = cross(u3, u4);
  // F2 per unit S3 and per unit S4 (solution of u3 x F2 = S3, u4 x F2 = S4)
  const Vec2<T> f3 = u4 / det, f4 = -u3 / det;
  const std::array<Vec2<T>, kJoints> dF2 = {Vec2<T>::Zero(), f3, Vec2<T>(-f3 - f4), f4,
                                            Vec2<T>::Zero()};
  ReactionResponse<T> out;
  for (int j = 0; j < kJoints; ++j) {
    for (int i = 0; i < 4; ++i) out[j][i] = dF2[j];
    out[j][4] = -dF2[j];
  }
  return out;
}

/// The change of the reactions per unit crank acceleration: R[k] * dthdd is the change of F_k
/// (no gravity, loads, velocity terms or friction torques in a change). The steps of
/// detail::reactions_of_accelerations for both unit accelerations at once, without the terms
/// that are zero in a change: each quantity is a matrix (or row) whose column c is its change per
/// unit thdd_c. f3, f4: F2 per unit coupler moment sum (u3 x F2 = S3, u4 x F2 = S4:
/// F2 = f3 S3 + f4 S4, f3 = u4 / det, f4 = -u3 / det, det = u3 x u4).
template <typename T>
void reaction_acceleration_response(const Params<T>& p, const Kinematics<T>& k, const Vec2<T>& f3,
                                    const Vec2<T>& f4, std::array<Mat2<T>, kJoints>* out) {
  // q x A.col(c) for both columns
  const auto cross_columns = [](const Vec2<T>& q, const Mat2<T>& A) -> Row2<T> {
    return q.x() * A.row(1) - q.y() * A.row(0);
  };
  const Mat2<T> R3 = p.links[2].mass * k.Gc[2];  // force balances: F2 - F3 = R3, F3 - F4 = R4
  const Mat2<T> R4 = p.links[3].mass * k.Gc[3];
  const Vec2<T> u4 = k.D - k.C;
  const Row2<T> S3 = p.links[2].inertia * k.G3 + cross_columns(Vec2<T>(k.c[2] - k.C), R3);
  const Row2<T> S4 = -p.links[3].inertia * k.G4 - cross_columns(Vec2<T>(k.c[3] - k.C), R4) +
                     cross_columns(u4, Mat2<T>(R3 + R4));
  std::array<Mat2<T>, kJoints>& R = *out;
  R[1] = f3 * S3 + f4 * S4;
  R[2] = R[1] - R3;
  R[3] = R[2] - R4;
  R[0] = p.links[0].mass * k.Gc[0] + R[1];
  R[4] = p.links[1].mass * k.Gc[1] - R[3];
}

/// The same with F2's response to the coupler moment sums formed here.
template <typename T>
std::array<Mat2<T>, kJoints> reaction_acceleration_response(const Params<T>& p,
                                                            const Kinematics<T>& k) {
  const Vec2<T> u3 = k.B - k.C, u4 = k.D - k.C;
  const T inv = T(1) / cross(u3, u4);
  std::array<Mat2<T>, kJoints> R;
  reaction_acceleration_response(p, k, Vec2<T>(u4 * inv), Vec2<T>(-u3 * inv), &R);
  return R;
}

/// |F_k| of the five joints.
template <typename T>
void reaction_norms(const std::array<Vec2<T>, kJoints>& F, std::array<T, kJoints>* N) {
  using std::sqrt;
  for (int j = 0; j < kJoints; ++j) (*N)[j] = sqrt(F[j].squaredNorm());
}

#ifdef FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM
// The command-line layer (apps/, at -O1) takes these double instances from fivebar::sim
// (model/src/double_instances.cc) rather than compiling -O1 copies the linker could keep in
// place of the libraries' optimized ones.
extern template void reactions<double>(const Params<double>&, const Kinematics<double>&,
                                       const Bias<double>&, const Loads<double>&,
                                       const Vec2<double>&, const Vec2<double>&,
                                       const std::array<double, kJoints>&,
                                       std::array<Vec2<double>, kJoints>*, double*, double*);
extern template void reaction_norms<double>(const std::array<Vec2<double>, kJoints>&,
                                            std::array<double, kJoints>*);
#endif

}  // namespace fivebar
