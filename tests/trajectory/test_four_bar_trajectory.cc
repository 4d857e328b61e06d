// Trajectories of the four-bar: one rest-to-rest task of the shipped crank-rocker solved end to
// end (run_four_bar_task), and the physics of its trajectory rows: lower energy than the
// minimum-jerk start, the torque limit held, the energy balance d(KE + PE) = W_in + W_ext -
// E_diss, friction never supplying power; the winding heat objective on its one motor; the
// Jet gradients against differences; task resolution by a coordinate of P.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fivebar/trajectory/four_bar_problem.h"
#include "fivebar/trajectory/four_bar_tasks.h"
#include "../model/four_bar_scenes.h"

namespace fivebar::trajectory {
namespace {

// datasets/reference/four_bar/crank_rocker.yaml (the model tests' copy of its values)
FourBarParams crank_rocker() { return testing::reference_scenes()[0].p; }

sim::FourBarLoadFunction loads() {
  return [](double) { return FourBarLoads{0.0, 0.2, 5.0, M_PI / 2}; };
}

TaskSpec task(double limit) {
  TaskSpec t;
  t.name = "half_turn";
  t.duration = 0.5;
  t.start = {false, M_PI / 2, NAN};
  t.goal = {false, 3 * M_PI / 2, NAN};
  t.torque_limit = limit;
  return t;
}

BatchOptions quick_options() {
  BatchOptions o;
  o.refine.control_points = {25};
  o.refine.continuation = {2e-3};
  return o;
}

TEST(FourBarTrajectory, SolvesATaskWithItsPhysicsOnTheRows) {
  const FourBarParams p = crank_rocker();
  const BatchOptions options = quick_options();
  const TaskResult r = run_four_bar_task(p, loads(), task(0.8), M_PI / 2, options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_LT(r.dissipated_energy, r.baseline_dissipated_energy);
  EXPECT_LE(r.peak_torque, 0.8 * (1 + options.limit_rtol));
  EXPECT_GT(r.baseline_peak_torque, 0.8);  // the limit binds: the start exceeds it
  EXPECT_LT(r.miss_distance, 1e-6);
  EXPECT_LT(r.miss_distance_exact, 1e-4);
  EXPECT_TRUE(std::isnan(r.start[1]));

  // the rows of trajectory.csv: the torque limit, the energy balance, friction power
  std::vector<sim::Row> rows;
  ASSERT_TRUE(four_bar_problem_of(p, loads(), r, options).rows(r.x.data(), 1e-3, &rows).ok());
  ASSERT_GT(rows.size(), 400u);
  const sim::Row& first = rows.front();
  double scale = 0, worst = 0;
  for (const sim::Row& row : rows) {
    EXPECT_LE(std::abs(row.M1), 0.8 * (1 + 1e-3)) << row.t;
    EXPECT_EQ(row.M2, 0.0);
    for (int k = 0; k < kFourBarJoints; ++k) {
      EXPECT_GE(row.Mf[k] * sim::four_bar_omega_rel(row, k), -1e-12) << row.t << " joint " << k;
    }
    const double d_energy = row.kinetic + row.potential - first.kinetic - first.potential;
    worst = std::max(worst, std::abs(d_energy - row.W_in - row.W_ext + row.E_diss));
    scale = std::max({scale, std::abs(row.W_in), row.E_diss, std::abs(d_energy)});
  }
  EXPECT_LT(worst, 1e-4 * scale);  // the trapezoidal rule on a 1 ms grid
  RecordProperty("energy_balance_relative", std::to_string(worst / scale));
  RecordProperty("dissipated_energy", std::to_string(r.dissipated_energy));
  RecordProperty("baseline_dissipated_energy", std::to_string(r.baseline_dissipated_energy));
  EXPECT_NEAR(rows.back().E_diss, r.dissipated_energy, 1e-3 * r.dissipated_energy);
  EXPECT_NEAR(rows.back().theta[0], 3 * M_PI / 2, 1e-12);
}

TEST(FourBarTrajectory, WindingHeatObjectiveUsesTheOneMotor) {
  const FourBarParams p = crank_rocker();
  BatchOptions options = quick_options();
  options.refine.enabled = false;
  options.problem.objective = Objective::kTotalDissipation;
  options.problem.winding_heat = {0.5, 0.0};
  const TaskResult r = run_four_bar_task(p, loads(), task(INFINITY), M_PI / 2, options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_GT(r.winding_heat, 0.0);
  EXPECT_NEAR(r.total_dissipation, r.dissipated_energy + r.winding_heat, 1e-12);
  EXPECT_LT(r.total_dissipation, r.baseline_total_dissipation);
  // the winding heat from the rows: int c M1^2 dt
  std::vector<sim::Row> rows;
  ASSERT_TRUE(four_bar_problem_of(p, loads(), r, options).rows(r.x.data(), 1e-4, &rows).ok());
  double heat = 0;
  for (size_t i = 1; i < rows.size(); ++i) {
    heat += 0.5 * (rows[i].t - rows[i - 1].t) * 0.5 *
            (rows[i].M1 * rows[i].M1 + rows[i - 1].M1 * rows[i - 1].M1);
  }
  EXPECT_NEAR(heat, r.winding_heat, 1e-3 * r.winding_heat);
}

TEST(FourBarTrajectory, GradientsMatchDifferences) {
  const FourBarParams p = crank_rocker();
  ProblemOptions o;
  o.torque_limit = 1.0;
  o.objective = Objective::kTotalDissipation;
  o.winding_heat = {0.3, 0.0};
  const FourBarTrajectoryProblem problem(
      p, loads(), RestToRestT<1>(10, 0.5, {0.4}, {2.0}, EndAcceleration::kFree), o);
  EXPECT_EQ(problem.num_constraints(), 2 * problem.num_nodes());
  std::vector<double> x = problem.motion().minimum_jerk();
  for (size_t i = 0; i < x.size(); ++i) x[i] += 0.05 * std::sin(1.0 + i);
  Evaluated e;
  ASSERT_TRUE(problem.evaluate(x.data(), true, &e).ok());
  const int nv = problem.num_variables(), nc = problem.num_constraints();
  for (int v = 0; v < nv; ++v) {
    const double h = 1e-6;
    std::vector<double> xp = x, xm = x;
    xp[v] += h;
    xm[v] -= h;
    Evaluated ep, em;
    ASSERT_TRUE(problem.evaluate(xp.data(), false, &ep).ok());
    ASSERT_TRUE(problem.evaluate(xm.data(), false, &em).ok());
    const double fd = (ep.objective - em.objective) / (2 * h);
    EXPECT_NEAR(e.objective_grad[v], fd, 1e-5 * (1 + std::abs(fd))) << v;
    for (int c = 0; c < nc; ++c) {
      const double cd = (ep.constraints[c] - em.constraints[c]) / (2 * h);
      EXPECT_NEAR(e.constraints_grad[static_cast<size_t>(c) * nv + v], cd, 1e-5 * (1 + std::abs(cd)))
          << "row " << c << " variable " << v;
    }
  }
}

TEST(FourBarTrajectory, ResolvesACoordinateOfP) {
  const FourBarParams p = crank_rocker();
  std::array<double, 2> at{};
  ASSERT_TRUE(four_bar_point_p(p, 2.5, &at));
  TaskSpec t = task(INFINITY);
  t.goal = {true, NAN, at[1]};
  const ResolvedFourBarTask r = resolve_four_bar_task(p, t, M_PI / 2, 1e-3);
  ASSERT_TRUE(r.ok()) << r.message;
  std::array<double, 2> got{};
  ASSERT_TRUE(four_bar_point_p(p, r.goal, &got));
  EXPECT_NEAR(got[1], at[1], 1e-12);
  EXPECT_LE(std::abs(r.goal - r.start), M_PI);  // the root nearest the start
  t.goal.b = 5.0;  // far above the coupler's reach
  const ResolvedFourBarTask out = resolve_four_bar_task(p, t, M_PI / 2, 1e-3);
  EXPECT_EQ(out.status, "goal_out_of_workspace");
}

}  // namespace
}  // namespace fivebar::trajectory
