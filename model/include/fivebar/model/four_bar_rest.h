// Holding a four-bar at rest: the crank torque of the frictionless equilibrium (the torque of
// gravity and the loads by virtual work), each joint's static friction bound there, and the range
// of M1 over which static friction at the four joints holds the pose (the simulator's lock,
// lock.h). The five-bar's counterpart is Holding in rest.h.
#pragma once

#include <array>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/status.h"

namespace fivebar {

struct FourBarHolding {
  double M1 = 0;  ///< frictionless equilibrium [N m]: M1 holds the pose with no friction torque
  std::array<double, kFourBarJoints> N{};      ///< joint reactions there [N] (O, B, C, D0)
  std::array<double, kFourBarJoints> bound{};  ///< mu_s,k r_k N_k [N m] (0 without friction)
  /// the range of M1 over which static friction holds the pose [N m] (the lock: friction at all
  /// four joints); M1 +- bound[0] is what joint O holds alone
  double M1_min = 0, M1_max = 0;
};

/// Frictionless equilibrium and holding range at crank angle th1 under loads L (L.M1 ignored).
/// Fails like the kinematics: kCannotAssemble, kNearSingular (opt.singular_margin); and
/// kIndeterminateModes where the range does not settle (lock_extent: self-locking). Compiled in
/// the simulation library (src/simulator.cc, beside the four-bar's other instantiations).
Status four_bar_holding(const FourBarParams& p, FourBarLoads L, double th1, const EvalOptions& opt,
                        FourBarHolding* h);

}  // namespace fivebar
