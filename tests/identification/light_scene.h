// datasets/scenes/light.yaml as the tests build it: the paper's links on a shorter geometry, no
// gravity, small pins, loads near zero.
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

}  // namespace fivebar::testing
