// Inverse-dynamics residual of one log sample, templated on the scalar for ceres::Jet.
#pragma once

#include <array>

#include "fivebar/identification/parameters.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/params.h"

namespace fivebar::identification {

/// One sample as the residual sees it: pose, rates, accelerations (measured or estimated), the
/// measured actuator torques and the scene's other loads (M3, F, F_angle) at that time.
struct Sample {
  double t = 0, th1 = 0, th2 = 0, w1 = 0, w2 = 0, a1 = 0, a2 = 0, tau1 = 0, tau2 = 0;
  Loads<double> loads;
};

/// r = (tau1 - M1(x), tau2 - M2(x)) [N m], M from the friction-aware inverse dynamics
/// (dynamics.h, the reaction/friction loop resolved inside) with the friction coefficients x laid
/// out by `layout` and every other constant from `scene`. With exact sign (smoothing_velocity 0)
/// the Coulomb sign of each joint is sign(w_k) of the sample's rates: data, not a function of x,
/// so r is smooth in x. `operator()` accepts double and ceres::Jet.
class InverseDynamicsResidual {
 public:
  InverseDynamicsResidual(const Params<double>& scene, const ParameterLayout& layout,
                          const Sample& sample, const EvalOptions& eval)
      : scene_(scene), layout_(layout), s_(sample), eval_(eval) {}

  template <typename T>
  bool operator()(const T* x, T* r) const {
    Params<T> p = scene_.template cast<T>();
    layout_.apply(x, &p.friction);
    Evaluation<T> ev;
    const Status st = inverse_dynamics(p, s_.loads.template cast<T>(), T(s_.th1), T(s_.th2),
                                       T(s_.w1), T(s_.w2), T(s_.a1), T(s_.a2), nullptr, eval_, &ev);
    if (!st.ok()) return false;  // Ceres rejects the step (e.g. the friction loop diverged)
    r[0] = T(s_.tau1) - ev.M1;
    r[1] = T(s_.tau2) - ev.M2;
    return true;
  }

  const Sample& sample() const { return s_; }

 private:
  const Params<double>& scene_;
  ParameterLayout layout_;
  Sample s_;
  EvalOptions eval_;
};

}  // namespace fivebar::identification
