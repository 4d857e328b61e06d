// Holding a four-bar at rest: the crank torque of the frictionless equilibrium (the torque of
// gravity and the loads by virtual work), each joint's static friction bound there, and the range
// of M1 over which static friction at the four joints holds the pose (the simulator's lock,
// lock.h). The five-bar's counterpart is Holding in rest.h.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "fivebar/model/four_bar.h"
#include "fivebar/model/lock.h"

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
/// Fails like the kinematics: kCannotAssemble, kNearSingular (opt.singular_margin).
inline Status four_bar_holding(const FourBarParams& p, FourBarLoads L, double th1,
                               const EvalOptions& opt, FourBarHolding* h) {
  FourBarParams frictionless = p;
  frictionless.friction.law = FrictionLaw::kNone;
  FourBarEvaluation ev;
  const Status st = four_bar_inverse(frictionless, L, th1, 0.0, 0.0, opt, &ev);
  if (!st.ok()) return st;
  h->M1 = ev.M1;
  for (int k = 0; k < kFourBarJoints; ++k) {
    h->N[k] = ev.N[k];
    h->bound[k] = p.friction.active() ? FourBar::holding_capacity(p, k, ev.N[k]) : 0.0;
  }
  double ext[2] = {0.0, 0.0};  // below, above the equilibrium
  if (p.friction.active()) {
    L.M1 = h->M1;
    const double start = std::max(h->bound[0], 1e-12 * (1.0 + std::abs(h->M1)));
    for (int e = 0; e < 2; ++e) {
      const Status s = lock_extent<FourBar>(
          p, L, FourBar::Q<double>(th1), opt, h->M1, e == 0 ? -1.0 : 1.0, start,
          [](FourBarLoads* l, double v) { l->M1 = v; }, &ext[e]);
      if (!s.ok()) return s;
    }
  }
  h->M1_min = h->M1 - ext[0];
  h->M1_max = h->M1 + ext[1];
  return Status::Ok();
}

}  // namespace fivebar
