// Actuator (motor, gearbox) friction: a load-independent Coulomb + viscous torque at the driven
// joints, added to their joint friction torques (docs/model.md, "Actuators"): the five-bar's O
// (actuator 0, M1) and D0 (actuator 1, M2), the four-bar's O (actuator 0, M1, its crank). The
// torque-sensor offsets of ActuatorParams never enter the dynamics: only measured torques
// (synth-log, identify).
#pragma once

#include <array>
#include <cmath>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// The drives of a mechanism: how many actuators it has (entries 0..count-1 of ActuatorParams;
/// the others stay zero) and the joint slot each drives.
struct ActuatorMap {
  int count = kActuators;
  std::array<int, kActuators> joint{};

  /// The actuator driving joint slot k, or -1 (an undriven joint).
  constexpr int actuator_of(int k) const {
    for (int a = 0; a < count; ++a) {
      if (joint[a] == k) return a;
    }
    return -1;
  }
};
/// The five-bar's M1 at O and M2 at D0; the four-bar's M1 at O.
inline constexpr ActuatorMap kFiveBarActuators{kActuators, {0, kJoints - 1}};
inline constexpr ActuatorMap kFourBarActuators{1, {0, -1}};

/// The joint a five-bar actuator drives (0: O, 1: D0) and the actuator of a joint (-1: not
/// driven).
inline constexpr int actuator_joint(int a) { return kFiveBarActuators.joint[a]; }
inline constexpr int joint_actuator(int k) { return kFiveBarActuators.actuator_of(k); }

/// True when some actuator friction coefficient can contribute (value or derivative non-zero).
template <typename T>
bool actuator_friction_active(const ActuatorParams<T>& a) {
  for (int i = 0; i < kActuators; ++i) {
    if (!is_exact_zero(a.coulomb[i]) || !is_exact_zero(a.viscous[i])) return true;
  }
  return false;
}

/// c_a sign + v_a w of actuator a at the rate w of its joint, the Coulomb direction taken as the
/// joint law's (coulomb_direction: `slip`, or smoothed).
template <typename T>
T actuator_friction_of(const FrictionParams<T>& fp, const ActuatorParams<T>& act, int a, const T& w,
                       int slip) {
  return act.coulomb[a] * coulomb_direction(fp, w, slip) + act.viscous[a] * w;
}

/// The five-bar's actuator friction at joint k (0 at the undriven joints).
template <typename T>
T actuator_friction(const FrictionParams<T>& fp, const ActuatorParams<T>& act, int k, const T& w,
                    int slip) {
  const int a = joint_actuator(k);
  if (a < 0) return T(0);
  return actuator_friction_of(fp, act, a, w, slip);
}

/// The actuator friction torques of the joint slots at relative rates w in modes `slip`, for the
/// drives `map` (zero at undriven and stuck joints: a stuck joint's holding torque includes
/// them). False, with *out untouched, when there is no actuator friction.
template <typename T>
bool actuator_torques(const FrictionParams<T>& fp, const ActuatorParams<T>& act,
                      const ActuatorMap& map, const std::array<T, kJoints>& w,
                      const JointModes& slip, std::array<T, kJoints>* out) {
  if (!actuator_friction_active(act)) return false;
  out->fill(T(0));
  for (int a = 0; a < map.count; ++a) {
    const int k = map.joint[a];
    if (slip[k] == kStuck) continue;
    (*out)[k] = actuator_friction_of(fp, act, a, w[k], coulomb_sign(slip[k]));
  }
  return true;
}

/// The five-bar's (kFiveBarActuators).
template <typename T>
bool actuator_torques(const Params<T>& p, const std::array<T, kJoints>& w, const JointModes& slip,
                      std::array<T, kJoints>* out) {
  return actuator_torques(p.friction, p.actuators, kFiveBarActuators, w, slip, out);
}

/// The most friction torque a stuck joint k can hold under the reaction N [N m]: mu_s,k r_k N_k,
/// plus the actuator's Coulomb friction c_a at a joint `map` drives.
template <typename T>
T holding_capacity(const FrictionParams<T>& fp, const ActuatorParams<T>& act,
                   const ActuatorMap& map, int k, const T& N) {
  const int a = map.actuator_of(k);
  const T joint = holding_bound(fp, k) * N;
  return a < 0 ? joint : T(joint + act.coulomb[a]);
}
template <typename T>
T holding_capacity(const Params<T>& p, int k, const T& N) {
  return holding_capacity(p.friction, p.actuators, kFiveBarActuators, k, N);
}

/// True when joint k can be held by friction at all (some static capacity).
inline bool can_hold(const FrictionParams<double>& fp, const ActuatorParams<double>& act,
                     const ActuatorMap& map, int k) {
  const int a = map.actuator_of(k);
  return holding_bound(fp, k) > 0.0 || (a >= 0 && act.coulomb[a] > 0.0);
}
inline bool can_hold(const Params<double>& p, int k) {
  return can_hold(p.friction, p.actuators, kFiveBarActuators, k);
}

}  // namespace fivebar
