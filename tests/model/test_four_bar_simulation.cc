// The simulator over the four-bar (simulate's events, joint modes, lock and checks, written once
// over the mechanism): against the independent references of datasets/reference/four_bar/, the
// energy balance without friction, and friction holding the mechanism at rest until the drive
// breaks it away.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "agreement.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/four_bar_rest.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"
#include "four_bar_scenes.h"
#include "paper.h"

namespace fivebar {
namespace {

using testing::sci;

sim::Options options(double duration, double tol) {
  sim::Options o;
  o.duration = duration;
  o.output_step = 1e-3;
  o.rtol = o.atol = tol;
  o.singular_margin = 0.0;
  return o;
}

sim::Initial crank_at(double theta1, double omega1 = 0.0) {
  sim::Initial i;
  i.theta1 = theta1;
  i.omega1 = omega1;
  return i;
}

/// Sign changes of each joint's relative rate between rows (joints O, B, C, D0 from the link
/// rates omega1..3, as trajectory.csv gives them).
std::array<int, 4> sign_changes(const std::vector<std::array<double, 3>>& omega) {
  std::array<int, 4> out{};
  const auto w = [](const std::array<double, 3>& o) {
    return std::array<double, 4>{o[0], o[1] - o[0], o[2] - o[1], o[2]};
  };
  for (size_t i = 1; i < omega.size(); ++i) {
    const auto a = w(omega[i - 1]), b = w(omega[i]);
    for (int k = 0; k < 4; ++k) out[k] += (a[k] > 0) != (b[k] > 0) && a[k] != 0 && b[k] != 0;
  }
  return out;
}

// Every row against the reference (RK4 at 5e-5 s with located switches, within ~2e-11 rad of the
// exact solution): the crank, the coupler and the rocker, their rates, the dissipated energy and
// the works; each joint's rate reverses between the same rows as in the reference.
TEST(FourBarSimulation, AgreesWithTheIndependentReferences) {
  for (const testing::ReferenceScene& sc : testing::reference_scenes()) {
    const auto ref = testing::read_csv(testing::reference_path("four_bar/" + sc.file + ".csv"));
    const sim::Result r = sim::simulate(sc.p, sc.loads, crank_at(sc.th0), options(2.0, 1e-12));
    ASSERT_TRUE(r.status.ok()) << sc.file << ": " << r.status.message;
    ASSERT_EQ(r.rows.size(), ref.at("t").size()) << sc.file;
    double angle = 0, rate = 0, energy = 0;
    std::vector<std::array<double, 3>> omega, omega_ref;
    for (size_t i = 0; i < r.rows.size(); ++i) {
      const sim::Row& row = r.rows[i];
      omega.push_back({row.omega[0], row.omega[1], row.omega[2]});
      omega_ref.push_back({ref.at("omega1")[i], ref.at("omega2")[i], ref.at("omega3")[i]});
      for (int k = 0; k < 3; ++k) {
        const std::string n = std::to_string(k + 1);
        angle = std::max(angle, std::abs(row.theta[k] - ref.at("theta" + n)[i]));
        rate = std::max(rate, std::abs(row.omega[k] - ref.at("omega" + n)[i]));
      }
      energy = std::max({energy, std::abs(row.E_diss - ref.at("E_diss")[i]),
                         std::abs(row.W_in - ref.at("W_in")[i]),
                         std::abs(row.W_ext - ref.at("W_ext")[i])});
    }
    EXPECT_LT(angle, 5e-9) << sc.file;
    EXPECT_LT(rate, 5e-8) << sc.file;
    EXPECT_LT(energy, 1e-8) << sc.file;
    const std::array<int, 4> reversals = sign_changes(omega);
    EXPECT_EQ(reversals, sign_changes(omega_ref)) << sc.file;
    EXPECT_GT(reversals[0] + reversals[1] + reversals[2] + reversals[3], 10) << sc.file;
    EXPECT_GE(r.stats.friction_events, reversals[0] + reversals[1] + reversals[2] + reversals[3]);
    const sim::RunChecks checks = sim::check_run(sc.p, sc.loads, r, 1e-12);
    EXPECT_TRUE(checks.verdict.ok()) << sc.file << ": " << checks.verdict.message;
    EXPECT_LT(checks.inverse_dynamics_max_abs_error, 1e-8) << sc.file;
    EXPECT_GE(checks.friction_power_min, 0.0) << sc.file;
    RecordProperty(sc.file + "_angle", sci(angle));
    RecordProperty(sc.file + "_rate", sci(rate));
    RecordProperty(sc.file + "_energy", sci(energy));
  }
}

// Without friction KE + PE changes by the work of the drive and the loads alone.
TEST(FourBarSimulation, FrictionlessRunBalancesEnergy) {
  for (testing::ReferenceScene sc : testing::reference_scenes()) {
    sc.p.friction.pin_radius.fill(0.0);
    const sim::Result r = sim::simulate(sc.p, sc.loads, crank_at(sc.th0, 1.0), options(1.0, 1e-10));
    ASSERT_TRUE(r.status.ok()) << sc.file << ": " << r.status.message;
    const sim::RunChecks checks = sim::check_run(sc.p, sc.loads, r, 1e-10);
    EXPECT_TRUE(checks.verdict.ok()) << sc.file << ": " << checks.verdict.message;
    EXPECT_LT(checks.energy_balance_relative, 1e-7) << sc.file;
    EXPECT_EQ(r.rows.back().E_diss, 0.0);
    RecordProperty(sc.file + "_energy_balance", sci(checks.energy_balance_relative));
  }
}

// The double rocker at rest under gravity, with static friction large enough to hold it: every
// joint is stuck (mode 2) and the crank stays put while the drive ramps up; where the ramp passes
// what friction can hold, the mechanism breaks away and moves in the drive's direction.
TEST(FourBarSimulation, FrictionHoldsTheMechanismUntilTheDriveBreaksItAway) {
  testing::ReferenceScene sc = testing::reference_scenes()[1];
  sc.p.friction.law = FrictionLaw::kCoulombViscous;
  sc.p.friction.pin_radius.fill(0.02);
  sc.p.friction.coulomb.fill(0.3);
  sc.p.friction.static_coulomb.fill(0.3);
  // the gravity torque at the start, held by friction, then a drive ramping past it
  FourBarKinematics k;
  ASSERT_TRUE(four_bar_kinematics(sc.p, sc.th0, &k).ok());
  FourBarEvaluation still;
  FourBarParams frictionless = sc.p;
  frictionless.friction.pin_radius.fill(0.0);
  ASSERT_TRUE(four_bar_inverse(frictionless, FourBarLoads{}, sc.th0, 0.0, 0.0, EvalOptions{}, &still)
                  .ok());
  const double hold = still.M1;  // the drive that holds the pose without friction
  const auto loads = [hold](double t) { return FourBarLoads{hold + 2.0 * t, 0.0, 0.0, 0.0}; };
  const sim::Result r = sim::simulate(sc.p, loads, crank_at(sc.th0), options(1.0, 1e-10));
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  size_t first_move = r.rows.size();
  for (size_t i = 0; i < r.rows.size(); ++i) {
    if (r.rows[i].omega[0] != 0.0) {
      first_move = i;
      break;
    }
    EXPECT_EQ(r.rows[i].theta[0], sc.th0) << "t=" << r.rows[i].t;
    for (int j = 0; j < kFourBarJoints; ++j) EXPECT_EQ(r.rows[i].mode[j], kStuck);
  }
  ASSERT_GT(first_move, 10u) << "friction did not hold the pose at the start";
  ASSERT_LT(first_move, r.rows.size() - 10) << "the drive never broke the mechanism away";
  EXPECT_GE(r.stats.breakaway_events, 1);
  EXPECT_GT(r.rows.back().theta[0], sc.th0);  // moves the way the drive pushes
  const sim::RunChecks checks = sim::check_run(sc.p, loads, r, 1e-10);
  EXPECT_TRUE(checks.verdict.ok()) << checks.verdict.message;
  RecordProperty("breakaway_t", sci(r.rows[first_move].t));
}

// The holding range of four_bar_holding is where the simulator's lock holds: from rest under a
// constant M1 0.1 % of the range inside either end, every joint stays stuck; 0.1 % outside, the
// mechanism breaks away the way M1 pushes. Both scenes at three poses each, gravity and a coupler
// load. The range holds at least what joint O holds alone.
TEST(FourBarSimulation, TheHoldingRangeIsWhereTheLockHolds) {
  int poses = 0;
  for (testing::ReferenceScene sc : testing::reference_scenes()) {
    sc.p.friction.law = FrictionLaw::kCoulombViscous;
    sc.p.friction.pin_radius.fill(0.02);
    sc.p.friction.coulomb.fill(0.3);
    sc.p.friction.static_coulomb.fill(0.3);
    for (double dth : {0.0, 0.15, -0.2}) {
      const double th = sc.th0 + dth;
      const FourBarLoads L{0.0, 0.05, 2.0, 0.3};
      FourBarHolding h;
      ASSERT_TRUE(four_bar_holding(sc.p, L, th, EvalOptions{}, &h).ok()) << sc.file << " " << th;
      ASSERT_LT(h.M1_min, h.M1);
      ASSERT_GT(h.M1_max, h.M1);
      EXPECT_GE(h.M1_max - h.M1, h.bound[0] * (1 - 1e-9));
      EXPECT_GE(h.M1 - h.M1_min, h.bound[0] * (1 - 1e-9));
      const double width = h.M1_max - h.M1_min;
      for (const auto& [drive, held] : {std::pair{h.M1_max - 1e-3 * width, true},
                                        std::pair{h.M1_min + 1e-3 * width, true},
                                        std::pair{h.M1_max + 1e-3 * width, false},
                                        std::pair{h.M1_min - 1e-3 * width, false}}) {
        FourBarLoads at = L;
        at.M1 = drive;
        const sim::Result r =
            sim::simulate(sc.p, [at](double) { return at; }, crank_at(th), options(0.05, 1e-10));
        ASSERT_TRUE(r.status.ok()) << r.status.message;
        const double moved = r.rows.back().theta[0] - th;
        if (held) {
          EXPECT_EQ(moved, 0.0) << sc.file << " th " << th << " M1 " << drive;
        } else {
          EXPECT_GT(moved * (drive - h.M1), 0.0) << sc.file << " th " << th << " M1 " << drive;
        }
      }
      ++poses;
    }
  }
  EXPECT_EQ(poses, 6);
}

// The crank motor's friction (actuator.h) in runs of both reference scenes: the energy balance
// closes with the motor's dissipation counted (more is dissipated than without it), and at rest
// the crank's holding capacity grows by c_a: the holding range is where the lock holds, as
// without the motor, and it holds a drive the bare joints let move.
TEST(FourBarSimulation, MotorFrictionBalancesEnergyAndHoldsTheCrank) {
  for (testing::ReferenceScene sc : testing::reference_scenes()) {
    FourBarParams motor = sc.p;
    motor.actuators.coulomb[0] = 0.04;
    motor.actuators.viscous[0] = 0.005;
    motor.actuators.offset[0] = 0.03;
    const sim::Result bare = sim::simulate(sc.p, sc.loads, crank_at(sc.th0), options(1.0, 1e-10));
    const sim::Result r = sim::simulate(motor, sc.loads, crank_at(sc.th0), options(1.0, 1e-10));
    ASSERT_TRUE(bare.status.ok() && r.status.ok()) << r.status.message;
    const sim::RunChecks checks = sim::check_run(motor, sc.loads, r, 1e-10);
    EXPECT_TRUE(checks.verdict.ok()) << checks.verdict.message;
    EXPECT_LT(checks.energy_balance_relative, 1e-7) << sc.file;
    // the motor's dissipated energy (trapezoidal), far above what the balance leaves open: the
    // balance counts it
    double motor_energy = 0.0;
    for (size_t i = 1; i < r.rows.size(); ++i) {
      const auto power = [](const sim::Row& row) {
        const double w = row.omega[0];
        return (0.04 * ((w > 0) - (w < 0)) + 0.005 * w) * w;
      };
      motor_energy +=
          0.5 * (r.rows[i].t - r.rows[i - 1].t) * (power(r.rows[i]) + power(r.rows[i - 1]));
    }
    EXPECT_GT(motor_energy, 0.01 * r.rows.back().E_diss) << sc.file;
    EXPECT_GT(motor_energy, 1e4 * checks.energy_balance_relative * checks.energy_scale) << sc.file;
    EXPECT_GT(sim::max_angle_difference(r.rows, bare.rows), 1e-3) << sc.file;
    // holding: the range with the motor, its ends 0.1 % inside held and outside moving
    const FourBarLoads L{0.0, 0.05, 2.0, 0.3};
    FourBarHolding h, h0;
    ASSERT_TRUE(four_bar_holding(motor, L, sc.th0, EvalOptions{}, &h).ok());
    ASSERT_TRUE(four_bar_holding(sc.p, L, sc.th0, EvalOptions{}, &h0).ok());
    EXPECT_NEAR(h.bound[0], h0.bound[0] + 0.04, 1e-12);
    EXPECT_GT(h.M1_max, h0.M1_max);
    EXPECT_LT(h.M1_min, h0.M1_min);
    const double width = h.M1_max - h.M1_min;
    for (const auto& [drive, held] :
         {std::pair{h.M1_max - 1e-3 * width, true}, std::pair{h.M1_min + 1e-3 * width, true},
          std::pair{h.M1_max + 1e-3 * width, false}, std::pair{h.M1_min - 1e-3 * width, false}}) {
      FourBarLoads at = L;
      at.M1 = drive;
      const auto loads = [at](double) { return at; };
      const sim::Result run = sim::simulate(motor, loads, crank_at(sc.th0), options(0.05, 1e-10));
      ASSERT_TRUE(run.status.ok()) << run.status.message;
      const double moved = run.rows.back().theta[0] - sc.th0;
      if (held) {
        EXPECT_EQ(moved, 0.0) << sc.file << " M1 " << drive;
      } else {
        EXPECT_GT(moved * (drive - h.M1), 0.0) << sc.file << " M1 " << drive;
      }
    }
    // a drive the bare joints let move, inside the motor's range
    FourBarLoads past = L;
    past.M1 = 0.5 * (h0.M1_max + h.M1_max);
    const sim::Result free = sim::simulate(
        sc.p, [past](double) { return past; }, crank_at(sc.th0), options(0.05, 1e-10));
    ASSERT_TRUE(free.status.ok()) << free.status.message;
    EXPECT_GT(free.rows.back().theta[0] - sc.th0, 0.0) << sc.file;
  }
}

// theta1 = pi puts B on the ground line: coupler and rocker turn alike there, so joint C neither
// moves nor accelerates at rest in any mode. Its slip direction comes from the third-order term
// of its rate (the velocity terms at v = qdd): the run from rest starts, and it agrees with the
// run started 1e-9 rad away, where C's acceleration decides.
TEST(FourBarSimulation, AStartAtRestWhereAJointsRateVanishesInEveryModeRuns) {
  const testing::ReferenceScene sc = testing::reference_scenes()[0];
  const sim::Result at = sim::simulate(sc.p, sc.loads, crank_at(M_PI), options(0.5, 1e-12));
  ASSERT_TRUE(at.status.ok()) << at.status.message;
  const sim::Result near =
      sim::simulate(sc.p, sc.loads, crank_at(M_PI + 1e-9), options(0.5, 1e-12));
  ASSERT_TRUE(near.status.ok()) << near.status.message;
  ASSERT_EQ(at.rows.size(), near.rows.size());
  double gap = 0;
  for (size_t i = 0; i < at.rows.size(); ++i) {
    for (int k = 0; k < 3; ++k) gap = std::max(gap, std::abs(at.rows[i].theta[k] - near.rows[i].theta[k]));
  }
  EXPECT_LT(gap, 1e-7);
  EXPECT_TRUE(sim::check_run(sc.p, sc.loads, at, 1e-12).verdict.ok());
  RecordProperty("gap_to_the_nearby_start", sci(gap));
}

// A row where inverse dynamics cannot be evaluated fails the run's checks with that row's time
// and the inverse's own reason (not a residual of inf).
TEST(FourBarSimulation, ARowWhoseInverseDynamicsFailsFailsTheChecksNamingWhy) {
  const testing::ReferenceScene sc = testing::reference_scenes()[1];
  sim::Result r = sim::simulate(sc.p, sc.loads, crank_at(sc.th0), options(0.2, 1e-10));
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  r.rows[100].theta[0] = M_PI;  // |BD0| = 0.52 > l2 + l3 = 0.34: the double rocker cannot close
  const sim::RunChecks checks = sim::check_run(sc.p, sc.loads, r, 1e-10);
  ASSERT_FALSE(checks.verdict.ok());
  EXPECT_THAT(checks.verdict.message,
              ::testing::HasSubstr("inverse dynamics of the run failed at t=0.1 s (theta1=3.14159): "
                                   "four-bar cannot assemble"));
  EXPECT_TRUE(std::isfinite(checks.inverse_dynamics_max_abs_error));
}

}  // namespace
}  // namespace fivebar
