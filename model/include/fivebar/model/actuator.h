// Actuator (motor, gearbox) friction: a load-independent Coulomb + viscous torque at the two
// driven joints, O (actuator 0, M1) and D0 (actuator 1, M2), added to their joint friction
// torques (docs/model.md, "Actuators"). The torque-sensor offsets of ActuatorParams never enter
// the dynamics: only measured torques (synth-log, identify).
#pragma once

#include <array>
#include <cmath>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// The joint an actuator drives (0: O, 1: D0) and the actuator of a joint (-1: not driven).
inline constexpr int actuator_joint(int a) { return a == 0 ? 0 : kJoints - 1; }
inline constexpr int joint_actuator(int k) { return k == 0 ? 0 : k == kJoints - 1 ? 1 : -1; }

/// True when some actuator friction coefficient can contribute (value or derivative non-zero).
template <typename T>
bool actuator_friction_active(const ActuatorParams<T>& a) {
  for (int i = 0; i < kActuators; ++i) {
    if (!is_exact_zero(a.coulomb[i]) || !is_exact_zero(a.viscous[i])) return true;
  }
  return false;
}

/// c_a sign + v_a w of the actuator driving joint k (0 for the undriven joints), the Coulomb
/// direction taken as the joint law's (coulomb_direction: `slip`, or smoothed).
template <typename T>
T actuator_friction(const FrictionParams<T>& fp, const ActuatorParams<T>& act, int k, const T& w,
                    int slip) {
  const int a = joint_actuator(k);
  if (a < 0) return T(0);
  return act.coulomb[a] * coulomb_direction(fp, w, slip) + act.viscous[a] * w;
}

/// The actuator friction torques of the five joints at relative rates w in modes `slip` (zero at
/// undriven and stuck joints: a stuck joint's holding torque includes them). False, with *out
/// untouched, when there is no actuator friction.
template <typename T>
bool actuator_torques(const Params<T>& p, const std::array<T, kJoints>& w, const JointModes& slip,
                      std::array<T, kJoints>* out) {
  if (!actuator_friction_active(p.actuators)) return false;
  out->fill(T(0));
  for (int a = 0; a < kActuators; ++a) {
    const int k = actuator_joint(a);
    if (slip[k] == kStuck) continue;
    (*out)[k] = actuator_friction(p.friction, p.actuators, k, w[k], coulomb_sign(slip[k]));
  }
  return true;
}

/// The most friction torque a stuck joint k can hold under the reaction N [N m]: mu_s,k r_k N_k,
/// plus the actuator's Coulomb friction c_a at a driven joint.
template <typename T>
T holding_capacity(const Params<T>& p, int k, const T& N) {
  const int a = joint_actuator(k);
  const T joint = holding_bound(p.friction, k) * N;
  return a < 0 ? joint : T(joint + p.actuators.coulomb[a]);
}

/// True when joint k can be held by friction at all (some static capacity).
inline bool can_hold(const Params<double>& p, int k) {
  const int a = joint_actuator(k);
  return holding_bound(p.friction, k) > 0.0 || (a >= 0 && p.actuators.coulomb[a] > 0.0);
}

}  // namespace fivebar
