// Exact stick-slip: a drive below breakaway does not move the mechanism at all; a slow drive
// sticks and slips again with located switches; the regularized law creeps where stick holds.
#include <gtest/gtest.h>

#include <cmath>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

// zero displacement while stuck, below 1e-12 rad
constexpr double kStuckDisplacement = 1e-12;

/// Paper mechanism without gravity: the 50 N force at P loads the joints, so friction holds
/// small drive torques (holding bound mu_s r N ~ 0.12 * 0.01 * 50 = 0.06 N m).
Params<double> weightless() {
  Params<double> p = paper_params();
  p.gravity = 0.0;
  return p;
}

/// Crank torques that hold the weightless mechanism still against the 50 N force at the
/// initial pose: minus the generalized force A thdd of the unheld, frictionless mechanism.
Vec2<double> equilibrium_torques() {
  Params<double> p = weightless();
  p.friction.law = FrictionLaw::kNone;
  Evaluation<double> ev;
  EXPECT_TRUE(forward_dynamics(p, Loads<double>{0, 0, 0, 50.0, M_PI / 2}, M_PI / 2, M_PI / 2, 0.0,
                               0.0, nullptr, EvalOptions{}, &ev)
                  .ok());
  return -(ev.A * ev.thdd);
}

/// Equilibrium torques plus (dM1, dM2) sin(omega t) (constant excess when omega = 0).
sim::LoadFunction drive(double dM1, double dM2, double omega) {
  const Vec2<double> eq = equilibrium_torques();
  return [=](double t) {
    const double s = omega == 0.0 ? 1.0 : std::sin(omega * t);
    return Loads<double>{eq[0] + dM1 * s, eq[1] + dM2 * s, 0.0, 50.0, M_PI / 2};
  };
}

double max_displacement(const sim::Result& r) { return testing::max_displacement(r, 4); }

bool any_stuck(const JointModes& modes) {
  for (JointMode m : modes) {
    if (m == kStuck) return true;
  }
  return false;
}

TEST(Stick, DriveBelowBreakawayDoesNotMove) {
  sim::Options opt;
  opt.duration = 1.0;
  // constant excess torques well inside the holding bound
  const sim::Result r =
      sim::simulate(weightless(), drive(0.01, -0.01, 0.0), testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_LT(max_displacement(r), kStuckDisplacement);
  EXPECT_EQ(r.rows.back().mode[0], kStuck);
  EXPECT_EQ(r.rows.back().mode[4], kStuck);
}

TEST(Stick, RegularizedLawCreepsWhereStickHolds) {
  Params<double> p = weightless();
  p.friction.smoothing_velocity = 1e-3;
  sim::Options opt;
  opt.duration = 1.0;
  const sim::Result r = sim::simulate(p, drive(0.01, -0.01, 0.0), testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_GT(max_displacement(r), 1e-6);  // tanh(w / w_s) needs w != 0 to carry any torque
}

TEST(Stick, SlowDriveSticksAndSlipsAgain) {
  sim::Options opt;
  opt.duration = 2.0;
  // amplitude above breakaway: slips, stops as the drive reverses, sticks, breaks away again
  const sim::Result r =
      sim::simulate(weightless(), drive(0.3, 0.0, 2 * M_PI), testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_GT(r.stats.stick_events, 0);
  EXPECT_GT(r.stats.breakaway_events, 0);
  const sim::RunChecks checks = sim::check_run(weightless(), drive(0.3, 0.0, 2 * M_PI), r);
  EXPECT_LT(checks.energy_balance_relative, 1e-7);
  // while a crank joint is stuck, that crank does not move at all
  for (size_t i = 1; i < r.rows.size(); ++i) {
    if (r.rows[i].mode[0] == kStuck && r.rows[i - 1].mode[0] == kStuck) {
      EXPECT_LT(std::abs(r.rows[i].theta[0] - r.rows[i - 1].theta[0]), kStuckDisplacement);
    }
  }
  std::printf("[ info ] sticks=%ld breakaways=%ld events=%ld balance=%.2e\n", r.stats.stick_events,
              r.stats.breakaway_events, r.stats.friction_events, checks.energy_balance_relative);
}

// The modes decided at every switch hold along the motion: at each output row with a stuck
// joint (not the whole mechanism at rest), the forward dynamics in the row's modes holds every
// stuck joint (margin >= 0) and every slipping joint moves its slip's way. The decisions try
// several modes at one point (the candidates, the sign rule, the consistency checks), each
// evaluated once there: an evaluation read back for the wrong modes or point would decide
// modes that do not hold.
TEST(Stick, DecidedModesHoldAtEveryRow) {
  const sim::LoadFunction loads = drive(0.3, 0.0, 2 * M_PI);
  sim::Options opt;
  opt.duration = 2.0;
  const sim::Result r = sim::simulate(weightless(), loads, testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  ASSERT_GT(r.stats.stick_events, 0);
  int checked = 0;
  for (const sim::Row& row : r.rows) {
    if (row.at_rest(2) || !any_stuck(row.mode)) continue;
    Evaluation<double> ev;
    ASSERT_TRUE(forward_dynamics(weightless(), loads(row.t), row.theta[0], row.theta[1],
                                 row.omega[0], row.omega[1], &row.mode, EvalOptions{}, &ev)
                    .ok());
    for (int k = 0; k < kJoints; ++k) {
      if (row.mode[k] == kStuck) {
        EXPECT_GE(ev.hold_margin[k], -1e-9) << "joint " << k << " at t=" << row.t;
      } else if (row.mode[k] != JointMode::kRest) {
        EXPECT_GE(coulomb_sign(row.mode[k]) * row.omega_rel(k), -1e-6)
            << "joint " << k << " at t=" << row.t;
      }
    }
    ++checked;
  }
  EXPECT_GT(checked, 10);
}

}  // namespace
}  // namespace fivebar
