// datasets/scenes/light.yaml as the tests build it: the paper's links on a shorter geometry, no
// gravity, small pins, loads near zero; and a featherweight mechanism under gravity.
#pragma once

#include <cmath>

#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::testing {

inline Params<double> light_params() {
  Params<double> p = paper_params();
  p.ground_length = 0.2;
  p.links[0] = {0.1, 1.0, 0.1, 0.05, 0.0};
  p.links[1] = {0.1, 1.0, 0.1, 0.03, 0.0};
  p.links[2] = {0.2, 1.0, 0.1, 0.15, 0.0};
  p.links[3] = {0.2, 1.0, 0.1, 0.15, 0.0};
  p.point_p = 0.2;
  p.gravity = 0;
  p.friction.pin_radius.fill(0.004);
  return p;
}

/// The light scene's loads (M3 0.001 N m, F 0.01 N) with motor torques `M1`, `M2` of t.
inline sim::LoadFunction light_loads(double (*M1)(double) = nullptr, double (*M2)(double) = nullptr) {
  return [M1, M2](double t) {
    return Loads<double>{M1 ? M1(t) : 0.0, M2 ? M2(t) : 0.0, 0.001, 0.01, M_PI / 2};
  };
}

/// A featherweight five-bar under gravity: links of 0.15-0.25 kg on a 0.15 m ground, pins of
/// 0.004 m, coulomb 0.15, viscous 0.004; motor torques of a few hundredths of a N m
/// (feather_loads). Its friction torques are a few thousandths of a N m, under the torque noise.
inline Params<double> feather_params() {
  Params<double> p = paper_params();
  p.ground_length = 0.15;
  p.links[0] = {0.06, 0.2, 0.004, 0.03, 0.1};
  p.links[1] = {0.07, 0.25, 0.005, 0.035, 0.0};
  p.links[2] = {0.15, 0.15, 0.003, 0.07, 0.0};
  p.links[3] = {0.16, 0.15, 0.003, 0.08, 0.0};
  p.point_p = 0.15;
  p.gravity = 9.81;
  p.friction.pin_radius.fill(0.004);
  p.friction.coulomb.fill(0.15);
  p.friction.static_coulomb.fill(0.15);
  p.friction.viscous.fill(0.004);
  return p;
}

/// The featherweight scene's loads: M1, M2 two tones each, M3 0.002 N m, F 0.05 N at 1 rad.
inline sim::LoadFunction feather_loads() {
  return [](double t) {
    return Loads<double>{0.03 * std::sin(5 * t) + 0.02 * std::sin(11 * t),
                         0.025 * std::cos(3 * t) - 0.015 * std::sin(13 * t), 0.002, 0.05, 1.0};
  };
}

/// A light, slow five-bar under weak gravity (links of 2-3 kg, loads of 0.4 N m, gravity
/// 0.49 m/s^2, coulomb 0.2, viscous 0.05 on pins of 0.015 m), logged with torque noise under a
/// thousandth of a N m: its clean angles-only logs have a torque residual 40 times the torque
/// noise (the angle noise through the estimated accelerations), and a delay of a few ms is
/// mostly absorbed by the links' inertial parameters in the model check. Start: slow_light_start.
inline Params<double> slow_light_params() {
  Params<double> p = paper_params();
  p.ground_length = 0.4;
  p.links[0] = {0.15, 3.0, 0.025, 0.07, 0.0};
  p.links[1] = {0.12, 2.5, 0.02, 0.06, 0.0};
  p.links[2] = {0.35, 2.0, 0.03, 0.2, 0.1};
  p.links[3] = {0.3, 2.0, 0.025, 0.12, 0.0};
  p.point_p = 0.3;
  p.gravity = 0.4905;
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.pin_radius.fill(0.015);
  p.friction.coulomb.fill(0.2);
  p.friction.static_coulomb.fill(0.2);
  p.friction.viscous.fill(0.05);
  return p;
}

/// The slow light scene's loads: M1, M2 one tone each about a small bias, M3 0.025 N m, F 1 N.
inline Loads<double> slow_light_loads(double t) {
  return {0.05 + 0.4 * std::sin(3 * t), -0.05 + 0.4 * std::cos(2 * t), 0.025, 1.0, 1.0};
}

/// The slow light scene's start: theta1 1.6, theta2 1.4 rad, rates 0.5, -0.3 rad/s.
inline sim::Initial slow_light_start() { return {1.6, 1.4, 0.5, -0.3}; }

/// The featherweight scene's start: theta1 1.7, theta2 1.4 rad, at rest.
inline sim::Initial feather_initial() { return {1.7, 1.4, 0.0, 0.0}; }

}  // namespace fivebar::testing
