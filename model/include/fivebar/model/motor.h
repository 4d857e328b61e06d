// The motors' winding data (scene `actuators.M1`, `.M2`: winding_resistance, torque_constant,
// gear_ratio) and the copper loss they give, R (M / (k_t G))^2 at crank torque M (docs/model.md,
// "Motor losses"). They never enter the dynamics: only the trajectory objectives.
#pragma once

#include <array>

#include "fivebar/model/params.h"

namespace fivebar {

/// Winding data of the motors (index 0: M1 at O, 1: M2 at D0; the four-bar's one motor, M1,
/// in index 0).
struct MotorWindings {
  std::array<double, kActuators> resistance{};       ///< R [ohm]; 0: no winding data
  std::array<double, kActuators> torque_constant{};  ///< k_t [N m/A] on the motor shaft; 0: none
  std::array<double, kActuators> gear_ratio{1.0, 1.0};  ///< G [motor turns per crank turn]

  /// True when the first `motors` motors (both by default) have winding data (R > 0 and
  /// k_t > 0).
  bool present(int motors = kActuators) const {
    for (int a = 0; a < motors; ++a) {
      if (!(resistance[a] > 0.0) || !(torque_constant[a] > 0.0)) return false;
    }
    return true;
  }
  /// c_a = R / (k_t G)^2 [W/(N m)^2]: the winding heat of motor a is c_a M^2 at crank torque M
  /// (0 without winding data).
  double heat_coefficient(int a) const {
    const double kg = torque_constant[a] * gear_ratio[a];
    return kg > 0.0 ? resistance[a] / (kg * kg) : 0.0;
  }
  std::array<double, kActuators> heat_coefficients() const {
    return {heat_coefficient(0), heat_coefficient(1)};
  }
};

}  // namespace fivebar
