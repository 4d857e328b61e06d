// The structure of one sample's inverse dynamics (residual.h).
#include "fivebar/identification/residual.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>

#include "jet_dynamics.h"

namespace fivebar::identification {

namespace {

/// Friction-free reactions (10) and actuator torques (2) of sample s for the inertial
/// parameters pi; false where the inverse dynamics fails.
bool frictionless(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                  const std::array<double, kInertialParams>& pi, Eigen::Matrix<double, 12, 1>* out) {
  Params<double> p = scene;
  p.friction.law = FrictionLaw::kNone;
  p.actuators = ActuatorParams<double>();  // StructuredResidual adds the actuator terms
  set_standard_inertial(pi.data(), &p);
  Evaluation<double> ev;
  if (!inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr, eval, &ev)
           .ok()) {
    return false;
  }
  for (int k = 0; k < kJoints; ++k) {
    (*out)(2 * k) = ev.F[k].x();
    (*out)(2 * k + 1) = ev.F[k].y();
  }
  (*out)(10) = ev.M1;
  (*out)(11) = ev.M2;
  return out->allFinite();
}

}  // namespace

bool sample_structure(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                      SampleStructure* out) {
  // inertial part: friction-free reactions and torques are affine in pi (forward differences
  // are exact up to rounding; Jets would be singular at a COM on the joint)
  const std::array<double, kInertialParams> pi0 = standard_inertial(scene);
  Eigen::Matrix<double, 12, 1> v0, v1;
  if (!frictionless(scene, s, eval, pi0, &v0)) return false;
  Eigen::Matrix<double, 12, kInertialParams> D;
  for (int i = 0; i < kInertialParams; ++i) {
    const int l = i / kInertialPerLink;
    const double h = 1e-3 * std::max(std::abs(pi0[i]), scene.links[l].mass * scene.links[l].length);
    std::array<double, kInertialParams> pi = pi0;
    pi[i] += h;
    if (!frictionless(scene, s, eval, pi, &v1)) return false;
    D.col(i) = (v1 - v0) / h;
  }
  const Eigen::Map<const Eigen::Matrix<double, kInertialParams, 1>> pv(pi0.data());
  out->A = D.topRows(10);
  out->b = v0.head(10) - out->A * pv;
  out->Y = D.bottomRows(2);
  out->c = v0.tail(2) - out->Y * pv;
  // friction part: Jets over the pin radii at 0 with unit Coulomb coefficients, so that
  // phi_j = r_j slip_j and d(F, M) / d r_j = (dF_j, G_j) slip_j N0_j
  using J5 = ceres::Jet<double, kJoints>;
  Params<J5> p = scene.cast<J5>();
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.smoothing_velocity = J5(0);
  p.actuators = ActuatorParams<J5>();
  for (int j = 0; j < kJoints; ++j) {
    p.friction.coulomb[j] = J5(1);
    p.friction.viscous[j] = J5(0);
    p.friction.pin_radius[j] = J5(0, j);
  }
  Evaluation<J5> ev;
  if (!inverse_dynamics(p, s.loads.cast<J5>(), J5(s.th1), J5(s.th2), J5(s.w1), J5(s.w2),
                        J5(s.a1), J5(s.a2), nullptr, eval, &ev)
           .ok()) {
    return false;
  }
  double nmax = 1e-300;
  for (int k = 0; k < kJoints; ++k) nmax = std::max(nmax, ev.N[k].a);
  for (int j = 0; j < kJoints; ++j) {
    out->slip[j] = ev.slip[j];
    out->w[j] = ev.w[j].a;
    const bool acts = ev.slip[j] != kStuck && ev.slip[j] != JointMode::kRest;
    // a joint without a Coulomb sign but moving: its viscous torque needs the full model
    if (!acts && ev.slip[j] == JointMode::kRest && out->w[j] != 0 && scene.friction.pin_radius[j] != 0) {
      return false;
    }
    const double scale = acts ? coulomb_sign(ev.slip[j]) * ev.N[j].a : 0.0;
    if (acts && std::abs(scale) < 1e-9 * nmax) return false;
    for (int k = 0; k < kJoints; ++k) {
      out->dF(2 * k, j) = acts ? ev.F[k].x().v[j] / scale : 0.0;
      out->dF(2 * k + 1, j) = acts ? ev.F[k].y().v[j] / scale : 0.0;
    }
    out->G(0, j) = acts ? ev.M1.v[j] / scale : 0.0;
    out->G(1, j) = acts ? ev.M2.v[j] / scale : 0.0;
  }
  return out->A.allFinite() && out->dF.allFinite() && out->G.allFinite();
}

}  // namespace fivebar::identification
