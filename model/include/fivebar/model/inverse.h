// Inverse dynamics of the five-bar: the motor torques and all reactions for a given motion,
// friction included, with the rest rule of joints at rest (rest.h; mechanism_dynamics.h, for the
// FiveBar mechanism).
#pragma once

#include <array>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/five_bar_mechanism.h"
#include "fivebar/model/mechanism_dynamics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"

namespace fivebar {

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
  return mech::inverse<FiveBar, T>(p, L, Vec2<T>(th1, th2), Vec2<T>(w1, w2), Vec2<T>(a1, a2),
                                   slip, opt, ev, bristle);
}

#ifdef FIVEBAR_COMPILED_DOUBLE_DYNAMICS
// Code that links fivebar::sim (which defines this macro for its users) takes the double pass
// of the inverse dynamics from model/src/inverse_double.cc instead of compiling it again: ~5 s
// of compilation in each unit that evaluates the inverse dynamics, in double or in Jets (whose
// shadow pass is the double one). Header-only users of fivebar::model compile it as before.
namespace mech::detail {
extern template Status inverse_pass<FiveBar, double>(
    const Params<double>&, const Loads<double>&, const Vec2<double>&, const Vec2<double>&,
    const Vec2<double>&, const JointModes*, const EvalOptions&, Evaluation<double>*,
    const std::array<double, kJoints>*, LoopSolution*);
}  // namespace mech::detail
#endif

}  // namespace fivebar
