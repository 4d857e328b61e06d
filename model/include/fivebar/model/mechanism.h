// The mechanism concept: what the dynamics written once (mechanism_dynamics.h) needs of a planar
// closed chain with load-dependent joint friction, in reduced coordinates q (the kDof driven
// angles). A mechanism is a traits struct M (five_bar_mechanism.h: FiveBar; four_bar.h: FourBar):
//
//   M::kDof, M::kJoints, M::kLinks     degrees of freedom, joints (<= the kJoints slots of the
//                                      friction arrays: slots from M::kJoints on stay inactive)
//   M::kClosedFormResponse             M provides the reactions' response to the friction torques
//   M::Params<T>, Loads<T>             constants (with `friction`, FrictionParams) and loads
//   M::Kinematics<T>, Bias<T>          a closed pose with its first-order coefficients; the
//                                      velocity terms at a rate v
//   M::Evaluation<T>                   what one evaluation computes; holds at least kin, bias,
//                                      A, thdd, F, N, Mf, w, slip, hold_margin, zdot, P_diss,
//                                      P_in, P_ext, iterations
//   M::Applied<T>                      the external loads resolved at a pose (forces at points)
//
//   close(p, q, kin, opt)              position closure; kCannotAssemble / kNearSingular
//   singular_measure(kin), kSingularName   zero at singular poses (the reactions grow as its
//                                      inverse; opt.singular_margin bounds it), and its name
//   singular_cosine(p, q, grad)        its smooth form at any q: a cosine c with 1 - c^2 =
//                                      singular_measure^2 where the chain closes, |c| > 1 where
//                                      it cannot; and its gradient in q (Row<kDof>) when asked
//   bias(p, kin, v, b)                 link rates and the accelerations at qdd = 0
//   applied(kin, L)                    the external loads at the pose
//   mass_and_force(p, kin, b, L, a, A, rhs0)   M(q), and the generalized force without friction
//   joint_rates(kin, b, v)             w = J_w v, one per joint slot
//   joint_rates_at(kin, v)             the same from the first-order kinematics alone
//   joint_accelerations(kin, b, qdd)   d w / dt
//   joint_row(kin, j)                  row j of J_w
//   friction_transpose(kin, Mf)        J_w^T Mf (the friction torques' generalized force, negated)
//   link_accelerations(kin, b, qdd, ev)  the dependent links' angular accelerations into ev
//   reactions(p, kin, b, L, a, qdd, Mf, F, ev)   Newton-Euler reactions (and link accelerations)
//   forward_response(p, kin, Ainv)     (kClosedFormResponse) dF_k per unit Mf_j at the forward
//                                      dynamics' accelerations, in the loop's low-rank form
//   inverse_response(kin)              (kClosedFormResponse) the same at given accelerations
//   set_drives(L, ev) / drive_torques(p, kin, qdd, ev)   forward: the drive torques given;
//                                      inverse: the drive torques that produce qdd
//   input_power(ev, v), external_power(kin, b, L, a, v)  [W]
//   actuator_torques(p, w, slip, act), holding_capacity(p, j, N)   drive friction, static hold
#pragma once

#include <Eigen/Core>
#include <array>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar::mech {

/// State vectors and matrices of a mechanism with n degrees of freedom.
template <int n, typename T>
using Vec = Eigen::Matrix<T, n, 1>;
template <int n, typename T>
using Row = Eigen::Matrix<T, 1, n>;
template <int n, typename T>
using Mat = Eigen::Matrix<T, n, n>;

/// One value per joint slot (friction arrays, reactions' norms, rates).
template <typename T>
using Joints = std::array<T, kJoints>;

/// The inverse of a small symmetric positive definite (mass) or square matrix in closed form
/// (Jet-friendly: no pivoting on derivative parts).
template <typename T>
Mat<1, T> inverse_small(const Mat<1, T>& m) {
  Mat<1, T> out;
  out(0, 0) = T(1) / m(0, 0);
  return out;
}
template <typename T>
Mat<2, T> inverse_small(const Mat<2, T>& m) {
  return inverse2(m);
}

/// The determinant's value of a small square matrix (the lock test of stuck joints).
template <typename T>
double determinant_value(const Mat<1, T>& m) {
  return value_of(m(0, 0));
}
template <typename T>
double determinant_value(const Mat<2, T>& m) {
  return value_of(det2(m));
}

}  // namespace fivebar::mech
