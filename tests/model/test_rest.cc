// Rest and holding: the rest rule of inverse dynamics, the holding torques and their
// range, and forward simulation of those torques (stick inside the range, breakaway outside).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fivebar/model/lock.h"
#include "fivebar/model/rest.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

// the required figures: equilibrium torques to 1e-9 N m; a held pose moves less than 1e-12 rad
constexpr double kTorqueTol = 1e-9;
constexpr double kStuckDisplacement = 1e-12;
// the equilibrium below is quoted rounded to 4 decimals
constexpr double kQuotedTol = 5e-5;
// a crank that breaks away moves visibly within 0.2 s (measured: ~1e-4 rad at 1% over the bound)
constexpr double kBreakaway = 1e-7;

const Loads<double> kPaperStaticLoads = testing::paper_static_loads();

Holding<double> paper_holding(const Params<double>& p = paper_params()) {
  Holding<double> h;
  const Status st = holding_torques(p, kPaperStaticLoads, M_PI / 2, M_PI / 2, EvalOptions{}, &h);
  EXPECT_TRUE(st.ok()) << st.message;
  return h;
}

double max_displacement(const sim::Result& r) { return testing::max_displacement(r, kDof); }

// simulate from rest at the paper pose with constant M1, M2 (and the paper's M3, F)
sim::Result hold(const Params<double>& p, double M1, double M2, double duration) {
  sim::Options opt;
  opt.duration = duration;
  opt.output_step = 1e-3;
  const sim::LoadFunction loads = [=](double) {
    return testing::paper_static_loads(M1, M2);
  };
  return sim::simulate(p, loads, testing::paper_initial(), opt);
}

TEST(Rest, PaperPoseHoldingTorquesAreTheFrictionlessEquilibrium) {
  const Holding<double> h = paper_holding();
  // the frictionless scene's inverse dynamics at rest: the same torques
  Params<double> none = paper_params();
  none.friction.law = FrictionLaw::kNone;
  Evaluation<double> ev;
  ASSERT_TRUE(inverse_dynamics(none, kPaperStaticLoads, M_PI / 2, M_PI / 2, 0.0, 0.0, 0.0, 0.0,
                               nullptr, EvalOptions{}, &ev)
                  .ok());
  EXPECT_NEAR(h.M1, ev.M1, kTorqueTol);
  EXPECT_NEAR(h.M2, ev.M2, kTorqueTol);
  EXPECT_NEAR(h.M1, -0.6917, kQuotedTol);
  EXPECT_NEAR(h.M2, -1.4379, kQuotedTol);
  // the static bound of each joint, and a range wider than what the crank joint holds alone
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(h.bound[k], 0.12 * 0.01 * h.N[k], 1e-15);
  EXPECT_GT(h.M1_max - h.M1, h.bound[0]);
  EXPECT_GT(h.M1 - h.M1_min, h.bound[0]);
  EXPECT_GT(h.M2_max - h.M2, h.bound[4]);
  EXPECT_GT(h.M2 - h.M2_min, h.bound[4]);
  // at the range's ends the simulator's lock is exactly saturated (lock.h)
  for (double M1 : {h.M1_min, h.M1_max}) {
    LockAnalysis lock;
    ASSERT_TRUE(lock_analysis(paper_params(), testing::paper_static_loads(M1, h.M2),
                              M_PI / 2, M_PI / 2, EvalOptions{}, &lock)
                    .ok());
    EXPECT_NEAR(lock.ratio, 1.0, 1e-12);
  }
}

TEST(Rest, NoisyStaticMotionGivesTheEquilibriumNotTheSignOfNoise) {
  const Params<double> p = paper_params();
  const Holding<double> h = paper_holding();
  // one second at 1 kHz, angles with 1e-12 rad noise, rates and accelerations by 5-point
  // central differences of them (what `fivebar inverse` estimates)
  std::mt19937_64 rng(14);
  std::normal_distribution<double> noise(0.0, 1e-12);
  const int n = 1001;
  const double dt = 1e-3;
  std::vector<double> th1(n), th2(n);
  for (int i = 0; i < n; ++i) {
    th1[i] = M_PI / 2 + noise(rng);
    th2[i] = M_PI / 2 + noise(rng);
  }
  std::vector<sim::Row> motion;
  for (int i = 2; i + 2 < n; ++i) {
    sim::Row r;
    r.t = i * dt;
    const std::vector<double>* th[2] = {&th1, &th2};
    for (int j = 0; j < 2; ++j) {
      const auto& f = *th[j];
      r.theta[j] = f[i];
      r.omega[j] = (f[i - 2] - 8 * f[i - 1] + 8 * f[i + 1] - f[i + 2]) / (12 * dt);
      r.alpha[j] = (-f[i - 2] + 16 * f[i - 1] - 30 * f[i] + 16 * f[i + 1] - f[i + 2]) /
                   (12 * dt * dt);
    }
    motion.push_back(r);
  }
  // thresholds from the angles' noise through the stencils' gains (as the inverse command)
  const double sigma = std::max(series_noise(th1), series_noise(th2));
  EXPECT_NEAR(sigma, 1e-12, 0.2e-12);
  const RestThresholds rest = rest_thresholds(5.6 * sigma / dt, 14.0 * sigma / (dt * dt));
  std::vector<sim::Row> rows;
  ASSERT_TRUE(sim::inverse_rows(p, testing::paper_loads, motion, &rows, rest).ok());
  for (const sim::Row& r : rows) {
    ASSERT_NEAR(r.M1, h.M1, kTorqueTol) << "t = " << r.t;
    ASSERT_NEAR(r.M2, h.M2, kTorqueTol) << "t = " << r.t;
    for (int k = 0; k < 5; ++k) ASSERT_EQ(r.mode[k], kStuck) << "joint " << k << ", t = " << r.t;
    ASSERT_NEAR(r.hold_range[0], h.M1_min, kTorqueTol);
    ASSERT_NEAR(r.hold_range[1], h.M1_max, kTorqueTol);
    ASSERT_NEAR(r.hold_range[2], h.M2_min, kTorqueTol);
    ASSERT_NEAR(r.hold_range[3], h.M2_max, kTorqueTol);
  }
  // the exact rule (only w = 0 at rest) lets the noise pick full kinetic friction instead
  std::vector<sim::Row> exact;
  ASSERT_TRUE(
      sim::inverse_rows(p, testing::paper_loads, motion, &exact, RestThresholds{0.0, -1.0}).ok());
  EXPECT_GT(std::abs(exact.front().M1 - h.M1), 0.05);
}

TEST(Rest, JointAtRestThatAcceleratesSlipsInTheDirectionOfItsAcceleration) {
  const Params<double> p = paper_params();
  sim::Row m;
  m.theta = {M_PI / 2, M_PI / 2, 0, 0};
  m.alpha = {40.0, -30.0, 0, 0};  // a turnaround: at rest, accelerating
  std::vector<sim::Row> rows;
  ASSERT_TRUE(sim::inverse_rows(p, testing::paper_loads, {m}, &rows).ok());
  EXPECT_EQ(rows[0].mode[0], JointMode::kSlipPositive);
  EXPECT_EQ(rows[0].mode[4], JointMode::kSlipNegative);
  EXPECT_GT(std::abs(rows[0].Mf[0]), 0.01);  // kinetic friction, not a holding torque
}

TEST(Rest, HoldingTorquesSimulatedForwardKeepThePose) {
  const Params<double> p = paper_params();
  const Holding<double> h = paper_holding();
  const double inside = 0.99;  // of the range, along each actuator; of the crank bounds, both
  for (const auto& M : {std::array<double, 2>{h.M1, h.M2},
                        std::array<double, 2>{h.M1 + inside * (h.M1_max - h.M1), h.M2},
                        std::array<double, 2>{h.M1 - inside * (h.M1 - h.M1_min), h.M2},
                        std::array<double, 2>{h.M1, h.M2 + inside * (h.M2_max - h.M2)},
                        std::array<double, 2>{h.M1, h.M2 - inside * (h.M2 - h.M2_min)},
                        std::array<double, 2>{h.M1 + inside * h.bound[0],
                                              h.M2 - inside * h.bound[4]},
                        std::array<double, 2>{h.M1 - inside * h.bound[0],
                                              h.M2 + inside * h.bound[4]}}) {
    const sim::Result r = hold(p, M[0], M[1], 1.0);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    EXPECT_LT(max_displacement(r), kStuckDisplacement) << "M = " << M[0] << ", " << M[1];
    EXPECT_EQ(r.rows.back().mode[0], kStuck);
    EXPECT_EQ(r.rows.back().mode[4], kStuck);
  }
}

TEST(Rest, TorquesJustOutsideTheRangeBreakAway) {
  const Params<double> p = paper_params();
  const Holding<double> h = paper_holding();
  const double outside = 1.01;
  const std::array<double, 2> cases[] = {{h.M1 + outside * (h.M1_max - h.M1), h.M2},
                                         {h.M1 - outside * (h.M1 - h.M1_min), h.M2},
                                         {h.M1, h.M2 + outside * (h.M2_max - h.M2)},
                                         {h.M1, h.M2 - outside * (h.M2 - h.M2_min)}};
  for (const auto& M : cases) {
    const sim::Result r = hold(p, M[0], M[1], 0.2);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    EXPECT_GT(max_displacement(r), kBreakaway) << "M = " << M[0] << ", " << M[1];
  }
}

// true when (x, y) lies inside (or on) the counter-clockwise convex polygon
bool inside_polygon(const std::vector<std::array<double, 2>>& poly, double x, double y) {
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    if ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]) < -1e-12) return false;
  }
  return true;
}

TEST(Rest, PolygonContainsTheRanges) {
  const Params<double> p = paper_params();
  const Holding<double> h = paper_holding();
  HoldingPolygon poly;
  ASSERT_TRUE(
      holding_polygon(p, kPaperStaticLoads, M_PI / 2, M_PI / 2, EvalOptions{}, h, &poly).ok());
  ASSERT_GE(poly.vertices.size(), 4u);
  // the crank joints' bounds alone: a rectangle inside the region
  for (double x : {h.M1 - h.bound[0], h.M1 + h.bound[0]}) {
    for (double y : {h.M2 - h.bound[4], h.M2 + h.bound[4]}) {
      EXPECT_TRUE(inside_polygon(poly.vertices, x, y));
    }
  }
  // the polygon's slices are the lock's ranges, to the straightness of its edges: O(mu r / l)
  const double edge_tol = 1e-3 * (h.M1_max - h.M1_min);
  EXPECT_NEAR(poly.M1_min, h.M1_min, edge_tol);
  EXPECT_NEAR(poly.M1_max, h.M1_max, edge_tol);
  EXPECT_NEAR(poly.M2_min, h.M2_min, edge_tol);
  EXPECT_NEAR(poly.M2_max, h.M2_max, edge_tol);
  // the corner with every joint slipping the same way is what the exact rule reports on the
  // quoted static motion (M1 = -0.8055, M2 = -1.5445: kinetic = static coefficient here)
  EXPECT_TRUE(inside_polygon(poly.vertices, -0.8055 + kQuotedTol, -1.5445 + kQuotedTol));
}

TEST(Rest, WithoutFrictionTheRangeIsThePoint) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kNone;
  const Holding<double> h = paper_holding(p);
  EXPECT_EQ(h.M1_min, h.M1);
  EXPECT_EQ(h.M2_max, h.M2);
  HoldingPolygon poly;
  ASSERT_TRUE(
      holding_polygon(p, kPaperStaticLoads, M_PI / 2, M_PI / 2, EvalOptions{}, h, &poly).ok());
  EXPECT_EQ(poly.vertices.size(), 1u);
  EXPECT_EQ(poly.M1_min, h.M1);
  // the frictionless mechanism at its equilibrium stays (no friction holds, none is needed)
  const sim::Result r = hold(p, h.M1, h.M2, 0.2);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_LT(max_displacement(r), 1e-9);  // an unstable equilibrium: rounding grows slowly
}

TEST(Rest, StribeckStaticCoefficientSetsTheRange) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kStribeck;
  p.friction.static_coulomb.fill(0.2);  // above coulomb = 0.12
  const Holding<double> h = paper_holding(p);
  EXPECT_NEAR(h.bound[0], 0.2 * 0.01 * h.N[0], 1e-15);
  // the range scales with mu_s, not mu_c
  const Holding<double> kinetic = paper_holding();
  EXPECT_NEAR((h.M1_max - h.M1) / (kinetic.M1_max - kinetic.M1), 0.2 / 0.12, 0.01);
  // between the kinetic and the static range: held by static friction
  const double dM = 0.15 / 0.2 * (h.M1_max - h.M1);
  EXPECT_GT(dM, kinetic.M1_max - kinetic.M1);
  const sim::Result r = hold(p, h.M1 + dM, h.M2, 0.5);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_LT(max_displacement(r), kStuckDisplacement);
  const sim::Result out = hold(p, h.M1 + 1.01 * (h.M1_max - h.M1), h.M2, 0.2);
  ASSERT_TRUE(out.status.ok()) << out.status.message;
  EXPECT_GT(max_displacement(out), kBreakaway);
}

// A passive joint stuck where a crank moves holds with any torque within its capacity, so the
// motion does not fix the drive torques: inverse dynamics of a simulated run gives ranges that
// hold the torques that made it (the row's own torques take that joint's friction torque as 0).
TEST(Rest, PassiveJointStuckWhereACrankMovesWidensTheTorqueRange) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kStribeck;
  p.friction.static_coulomb.fill(0.2);
  const Holding<double> h = paper_holding(p);
  sim::Options opt;
  opt.duration = 0.3;
  opt.output_step = 1e-3;
  // crank 2 driven out of its range from rest, crank 1 at its holding torque
  const double M2 = h.M2_max + 0.5;
  const sim::LoadFunction loads = [=](double) { return testing::paper_static_loads(h.M1, M2); };
  const sim::Result run = sim::simulate(p, loads, testing::paper_initial(), opt);
  ASSERT_TRUE(run.status.ok()) << run.status.message;
  std::vector<sim::Row> rows;
  ASSERT_TRUE(sim::inverse_rows(p, loads, run.rows, &rows).ok());
  int passive = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    const sim::Row& r = rows[i];
    const auto& g = r.hold_range;
    EXPECT_GE(h.M1, g[0] - kTorqueTol) << "t = " << r.t;
    EXPECT_LE(h.M1, g[1] + kTorqueTol) << "t = " << r.t;
    EXPECT_GE(M2, g[2] - kTorqueTol) << "t = " << r.t;
    EXPECT_LE(M2, g[3] + kTorqueTol) << "t = " << r.t;
    const bool moving = r.mode[0] != kStuck || r.mode[4] != kStuck;
    if (moving && (r.mode[1] == kStuck || r.mode[2] == kStuck || r.mode[3] == kStuck)) {
      ++passive;
      EXPECT_GT(g[1] - g[0], 1e-3) << "t = " << r.t;  // the joint's capacity moves the torques
    }
  }
  EXPECT_GT(passive, 0);
}

TEST(Rest, PosesThatCannotAssembleOrAreSingularFail) {
  Params<double> p = paper_params();
  Holding<double> h;
  EvalOptions opt;
  opt.singular_margin = 1e-3;
  // the paper mechanism assembles at every pose (|BD| <= l0 + l1 + l2 = 0.42 m < l3 + l4);
  // shorter couplers (l3 = l4 = 0.2 m) do not reach with the cranks apart (theta1 = pi,
  // theta2 = 0: |BD| = 0.42 m) and align at |BD| = 0.4 m
  p.links[2].length = p.links[3].length = 0.2;
  p.point_p = 0.15;
  EXPECT_EQ(holding_torques(p, kPaperStaticLoads, M_PI, 0.0, opt, &h).code,
            StatusCode::kCannotAssemble);
  // B = (-l1, 0), D = (l0 + l2 cos th2, l2 sin th2): |BD| = 0.4 (1 - 1e-9), couplers aligned
  const double l0 = 0.29, l1 = 0.08, l2 = 0.05, reach = 0.4 * (1 - 1e-9);
  const double c = (reach * reach - (l0 + l1) * (l0 + l1) - l2 * l2) / (2 * l2 * (l0 + l1));
  const Status st = holding_torques(p, kPaperStaticLoads, M_PI, std::acos(c), opt, &h);
  EXPECT_EQ(st.code, StatusCode::kNearSingular) << st.message;
}

TEST(Rest, SeriesNoiseIsFlooredAtRounding) {
  const std::vector<double> flat(100, M_PI / 2);
  EXPECT_NEAR(series_noise(flat), 2.220446049250313e-16 * M_PI / 2, 1e-30);
  // a smooth ramp has no fourth difference beyond rounding
  std::vector<double> ramp(100);
  for (int i = 0; i < 100; ++i) ramp[i] = 0.5 + 1e-3 * i;
  EXPECT_LT(series_noise(ramp), 1e-15);
}

}  // namespace
}  // namespace fivebar
