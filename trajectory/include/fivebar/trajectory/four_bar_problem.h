// The four-bar's trajectory problem (TrajectoryProblemT<FourBar>: one spline for the crank angle
// th1, one torque row per node for M1 and the singular margin on |sin(th3 - th2)|), and the
// problem of a solved task. Its tasks and their run: four_bar_tasks.h.
#pragma once

#include <array>

#include "fivebar/model/four_bar.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/problem.h"

namespace fivebar::trajectory {

template <>
struct TrajectoryMechanism<FourBar> {
  template <typename T>
  static Status inverse(const FourBarParamsT<T>& p, const FourBarLoadsT<T>& L,
                        const std::array<T, 3>& s, const EvalOptions& opt,
                        FourBarEvaluationT<T>* ev) {
    return four_bar_inverse(p, L, s[0], s[1], s[2], opt, ev);
  }
  template <typename T>
  static std::array<T, 1> drives(const FourBarEvaluationT<T>& ev) {
    return {ev.M1};
  }
};

/// The four-bar's problem (instantiated once, in problem_four_bar.cc).
extern template class TrajectoryProblemT<FourBar>;
using FourBarTrajectoryProblem = TrajectoryProblemT<FourBar>;

/// The problem a four-bar result was solved on (to recompute its rows or torques).
FourBarTrajectoryProblem four_bar_problem_of(const FourBarParams& params,
                                             const sim::FourBarLoadFunction& loads,
                                             const TaskResult& result,
                                             const BatchOptions& options);


}  // namespace fivebar::trajectory
