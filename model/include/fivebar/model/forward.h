// Forward dynamics of the five-bar: the accelerations from the state and the loads, with the
// reaction/friction loop resolved and stuck joints (exact stick-slip) held by constraint torques
// (mechanism_dynamics.h, for the FiveBar mechanism).
#pragma once

#include <array>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/five_bar_mechanism.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/mechanism_dynamics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"

namespace fivebar {

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
  return mech::forward<FiveBar, T>(p, L, Vec2<T>(th1, th2), Vec2<T>(w1, w2), slip, opt, ev,
                                   bristle, warm);
}

#ifdef FIVEBAR_COMPILED_DOUBLE_DYNAMICS
// Code that links fivebar::sim (which defines this macro for its users) takes the double pass
// of the forward dynamics from model/src/forward_double.cc instead of compiling it again (~6 s
// of compilation in each unit that evaluates it). Header-only users of fivebar::model compile
// it as before.
namespace mech::detail {
extern template Status forward_pass<FiveBar, double>(
    const Params<double>&, const Loads<double>&, const Vec2<double>&, const Vec2<double>&,
    const JointModes*, const EvalOptions&, Evaluation<double>*,
    const std::array<double, kJoints>*, LoopSolution*, FrictionWarmStart*);
}  // namespace mech::detail
#endif

}  // namespace fivebar
