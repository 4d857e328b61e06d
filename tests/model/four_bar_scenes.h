// The four-bar scenes of datasets/reference/four_bar/ as tests build them (their values repeated,
// so that the model's tests do not depend on the scene reader).
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "fivebar/model/four_bar.h"

namespace fivebar::testing {

/// A scene of datasets/reference/four_bar/ (its values repeated: the scene reader reads five-bars
/// only) and its loads as functions of t.
struct ReferenceScene {
  std::string file;
  FourBarParams p;
  double th0;
  std::function<FourBarLoads(double)> loads;
  double difference_tol;  ///< relative; the stencil's own error (measured 7.4e-6 and 1.1e-9)
};

inline std::vector<ReferenceScene> reference_scenes() {
  FourBarParams cr, dr;
  cr.ground_length = 0.30;
  cr.links = {Link<double>{0.08, 0.5, 0.0003, 0.04, 0.0},
              Link<double>{0.28, 1.0, 0.0065, 0.14, 0.1},
              Link<double>{0.20, 0.8, 0.0027, 0.10, 0.0}};
  cr.point_p = 0.18;
  cr.assembly = kElbowUp;
  dr.ground_length = 0.32;
  dr.links = {Link<double>{0.20, 0.8, 0.0027, 0.10, 0.0},
              Link<double>{0.12, 0.4, 0.0005, 0.06, 0.0},
              Link<double>{0.22, 0.9, 0.0036, 0.11, 0.0}};
  dr.point_p = 0.06;
  dr.assembly = kElbowDown;
  for (FourBarParams* p : {&cr, &dr}) {
    p->gravity = 9.81;
    p->friction.law = FrictionLaw::kCoulombViscous;
    p->friction.pin_radius.fill(0.01);
    p->friction.coulomb.fill(0.12);
    p->friction.static_coulomb.fill(0.12);
    p->friction.viscous.fill(0.02);
  }
  return {{"crank_rocker", cr, M_PI / 2,
           [](double t) {
             return FourBarLoads{0.9 + 0.6 * std::sin(4 * M_PI * t), 0.2, 5.0, M_PI / 2};
           },
           2e-5},
          {"double_rocker", dr, -0.75,
           [](double t) {
             return FourBarLoads{1.0 + 0.4 * std::sin(3 * M_PI * t), 0.0, 2.0, 0.0};
           },
           1e-8}};
}

}  // namespace fivebar::testing
