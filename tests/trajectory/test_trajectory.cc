// Tests of fivebar::trajectory: splines, quadrature, exact gradients, the optimizer, tasks files
// and batch determinism.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/bspline.h"
#include "fivebar/trajectory/nlopt_status.h"
#include "fivebar/trajectory/optimizer.h"
#include "fivebar/trajectory/path_search.h"
#include "fivebar/trajectory/problem.h"
#include "fivebar/trajectory/quadrature.h"
#include "fivebar/trajectory/sweep.h"
#include "fivebar/trajectory/tasks.h"
#include "paper_fixture.h"

namespace fivebar::trajectory {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

using testing::paper_initial;
using testing::paper_loads;
using testing::optimized_rows;
using testing::paper_tasks;
using testing::task_problem;
const std::array<double, 2> kStart = {M_PI / 2, M_PI / 2};

TEST(BSpline, RestToRestEndsAndPartitionOfUnity) {
  // ends fixed at start / goal with zero rate and acceleration, for any inner control points
  const RestToRest m(11, 0.7, {0.3, -1.0}, {1.2, 0.4});
  std::vector<double> x(m.num_variables());
  for (size_t i = 0; i < x.size(); ++i) x[i] = std::sin(3.0 * i + 1.0);
  constexpr double kTol = 1e-12;  // rounding of the basis recurrences
  const auto s0 = m.state(x.data(), 0.0), s1 = m.state(x.data(), 0.7);
  for (int j = 0; j < 2; ++j) {
    EXPECT_NEAR(s0[0][j], m.start()[j], kTol);
    EXPECT_NEAR(s1[0][j], m.goal()[j], kTol);
    for (int k = 1; k < 3; ++k) {
      EXPECT_NEAR(s0[k][j], 0.0, 1e-9);
      EXPECT_NEAR(s1[k][j], 0.0, 1e-9);
    }
  }
  for (double t : {0.0, 0.11, 0.35, 0.5, 0.7}) {
    const BasisAt b = m.basis().at(t);
    double sum = 0, dsum = 0;
    for (int i = 0; i <= kDegree; ++i) {
      sum += b.d[0][i];
      dsum += b.d[1][i];
    }
    EXPECT_NEAR(sum, 1.0, kTol);
    EXPECT_NEAR(dsum, 0.0, 1e-9);
  }
}

TEST(BSpline, MinimumJerkIsReproducedExactly) {
  const RestToRest m(10, 0.5, {0.2, 1.0}, {1.1, 0.3});
  const std::vector<double> x = m.minimum_jerk();
  for (double t : {0.05, 0.2, 0.33, 0.48}) {
    const auto s = m.state(x.data(), t);
    const auto b = minimum_jerk_blend(t / 0.5);
    for (int j = 0; j < 2; ++j) {
      const double d = m.goal()[j] - m.start()[j];
      EXPECT_NEAR(s[0][j], m.start()[j] + d * b[0], 1e-12);
      EXPECT_NEAR(s[1][j], d * b[1] / 0.5, 1e-10);
      EXPECT_NEAR(s[2][j], d * b[2] / 0.25, 1e-8);
    }
  }
}

TEST(Quadrature, GaussLegendreIsExactToDegree2nMinus1) {
  const Rule r = gauss_legendre(6, 0.5, 2.0);
  double s = 0;
  for (size_t i = 0; i < r.nodes.size(); ++i) s += r.weights[i] * std::pow(r.nodes[i], 11);
  EXPECT_NEAR(s, (std::pow(2.0, 12) - std::pow(0.5, 12)) / 12.0, 1e-11);
}

// the default rule (12 points per span) against a 6x denser one, on the baseline and optimum
TEST(Quadrature, DissipatedEnergyAccurateTo1e6Relative) {
  constexpr double kRelTol = 1e-6;  // the accuracy required of E
  const std::vector<TaskSpec> tasks = paper_tasks();
  for (const TaskSpec& task : tasks) {
    const ResolvedTask rt = resolve_task(paper_params(), task, paper_initial(), 0.1);
    ASSERT_TRUE(rt.ok()) << task.name << ": " << rt.message;
    ProblemOptions o;
    const TrajectoryProblem p(paper_params(), paper_loads(),
                              RestToRest(o.control_points, task.duration, rt.start, rt.goal), o);
    const std::vector<double> x = p.motion().minimum_jerk();
    Energies e, ref;
    ASSERT_TRUE(p.energies(x.data(), o.quadrature_points, &e).ok());
    ASSERT_TRUE(p.energies(x.data(), 6 * o.quadrature_points, &ref).ok());
    EXPECT_LT(std::abs(e.dissipated - ref.dissipated), kRelTol * ref.dissipated) << task.name;
  }
}

// exact gradients (Jets through the model) against central differences
TEST(Gradient, JetMatchesCentralDifferences) {
  ProblemOptions o;
  o.torque_limit = 20.0;
  for (Objective objective : {Objective::kDissipatedEnergy, Objective::kInputEnergy}) {
    o.objective = objective;
    const TrajectoryProblem p(paper_params(), paper_loads(),
                              RestToRest(10, 0.5, kStart, {2.2, 1.0}), o);
    std::vector<double> x = p.motion().minimum_jerk();
    for (size_t i = 0; i < x.size(); ++i) x[i] += 0.05 * std::sin(7.0 * i);  // off the baseline
    Evaluated e;
    ASSERT_TRUE(p.evaluate(x.data(), true, &e).ok());
    const int nv = p.num_variables(), nc = p.num_constraints();
    // step 1e-5 rad: truncation error ~ h^2 f''' ~ 1e-10, rounding ~ 1e-16 / h ~ 1e-11
    constexpr double kStep = 1e-5, kRelTol = 1e-6;
    double scale_f = 0;
    for (double g : e.objective_grad) scale_f = std::max(scale_f, std::abs(g));
    for (int v = 0; v < nv; ++v) {
      std::vector<double> xp = x, xm = x;
      xp[v] += kStep;
      xm[v] -= kStep;
      Evaluated ep, em;
      ASSERT_TRUE(p.evaluate(xp.data(), false, &ep).ok());
      ASSERT_TRUE(p.evaluate(xm.data(), false, &em).ok());
      const double fd = (ep.objective - em.objective) / (2 * kStep);
      EXPECT_NEAR(e.objective_grad[v], fd, kRelTol * scale_f) << "variable " << v;
      for (int c = 0; c < nc; c += 7) {
        const double cfd = (ep.constraints[c] - em.constraints[c]) / (2 * kStep);
        const double g = e.constraints_grad[static_cast<size_t>(c) * nv + v];
        EXPECT_NEAR(g, cfd, kRelTol * std::max(1.0, std::abs(cfd))) << "constraint " << c;
      }
    }
  }
}

TEST(Optimizer, BeatsBaselineAndKeepsConstraints) {
  const std::vector<TaskSpec> tasks = paper_tasks();
  BatchOptions options;
  options.validate = true;
  // the motors of datasets/scenes/paper_motors.yaml: a smooth optimum within the limits
  const double c = 0.3 / ((0.03 * 66) * (0.03 * 66));
  options.problem.objective = Objective::kTotalDissipation;
  options.problem.winding_heat = {c, c};
  const TaskResult r = run_task(paper_params(), paper_loads(), tasks[1], paper_initial(), options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_LE(r.total_dissipation, r.baseline_total_dissipation);
  EXPECT_LE(r.max_constraint_violation, options.limit_rtol);
  EXPECT_LE(r.peak_torque, tasks[1].torque_limit * (1 + options.limit_rtol));
  EXPECT_LT(r.miss_distance, 1e-6);  // open-loop simulation of the optimal torques
  // the paper's objective rides the limits: ok only within them to limit_rtol
  options.problem.objective = Objective::kDissipatedEnergy;
  const TaskResult d = run_task(paper_params(), paper_loads(), tasks[1], paper_initial(), options);
  ASSERT_TRUE(d.status == "ok" || d.status == "violates_constraints") << d.status << d.message;
  if (d.status == "ok") {
    EXPECT_LE(d.peak_torque, tasks[1].torque_limit * (1 + options.limit_rtol));
  }
  EXPECT_LE(d.dissipated_energy, d.baseline_dissipated_energy);
}

TEST(Optimizer, TightTorqueLimitIsRespected) {
  // the minimum-jerk motion needs more than the limit: the optimum must stay within it on the
  // dense check grid (between the quadrature nodes too)
  ProblemOptions o;
  const TrajectoryProblem p(paper_params(), paper_loads(),
                            RestToRest(10, 0.3, kStart, {2.4, 2.0}), o);
  const std::vector<double> x0 = p.motion().minimum_jerk();
  const double peak = p.check(x0.data(), 400).peak_torque;
  TaskSpec task;
  task.name = "tight";
  task.duration = 0.3;
  task.start = {false, kStart[0], kStart[1]};
  task.goal = {false, 2.4, 2.0};
  task.torque_limit = 0.9 * peak;
  BatchOptions options;
  options.validate = false;
  const TaskResult r = run_task(paper_params(), paper_loads(), task, paper_initial(), options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_LE(r.max_constraint_violation, options.feasibility_tol);
  EXPECT_LE(r.peak_torque, task.torque_limit * (1 + options.feasibility_tol));
}

TEST(Optimizer, ScreenedConstraintsGiveTheUnscreenedOptimum) {
  // screening hands NLopt only the rows near activity; rows the result violates are added and
  // the solve resumed: the answer keeps every row and is the same optimum (seeded, no timing).
  // swing_right with 25 control points rides its torque limit, which the minimum-jerk start
  // stays far below (most active rows are left out at first)
  const TaskSpec task = paper_tasks()[1];
  const TrajectoryProblem p = task_problem(task, 25, 6);
  const std::vector<double> x0 = p.motion().minimum_jerk();
  Evaluated e0;
  ASSERT_TRUE(p.evaluate(x0.data(), false, &e0).ok());
  EXPECT_LT(*std::max_element(e0.constraints.begin(), e0.constraints.end()), -0.5);
  OptimizerOptions all, screened;
  all.screen = 0.0;
  screened.screen = 0.5;
  const OptimizeResult a = optimize(p, x0, all), b = optimize(p, x0, screened);
  ASSERT_TRUE(a.solver.usable()) << a.solver.message;
  ASSERT_TRUE(b.solver.usable()) << b.solver.message;
  EXPECT_LE(b.max_node_constraint, 10 * screened.constraint_tol);
  EXPECT_GT(b.max_node_constraint, -1e-3);  // rows left out at the start are active now
  EXPECT_NEAR(b.objective, a.objective, 2e-3 * a.objective);
}

TEST(BSpline, RefitOnNestedKnotsIsExact) {
  // the default refinement levels double the knot spans (10 -> 25 -> 45 -> 85 control points):
  // the least-squares refit of a coarse spline into the finer space is knot insertion, exact
  const RestToRest coarse(10, 0.5, kStart, {0.7, 0.6});
  std::vector<double> x = coarse.minimum_jerk();
  for (size_t i = 0; i < x.size(); ++i) x[i] += 0.1 * std::sin(1.0 + 2.0 * i);
  std::vector<int> levels = {10};
  levels.insert(levels.end(), kRefineLevels.begin(), kRefineLevels.end());
  for (size_t k = 1; k < levels.size(); ++k) {
    EXPECT_EQ((levels[k] - kDegree) % (levels[k - 1] - kDegree), 0) << levels[k];
    const RestToRest fine(levels[k], 0.5, kStart, {0.7, 0.6});
    const std::vector<double> y = fine.fit([&](double t) { return coarse.state(x.data(), t)[0]; });
    double worst = 0.0;
    for (int i = 0; i <= 1000; ++i) {
      const double t = 0.5 * i / 1000;
      const auto a = coarse.state(x.data(), t), b = fine.state(y.data(), t);
      for (int d = 0; d < 3; ++d) {
        for (int j = 0; j < 2; ++j) worst = std::max(worst, std::abs(a[d][j] - b[d][j]));
      }
    }
    EXPECT_LT(worst, 1e-7) << levels[k];  // accelerations of hundreds of rad/s^2
  }
}

TEST(Batch, IdenticalForOneAndTwoThreads) {
  const std::vector<TaskSpec> tasks = paper_tasks();
  BatchOptions options;
  options.validate = false;
  auto work = [&](int i) {
    TaskResult r = run_task(paper_params(), paper_loads(), tasks[i], paper_initial(), options);
    r.wall_time_s = 0;  // the only field allowed to differ
    return r;
  };
  const int n = static_cast<int>(tasks.size());
  const std::vector<TaskResult> a = run_parallel(n, 1, work), b = run_parallel(n, 2, work);
  ASSERT_EQ(a.size(), b.size());
  for (int i = 0; i < n; ++i) EXPECT_EQ(encode(a[i]), encode(b[i])) << tasks[i].name;
  const TaskResult back = decode(encode(a[0]));
  EXPECT_EQ(encode(back), encode(a[0]));
}

// a design with shorter couplers, whose minimum-jerk motion of the detour task leaves
// the workspace (|BD| > l3 + l4 near theta1 = 2.3)
Params<double> short_coupler_params() {
  Params<double> p = paper_params();
  for (int i : {2, 3}) {
    p.links[i].length = 0.17;
    p.links[i].com_offset = 0.1;
  }
  p.point_p = 0.1;
  return p;
}

TaskSpec detour_task() {
  TaskSpec t;
  t.name = "detour";
  t.duration = 1.0;
  t.start = {false, M_PI / 2, M_PI / 2};
  t.goal = {false, 4.95, 1.6};
  t.torque_limit = 30.0;
  return t;
}

TEST(PathSearch, FindsADetourWhereTheStraightPathCannotClose) {
  const Params<double> p = short_coupler_params();
  const std::array<double, 2> goal = {4.95, 1.6};
  constexpr double kMargin = 0.1;
  ASSERT_FALSE(segment_clear(p, kStart, goal, 0.0, 0.01));  // the straight path does not close
  PathSearchOptions o;
  o.margin = kMargin;
  const JointPath path = find_joint_path(p, kStart, goal, o);
  ASSERT_TRUE(path.ok()) << path.message;
  ASSERT_GE(path.waypoints.size(), 3u);
  EXPECT_EQ(path.waypoints.front(), kStart);
  EXPECT_EQ(path.waypoints.back(), goal);
  for (size_t i = 1; i < path.waypoints.size(); ++i) {
    EXPECT_TRUE(segment_clear(p, path.waypoints[i - 1], path.waypoints[i], kMargin, 1e-3)) << i;
  }
  // the rest-to-rest spline along it keeps the margin with 14 control points
  const RestToRest motion(14, 1.0, kStart, goal);
  EXPECT_GE(min_coupler_sine(p, motion, follow_path(motion, path), 2000), kMargin);
}

TEST(PathSearch, SaysWhyWhenTheGoalIsAcrossTheSingularCurve) {
  // couplers of 0.13 m: crank 1 cannot turn fully (|BD| would exceed l3 + l4 = 0.26 m), so the
  // same pose one turn of theta1 further on is out of reach of any continuous motion
  Params<double> p = paper_params();
  for (int i : {2, 3}) {
    p.links[i].length = 0.13;
    p.links[i].com_offset = 0.06;
  }
  p.point_p = 0.06;
  const std::array<double, 2> start = {0.3, 2.6}, goal = {0.3 + 2 * M_PI, 2.6};
  ASSERT_GE(coupler_sine(p, start[0], start[1]), 0.1);
  PathSearchOptions o;
  const JointPath path = find_joint_path(p, start, goal, o);
  EXPECT_EQ(path.status, "unreachable");
  EXPECT_THAT(path.message, HasSubstr("couplers stretched"));
  EXPECT_THAT(path.message, HasSubstr("elbow_up"));
}

TEST(PathSearch, GoalsManyTurnsAwayKeepTheGridBounded) {
  // 200 turns of theta1: the grid step grows so that the box holds at most 1e6 poses (instead of
  // 3.2e7 at the default step); the answer stays a path or a reason
  const std::array<double, 2> goal = {kStart[0] + 400 * M_PI, kStart[1]};
  const JointPath path = find_joint_path(paper_params(), kStart, goal, PathSearchOptions{});
  // each side rounded up, plus its end pose: (a + 2)(b + 2) <= 1.05 a b for the narrow side b ~ 80
  EXPECT_LE(path.grid_poses, 1000000 * 1.05);
  EXPECT_TRUE(path.ok() || !path.message.empty());
}

TEST(Batch, InfeasibleBaselineIsNotAFailedTask) {
  BatchOptions options;
  options.validate = false;
  const TaskSpec task = detour_task();
  const TaskResult r = run_task(short_coupler_params(), paper_loads(), task, paper_initial(),
                                options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_EQ(r.baseline_status, "cannot_assemble");
  EXPECT_TRUE(std::isnan(r.baseline_dissipated_energy));
  EXPECT_EQ(r.initial_guess, "path_search");
  EXPECT_LE(r.peak_torque, task.torque_limit * (1 + options.feasibility_tol));
  EXPECT_GE(r.min_coupler_sine, options.problem.singular_margin);
  EXPECT_LT(r.dissipated_energy, r.initial_dissipated_energy);  // optimized from the detour
  // the control points of the solve are those the summary reports and problem_of rebuilds
  EXPECT_EQ(problem_of(short_coupler_params(), paper_loads(), r, options).num_variables(),
            static_cast<int>(r.x.size()));
  EXPECT_EQ(decode(encode(r)).initial_guess, "path_search");
}

TEST(Batch, FeasibleBaselineStartsTheSolve) {
  BatchOptions options;
  options.validate = false;
  const TaskResult r =
      run_task(paper_params(), paper_loads(), paper_tasks()[0], paper_initial(), options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_EQ(r.baseline_status, "ok");
  EXPECT_EQ(r.initial_guess, "minimum_jerk");
  EXPECT_EQ(r.initial_dissipated_energy, r.baseline_dissipated_energy);
  EXPECT_EQ(r.control_points, options.problem.control_points);
}

TEST(Batch, UnreachableTaskNamesWhy) {
  // the start pose one turn of theta1 on: the same pose, out of reach of a continuous motion
  BatchOptions options;
  options.validate = false;
  Params<double> p = paper_params();
  for (int i : {2, 3}) {
    p.links[i].length = 0.13;
    p.links[i].com_offset = 0.06;
  }
  p.point_p = 0.06;
  TaskSpec t = detour_task();
  t.start = {false, 0.3, 2.6};
  t.goal = {false, 0.3 + 2 * M_PI, 2.6};
  const TaskResult r = run_task(p, paper_loads(), t, {0.3, 2.6, 0, 0}, options);
  EXPECT_EQ(r.status, "unreachable");
  EXPECT_THAT(r.message, HasSubstr("singular curve"));
  EXPECT_FALSE(r.solved());
}

TEST(Rows, WorkColumnsCloseTheEnergyBalance) {
  // d(KE + PE) = W_in + W_ext - E_diss along the rows of an optimized motion
  std::vector<sim::Row> rows;
  ASSERT_NO_FATAL_FAILURE(optimized_rows(paper_tasks()[1], &rows));
  const double e0 = rows.front().kinetic + rows.front().potential;
  double worst = 0, scale = 0;
  for (const sim::Row& row : rows) {
    const double change = row.kinetic + row.potential - e0;
    worst = std::max(worst, std::abs(change - row.W_in - row.W_ext + row.E_diss));
    scale = std::max({scale, std::abs(row.W_in) + std::abs(row.W_ext), row.E_diss});
  }
  EXPECT_GT(std::abs(rows.back().W_in), 0.1);   // not the zeros of before
  EXPECT_GT(std::abs(rows.back().W_ext), 0.1);
  constexpr double kTrapezoid = 1e-4;  // trapezoidal rule at 1 ms on a 0.5 s motion: O(1e-6)
  EXPECT_LT(worst / scale, kTrapezoid);
}

// the motors' load-independent friction (actuators:) is part of what optimize minimizes and of
// the torques and energies it reports: more dissipation than without, the balance still closes
TEST(Actuators, OptimizeHonoursTheMotorFriction) {
  BatchOptions options;
  options.validate = false;
  Params<double> motors = paper_params();
  motors.actuators.coulomb = {0.1, 0.1};
  motors.actuators.viscous = {0.01, 0.01};
  const TaskResult bare =
      run_task(paper_params(), paper_loads(), paper_tasks()[1], paper_initial(), options);
  const TaskResult r = run_task(motors, paper_loads(), paper_tasks()[1], paper_initial(), options);
  ASSERT_TRUE(bare.solved()) << bare.message;
  ASSERT_TRUE(r.solved()) << r.message;
  EXPECT_GT(r.dissipated_energy, bare.dissipated_energy + 0.01);
  const TrajectoryProblem problem = problem_of(motors, paper_loads(), r, options);
  std::vector<sim::Row> rows, inverse;
  ASSERT_TRUE(problem.rows(r.x.data(), 1e-3, &rows).ok());
  ASSERT_TRUE(sim::inverse_rows(motors, paper_loads(), rows, &inverse).ok());
  const double e0 = rows.front().kinetic + rows.front().potential;
  double worst = 0, scale = 0, same = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    const sim::Row& row = rows[i];
    worst = std::max(worst, std::abs(row.kinetic + row.potential - e0 - row.W_in - row.W_ext +
                                     row.E_diss));
    scale = std::max({scale, std::abs(row.W_in) + std::abs(row.W_ext), row.E_diss});
    same = std::max(same, std::abs(row.M1 - inverse[i].M1));
  }
  EXPECT_LT(worst / scale, 1e-4);  // trapezoidal rule at 1 ms
  EXPECT_LE(same, 1e-9);
}

TEST(ExactLaw, RowsAreTheInverseDynamicsOfTheSceneLaw) {
  // trajectory.csv torques = what `fivebar inverse` computes on the same motion:
  // sim::inverse_rows with the scene's own (exact sign) friction, not the optimizer's tanh
  BatchOptions options;
  options.validate = false;
  const TaskResult r =
      run_task(paper_params(), paper_loads(), paper_tasks()[2], paper_initial(), options);
  ASSERT_TRUE(r.solved()) << r.message;
  const TrajectoryProblem problem = problem_of(paper_params(), paper_loads(), r, options);
  std::vector<sim::Row> rows, inverse, smoothed;
  ASSERT_TRUE(problem.rows(r.x.data(), 1e-3, &rows).ok());
  ASSERT_TRUE(sim::inverse_rows(paper_params(), paper_loads(), rows, &inverse).ok());
  ASSERT_TRUE(sim::inverse_rows(problem.params(), paper_loads(), rows, &smoothed).ok());
  constexpr double kSameCode = 1e-9;  // the contract: same motion, same torques
  double worst = 0, smoothing = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    worst = std::max({worst, std::abs(rows[i].M1 - inverse[i].M1),
                      std::abs(rows[i].M2 - inverse[i].M2)});
    smoothing = std::max({smoothing, std::abs(rows[i].M1 - smoothed[i].M1),
                          std::abs(rows[i].M2 - smoothed[i].M2)});
  }
  EXPECT_LE(worst, kSameCode);
  EXPECT_GT(smoothing, 1e-2);  // the smoothed law differs near rest by ~0.1 N m: not tested twice
  double M1 = 0, M2 = 0;
  ASSERT_TRUE(problem.torques(r.x.data(), rows[100].t, &M1, &M2).ok());
  EXPECT_NEAR(M1, inverse[100].M1, kSameCode);
}

TEST(ExactLaw, EnergiesAreExactLawWithTheSmoothedBeside) {
  BatchOptions options;
  options.validate = false;
  options.refine.enabled = false;  // the first solve, at w_s = 0.05 rad/s
  const TaskResult r =
      run_task(paper_params(), paper_loads(), paper_tasks()[3], paper_initial(), options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_EQ(r.dissipated_energy, r.dissipated_energy_exact);
  EXPECT_EQ(r.baseline_dissipated_energy, r.baseline_dissipated_energy_exact);
  // sign(w) dissipates more than tanh(w / w_s) at the same motion (|tanh| < 1)
  EXPECT_GT(r.dissipated_energy, r.dissipated_energy_smoothed);
  EXPECT_GT(r.baseline_dissipated_energy, r.baseline_dissipated_energy_smoothed);
  // ... by less than 1% here: the joints spend little time below w_s = 0.05 rad/s
  EXPECT_LT(r.dissipated_energy, 1.01 * r.dissipated_energy_smoothed);
  EXPECT_NEAR(r.objective, r.dissipated_energy_smoothed, 1e-12 * r.objective);
}

TEST(Tasks, BadTaskIsAStatusNotAnError) {
  TaskSpec t;
  t.name = "x";
  t.duration = -1;
  t.start = {false, M_PI / 2, M_PI / 2};
  t.goal = {true, 0.15, 0.25};
  EXPECT_EQ(resolve_task(paper_params(), t, paper_initial(), 0.1).status, "invalid_duration");
  t.duration = 0.5;
  t.torque_limit = 0;
  EXPECT_EQ(resolve_task(paper_params(), t, paper_initial(), 0.1).status, "invalid_torque_limit");
  t.torque_limit = 10;
  t.goal = {true, 0.5, 0.5};
  EXPECT_EQ(resolve_task(paper_params(), t, paper_initial(), 0.1).status,
            "goal_out_of_workspace");
  // short couplers: |BD| = l0 + l1 + l2 = 0.42 m > l3 + l4 at theta1 = pi, theta2 = 0
  Params<double> short_couplers = paper_params();
  short_couplers.links[2].length = short_couplers.links[3].length = 0.15;
  t.start = {false, M_PI, 0.0};
  EXPECT_EQ(resolve_task(short_couplers, t, paper_initial(), 0.1).status,
            "start_cannot_assemble");
  // a Cartesian goal resolves to angles whose C is the goal
  t.start = {false, M_PI / 2, M_PI / 2};
  t.goal = {true, 0.2, 0.22};
  const ResolvedTask r = resolve_task(paper_params(), t, paper_initial(), 0.1);
  ASSERT_TRUE(r.ok()) << r.message;
  std::array<double, 2> c{};
  ASSERT_TRUE(point_c(paper_params(), r.goal[0], r.goal[1], &c));
  EXPECT_NEAR(c[0], 0.2, 1e-12);
  EXPECT_NEAR(c[1], 0.22, 1e-12);
}

TEST(Sweep, ParsesAndRejects) {
  const Sweep s = parse_sweep("mechanism.links.0.length=0.06:0.12:7");
  EXPECT_EQ(s.key, "mechanism.links.0.length");
  EXPECT_EQ(s.n, 7);
  EXPECT_DOUBLE_EQ(s.value(6), 0.12);
  EXPECT_THROW(parse_sweep("a=1:2"), std::invalid_argument);
  EXPECT_THROW(parse_sweep("a=2:1:3"), std::invalid_argument);
  EXPECT_THROW(parse_sweep("a=1:2:0"), std::invalid_argument);
  EXPECT_THROW(parse_sweep("=1:2:3"), std::invalid_argument);
  const std::vector<Sweep> grid = {parse_sweep("a=0:1:2"), parse_sweep("b=0:2:3")};
  EXPECT_EQ(design_count(grid), 6);
  EXPECT_EQ(design_values(grid, 4), (std::vector<double>{1.0, 1.0}));
}

TEST(NloptStatus, EveryResultAndExceptionIsMapped) {
  EXPECT_EQ(status_from_result(4).outcome, SolverOutcome::kConverged);  // XTOL_REACHED
  EXPECT_EQ(status_from_result(5).outcome, SolverOutcome::kMaxEvaluations);
  EXPECT_EQ(status_from_result(-4).outcome, SolverOutcome::kRoundoffLimited);
  EXPECT_EQ(status_from_result(-5).outcome, SolverOutcome::kForcedStop);
  EXPECT_EQ(status_from_result(-2).outcome, SolverOutcome::kInvalidArgument);
  EXPECT_EQ(status_from_result(-3).outcome, SolverOutcome::kOutOfMemory);
  EXPECT_EQ(status_from_result(-1).outcome, SolverOutcome::kFailure);
  EXPECT_EQ(status_from_exception(std::make_exception_ptr(std::invalid_argument("x"))).outcome,
            SolverOutcome::kInvalidArgument);
  EXPECT_EQ(status_from_exception(std::make_exception_ptr(std::bad_alloc())).outcome,
            SolverOutcome::kOutOfMemory);
  EXPECT_EQ(status_from_exception(std::make_exception_ptr(42)).outcome, SolverOutcome::kFailure);
}

}  // namespace
}  // namespace fivebar::trajectory
