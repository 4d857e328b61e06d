// Inverse dynamics: the motor torques and all reactions for a given motion, friction included,
// with the rest rule of joints at rest (rest.h).
#pragma once

#include <algorithm>
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
JointMode inverse_slip(const EvalOptions& opt, const T& w, const T& wdot) {
  if (std::abs(value_of(w)) > opt.rest_rate) return slip_mode(sign_of(w));
  const bool still = std::abs(value_of(wdot)) <= std::max(opt.rest_acceleration, 0.0);
  if (opt.rest_acceleration >= 0.0 && still) return kStuck;
  return still ? JointMode::kRest : slip_mode(sign_of(wdot));
}

/// phi_k = r_k f_k(w_k) of every joint in inverse dynamics and the slip used (ev->slip): the
/// rest rule's sign unless `slip` is given; stuck joints get 0 (the motors carry the holding
/// torque: frictionless equilibrium there).
template <typename T>
std::array<T, kJoints> inverse_friction_arms(const Params<T>& p, const EvalOptions& opt,
                                       const std::array<T, kJoints>& wdot,
                                       const JointModes* slip,
                                       const std::array<T, kJoints>* bristle, Evaluation<T>* ev) {
  std::array<T, kJoints> phi;
  for (int j = 0; j < kJoints; ++j) {
    const JointMode s = inverse_slip(opt, ev->w[j], wdot[j]);
    ev->slip[j] = slip ? (*slip)[j] : s;
    if (ev->slip[j] == kStuck) {
      phi[j] = T(0);
    } else if (p.friction.law == FrictionLaw::kLuGre) {
      // without bristle states: their steady state z = g(w) sign(w) / sigma0 (Stribeck)
      const T z = bristle ? (*bristle)[j]
                          : T(double(coulomb_sign(s))) *
                                stribeck_level(p.friction, j, ev->w[j]) / p.friction.sigma0[j];
      phi[j] = p.friction.pin_radius[j] * lugre_law(p.friction, j, ev->w[j], z, &ev->zdot[j]);
    } else {
      phi[j] = p.friction.pin_radius[j] * friction_law(p.friction, j, ev->w[j], coulomb_sign(ev->slip[j]));
    }
  }
  return phi;
}

/// Motor torques from the moments about the fixed pivots O and D0 of the two cranks.
template <typename T>
void crank_torques(const Params<T>& p, const T& a1, const T& a2, Evaluation<T>* ev) {
  const Kinematics<T>& k = ev->kin;
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
}

/// inverse_dynamics below; `loop` as in friction_loop (records the double solution, or
/// differentiates it in Jets).
template <typename T>
Status inverse_pass(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                    const T& w1_in, const T& w2_in, const T& a1_in, const T& a2_in,
                    const JointModes* slip, const EvalOptions& opt, Evaluation<T>* ev,
                    const std::array<T, kJoints>* bristle, LoopSolution* loop) {
  Status st = solve_kinematics(p, th1, th2, &ev->kin, opt.singular_margin);
  if (!st.ok()) return st;
  // rest rule: a crank at rest and not accelerating stands exactly still
  T w1 = w1_in, w2 = w2_in, a1 = a1_in, a2 = a2_in;
  if (opt.rest_acceleration >= 0.0) {
    still_crank(opt, &w1, &a1);
    still_crank(opt, &w2, &a2);
  }
  const Kinematics<T>& k = ev->kin;
  compute_bias(p, k, w1, w2, &ev->bias);
  const Vec2<T> Fvec = force_vector(k, L);
  ev->thdd = Vec2<T>(a1, a2);
  ev->w = relative_rates(w1, w2, ev->bias.w3, ev->bias.w4);
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  auto solve = [&](const std::array<T, kJoints>& Mf, std::array<Vec2<T>, kJoints>* F) {
    reactions(p, k, ev->bias, L, Fvec, ev->thdd, Mf, F, &ev->alpha3, &ev->alpha4);
  };
  if (p.friction.active()) {  // alpha3, alpha4 for the relative accelerations (as reactions)
    ev->alpha3 = k.G3.dot(ev->thdd) + ev->bias.h3;
    ev->alpha4 = k.G4.dot(ev->thdd) + ev->bias.h4;
  } else {
    solve(ev->Mf, &ev->F);
  }
  const std::array<T, kJoints> wdot = relative_accelerations(ev->thdd, ev->alpha3, ev->alpha4);
  if (p.friction.active()) {
    const std::array<T, kJoints> phi =
        inverse_friction_arms(p, opt, wdot, slip, bristle, ev);
    std::array<T, kJoints> act;
    const bool motors = actuator_torques(p, ev->w, ev->slip, &act);
    st = friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations,
                       motors ? &act : nullptr, loop);
    if (!st.ok()) return st;
    // the implicit derivative (Jets) returns F of the final Mf already (F is affine in Mf)
    if (std::is_same_v<T, double> || !loop || !loop->set) solve(ev->Mf, &ev->F);
    reaction_norms(ev->F, &ev->N);
    for (int j = 0; j < kJoints; ++j) {
      if (ev->slip[j] == kStuck) ev->hold_margin[j] = holding_capacity(p, j, ev->N[j]);
    }
  } else {
    reaction_norms(ev->F, &ev->N);
    // no friction: nothing holds, but joints at rest are still reported (hold_margin 0)
    for (int j = 0; j < kJoints; ++j) {
      const bool stuck = opt.rest_acceleration >= 0.0 &&
                         inverse_slip(opt, ev->w[j], wdot[j]) == kStuck;
      ev->slip[j] = stuck ? kStuck : JointMode::kRest;
    }
  }
  crank_torques(p, a1, a2, ev);
  ev->P_diss = T(0);
  for (int j = 0; j < kJoints; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  ev->P_in = ev->M1 * w1 + ev->M2 * w2;
  ev->P_ext = L.M3 * ev->bias.w3 + Fvec.dot(k.GP * Vec2<T>(w1, w2));
  return Status::Ok();
}

}  // namespace detail

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
                        const T& w1, const T& w2, const T& a1, const T& a2,
                        const JointModes* slip, const EvalOptions& opt,
                        Evaluation<T>* ev, const std::array<T, kJoints>* bristle = nullptr) {
  return detail::with_loop_shadow(
      p, L, slip, opt, ev, bristle,
      [&](const auto& pp, const auto& LL, const auto& v, const JointModes* s, auto* e,
          const auto* z, detail::LoopSolution* loop) {
        return detail::inverse_pass(pp, LL, v(th1), v(th2), v(w1), v(w2), v(a1), v(a2), s, opt,
                                    e, z, loop);
      });
}

#ifdef FIVEBAR_COMPILED_INVERSE_DOUBLE
// Code that links fivebar::sim (which defines this macro for its users) takes the double pass
// of the inverse dynamics from model/src/inverse_double.cc instead of compiling it again: ~5 s
// of compilation in each unit that evaluates the inverse dynamics, in double or in Jets (whose
// shadow pass is the double one). Header-only users of fivebar::model compile it as before.
namespace detail {
extern template Status inverse_pass<double>(const Params<double>&, const Loads<double>&,
                                            const double&, const double&, const double&,
                                            const double&, const double&, const double&,
                                            const JointModes*, const EvalOptions&,
                                            Evaluation<double>*,
                                            const std::array<double, kJoints>*, LoopSolution*);
}  // namespace detail
#endif

}  // namespace fivebar
