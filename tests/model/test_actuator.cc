// Actuator friction (actuator.h): a load-independent c sign(w) + v w at the driven joints O and
// D0. Inverse of forward, the exact torque it adds, friction never supplying power, the energy
// balance of a run, sticking up to the joint's static capacity plus c, and Jets through it.
#include <gtest/gtest.h>

#include <ceres/jet.h>

#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

Params<double> with_actuators(double c1 = 0.08, double c2 = 0.05, double v1 = 0.004,
                              double v2 = 0.002) {
  Params<double> p = paper_params();
  p.actuators.coulomb = {c1, c2};
  p.actuators.viscous = {v1, v2};
  p.actuators.offset = {0.3, -0.2};  // a sensor bias: no effect on the dynamics
  return p;
}

using State = testing::RandomState;

std::vector<State> states(const Params<double>& p, int n, uint64_t seed) {
  return testing::random_states(p, n, seed);
}

TEST(Actuator, InverseOfForwardReturnsTheTorques) {
  const Params<double> p = with_actuators();
  for (const State& s : states(p, 200, 11)) {
    Evaluation<double> fwd, inv;
    ASSERT_TRUE(forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &fwd)
                    .ok());
    ASSERT_TRUE(inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, fwd.thdd[0], fwd.thdd[1],
                                 nullptr, EvalOptions{}, &inv)
                    .ok());
    EXPECT_NEAR(inv.M1, s.loads.M1, 1e-10);
    EXPECT_NEAR(inv.M2, s.loads.M2, 1e-10);
  }
}

// with no joint friction the motor torque grows by exactly c sign(w) + v w; with joint friction
// the actuator torque also changes the reactions, so the joint friction changes too
TEST(Actuator, AddsItsTorqueToTheDrivenJoints) {
  Params<double> bare = paper_params();
  bare.friction.pin_radius.fill(0.0);  // the law is on, every joint friction torque is 0
  Params<double> act = bare;
  act.actuators = with_actuators().actuators;
  for (const State& s : states(bare, 50, 12)) {
    Evaluation<double> a, b;
    ASSERT_TRUE(inverse_dynamics(bare, s.loads, s.th1, s.th2, s.w1, s.w2, 3.0, -2.0, nullptr,
                                 EvalOptions{}, &a)
                    .ok());
    ASSERT_TRUE(inverse_dynamics(act, s.loads, s.th1, s.th2, s.w1, s.w2, 3.0, -2.0, nullptr,
                                 EvalOptions{}, &b)
                    .ok());
    const auto sgn = [](double w) { return w > 0 ? 1.0 : -1.0; };
    EXPECT_NEAR(b.M1 - a.M1, 0.08 * sgn(s.w1) + 0.004 * s.w1, 1e-12);
    EXPECT_NEAR(b.M2 - a.M2, 0.05 * sgn(s.w2) + 0.002 * s.w2, 1e-12);
    EXPECT_NEAR(b.P_diss - a.P_diss, (b.M1 - a.M1) * s.w1 + (b.M2 - a.M2) * s.w2, 1e-9);
  }
}

TEST(Actuator, FrictionNeverSuppliesPower) {
  const Params<double> p = with_actuators(0.5, 0.5, 0.01, 0.01);
  for (const State& s : states(p, 200, 13)) {
    Evaluation<double> ev;
    ASSERT_TRUE(
        forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &ev).ok());
    for (int k = 0; k < kJoints; ++k) EXPECT_GE(ev.Mf[k] * ev.w[k], 0.0) << k;
    // the driven joints carry at least the actuator's share
    EXPECT_GE(std::abs(ev.Mf[0]), 0.5 + 0.01 * std::abs(s.w1) - 1e-12);
  }
}

// a run with actuator friction: the energy balance (work in = KE + PE + dissipated, the
// actuators' dissipation included) closes, and the motion differs from the run without
TEST(Actuator, RunBalancesEnergyAndDiffersFromTheBareRun) {
  sim::Options opt;
  opt.duration = 0.5;
  const Params<double> p = with_actuators(0.2, 0.2, 0.01, 0.01);
  const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const sim::RunChecks checks = sim::check_run(p, testing::paper_loads, r);
  EXPECT_LT(checks.energy_balance_relative, 1e-7);
  const sim::Result bare =
      sim::simulate(paper_params(), testing::paper_loads, testing::paper_initial(), opt);
  ASSERT_TRUE(bare.status.ok());
  EXPECT_GT(sim::max_angle_difference(r.rows, bare.rows), 1e-3);
  EXPECT_GT(r.rows.back().E_diss, bare.rows.back().E_diss);
}

/// Equilibrium torques of the weightless paper mechanism under the 50 N force at the start.
Vec2<double> equilibrium(const Params<double>& weightless) {
  Params<double> p = weightless;
  p.friction.law = FrictionLaw::kNone;
  p.actuators = {};
  Evaluation<double> ev;
  EXPECT_TRUE(forward_dynamics(p, Loads<double>{0, 0, 0, 50.0, M_PI / 2}, M_PI / 2, M_PI / 2, 0.0,
                               0.0, nullptr, EvalOptions{}, &ev)
                  .ok());
  return -(ev.A * ev.thdd);
}

// an excess torque on M1 beyond the joints' static capacity moves the bare mechanism; the
// actuator's Coulomb friction (c = 0.35 N m) holds it
TEST(Actuator, CoulombHoldsAStuckCrank) {
  Params<double> bare = paper_params();
  bare.gravity = 0.0;
  Params<double> held = bare;
  held.actuators.coulomb = {0.35, 0.35};
  const Vec2<double> eq = equilibrium(bare);
  const sim::LoadFunction drive = [eq](double) {
    return Loads<double>{eq[0] + 0.3, eq[1], 0.0, 50.0, M_PI / 2};
  };
  sim::Options opt;
  opt.duration = 0.5;
  const sim::Result moves = sim::simulate(bare, drive, testing::paper_initial(), opt);
  const sim::Result stays = sim::simulate(held, drive, testing::paper_initial(), opt);
  ASSERT_TRUE(moves.status.ok()) << moves.status.message;
  ASSERT_TRUE(stays.status.ok()) << stays.status.message;
  EXPECT_GT(testing::max_displacement(moves, 2), 1e-3);
  EXPECT_LT(testing::max_displacement(stays, 2), 1e-12);
}

// Jets through the friction loop: d M1 / d c1 = sign(w1) + (the joint friction's response)
TEST(Actuator, JetsDifferentiateTheActuatorTerms) {
  using J = ceres::Jet<double, 2>;
  const Params<double> p0 = with_actuators();
  Params<J> p = p0.cast<J>();
  p.actuators.coulomb[0] = J(0.08, 0);
  p.actuators.viscous[0] = J(0.004, 1);
  const Loads<double> L = testing::paper_loads(0.3);
  Evaluation<J> ev;
  ASSERT_TRUE(inverse_dynamics(p, L.cast<J>(), J(2.0), J(1.0), J(30.0), J(-20.0), J(3.0), J(-2.0),
                               nullptr, EvalOptions{}, &ev)
                  .ok());
  for (int d = 0; d < 2; ++d) {
    const double h = 1e-6;
    Params<double> q = p0;
    (d == 0 ? q.actuators.coulomb[0] : q.actuators.viscous[0]) += h;
    Evaluation<double> plus, minus;
    ASSERT_TRUE(inverse_dynamics(q, L, 2.0, 1.0, 30.0, -20.0, 3.0, -2.0, nullptr, EvalOptions{},
                                 &plus)
                    .ok());
    (d == 0 ? q.actuators.coulomb[0] : q.actuators.viscous[0]) -= 2 * h;
    ASSERT_TRUE(inverse_dynamics(q, L, 2.0, 1.0, 30.0, -20.0, 3.0, -2.0, nullptr, EvalOptions{},
                                 &minus)
                    .ok());
    EXPECT_NEAR(ev.M1.v[d], (plus.M1 - minus.M1) / (2 * h), 1e-6);
  }
  EXPECT_NEAR(ev.M1.v[1] / ev.M1.v[0], 30.0, 3.0);  // the viscous term scales with w1 = 30
}

}  // namespace
}  // namespace fivebar
