// Forward and inverse dynamics of any mechanism (mechanism.h), written once: the reaction/friction
// loop, the joint modes (slip directions, stuck joints held by constraint torques), the rest rule
// of inverse dynamics, LuGre's bristles, actuator friction and the loop's implicit derivatives
// for Jets.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <type_traits>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/mechanism.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar::mech {

template <class M, typename T>
using ParamsOf = typename M::template Params<T>;
template <class M, typename T>
using LoadsOf = typename M::template Loads<T>;
template <class M, typename T>
using EvaluationOf = typename M::template Evaluation<T>;
template <class M, typename T>
using State = Vec<M::kDof, T>;

/// Below this singular measure (|sin(th4 - th3)| of the five-bar, |sin(th3 - th2)| of the
/// four-bar) a failed friction loop is put down to the pose: the reactions grow as its inverse
/// there (with the rates, the coupler accelerations as its cube), so the loop's gain passes 1
/// with any friction (a light scene with r mu = 4e-4 was told "r_k * mu too large").
inline constexpr double kSingularCause = 0.05;
/// ... and below this one too where every friction arm r_k mu_k is under kSmallArm of the shortest
/// link: arms that small do not bring the loop's gain to 1 at a regular pose (a double rocker
/// driven at 1 rad/s failed its loop at |sin| = 0.095 with r mu = 0.6 % of its shortest link);
/// with larger arms the pose is named beside the friction
inline constexpr double kNearSingularCause = 0.25;
inline constexpr double kSmallArm = 0.05;

namespace detail {

using fivebar::detail::LoopSolution;

/// A failed friction loop's status with its cause first when the pose explains it (near the
/// singular pose, kSingularCause): names the singular measure and the largest r_k mu_k, so that
/// the friction is not blamed for the geometry (same code: callers decide on it as before).
template <class M, typename T>
Status singular_cause(const ParamsOf<M, T>& p, const typename M::template Kinematics<T>& k,
                      const Status& st) {
  using std::abs;
  if (st.ok() || st.code != StatusCode::kFrictionNotConverged) return st;
  const double sine = abs(value_of(M::singular_measure(k)));
  double arm = 0.0, shortest = std::numeric_limits<double>::infinity();
  for (int j = 0; j < M::kJoints; ++j) {
    arm = std::max(arm, abs(value_of(p.friction.pin_radius[j] * p.friction.coulomb[j])));
  }
  for (const auto& link : p.links) shortest = std::min(shortest, abs(value_of(link.length)));
  const bool small_arms = arm < kSmallArm * shortest;
  if (!(sine < kNearSingularCause)) return st;
  // with small friction arms the pose alone explains it: the loop's own guess (the friction's)
  // is dropped; with larger arms both are named
  std::string loop = st.message;
  if (sine < kSingularCause || small_arms) {
    for (const char* guess :
         {" (r_k * mu too large for the reactions at this pose and speed)",
          ": r_k * mu too large for the loads (friction would lock the joints)"}) {
      const size_t at = loop.find(guess);
      if (at != std::string::npos) loop.erase(at, std::string(guess).size());
    }
  }
  std::ostringstream msg;
  msg.precision(3);
  msg << (sine < kSingularCause || small_arms ? "near-singular pose" : "friction near a singular pose")
      << ": |" << M::kSingularName << "| = " << sine << " (the reactions grow as 1 / "
      << M::kSingularName << ", and with the rates as its cube), where the friction loop cannot "
      << "close with r_k * mu up to " << arm << " m (" << 100 * arm / shortest
      << " % of the shortest link; simulation.singular_margin above " << sine
      << " stops a run before this pose); " << loop;
  return Status::Error(st.code, msg.str());
}

/// A failed friction loop's status with the joint rates first when they explain it: a friction
/// arm r_k f(w_k) of the law at the evaluation's rates kFastArm times the largest at rest
/// (r_k mu_k), as viscous friction at a rate of hundreds of rad/s, names the rate and both arms,
/// so that the coefficients are not blamed for a speed (same code).
inline constexpr double kFastArm = 3.0;
template <class M, typename T>
Status rate_cause(const ParamsOf<M, T>& p, const Joints<T>& phi, const Joints<T>& w,
                  const Status& st) {
  using std::abs;
  if (st.ok() || st.code != StatusCode::kFrictionNotConverged) return st;
  double arm = 0.0, still = 0.0, rate = 0.0;
  for (int j = 0; j < M::kJoints; ++j) {
    still = std::max(still, abs(value_of(p.friction.pin_radius[j] * p.friction.coulomb[j])));
    if (abs(value_of(phi[j])) > arm) {
      arm = abs(value_of(phi[j]));
      rate = abs(value_of(w[j]));
    }
  }
  if (!(arm > kFastArm * still)) return st;
  std::ostringstream msg;
  msg.precision(3);
  msg << "joint rates too fast for the friction law: at |w| = " << rate
      << " rad/s a joint's friction arm r_k f(w_k) is " << arm << " m, " << arm / still
      << " times r_k mu_k at rest (the rate-dependent friction grows with the rate: check the "
      << "initial rates and the loads); " << st.message;
  return Status::Error(st.code, msg.str());
}

/// The stuck joints of a forward evaluation (mode kStuck): J_k qdd + wb_k = 0, with wb the
/// relative accelerations at qdd = 0. At most kDof (that many independent ones lock the
/// mechanism).
template <int n, typename T>
struct StuckJoints {
  std::array<int, n> joint{};
  int count = 0;
  Mat<n, T> J = Mat<n, T>::Zero();  ///< rows of the stuck joints
  Vec<n, T> wb = Vec<n, T>::Zero();  ///< their relative accelerations at qdd = 0
};

template <class M, typename T>
Status stuck_joints(const typename M::template Kinematics<T>& k,
                    const typename M::template Bias<T>& bias, const JointModes* slip,
                    StuckJoints<M::kDof, T>* s) {
  if (!slip) return Status::Ok();
  for (int j = 0; j < M::kJoints; ++j) {
    if ((*slip)[j] == kStuck && s->count < M::kDof) s->joint[s->count++] = j;
  }
  if (s->count == 0) return Status::Ok();
  const Joints<T> wb = M::joint_accelerations(k, bias, Vec<M::kDof, T>(Vec<M::kDof, T>::Zero()));
  for (int i = 0; i < s->count; ++i) {
    s->J.row(i) = M::joint_row(k, s->joint[i]);
    s->wb[i] = wb[s->joint[i]];
  }
  if (s->count == M::kDof && std::abs(determinant_value(s->J)) < 1e-12) {
    return Status::Error(StatusCode::kNearSingular,
                         "stuck joints whose constraints are dependent (singular pose)");
  }
  return Status::Ok();
}

/// Accelerations with the stuck joints held, for the generalized force r (friction of the
/// slipping joints included); the holding torques go to hold[joint].
template <int n, typename T>
Vec<n, T> constrained_accelerations(const Mat<n, T>& A, const Mat<n, T>& Ainv,
                                    const Vec<n, T>& r, const StuckJoints<n, T>& s,
                                    Joints<T>* hold) {
  static_assert(n <= 2, "held joints are solved for up to two degrees of freedom");
  if (s.count == 0) return Ainv * r;
  if (s.count < n) {
    // one joint of two held: [A J^T; J 0] [qdd; lambda] = [r; -wb]
    const Row<n, T> J = s.J.row(0);
    const Vec<n, T> Ar = Ainv * r;
    const T lambda = (J.dot(Ar) + s.wb[0]) / J.dot(Ainv * J.transpose());
    (*hold)[s.joint[0]] = lambda;
    return Ar - Ainv * (lambda * J.transpose());
  }
  // locked: qdd from the constraints, holding torques from A qdd = r - J^T lambda
  const Mat<n, T> Jinv = inverse_small(s.J);
  const Vec<n, T> qdd = -(Jinv * s.wb);
  const Vec<n, T> lambda = Jinv.transpose() * (r - A * qdd);
  for (int i = 0; i < n; ++i) (*hold)[s.joint[i]] = lambda[i];
  return qdd;
}

/// phi_k = r_k f_k(w_k) of every joint for the slip modes ev->slip (stuck joints get 0); LuGre
/// takes the bristle states `z` (ev->zdot receives their rates). Slots from M::kJoints on: 0.
template <class M, typename T>
Joints<T> friction_arms(const ParamsOf<M, T>& p, const Joints<T>& z, EvaluationOf<M, T>* ev) {
  Joints<T> phi{};
  if (plain_coulomb_viscous(p.friction)) {  // the common law, decided once for all joints
    for (int j = 0; j < M::kJoints; ++j) {
      if (ev->slip[j] == kStuck) continue;
      phi[j] = p.friction.pin_radius[j] *
               coulomb_viscous_law(p.friction, j, ev->w[j], T(double(coulomb_sign(ev->slip[j]))));
    }
    return phi;
  }
  for (int j = 0; j < M::kJoints; ++j) {
    if (ev->slip[j] == kStuck) {
      phi[j] = T(0);
    } else if (p.friction.law == FrictionLaw::kLuGre) {
      phi[j] = p.friction.pin_radius[j] * lugre_law(p.friction, j, ev->w[j], z[j], &ev->zdot[j]);
    } else {
      phi[j] = p.friction.pin_radius[j] *
               friction_law(p.friction, j, ev->w[j], coulomb_sign(ev->slip[j]));
    }
  }
  return phi;
}

/// Forward dynamics' friction arms: the Coulomb sign of `slip`, or sign(w) (null); the bristle
/// states z (null: 0).
template <class M, typename T>
Joints<T> forward_friction_arms(const ParamsOf<M, T>& p, const JointModes* slip,
                                const Joints<T>* bristle, EvaluationOf<M, T>* ev) {
  for (int j = 0; j < kJoints; ++j) {
    ev->slip[j] = j >= M::kJoints ? JointMode::kRest
                  : slip          ? (*slip)[j]
                                  : slip_mode(sign_of(ev->w[j]));
  }
  return friction_arms<M>(p, bristle ? *bristle : Joints<T>{}, ev);
}

/// Rest rule (EvalOptions::rest_rate, rest_acceleration): a driven coordinate whose rate and
/// acceleration are both within the thresholds stands still; both become exactly zero.
template <typename T>
void still_drive(const EvalOptions& opt, T* w, T* a) {
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

/// Inverse dynamics' friction arms: the rest rule's modes unless `slip` is given; stuck joints
/// get 0 (the drives carry the holding torque: frictionless equilibrium there). LuGre without
/// bristle states takes their steady state z = g(w) sign(w) / sigma0 (the Stribeck law).
template <class M, typename T>
Joints<T> inverse_friction_arms(const ParamsOf<M, T>& p, const EvalOptions& opt,
                                const Joints<T>& wdot, const JointModes* slip,
                                const Joints<T>* bristle, EvaluationOf<M, T>* ev) {
  Joints<T> z{};
  for (int j = 0; j < kJoints; ++j) {
    if (j >= M::kJoints) {
      ev->slip[j] = JointMode::kRest;
      continue;
    }
    const JointMode s = inverse_slip(opt, ev->w[j], wdot[j]);
    ev->slip[j] = slip ? (*slip)[j] : s;
    if (p.friction.law != FrictionLaw::kLuGre || ev->slip[j] == kStuck) continue;
    z[j] = bristle ? (*bristle)[j]
                   : T(double(coulomb_sign(s))) * stribeck_level(p.friction, j, ev->w[j]) /
                         p.friction.sigma0[j];
  }
  return friction_arms<M>(p, z, ev);
}

/// The change of the reactions per unit friction torque in forward dynamics with no joint stuck,
/// as the full 5 x 5 response: at fixed accelerations (M::reaction_torque_response) and through
/// the accelerations it brings, dqdd = -A^-1 J_w^T e_j (M::reaction_acceleration_response). The
/// reference for M::forward_response, which the loop uses.
template <class M, typename T>
ReactionResponse<T> forward_torque_response(const ParamsOf<M, T>& p,
                                            const typename M::template Kinematics<T>& k,
                                            const Mat<M::kDof, T>& Ainv) {
  ReactionResponse<T> dF = M::reaction_torque_response(k);
  const auto R = M::reaction_acceleration_response(p, k);
  for (int j = 0; j < M::kJoints; ++j) {
    const Vec<M::kDof, T> dqdd = -(Ainv * M::joint_row(k, j).transpose());
    for (int k2 = 0; k2 < M::kJoints; ++k2) dF[j][k2] += R[k2] * dqdd;
  }
  return dF;
}

/// The friction loop of a forward pass, its converged reactions and the holding torques of the
/// stuck joints (ev->Mf, hold_margin), with `solve(Mf, F)` the accelerations and reactions.
template <class M, typename T, typename Solve>
Status forward_friction(const ParamsOf<M, T>& p, const EvalOptions& opt, const Mat<M::kDof, T>& Ainv,
                        const StuckJoints<M::kDof, T>& stuck, const Joints<T>& hold, Solve& solve,
                        const JointModes* slip, const Joints<T>* bristle, EvaluationOf<M, T>* ev,
                        LoopSolution* loop, FrictionWarmStart* warm) {
  const Joints<T> phi = forward_friction_arms<M>(p, slip, bristle, ev);
  Joints<T> act;
  const bool motors = M::actuator_torques(p, ev->w, ev->slip, &act);
  LoopAids<T> aids;
  aids.warm = warm;
  const bool closed_form = M::kClosedFormResponse && stuck.count == 0 && !(loop && loop->set);
  const LowRankResponse<T> response = [&] {  // (built in place)
    if constexpr (M::kClosedFormResponse) {
      if (closed_form) return M::forward_response(p, ev->kin, Ainv);
    }
    return LowRankResponse<T>();
  }();
  if (closed_form) aids.low_rank = &response;
  const Status st = friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations,
                                  motors ? &act : nullptr, loop, aids);
  if (!st.ok()) {
    const Status pose = singular_cause<M, T>(p, ev->kin, st);
    return pose.message != st.message ? pose : rate_cause<M, T>(p, phi, ev->w, st);
  }
  if (opt.want_reactions || stuck.count > 0) {
    solve(ev->Mf, &ev->F);  // accelerations and reactions of the converged friction torques
    reaction_norms(ev->F, &ev->N);
  }
  for (int i = 0; i < stuck.count; ++i) {
    const int j = stuck.joint[i];
    using std::abs;
    ev->Mf[j] = hold[j];
    ev->hold_margin[j] = M::holding_capacity(p, j, ev->N[j]) - abs(hold[j]);
  }
  return Status::Ok();
}

/// Whether every torque is exactly zero, in double evaluations (a Jet's zero value may carry
/// derivatives: false).
template <typename T>
bool no_torque(const Joints<T>& Mf) {
  if constexpr (std::is_same_v<T, double>) {
    for (const double m : Mf) {
      if (m != 0.0) return false;
    }
    return true;
  } else {
    return false;
  }
}

/// forward below; `loop` as in friction_loop (records the double solution, or differentiates it
/// in Jets); `warm` as in LoopAids.
template <class M, typename T>
Status forward_pass(const ParamsOf<M, T>& p, const LoadsOf<M, T>& L, const State<M, T>& q,
                    const State<M, T>& v, const JointModes* slip, const EvalOptions& opt,
                    EvaluationOf<M, T>* ev, const Joints<T>* bristle, LoopSolution* loop,
                    FrictionWarmStart* warm = nullptr) {
  constexpr int n = M::kDof;
  // (each step's status its own object: no string moves on the common path)
  if (Status st = M::close(p, q, &ev->kin, opt); !st.ok()) return st;
  const auto& k = ev->kin;
  M::bias(p, k, v, &ev->bias);
  const auto applied = M::applied(k, L);
  Vec<n, T> rhs0;
  M::mass_and_force(p, k, ev->bias, L, applied, &ev->A, &rhs0);
  M::set_drives(L, ev);
  ev->w = M::joint_rates(k, ev->bias, v);
  const Mat<n, T> Ainv = inverse_small(ev->A);  // A is symmetric positive definite
  const Vec<n, T> thdd0 = Ainv * rhs0;          // the accelerations without friction
  ev->thdd = thdd0;
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  ev->P_diss = T(0);
  StuckJoints<n, T> stuck;
  if (Status st = stuck_joints<M>(k, ev->bias, slip, &stuck); !st.ok()) return st;
  Joints<T> hold{};  // holding torques of the stuck joints
  // accelerations and reactions for the friction torques Mf of the slipping joints
  auto solve = [&](const Joints<T>& Mf, std::array<Vec2<T>, kJoints>* F) {
    if (stuck.count == 0) {  // every joint slips or rests: no holding torque (the common case)
      // (no friction torque: rhs0 - J_w^T 0 is rhs0 itself, J_w^T 0 being +0)
      ev->thdd = no_torque(Mf) ? thdd0 : Vec<n, T>(Ainv * (rhs0 - M::friction_transpose(k, Mf)));
      M::reactions(p, k, ev->bias, L, applied, ev->thdd, Mf, F, ev);
      return;
    }
    Joints<T> Mf_all = Mf;
    for (int i = 0; i < stuck.count; ++i) Mf_all[stuck.joint[i]] = T(0);
    const Vec<n, T> r = rhs0 - M::friction_transpose(k, Mf_all);
    ev->thdd = constrained_accelerations(ev->A, Ainv, r, stuck, &hold);
    for (int i = 0; i < stuck.count; ++i) Mf_all[stuck.joint[i]] = hold[stuck.joint[i]];
    M::reactions(p, k, ev->bias, L, applied, ev->thdd, Mf_all, F, ev);
  };
  if (p.friction.active()) {
    Status st =
        forward_friction<M>(p, opt, Ainv, stuck, hold, solve, slip, bristle, ev, loop, warm);
    if (!st.ok()) return st;
    if (!opt.want_reactions && stuck.count == 0) {
      // the accelerations of the converged friction torques; F and N stay the loop's (consistent
      // with Mf to friction_tol)
      ev->thdd = Ainv * (rhs0 - M::friction_transpose(k, ev->Mf));
      M::link_accelerations(k, ev->bias, ev->thdd, ev);
    }
    for (int j = 0; j < M::kJoints; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  } else {
    ev->slip.fill(JointMode::kRest);
    if (opt.want_reactions) {
      solve(ev->Mf, &ev->F);
      reaction_norms(ev->F, &ev->N);
    } else {
      M::link_accelerations(k, ev->bias, ev->thdd, ev);
    }
  }
  ev->P_in = M::input_power(*ev, v);
  ev->P_ext = M::external_power(k, ev->bias, L, applied, v);
  return Status::Ok();
}

/// The friction part of an inverse pass: modes, the loop, the final reactions and the stuck
/// joints' holding margins.
template <class M, typename T, typename Solve>
Status inverse_friction(const ParamsOf<M, T>& p, const EvalOptions& opt, const Joints<T>& wdot,
                        Solve& solve, const JointModes* slip, const Joints<T>* bristle,
                        EvaluationOf<M, T>* ev, LoopSolution* loop) {
  const Joints<T> phi = inverse_friction_arms<M>(p, opt, wdot, slip, bristle, ev);
  Joints<T> act;
  const bool motors = M::actuator_torques(p, ev->w, ev->slip, &act);
  LoopAids<T> aids;
  CouplerResponse<T> response;
  if constexpr (M::kClosedFormResponse) {
    if (!(loop && loop->set)) {
      response = M::inverse_response(ev->kin);
      aids.coupler = &response;
    }
  }
  const Status st = friction_loop(phi, opt, solve, &ev->N, &ev->Mf, &ev->F, &ev->iterations,
                                  motors ? &act : nullptr, loop, aids);
  if (!st.ok()) return singular_cause<M, T>(p, ev->kin, st);
  // the implicit derivative (Jets) returns F of the final Mf already (F is affine in Mf)
  if (std::is_same_v<T, double> || !loop || !loop->set) solve(ev->Mf, &ev->F);
  reaction_norms(ev->F, &ev->N);
  for (int j = 0; j < M::kJoints; ++j) {
    if (ev->slip[j] == kStuck) ev->hold_margin[j] = M::holding_capacity(p, j, ev->N[j]);
  }
  return Status::Ok();
}

/// inverse below; `loop` as in friction_loop.
template <class M, typename T>
Status inverse_pass(const ParamsOf<M, T>& p, const LoadsOf<M, T>& L, const State<M, T>& q,
                    const State<M, T>& v_in, const State<M, T>& a_in, const JointModes* slip,
                    const EvalOptions& opt, EvaluationOf<M, T>* ev, const Joints<T>* bristle,
                    LoopSolution* loop) {
  Status st = M::close(p, q, &ev->kin, opt);
  if (!st.ok()) return st;
  // rest rule: a driven coordinate at rest and not accelerating stands exactly still
  State<M, T> v = v_in, a = a_in;
  if (opt.rest_acceleration >= 0.0) {
    for (int i = 0; i < M::kDof; ++i) still_drive(opt, &v[i], &a[i]);
  }
  const auto& k = ev->kin;
  M::bias(p, k, v, &ev->bias);
  const auto applied = M::applied(k, L);
  ev->thdd = a;
  ev->w = M::joint_rates(k, ev->bias, v);
  ev->iterations = 0;
  ev->Mf.fill(T(0));
  auto solve = [&](const Joints<T>& Mf, std::array<Vec2<T>, kJoints>* F) {
    M::reactions(p, k, ev->bias, L, applied, ev->thdd, Mf, F, ev);
  };
  M::link_accelerations(k, ev->bias, ev->thdd, ev);
  const Joints<T> wdot = M::joint_accelerations(k, ev->bias, ev->thdd);
  if (p.friction.active()) {
    st = inverse_friction<M>(p, opt, wdot, solve, slip, bristle, ev, loop);
    if (!st.ok()) return st;
  } else {
    solve(ev->Mf, &ev->F);
    reaction_norms(ev->F, &ev->N);
    // no friction: nothing holds, but joints at rest are still reported (hold_margin 0)
    for (int j = 0; j < kJoints; ++j) {
      const bool stuck = j < M::kJoints && opt.rest_acceleration >= 0.0 &&
                         inverse_slip(opt, ev->w[j], wdot[j]) == kStuck;
      ev->slip[j] = stuck ? kStuck : JointMode::kRest;
    }
  }
  M::drive_torques(p, k, a, ev);
  ev->P_diss = T(0);
  for (int j = 0; j < M::kJoints; ++j) ev->P_diss += ev->Mf[j] * ev->w[j];
  ev->P_in = M::input_power(*ev, v);
  ev->P_ext = M::external_power(k, ev->bias, L, applied, v);
  return Status::Ok();
}

/// The value parts of a state (the double shadow of a Jet evaluation).
template <int n, typename T>
Vec<n, double> values(const Vec<n, T>& x) {
  Vec<n, double> out;
  for (int i = 0; i < n; ++i) out[i] = value_of(x[i]);
  return out;
}

/// Runs a dynamics pass with the friction loop's implicit derivative: for Jets with friction on
/// (and EvalOptions::implicit_loop_derivative), a double shadow pass first decides the joint
/// modes and solves the loop, then the Jet pass differentiates that solution; otherwise one pass.
/// `pass(params, loads, slip, ev, bristle, loop)` runs the pass in the scalar of its arguments.
template <class M, typename T, typename Pass>
Status with_loop_shadow(const ParamsOf<M, T>& p, const LoadsOf<M, T>& L, const JointModes* slip,
                        const EvalOptions& opt, EvaluationOf<M, T>* ev, const Joints<T>* bristle,
                        const Pass& pass) {
  if constexpr (!std::is_same_v<T, double>) {
    if (p.friction.active() && opt.implicit_loop_derivative) {
      LoopSolution loop;
      EvaluationOf<M, double> vd;
      Joints<double> zd;
      const Status st = pass(p.template cast<double>(), L.template cast<double>(), slip, &vd,
                             fivebar::detail::array_values(bristle, &zd), &loop);
      if (!st.ok()) return st;
      return pass(p, L, &vd.slip, ev, bristle, &loop);
    }
  }
  return pass(p, L, slip, ev, bristle, static_cast<LoopSolution*>(nullptr));
}

}  // namespace detail

/// Forward dynamics of mechanism M: the accelerations qdd (ev->thdd) from the state (q, v) and
/// the loads, with the friction loop resolved. `slip` gives each joint's mode (the integrator's
/// segment mode: slip directions, stuck joints held by constraint torques); nullptr uses
/// sign(w_k), with sign(0) = 0. `bristle` holds the LuGre states z (nullptr: z = 0). `warm` (may
/// be null): the friction loop's previous solution, updated here (FrictionWarmStart).
template <class M, typename T>
Status forward(const ParamsOf<M, T>& p, const LoadsOf<M, T>& L, const State<M, T>& q,
               const State<M, T>& v, const JointModes* slip, const EvalOptions& opt,
               EvaluationOf<M, T>* ev, const Joints<T>* bristle = nullptr,
               FrictionWarmStart* warm = nullptr) {
  return detail::with_loop_shadow<M>(
      p, L, slip, opt, ev, bristle,
      [&](const auto& pp, const auto& LL, const JointModes* s, auto* e, const auto* z,
          detail::LoopSolution* loop) {
        if constexpr (std::is_same_v<std::decay_t<decltype(*e)>, EvaluationOf<M, T>>) {
          return detail::forward_pass<M, T>(pp, LL, q, v, s, opt, e, z, loop, warm);
        } else {  // the double shadow
          return detail::forward_pass<M, double>(pp, LL, detail::values(q), detail::values(v), s,
                                                 opt, e, z, loop, warm);
        }
      });
}

/// Inverse dynamics of mechanism M: the drive torques and all reactions for a given motion
/// (q, v, qdd), friction included. The Coulomb sign is sign(w_k); where w_k = 0 it is the sign
/// of the relative acceleration, unless `slip` is given. With the rest rule on
/// (EvalOptions::rest_rate, rest_acceleration; rest.h) "w_k = 0" reads "|w_k| <= rest_rate", and
/// joints at rest that do not accelerate are stuck (kStuck): no friction torque,
/// hold_margin_k = the static capacity. LuGre needs the bristle states z (`bristle`); without
/// them the bristles are at their steady state (the Stribeck law).
template <class M, typename T>
Status inverse(const ParamsOf<M, T>& p, const LoadsOf<M, T>& L, const State<M, T>& q,
               const State<M, T>& v, const State<M, T>& a, const JointModes* slip,
               const EvalOptions& opt, EvaluationOf<M, T>* ev,
               const Joints<T>* bristle = nullptr) {
  return detail::with_loop_shadow<M>(
      p, L, slip, opt, ev, bristle,
      [&](const auto& pp, const auto& LL, const JointModes* s, auto* e, const auto* z,
          detail::LoopSolution* loop) {
        if constexpr (std::is_same_v<std::decay_t<decltype(*e)>, EvaluationOf<M, T>>) {
          return detail::inverse_pass<M, T>(pp, LL, q, v, a, s, opt, e, z, loop);
        } else {  // the double shadow
          return detail::inverse_pass<M, double>(pp, LL, detail::values(q), detail::values(v),
                                                 detail::values(a), s, opt, e, z, loop);
        }
      });
}

}  // namespace fivebar::mech
