// Forward dynamics: the accelerations from the state and the loads, with the reaction/friction
// loop resolved and stuck joints (exact stick-slip) held by constraint torques.
#pragma once

#include <array>
#include <cmath>
#include <type_traits>

#include "fivebar/model/actuator.h"
#include "fivebar/model/appell.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/reactions.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {
namespace detail {

/// The stuck joints of a forward evaluation (mode kStuck): J_k thdd + wb_k = 0, with wb the
/// relative accelerations at thdd = 0. At most two (two independent ones lock the mechanism).
template <typename T>
struct StuckJoints {
  int joint[kDof] = {-1, -1};
  int count = 0;
  Mat2<T> J = Mat2<T>::Zero();     ///< rows of the stuck joints
  Vec2<T> wb = Vec2<T>::Zero();    ///< their relative accelerations at thdd = 0
};

template <typename T>
Status stuck_joints(const Kinematics<T>& k, const Bias<T>& bias,
                    const JointModes* slip, StuckJoints<T>* s) {
  if (!slip) return Status::Ok();
  for (int j = 0; j < kJoints; ++j) {
    if ((*slip)[j] == kStuck && s->count < kDof) s->joint[s->count++] = j;
  }
  if (s->count == 0) return Status::Ok();
  const std::array<T, kJoints> wb = relative_rates(T(0), T(0), bias.h3, bias.h4);
  for (int i = 0; i < s->count; ++i) {
    s->J.row(i) = joint_row(k, s->joint[i]);
    s->wb[i] = wb[s->joint[i]];
  }
  if (s->count == kDof && std::abs(value_of(det2(s->J))) < 1e-12) {
    return Status::Error(StatusCode::kNearSingular,
                         "two stuck joints whose constraints are dependent (singular pose)");
  }
  return Status::Ok();
}

/// Accelerations with the stuck joints held, for the generalized force r (friction of the
/// slipping joints included); the holding torques go to hold[joint].
template <typename T>
Vec2<T> constrained_accelerations(const Mat2<T>& A, const Mat2<T>& Ainv, const Vec2<T>& r,
                                  const StuckJoints<T>& s, std::array<T, kJoints>* hold) {
  if (s.count == 0) return Ainv * r;
  if (s.count == 1) {
    // [A J^T; J 0] [thdd; lambda] = [r; -wb]
    const Row2<T> J = s.J.row(0);
    const Vec2<T> Ar = Ainv * r;
    const T lambda = (J.dot(Ar) + s.wb[0]) / J.dot(Ainv * J.transpose());
    (*hold)[s.joint[0]] = lambda;
    return Ar - Ainv * (lambda * J.transpose());
  }
  // locked: thdd from the two constraints, holding torques from A thdd = r - J^T lambda
  const Mat2<T> Jinv = inverse2(s.J);
  const Vec2<T> thdd = -(Jinv * s.wb);
  const Vec2<T> lambda = Jinv.transpose() * (r - A * thdd);
  (*hold)[s.joint[0]] = lambda[0];
  (*hold)[s.joint[1]] = lambda[1];
  return thdd;
}

/// phi_k = r_k f_k(w_k) of every joint, and the slip sign used (ev->slip); stuck joints get 0.
template <typename T>
std::array<T, kJoints> forward_friction_arms(const Params<T>& p,
                                             const JointModes* slip,
                                             const std::array<T, kJoints>* bristle,
                                             Evaluation<T>* ev) {
  std::array<T, kJoints> phi;
  for (int j = 0; j < kJoints; ++j) {
    ev->slip[j] = slip ? (*slip)[j] : slip_mode(sign_of(ev->w[j]));
    if (ev->slip[j] == kStuck) {
      phi[j] = T(0);
    } else if (p.friction.law == FrictionLaw::kLuGre) {
      const T z = bristle ? (*bristle)[j] : T(0);
      phi[j] = p.friction.pin_radius[j] * lugre_law(p.friction, j, ev->w[j], z, &ev->zdot[j]);
    } else {
      phi[j] = p.friction.pin_radius[j] *
               friction_law(p.friction, j, ev->w[j], coulomb_sign(ev->slip[j]));
    }
  }
  return phi;
}

/// The change of the reactions per unit friction torque in forward dynamics with no joint stuck,
/// in rank-4 form (LowRankResponse): directly through the coupler moments
/// (reaction_torque_response) and through the accelerations it brings,
/// dthdd = -A^-1 J_w^T e_j (reaction_acceleration_response).
template <typename T>
LowRankResponse<T> forward_low_rank_response(const Params<T>& p, const Kinematics<T>& k,
                                             const Mat2<T>& Ainv) {
  LowRankResponse<T> r;
  const Vec2<T> u3 = k.B - k.C, u4 = k.D - k.C;
  const T det = cross(u3, u4);
  r.f3 = u4 / det;  // as in reaction_torque_response
  r.f4 = -u3 / det;
  r.R = reaction_acceleration_response(p, k);
  for (int j = 0; j < kJoints; ++j) r.m[j] = -(Ainv * joint_row(k, j).transpose());
  return r;
}

/// The same as the full 5 x 5 response (ReactionResponse): dF[j][k] per unit torque at joint j.
template <typename T>
ReactionResponse<T> forward_torque_response(const Params<T>& p, const Kinematics<T>& k,
                                            const Mat2<T>& Ainv) {
  return forward_low_rank_response(p, k, Ainv).expand();
}

/// forward_dynamics below; `loop` as in friction_loop (records the double solution, or
/// differentiates it in Jets); `warm` as in LoopAids.
template <typename T>
Status forward_pass(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                    const T& w1, const T& w2, const JointModes* slip, const EvalOptions& opt,
                    Evaluation<T>* ev, const std::array<T, kJoints>* bristle,
                    LoopSolution* loop, FrictionWarmStart* warm = nullptr) {
  Status st = solve_kinematics(p, th1, th2, &ev->kin, opt.singular_margin, opt.want_angles);
  if (!st.ok()) return st;
  const Kinematics<T>& k = ev->kin;
  compute_bias(p, k, w1, w2, &ev->bias);
  const Vec2<T> Fvec = force_vector(k, L);
  Vec2<T> rhs0;
  mass_and_forces(p, k, ev->bias, L, Fvec, &ev->A, &rhs0);
  ev->M1 = L.M1;
  ev->M2 = L.M2;
  ev->w = relative_rates(w1, w2, ev->bias.w3, ev->bias.w4);
  const Mat2<T> Ainv = inverse2(ev->A);  // A is symmetric positive definite
  ev->thdd = Ainv * rhs0;
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  ev->P_diss = T(0);
  StuckJoints<T> stuck;
  st = stuck_joints(k, ev->bias, slip, &stuck);
  if (!st.ok()) return st;
  std::array<T, kJoints> hold{};  // holding torques of the stuck joints
  // accelerations and reactions for the friction torques Mf of the slipping joints
  auto solve = [&](const std::array<T, kJoints>& Mf, std::array<Vec2<T>, kJoints>* F) {
    if (stuck.count == 0) {  // every joint slips or rests: no holding torque (the common case)
      ev->thdd = Ainv * (rhs0 - friction_transpose(k, Mf));
      reactions(p, k, ev->bias, L, Fvec, ev->thdd, Mf, F, &ev->alpha3, &ev->alpha4);
      return;
    }
    std::array<T, kJoints> Mf_all = Mf;
    for (int i = 0; i < stuck.count; ++i) Mf_all[stuck.joint[i]] = T(0);
    const Vec2<T> r = rhs0 - friction_transpose(k, Mf_all);
    ev->thdd = constrained_accelerations(ev->A, Ainv, r, stuck, &hold);
    for (int i = 0; i < stuck.count; ++i) Mf_all[stuck.joint[i]] = hold[stuck.joint[i]];
    reactions(p, k, ev->bias, L, Fvec, ev->thdd, Mf_all, F, &ev->alpha3, &ev->alpha4);
  };
  if (p.friction.active()) {
    const std::array<T, kJoints> phi = forward_friction_arms(p, slip, bristle, ev);
    std::array<T, kJoints> act;
    const bool motors = actuator_torques(p, ev->w, ev->slip, &act);
    LoopAids<T> aids;
    aids.warm = warm;
    LowRankResponse<T> response;
    if (stuck.count == 0 && !(loop && loop->set)) {
      response = forward_low_rank_response(p, k, Ainv);
      aids.low_rank = &response;
    }
    st = friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations,
                       motors ? &act : nullptr, loop, aids);
    if (!st.ok()) return st;
    if (opt.want_reactions || stuck.count > 0) {
      solve(ev->Mf, &ev->F);  // accelerations and reactions of the converged friction torques
      reaction_norms(ev->F, &ev->N);
    } else {
      // the accelerations of the converged friction torques; F and N stay the loop's (consistent
      // with Mf to friction_tol)
      ev->thdd = Ainv * (rhs0 - friction_transpose(k, ev->Mf));
      ev->alpha3 = k.G3.dot(ev->thdd) + ev->bias.h3;
      ev->alpha4 = k.G4.dot(ev->thdd) + ev->bias.h4;
    }
    for (int i = 0; i < stuck.count; ++i) {
      const int j = stuck.joint[i];
      using std::abs;
      ev->Mf[j] = hold[j];
      ev->hold_margin[j] = holding_capacity(p, j, ev->N[j]) - abs(hold[j]);
    }
    for (int j = 0; j < kJoints; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  } else {
    ev->slip.fill(JointMode::kRest);
    if (opt.want_reactions) {
      solve(ev->Mf, &ev->F);
      reaction_norms(ev->F, &ev->N);
    } else {
      ev->alpha3 = k.G3.dot(ev->thdd) + ev->bias.h3;
      ev->alpha4 = k.G4.dot(ev->thdd) + ev->bias.h4;
    }
  }
  ev->P_in = L.M1 * w1 + L.M2 * w2;
  ev->P_ext = L.M3 * ev->bias.w3 + Fvec.dot(k.GP * Vec2<T>(w1, w2));
  return Status::Ok();
}

}  // namespace detail

/// Forward dynamics: thdd from the state (th, thd) and the loads, with the friction loop
/// resolved. `slip` gives the Coulomb sign of each joint (the integrator's segment mode); pass
/// nullptr to use sign(w_k), with sign(0) = 0. `bristle` holds the LuGre states z (kLuGre only;
/// nullptr means z = 0). `warm` (may be null): the friction loop's solution of the previous
/// evaluation, updated here; a caller evaluating nearby states in a row (the simulator) keeps it
/// to start the next loop from (FrictionWarmStart: the same solution, in fewer iterations).
template <typename T>
Status forward_dynamics(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                        const T& w1, const T& w2, const JointModes* slip,
                        const EvalOptions& opt, Evaluation<T>* ev,
                        const std::array<T, kJoints>* bristle = nullptr,
                        FrictionWarmStart* warm = nullptr) {
  return detail::with_loop_shadow(
      p, L, slip, opt, ev, bristle,
      [&](const auto& pp, const auto& LL, const auto& v, const JointModes* s, auto* e,
          const auto* z, detail::LoopSolution* loop) {
        return detail::forward_pass(pp, LL, v(th1), v(th2), v(w1), v(w2), s, opt, e, z, loop,
                                    warm);
      });
}

}  // namespace fivebar
