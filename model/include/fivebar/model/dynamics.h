// Equations of motion (Appell, eq. 10 as corrected in model.md), Newton-Euler joint reactions,
// the reaction/friction loop (section 4), forward and inverse dynamics, energies.
//
// Conventions (model.md, joints table): joint k in order O, B, C, D, D0 joins body i to body j;
// F_k is the force body i exerts on body j; the friction torque Mf_k acts on j as -Mf_k and on
// i as +Mf_k. Link 1: F1 at O, -F2 at B. Link 3: F2 at B, -F3 at C. Link 4: F3 at C, -F4 at D.
// Link 2: F4 at D, F5 at D0.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include <Eigen/LU>

#include "fivebar/model/friction.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

/// Joint mode value for a stuck joint (exact stick-slip): its relative rate is held at zero by a
/// holding torque solved with the motion. Other modes are the slip direction +1 / -1, or 0.
inline constexpr int kStuck = 2;

/// Settings of an evaluation: singularity margin and the reaction/friction loop.
struct EvalOptions {
  double singular_margin = 0.0;  ///< fail with kNearSingular when |sin(th4 - th3)| is below
  double friction_tol = 1e-13;   ///< stop when max |N^i - N^(i-1)| <= tol * (max N + 1e-300)
  int friction_max_iter = 50;
  bool want_reactions = true;    ///< compute F_k even when the scene has no friction
  bool want_angles = true;       ///< compute th3, th4 (the dynamics itself needs neither)
  /// Rest rule of inverse dynamics (rest.h; forward dynamics ignores both): a joint with
  /// |w_k| <= rest_rate [rad/s] is at rest, not slipping: its Coulomb sign is that of its relative
  /// acceleration, or 0 where that is within rest_acceleration. The defaults keep the exact rule
  /// (only w_k = 0 is at rest).
  double rest_rate = 0.0;
  /// < 0: no joint is stuck in inverse dynamics. >= 0 [rad/s^2]: a joint at rest whose
  /// |d w_k / dt| <= rest_acceleration is stuck (mode kStuck): it carries no friction torque (the
  /// motors hold the pose: frictionless equilibrium at that joint) and hold_margin_k =
  /// mu_s r_k N_k is how much friction torque it could add. A crank at rest and not
  /// accelerating is taken as exactly still (w = dw/dt = 0: the rest of its rates is noise).
  double rest_acceleration = -1.0;
};

/// Everything one evaluation computes. Forward dynamics fills thdd from the torques; inverse
/// dynamics fills M1, M2 from thdd.
template <typename T>
struct Evaluation {
  Kinematics<T> kin;
  Bias<T> bias;
  Mat2<T> A;                      ///< generalized mass matrix (eq. 10)
  Vec2<T> thdd;                   ///< (alpha1, alpha2) [rad/s^2]
  T alpha3{}, alpha4{};           ///< coupler angular accelerations [rad/s^2]
  T M1{}, M2{};                   ///< motor torques [N m] (input of forward, output of inverse)
  std::array<Vec2<T>, 5> F;       ///< joint reactions [N]
  std::array<T, 5> N{}, Mf{}, w{};  ///< |F_k| [N], friction torques [N m], relative rates [rad/s]
  std::array<int, 5> slip{};      ///< Coulomb sign used at each joint, or kStuck
  /// stuck joints: mu_s r_k N_k - |holding torque| (>= 0 while friction can hold the joint);
  /// the holding torque itself is in Mf
  std::array<T, 5> hold_margin{};
  std::array<T, 5> zdot{};        ///< LuGre bristle rates [rad/s] (zero for other laws)
  T P_diss{};                     ///< sum Mf_k w_k >= 0 [W]
  T P_in{};                       ///< M1 w1 + M2 w2 [W]
  T P_ext{};                      ///< M3 w3 + F . v_P [W]
  int iterations = 0;             ///< reaction/friction loop iterations
};

namespace detail {

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
  for (int i = 0; i < 4; ++i) {
    const T& m = p.links[i].mass;
    *A += m * k.Gc[i].transpose() * k.Gc[i];
    bias += m * k.Gc[i].transpose() * b.hc[i];
  }
  // M_d = (M1, M2) + M3 G3^T + G_P^T F (eq. 9 with erratum 1), Q_U = -g sum m_i G_yci^T (eq. 8)
  *rhs = Vec2<T>(L.M1, L.M2) - bias;
  if (!is_exact_zero(L.M3)) *rhs += L.M3 * k.G3.transpose();
  if (!is_exact_zero(L.F)) *rhs += k.GP.transpose() * Fvec;
  if (!is_exact_zero(p.gravity)) {
    for (int i = 0; i < 4; ++i) *rhs -= p.gravity * p.links[i].mass * k.Gc[i].row(1).transpose();
  }
}

/// Relative joint rates w = J_w thd, order O, B, C, D, D0.
template <typename T>
std::array<T, 5> relative_rates(const T& w1, const T& w2, const T& w3, const T& w4) {
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
Vec2<T> friction_transpose(const Kinematics<T>& k, const std::array<T, 5>& Mf) {
  Vec2<T> q(Mf[0] - Mf[1], Mf[4] + Mf[3]);
  q += (Mf[1] - Mf[2]) * k.G3.transpose() + (Mf[2] - Mf[3]) * k.G4.transpose();
  return q;
}

/// Newton-Euler reactions of the five joints for given accelerations thdd and friction torques.
/// Links 3 and 4: moments about C give two equations in F2 (determinant l3 l4 sin(th4 - th3));
/// then F3, F4 from the coupler force balances and F1, F5 from the cranks'.
template <typename T>
void reactions(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b, const Loads<T>& L,
               const Vec2<T>& Fvec, const Vec2<T>& thdd, const std::array<T, 5>& Mf,
               std::array<Vec2<T>, 5>* F, T* alpha3, T* alpha4) {
  const T al3 = k.G3.dot(thdd) + b.h3;
  const T al4 = k.G4.dot(thdd) + b.h4;
  std::array<Vec2<T>, 4> a;  // centre-of-mass accelerations
  for (int i = 0; i < 4; ++i) a[i] = k.Gc[i] * thdd + b.hc[i];
  const Vec2<T> gvec(T(0), -p.gravity);
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
               cross(Vec2<T>(k.P - k.C), Fvec) - L.M3 + Mf[1] - Mf[2];
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
  *alpha3 = al3;
  *alpha4 = al4;
}

template <typename T>
void norms(const std::array<Vec2<T>, 5>& F, std::array<T, 5>* N) {
  using std::sqrt;
  for (int j = 0; j < 5; ++j) (*N)[j] = sqrt(F[j].squaredNorm());
}

/// One relative acceleration per joint (d/dt of w), from the link accelerations.
template <typename T>
std::array<T, 5> relative_accelerations(const Vec2<T>& thdd, const T& al3, const T& al4) {
  return relative_rates(thdd[0], thdd[1], al3, al4);
}

/// Newton on R(N) = N - |F(phi N)| (F is affine in the friction torques: F = F0 + sum_j dF_j
/// Mf_j, from unit probes), from the start N. Converged: true and *N_out set.
template <typename T>
bool friction_newton(const std::array<T, 5>& phi, const EvalOptions& opt,
                     const std::array<Vec2<T>, 5>& F0, const std::array<std::array<Vec2<T>, 5>, 5>& dF,
                     std::array<T, 5> N, std::array<T, 5>* N_out) {
  using std::sqrt;
  for (int it = 0; it < 50; ++it) {
    std::array<Vec2<T>, 5> F = F0;
    for (int j = 0; j < 5; ++j) {
      for (int k = 0; k < 5; ++k) F[k] += dF[j][k] * (phi[j] * N[j]);
    }
    Eigen::Matrix<T, 5, 1> R;
    Eigen::Matrix<T, 5, 5> J = Eigen::Matrix<T, 5, 5>::Identity();
    for (int k = 0; k < 5; ++k) {
      const T n = sqrt(F[k].squaredNorm());
      R[k] = N[k] - n;
      if (value_of(n) > 0.0) {
        for (int j = 0; j < 5; ++j) J(k, j) -= F[k].dot(dF[j][k]) * phi[j] / n;
      }
    }
    const Eigen::Matrix<T, 5, 1> step = J.partialPivLu().solve(R);
    double change = 0.0, scale = 1e-300;
    for (int k = 0; k < 5; ++k) {
      N[k] -= step[k];
      change = std::max(change, std::abs(value_of(step[k])));
      scale = std::max(scale, std::abs(value_of(N[k])));
    }
    if (!std::isfinite(change)) return false;
    if (change <= opt.friction_tol * scale) {
      for (int k = 0; k < 5; ++k) {
        if (value_of(N[k]) < -1e-9 * scale) return false;  // not a magnitude: no solution
      }
      *N_out = N;
      return true;
    }
  }
  return false;
}

/// Resolution of the reaction/friction loop (section 4, steps 1-4, at every call): a fixed point
/// on N, which contracts when r_k |f_k| is small against the geometry; where it stops
/// contracting, Newton from two starts. The caller solves once more with the returned Mf. `solve(Mf, F)` evaluates the reactions for friction
/// torques Mf; phi_k = r_k f_k(w_k) is fixed.
template <typename T, typename Solve>
Status friction_loop(const std::array<T, 5>& phi, const EvalOptions& opt, Solve&& solve,
                     std::array<T, 5>* N, std::array<T, 5>* Mf, std::array<Vec2<T>, 5>* F,
                     int* iterations) {
  // the reactions are affine in the friction torques: F(Mf) = F0 + sum_j dF_j Mf_j, probed once
  // (one solve per joint with friction), then the iteration costs a 10x5 product
  Mf->fill(T(0));
  solve(*Mf, F);
  const std::array<Vec2<T>, 5> F0 = *F;
  std::array<std::array<Vec2<T>, 5>, 5> dF;
  for (int j = 0; j < 5; ++j) {
    if (is_exact_zero(phi[j])) {
      for (auto& v : dF[j]) v.setZero();
      continue;
    }
    std::array<T, 5> unit_torque{};
    unit_torque[j] = T(1);
    std::array<Vec2<T>, 5> Fj;
    solve(unit_torque, &Fj);
    for (int k = 0; k < 5; ++k) dF[j][k] = Fj[k] - F0[k];
  }
  auto affine = [&](const std::array<T, 5>& torque, std::array<Vec2<T>, 5>* out) {
    *out = F0;
    for (int j = 0; j < 5; ++j) {
      if (is_exact_zero(phi[j])) continue;
      for (int k = 0; k < 5; ++k) (*out)[k] += dF[j][k] * torque[j];
    }
  };
  norms(F0, N);
  double prev_err = 0.0, ratio = 0.0;
  bool contracting = true;
  for (int it = 1; it <= opt.friction_max_iter; ++it) {
    for (int j = 0; j < 5; ++j) (*Mf)[j] = phi[j] * (*N)[j];
    const std::array<T, 5> N_old = *N;
    affine(*Mf, F);
    norms(*F, N);
    double err = 0.0, scale = 1e-300;
    for (int j = 0; j < 5; ++j) {
      err = std::max(err, std::abs(value_of((*N)[j]) - value_of(N_old[j])));
      scale = std::max(scale, std::abs(value_of((*N)[j])));
    }
    *iterations = it;
    if (!std::isfinite(err)) {
      contracting = false;
      break;
    }
    if (err <= opt.friction_tol * scale) {
      // friction torques consistent with the final reactions
      for (int j = 0; j < 5; ++j) (*Mf)[j] = phi[j] * (*N)[j];
      return Status::Ok();
    }
    ratio = prev_err > 0.0 ? err / prev_err : 0.0;
    // growing changes after the first few iterations: the loop does not contract
    if (it >= 4 && ratio > 1.0) {
      contracting = false;
      break;
    }
    prev_err = err;
  }
  // Newton on the same affine map, from two starts
  std::array<T, 5> N0, Na, Nb;
  norms(F0, &N0);
  const bool a = friction_newton(phi, opt, F0, dF, N0, &Na);
  std::array<T, 5> N_big = N0;
  for (auto& n : N_big) n = n * T(100) + T(1);
  const bool b = friction_newton(phi, opt, F0, dF, N_big, &Nb);
  std::ostringstream msg;
  msg << "friction loop: fixed point " << (contracting ? "did not converge" : "does not contract")
      << " (ratio " << ratio << "); ";
  if (!a && !b) {
    msg << "Newton finds no consistent reaction forces: r_k * mu too large for the loads "
           "(friction would lock the joints)";
    return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
  }
  if (a && b) {
    double diff = 0.0, scale = 1e-300;
    for (int j = 0; j < 5; ++j) {
      diff = std::max(diff, std::abs(value_of(Na[j]) - value_of(Nb[j])));
      scale = std::max(scale, std::abs(value_of(Na[j])));
    }
    if (diff > 1e-6 * scale) {
      msg << "several consistent reaction forces (max |N| " << scale << " N and differing by "
          << diff << " N): the motion is not unique (r_k * mu too large)";
      return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
    }
  }
  *N = a ? Na : Nb;
  for (int j = 0; j < 5; ++j) (*Mf)[j] = phi[j] * (*N)[j];
  solve(*Mf, F);
  norms(*F, N);
  *iterations = opt.friction_max_iter + 1;  // marks a Newton solve
  return Status::Ok();
}

/// Rest rule (EvalOptions::rest_rate, rest_acceleration): a crank whose rate and acceleration
/// are both within the thresholds stands still; its rate and acceleration become exactly zero.
template <typename T>
void still_crank(const EvalOptions& opt, T* w, T* a) {
  if (std::abs(value_of(*w)) <= opt.rest_rate && std::abs(value_of(*a)) <= opt.rest_acceleration) {
    *w = T(0);
    *a = T(0);
  }
}

/// Coulomb sign of a joint in inverse dynamics: sign(w) while it slips; at rest (|w| <=
/// rest_rate) the sign of its relative acceleration wdot (the direction in which it starts to
/// slip), 0 where |wdot| <= rest_acceleration, or kStuck there when rest_acceleration >= 0.
template <typename T>
int inverse_slip(const EvalOptions& opt, const T& w, const T& wdot) {
  if (std::abs(value_of(w)) > opt.rest_rate) return sign_of(w);
  const bool still = std::abs(value_of(wdot)) <= std::max(opt.rest_acceleration, 0.0);
  if (opt.rest_acceleration >= 0.0 && still) return kStuck;
  return still ? 0 : sign_of(wdot);
}

}  // namespace detail

/// Forward dynamics: thdd from the state (th, thd) and the loads, with the friction loop
/// resolved. `slip` gives the Coulomb sign of each joint (the integrator's segment mode); pass
/// nullptr to use sign(w_k), with sign(0) = 0. `bristle` holds the LuGre states z (kLuGre only;
/// nullptr means z = 0).
template <typename T>
Status forward_dynamics(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                        const T& w1, const T& w2, const std::array<int, 5>* slip,
                        const EvalOptions& opt, Evaluation<T>* ev,
                        const std::array<T, 5>* bristle = nullptr) {
  Status st = solve_kinematics(p, th1, th2, &ev->kin, opt.singular_margin, opt.want_angles);
  if (!st.ok()) return st;
  const Kinematics<T>& k = ev->kin;
  compute_bias(p, k, w1, w2, &ev->bias);
  const Vec2<T> Fvec = detail::force_vector(k, L);
  Vec2<T> rhs0;
  detail::mass_and_forces(p, k, ev->bias, L, Fvec, &ev->A, &rhs0);
  ev->M1 = L.M1;
  ev->M2 = L.M2;
  ev->w = detail::relative_rates(w1, w2, ev->bias.w3, ev->bias.w4);
  const Mat2<T>& A = ev->A;
  const Mat2<T> Ainv = inverse2(A);  // A is symmetric positive definite
  ev->thdd = Ainv * rhs0;
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  ev->P_diss = T(0);

  // stuck joints (mode kStuck): J_k thdd + wb_k = 0, with wb the relative accelerations at
  // thdd = 0; at most two constraints (two independent ones lock the mechanism)
  int stuck[2] = {-1, -1}, ns = 0;
  if (slip) {
    for (int j = 0; j < 5; ++j) {
      if ((*slip)[j] == kStuck && ns < 2) stuck[ns++] = j;
    }
  }
  Mat2<T> Js = Mat2<T>::Zero();  // rows of the stuck joints
  Vec2<T> wb_s = Vec2<T>::Zero();
  if (ns > 0) {
    const std::array<T, 5> wb = detail::relative_rates(T(0), T(0), ev->bias.h3, ev->bias.h4);
    for (int i = 0; i < ns; ++i) {
      Js.row(i) = detail::joint_row(k, stuck[i]);
      wb_s[i] = wb[stuck[i]];
    }
    if (ns == 2 && std::abs(value_of(det2(Js))) < 1e-12) {
      return Status::Error(StatusCode::kNearSingular,
                           "two stuck joints whose constraints are dependent (singular pose)");
    }
  }
  std::array<T, 5> hold{};  // holding torques of the stuck joints
  // accelerations and reactions for the friction torques Mf of the slipping joints
  auto solve = [&](const std::array<T, 5>& Mf, std::array<Vec2<T>, 5>* F) {
    std::array<T, 5> Mf_all = Mf;
    for (int i = 0; i < ns; ++i) Mf_all[stuck[i]] = T(0);
    const Vec2<T> r = rhs0 - detail::friction_transpose(k, Mf_all);
    if (ns == 0) {
      ev->thdd = Ainv * r;
    } else if (ns == 1) {
      // [A J^T; J 0] [thdd; lambda] = [r; -wb]
      const Row2<T> J = Js.row(0);
      const Vec2<T> Ar = Ainv * r;
      const T lambda = (J.dot(Ar) + wb_s[0]) / J.dot(Ainv * J.transpose());
      ev->thdd = Ar - Ainv * (lambda * J.transpose());
      hold[stuck[0]] = lambda;
    } else {
      // locked: thdd from the two constraints, holding torques from A thdd = r - Js^T lambda
      const Mat2<T> Jinv = inverse2(Js);
      ev->thdd = -(Jinv * wb_s);
      const Vec2<T> lambda = Jinv.transpose() * (r - A * ev->thdd);
      hold[stuck[0]] = lambda[0];
      hold[stuck[1]] = lambda[1];
    }
    for (int i = 0; i < ns; ++i) Mf_all[stuck[i]] = hold[stuck[i]];
    detail::reactions(p, k, ev->bias, L, Fvec, ev->thdd, Mf_all, F, &ev->alpha3, &ev->alpha4);
  };
  if (p.friction.active()) {
    std::array<T, 5> phi;
    for (int j = 0; j < 5; ++j) {
      ev->slip[j] = slip ? (*slip)[j] : sign_of(ev->w[j]);
      if (ev->slip[j] == kStuck) {
        phi[j] = T(0);
      } else if (p.friction.law == FrictionLaw::kLuGre) {
        const T z = bristle ? (*bristle)[j] : T(0);
        phi[j] = p.friction.pin_radius[j] * lugre_law(p.friction, j, ev->w[j], z, &ev->zdot[j]);
      } else {
        phi[j] = p.friction.pin_radius[j] * friction_law(p.friction, j, ev->w[j], ev->slip[j]);
      }
    }
    st = detail::friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations);
    if (!st.ok()) return st;
    solve(ev->Mf, &ev->F);  // accelerations and reactions of the converged friction torques
    detail::norms(ev->F, &ev->N);
    for (int i = 0; i < ns; ++i) {
      const int j = stuck[i];
      using std::abs;
      ev->Mf[j] = hold[j];
      ev->hold_margin[j] = holding_bound(p.friction, j) * ev->N[j] - abs(hold[j]);
    }
    for (int j = 0; j < 5; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  } else {
    ev->slip.fill(0);
    if (opt.want_reactions) {
      solve(ev->Mf, &ev->F);
      detail::norms(ev->F, &ev->N);
    } else {
      ev->alpha3 = k.G3.dot(ev->thdd) + ev->bias.h3;
      ev->alpha4 = k.G4.dot(ev->thdd) + ev->bias.h4;
    }
  }
  ev->P_in = L.M1 * w1 + L.M2 * w2;
  ev->P_ext = L.M3 * ev->bias.w3 + Fvec.dot(k.GP * Vec2<T>(w1, w2));
  return Status::Ok();
}

/// Inverse dynamics: M1, M2 and all reactions for a given motion (th, thd, thdd), friction
/// included. The Coulomb sign is sign(w_k); where w_k = 0 it is the sign of the relative
/// acceleration (the direction in which the joint starts to slip), unless `slip` is given.
/// With the rest rule on (EvalOptions::rest_rate, rest_acceleration; rest.h) "w_k = 0" reads
/// "|w_k| <= rest_rate", and joints at rest that do not accelerate are stuck (kStuck): no
/// friction torque, hold_margin_k = mu_s r_k N_k (a `slip` entry kStuck does the same).
/// LuGre needs the bristle states z (`bristle`); without them the bristles are taken at their
/// steady state z = g(w) sign(w) / sigma0, i.e. the Stribeck law.
template <typename T>
Status inverse_dynamics(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                        const T& w1_in, const T& w2_in, const T& a1_in, const T& a2_in,
                        const std::array<int, 5>* slip, const EvalOptions& opt,
                        Evaluation<T>* ev, const std::array<T, 5>* bristle = nullptr) {
  Status st = solve_kinematics(p, th1, th2, &ev->kin, opt.singular_margin);
  if (!st.ok()) return st;
  // rest rule: a crank at rest and not accelerating stands exactly still
  T w1 = w1_in, w2 = w2_in, a1 = a1_in, a2 = a2_in;
  if (opt.rest_acceleration >= 0.0) {
    detail::still_crank(opt, &w1, &a1);
    detail::still_crank(opt, &w2, &a2);
  }
  const Kinematics<T>& k = ev->kin;
  compute_bias(p, k, w1, w2, &ev->bias);
  const Vec2<T> Fvec = detail::force_vector(k, L);
  ev->thdd = Vec2<T>(a1, a2);
  ev->w = detail::relative_rates(w1, w2, ev->bias.w3, ev->bias.w4);
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  auto solve = [&](const std::array<T, 5>& Mf, std::array<Vec2<T>, 5>* F) {
    detail::reactions(p, k, ev->bias, L, Fvec, ev->thdd, Mf, F, &ev->alpha3, &ev->alpha4);
  };
  if (p.friction.active()) {
    solve(ev->Mf, &ev->F);  // alpha3, alpha4 for the relative accelerations
    const std::array<T, 5> wdot = detail::relative_accelerations(ev->thdd, ev->alpha3, ev->alpha4);
    std::array<T, 5> phi;
    for (int j = 0; j < 5; ++j) {
      const int s = detail::inverse_slip(opt, ev->w[j], wdot[j]);
      ev->slip[j] = slip ? (*slip)[j] : s;
      if (ev->slip[j] == kStuck) {
        phi[j] = T(0);  // the motors carry the holding torque (frictionless equilibrium)
      } else if (p.friction.law == FrictionLaw::kLuGre) {
        const T z = bristle ? (*bristle)[j]
                            : T(double(s == kStuck ? 0 : s)) * stribeck_level(p.friction, j, ev->w[j]) /
                                  p.friction.sigma0[j];
        phi[j] = p.friction.pin_radius[j] * lugre_law(p.friction, j, ev->w[j], z, &ev->zdot[j]);
      } else {
        phi[j] = p.friction.pin_radius[j] * friction_law(p.friction, j, ev->w[j], ev->slip[j]);
      }
    }
    st = detail::friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations);
    if (!st.ok()) return st;
    solve(ev->Mf, &ev->F);
    detail::norms(ev->F, &ev->N);
    for (int j = 0; j < 5; ++j) {
      if (ev->slip[j] == kStuck) ev->hold_margin[j] = holding_bound(p.friction, j) * ev->N[j];
    }
  } else {
    solve(ev->Mf, &ev->F);
    detail::norms(ev->F, &ev->N);
    // no friction: nothing holds, but joints at rest are still reported (hold_margin 0)
    const std::array<T, 5> wdot = detail::relative_accelerations(ev->thdd, ev->alpha3, ev->alpha4);
    for (int j = 0; j < 5; ++j) {
      const bool stuck = opt.rest_acceleration >= 0.0 &&
                         detail::inverse_slip(opt, ev->w[j], wdot[j]) == kStuck;
      ev->slip[j] = stuck ? kStuck : 0;
    }
  }
  // crank moments about their fixed pivots O and D0
  const Vec2<T> gvec(T(0), -p.gravity);
  const Link<T>& L1 = p.links[0];
  const Link<T>& L2 = p.links[1];
  const Vec2<T> D0(p.ground_length, T(0));
  const T I1 = L1.inertia + L1.mass * L1.com_offset * L1.com_offset;
  const T I2 = L2.inertia + L2.mass * L2.com_offset * L2.com_offset;
  ev->M1 = I1 * a1 + ev->Mf[0] - ev->Mf[1] + cross(k.B, ev->F[1]) -
           cross(k.c[0], Vec2<T>(L1.mass * gvec));
  ev->M2 = I2 * a2 + ev->Mf[4] + ev->Mf[3] - cross(Vec2<T>(k.D - D0), ev->F[3]) -
           cross(Vec2<T>(k.c[1] - D0), Vec2<T>(L2.mass * gvec));
  ev->P_diss = T(0);
  for (int j = 0; j < 5; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  ev->P_in = ev->M1 * w1 + ev->M2 * w2;
  ev->P_ext = L.M3 * ev->bias.w3 + Fvec.dot(k.GP * Vec2<T>(w1, w2));
  return Status::Ok();
}

/// Kinetic energy sum (m_i |v_ci|^2 + J_i thd_i^2) / 2 = thd^T A thd / 2 [J].
template <typename T>
T kinetic_energy(const Params<T>& p, const Kinematics<T>& k, const T& w1, const T& w2) {
  const Vec2<T> thd(w1, w2);
  const T w3 = k.G3.dot(thd), w4 = k.G4.dot(thd);
  T ke = p.links[0].inertia * w1 * w1 + p.links[1].inertia * w2 * w2 +
         p.links[2].inertia * w3 * w3 + p.links[3].inertia * w4 * w4;
  for (int i = 0; i < 4; ++i) ke += p.links[i].mass * (k.Gc[i] * thd).squaredNorm();
  return T(0.5) * ke;
}

/// Potential energy U = g sum m_i y_ci [J] (eq. 8).
template <typename T>
T potential_energy(const Params<T>& p, const Kinematics<T>& k) {
  T u = T(0);
  for (int i = 0; i < 4; ++i) u += p.links[i].mass * k.c[i].y();
  return p.gravity * u;
}

}  // namespace fivebar
