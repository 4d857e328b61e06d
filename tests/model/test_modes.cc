// Slip decisions that are provably consistent and runs that prove themselves:
// friction never supplies power, inverse dynamics returns the input torques, with every
// integrator, on long runs, hard drives, breakaways from rest and seeded random mechanisms.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/lock.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

using sim::kAllMethods;

// the bounds on friction power and inverse residual on every row
constexpr double kPowerTol = 1e-9;    // W
constexpr double kInverseTol = 1e-8;  // N m

/// The run is ok, its own checks pass, friction power >= -kPowerTol on every slipping joint
/// and row, E_diss never decreases, and no decision found a missed switch.
void expect_consistent(const Params<double>& p, const sim::LoadFunction& loads,
                       const sim::Result& r, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const sim::RunChecks checks = sim::check_run(p, loads, r);
  EXPECT_TRUE(checks.verdict.ok()) << checks.verdict.message;
  EXPECT_LE(checks.inverse_dynamics_max_abs_error, kInverseTol);
  EXPECT_EQ(r.stats.mode_corrections, 0);
  for (size_t i = 0; i < r.rows.size(); ++i) {
    const sim::Row& row = r.rows[i];
    for (int k = 0; k < 5; ++k) {
      if (row.mode[k] == kStuck) continue;
      ASSERT_GE(row.Mf[k] * row.omega_rel(k), -kPowerTol) << "t=" << row.t << " joint " << k;
    }
    if (i > 0) ASSERT_GE(row.E_diss, r.rows[i - 1].E_diss - 1e-12) << "t=" << row.t;
  }
}

sim::LoadFunction constant_drive(double M1, double M2) {
  return [=](double t) {
    Loads<double> L = testing::paper_loads(t);
    L.M1 = M1;
    L.M2 = M2;
    return L;
  };
}

// the +-40 N m drive's slip reversal at joint C is easy to step over; every integrator finds it
TEST(Modes, HardDriveEveryIntegrator) {
  const Params<double> p = paper_params();
  const sim::LoadFunction loads = constant_drive(40.0, -40.0);
  for (sim::Method m : kAllMethods) {
    sim::Options o;
    o.method = m;
    const sim::Result r = sim::simulate(p, loads, testing::paper_initial(), o);
    expect_consistent(p, loads, r, sim::method_name(m));
    EXPECT_GT(r.stats.friction_events, 20);
  }
}

// the 12 s paper run's reversal at t = 11.4465 s is easy to step over (Adams, ERK45); 60 s here
TEST(Modes, LongRunEveryIntegrator) {
  const Params<double> p = paper_params();
  for (sim::Method m : kAllMethods) {
    sim::Options o;
    o.method = m;
    o.duration = 60.0;
    o.full_rows = true;
    const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), o);
    expect_consistent(p, testing::paper_loads, r, sim::method_name(m));
  }
}

// arkode_dirk with switches not located can end 5e-3 rad off, its angles inconsistent with its
// rates, if ARKODE's difference-quotient Jacobian divides a Coulomb sign flip by ~1e-20. Every
// method agrees with the located reference to 1e-6 rad, except Fehlberg 7(8), whose
// error control steps over unlocated kinks less well: its own error estimate must say so.
TEST(Modes, SwitchesNotLocatedAgreeWithLocatedOnes) {
  const Params<double> p = paper_params();
  sim::Options ref_opt;
  ref_opt.method = sim::Method::kCvodeBdf;
  ref_opt.duration = 0.3;
  ref_opt.rtol = ref_opt.atol = 1e-12;
  const sim::Result ref = sim::simulate(p, testing::paper_loads, testing::paper_initial(), ref_opt);
  ASSERT_TRUE(ref.status.ok()) << ref.status.message;
  for (sim::Method m : kAllMethods) {
    SCOPED_TRACE(sim::method_name(m));
    sim::Options o = ref_opt;
    o.method = m;
    o.locate_switches = false;
    const sim::EstimatedRun e =
        sim::simulate_to_target(p, testing::paper_loads, testing::paper_initial(), o);
    if (!e.run.status.ok()) {
      ADD_FAILURE() << e.run.status.message;
      continue;
    }
    EXPECT_TRUE(sim::check_run(p, testing::paper_loads, e.run).verdict.ok());
    const double diff = sim::max_angle_difference(e.run.rows, ref.rows);
    EXPECT_LT(diff, m == sim::Method::kArkodeErk87 ? 1e-4 : 1e-6);
    EXPECT_LT(diff, std::max(1e-8, 3.0 * e.estimated_max_error_rad));
  }
}

/// The weightless paper mechanism held by the crank torques that balance the 50 N force, plus
/// (dM1, dM2): stick_below_breakaway.yaml.
sim::LoadFunction held_plus(double dM1, double dM2) {
  return [=](double) {
    return Loads<double>{-1.31570913923345 + dM1, -1.04791037143488 + dM2, 0.0, 50.0, M_PI / 2};
  };
}

Params<double> weightless() {
  Params<double> p = paper_params();
  p.gravity = 0.0;
  return p;
}

// breakaway from rest must not push the mechanism with friction (w and Mf of opposite signs at
// any of the five joints)
TEST(Modes, BreakawayFromRestIsConsistent) {
  const Params<double> p = weightless();
  for (auto [d1, d2] : {std::pair{0.04, 0.0}, {0.025, 0.0}, {0.1, 0.0}, {-0.04, 0.0},
                        {0.0, -0.06}, {0.3, 0.0}, {0.0, 0.5}}) {
    sim::Options o;
    o.duration = 0.1;
    const sim::LoadFunction loads = held_plus(d1, d2);
    const sim::Result r = sim::simulate(p, loads, testing::paper_initial(), o);
    expect_consistent(p, loads, r, "dM = " + std::to_string(d1) + ", " + std::to_string(d2));
  }
}

// friction at all five joints shares the holding torque: the mechanism stays locked exactly
// when lock_analysis finds a distribution within every joint's bound, and moves otherwise
TEST(Modes, LockedExactlyWhenFrictionCanHold) {
  const Params<double> p = weightless();
  for (double d : {0.02, 0.04, 0.08, 0.12, 0.2}) {
    const sim::LoadFunction loads = held_plus(d, 0.0);
    LockAnalysis lock;
    ASSERT_TRUE(lock_analysis(p, loads(0.0), M_PI / 2, M_PI / 2, EvalOptions{}, &lock).ok());
    sim::Options o;
    o.duration = 0.05;
    const sim::Result r = sim::simulate(p, loads, testing::paper_initial(), o);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    const double moved = std::abs(r.rows.back().theta[0] - M_PI / 2) +
                         std::abs(r.rows.back().theta[1] - M_PI / 2);
    SCOPED_TRACE("dM1 = " + std::to_string(d) + ", lock ratio " + std::to_string(lock.ratio));
    if (lock.ratio <= 1.0) {
      EXPECT_EQ(moved, 0.0);
      // the holding torques balance the loads: J_w^T lambda = Q within the bounds
      for (int k = 0; k < 5; ++k) {
        EXPECT_LE(std::abs(lock.hold[k]), holding_bound(p.friction, k) * lock.N[k] * (1 + 1e-12));
      }
    } else {
      EXPECT_GT(moved, 1e-9);
    }
  }
}

double max_angle_gap(const sim::Result& a, const sim::Result& b) {
  return sim::max_angle_difference(a.rows, b.rows);
}

// a lock reached mid-run must break away when friction can no longer hold it, with every
// integrator (a solver stepping over the lock margin's zero leaves it locked: nothing moves)
TEST(Modes, MidRunLockBreaksAwayWithEveryIntegrator) {
  Params<double> p = paper_params();
  p.friction.pin_radius.fill(0.05);
  p.friction.coulomb.fill(0.5);
  p.friction.static_coulomb.fill(0.5);
  sim::Options o;
  o.method = sim::Method::kArkodeErk45;
  const sim::Result ref = sim::simulate(p, testing::paper_loads, testing::paper_initial(), o);
  ASSERT_TRUE(ref.status.ok()) << ref.status.message;
  for (sim::Method m : kAllMethods) {
    o.method = m;
    const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), o);
    expect_consistent(p, testing::paper_loads, r, sim::method_name(m));
    EXPECT_GT(r.stats.breakaway_events, 0);
    EXPECT_LT(max_angle_gap(r, ref), 1e-6) << sim::method_name(m);
    for (const sim::Row& row : r.rows) {  // holding torques within their bounds while stuck
      for (int k = 0; k < 5; ++k) {
        if (row.mode[k] != kStuck) continue;
        ASSERT_LE(std::abs(row.Mf[k]), holding_bound(p.friction, k) * row.N[k] * (1 + 1e-6))
            << sim::method_name(m) << " t=" << row.t << " joint " << k;
      }
    }
  }
}

// with a joint stuck, another joint's rate can cross zero at a dead point while the mechanism
// moves; that is not a lock (taken for one, the rates would jump to zero)
TEST(Modes, DeadPointWithAStuckJointIsNotALock) {
  const Params<double> p = testing::with_law(weightless(), FrictionLaw::kStribeck,
                                             {{Coefficient::kStaticCoulomb, 0.3},
                                              {Coefficient::kStribeckVelocity, 0.05},
                                              {Coefficient::kStribeckExponent, 2.0}});
  const sim::LoadFunction loads = held_plus(-0.2, 0.0);
  sim::Options o;
  o.method = sim::Method::kArkodeErk45;
  const sim::Result ref = sim::simulate(p, loads, testing::paper_initial(), o);
  ASSERT_TRUE(ref.status.ok()) << ref.status.message;
  for (sim::Method m : {sim::Method::kCvodeAdams, sim::Method::kCvodeBdf,
                        sim::Method::kArkodeErk65, sim::Method::kArkodeDirk}) {
    o.method = m;
    const sim::Result r = sim::simulate(p, loads, testing::paper_initial(), o);
    expect_consistent(p, loads, r, sim::method_name(m));
    EXPECT_LT(max_angle_gap(r, ref), 1e-5) << sim::method_name(m);  // erk65: 2.3e-6
  }
}

/// A seeded random mechanism near the paper's: lengths, masses, COM, per-joint friction, loads.
struct RandomScene {
  Params<double> params;
  sim::LoadFunction loads;
  sim::Initial initial;
};

RandomScene random_scene(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RandomScene s;
  Params<double>& p = s.params;
  p = paper_params();
  for (int i = 0; i < 4; ++i) {
    p.links[i].mass *= 0.5 + u(rng);
    p.links[i].inertia *= 0.3 + u(rng);
    p.links[i].com_angle = 0.4 * (u(rng) - 0.5);
  }
  for (int k = 0; k < 5; ++k) {
    p.friction.coulomb[k] = 0.02 + 0.3 * u(rng);
    p.friction.static_coulomb[k] = p.friction.coulomb[k] * (1.0 + 0.5 * u(rng));
    p.friction.viscous[k] = 0.05 * u(rng);
  }
  p.friction.law = FrictionLaw::kCoulombViscous;
  const double a1 = 6 * (u(rng) - 0.5), a2 = 6 * (u(rng) - 0.5), f1 = 1 + 6 * u(rng),
               f2 = 1 + 6 * u(rng), F = 60 * u(rng);
  s.loads = [=](double t) {
    return Loads<double>{a1 * std::sin(f1 * t), a2 * std::cos(f2 * t), 0.0, F, M_PI / 2};
  };
  s.initial = {M_PI / 2 + 0.3 * (u(rng) - 0.5), M_PI / 2 + 0.3 * (u(rng) - 0.5), 0.0, 0.0};
  return s;
}

// one second of a random scene under the default options
sim::Result run_for_a_second(const RandomScene& s) {
  sim::Options o;
  o.duration = 1.0;
  return sim::simulate(s.params, s.loads, s.initial, o);
}

// property test: seeded random scenes with breakaways from rest, sticks and reversals;
// a run either passes its checks, or stops with a status that names why
TEST(Modes, RandomScenesNeverLetFrictionDriveTheMotion) {
  std::mt19937 rng(20261123);
  int ok = 0, events = 0;
  for (int i = 0; i < 20; ++i) {
    const RandomScene s = random_scene(rng);
    const sim::Result r = run_for_a_second(s);
    if (!r.status.ok()) {
      EXPECT_FALSE(r.status.message.empty());
      continue;
    }
    expect_consistent(s.params, s.loads, r, "random scene " + std::to_string(i));
    ++ok;
    events += r.stats.friction_events;
  }
  EXPECT_GE(ok, 15);
  EXPECT_GT(events, 20);  // the sweep exercises switches
}

// the larger sweep (200 scenes, ~10 s): run with
//   build/release/tests/model/test_model --gtest_also_run_disabled_tests
//   --gtest_filter='*Sweep200*'
TEST(Modes, DISABLED_RandomSweep200) {
  std::mt19937 rng(15);
  int ok = 0, failed = 0;
  long events = 0, decisions = 0, sticks = 0, breakaways = 0, naive_wrong = 0;
  for (int i = 0; i < 200; ++i) {
    const RandomScene s = random_scene(rng);
    const sim::Result r = run_for_a_second(s);
    if (!r.status.ok()) {
      ++failed;
      std::printf("[ info ] scene %d stopped: %s\n", i, r.status.message.c_str());
      continue;
    }
    expect_consistent(s.params, s.loads, r, "random scene " + std::to_string(i));
    ++ok;
    events += r.stats.friction_events;
    decisions += r.stats.mode_decisions;
    sticks += r.stats.stick_events;
    breakaways += r.stats.breakaway_events;
    naive_wrong += r.stats.sign_rule_inconsistent;
  }
  std::printf("[ info ] %d ok, %d stopped; %ld switches, %ld decisions, %ld sticks, %ld breakaways;"
              " %ld decisions where the sign-of-acceleration rule was inconsistent\n",
              ok, failed, events, decisions, sticks, breakaways, naive_wrong);
}

// the balance of a conservative run is relative to an energy scale it has
TEST(Modes, ConservativeRunBalanceIsRelativeToItsEnergy) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kNone;
  p.gravity = 0.0;
  const sim::LoadFunction none = [](double) { return Loads<double>{}; };
  sim::Options o;
  o.duration = 1.0;
  o.rtol = o.atol = 1e-11;  // at the default 1e-10 the integration error itself is 2.2e-9
  const sim::Result r = sim::simulate(p, none, {M_PI / 2, M_PI / 2, 3.0, -2.0}, o);
  ASSERT_TRUE(r.status.ok());
  EXPECT_LE(sim::check_run(p, none, r, o.rtol).energy_balance_relative, 1e-9);  // was 1.00
}

// the last row is at the duration, also off the output grid
TEST(Modes, LastRowIsAtTheDuration) {
  sim::Options o;
  o.duration = 0.01;
  o.output_step = 0.003;
  const sim::Result r =
      sim::simulate(paper_params(), testing::paper_loads, testing::paper_initial(), o);
  ASSERT_TRUE(r.status.ok());
  ASSERT_EQ(r.rows.size(), 5u);
  EXPECT_DOUBLE_EQ(r.rows.back().t, 0.01);
  EXPECT_NEAR(r.rows[3].t, 0.009, 1e-15);
}

// ARKODE's tolerance is honoured with located switches (no cap at the output step)
TEST(Modes, ExplicitStepsAreNotCappedByTheOutputStep) {
  sim::Options o;
  o.method = sim::Method::kArkodeErk45;
  o.rtol = o.atol = 1e-4;
  const sim::Result r =
      sim::simulate(paper_params(), testing::paper_loads, testing::paper_initial(), o);
  ASSERT_TRUE(r.status.ok());
  EXPECT_LT(r.stats.steps, 1000);  // was 2039 with the cap, for 2000 output rows
}

// the error estimate is honest: at least a third of the true error against the reference
TEST(Modes, ErrorEstimateIsHonestOnThePaperScene) {
  sim::Options o;
  o.auto_tolerance = true;
  const sim::EstimatedRun er = sim::simulate_to_target(paper_params(), testing::paper_loads,
                                                       testing::paper_initial(), o);
  ASSERT_TRUE(er.run.status.ok());
  const auto ref = testing::read_csv(testing::reference_path("paper_friction.csv"));
  double truth = 0.0;
  for (size_t i = 0; i < er.run.rows.size() && i < ref.at("theta1").size(); ++i) {
    truth = std::max({truth, std::abs(er.run.rows[i].theta[0] - ref.at("theta1")[i]),
                      std::abs(er.run.rows[i].theta[1] - ref.at("theta2")[i])});
  }
  EXPECT_TRUE(er.target_met);
  EXPECT_LE(truth, o.target_error);
  EXPECT_GE(er.estimated_max_error_rad, truth / 3);
}

}  // namespace
}  // namespace fivebar
