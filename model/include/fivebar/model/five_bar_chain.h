// The five-bar as a joint table of the general planar chain (planar_chain.h): bodies 0..3 are
// links 1..4 with their frames at the proximal joints (O, D0, B, D), joints O, B, C, D, D0 in the
// five-bar's order and friction indices, drives M1 at O and M2 at D0. The chain solves the same
// dynamics in maximal coordinates, independently of the Appell form (appell.h).
#pragma once

#include <cmath>
#include <vector>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/planar_chain.h"

namespace fivebar {

/// The five-bar's joint table.
inline chain::Chain five_bar_chain(const Params<double>& p) {
  using chain::kGround;
  using chain::Vec;
  chain::Chain c;
  for (const Link<double>& l : p.links) c.bodies.push_back(chain::link_body(l));
  const double l1 = p.links[0].length, l2 = p.links[1].length, l3 = p.links[2].length;
  const double l4 = p.links[3].length;
  const std::array<double, kJoints>& r = p.friction.pin_radius;
  c.joints = {{kGround, 0, Vec(0, 0), Vec(0, 0), r[0], 0},                 // O: ground - link 1
              {0, 2, Vec(l1, 0), Vec(0, 0), r[1], 1},                      // B: link 1 - link 3
              {2, 3, Vec(l3, 0), Vec(l4, 0), r[2], 2},                     // C: link 3 - link 4
              {3, 1, Vec(0, 0), Vec(l2, 0), r[3], 3},                      // D: link 4 - link 2
              {kGround, 1, Vec(p.ground_length, 0), Vec(0, 0), r[4], 4}};  // D0: ground - link 2
  c.drives = {{kGround, 0}, {kGround, 1}};
  c.gravity = p.gravity;
  c.friction = p.friction;
  return c;
}

/// The chain's pose of a closed five-bar pose (solve_kinematics with angles).
inline chain::Pose five_bar_pose(const Params<double>& p, const Kinematics<double>& k) {
  return {{Vec2<double>(0, 0), Vec2<double>(p.ground_length, 0), k.B, k.D},
          {k.th1, k.th2, k.th3, k.th4}};
}

/// The bodies' rates (w1, w2, w3, w4) from the cranks' rates.
inline std::vector<double> five_bar_rates(const Kinematics<double>& k, double w1, double w2) {
  const Vec2<double> thd(w1, w2);
  return {w1, w2, k.G3.dot(thd), k.G4.dot(thd)};
}

/// The chain's loads: M1, M2 on the drives, M3 on link 3 and F at P (angle F_angle from link 3).
inline chain::ChainLoads five_bar_loads(const Params<double>& p, const Kinematics<double>& k,
                                        const Loads<double>& L) {
  chain::ChainLoads out;
  out.drive = {L.M1, L.M2};
  out.torque = {0.0, 0.0, L.M3, 0.0};
  out.forces = {{2, chain::Vec(p.point_p, 0), L.F * unit(k.th3 + L.F_angle)}};
  return out;
}

}  // namespace fivebar
