// The continuation to the exact friction law, the refinement of the control points,
// warm starts from a neighbouring design, and the outer loop of `fivebar design`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/design.h"
#include "fivebar/trajectory/tasks.h"
#include "paper_fixture.h"

namespace fivebar::trajectory {
namespace {

using testing::paper_initial;
using testing::paper_loads;
using testing::paper_tasks;
using testing::task_problem;

// these tests pin figures of the paper's objective (dissipated_energy) on motions whose end
// accelerations are zero (--end-acceleration zero)
TaskResult solve(const TaskSpec& task, BatchOptions options,
                 const Params<double>& params = paper_params(), const TaskResult* warm = nullptr) {
  options.problem.end_acceleration = EndAcceleration::kZero;
  return run_task(params, paper_loads(), task, paper_initial(), options, warm);
}

// the exact-law objectives E of the stages "w_s:E[x];..." of TaskResult::continuation
std::vector<double> stage_energies(const std::string& log) {
  std::vector<double> e;
  for (size_t at = 0; at < log.size();) {
    const size_t end = std::min(log.find(';', at), log.size());
    const std::string stage = log.substr(at, end - at);
    e.push_back(std::stod(stage.substr(stage.find(':') + 1)));
    at = end + 1;
  }
  return e;
}

TEST(Continuation, ReachesTheExactLawEnergy) {
  // swing_right: at w_s = 0.05 rad/s the smoothed law is 3e-4 (relative) off the exact one;
  // the continuation lowers the exact-law energy stage by stage and ends at the first stage
  // that lowers it by less than the refinement's tolerance
  const TaskSpec task = paper_tasks()[1];
  BatchOptions first;
  first.validate = false;
  first.refine.enabled = false;
  BatchOptions cont = first;
  cont.refine.enabled = true;
  const TaskResult a = solve(task, first), b = solve(task, cont);
  ASSERT_EQ(a.status, "ok") << a.message;
  ASSERT_EQ(b.status, "ok") << b.message;
  EXPECT_GT(std::abs(a.dissipated_energy_smoothed / a.dissipated_energy - 1.0), 2e-4);
  EXPECT_LT(b.dissipated_energy, a.dissipated_energy * (1.0 - 1e-4));
  const std::vector<double> e = stage_energies(b.continuation);  // the start, then each stage
  ASSERT_GE(e.size(), 2u) << b.continuation;
  ASSERT_LE(e.size(), cont.refine.continuation.size() + 1) << b.continuation;
  const double tol = cont.refine.tol;
  for (size_t k = 1; k + 1 < e.size(); ++k) EXPECT_GT(e[k - 1] - e[k], tol * e[k - 1]) << k;
  if (e.size() < cont.refine.continuation.size() + 1) {
    EXPECT_LE(e[e.size() - 2] - e.back(), tol * e[e.size() - 2]) << b.continuation;
  }
}

TEST(Continuation, SaysWhenItsLastStageStillLowersTheEnergy) {
  // swing_right with one stage (w_s = 0.01 rad/s) and no refinement level: that stage lowers
  // the exact-law energy by far more than 1e-6, so the message says the continuation did not
  // settle; with the stages to 4e-4 rad/s and the default tolerance it settles, and says nothing
  const TaskSpec task = paper_tasks()[1];
  BatchOptions one;
  one.validate = false;
  one.refine.control_points = {};
  one.refine.continuation = {1e-2};
  one.refine.tol = 1e-6;
  const TaskResult a = solve(task, one);
  ASSERT_EQ(a.status, "ok") << a.message;
  const std::vector<double> e = stage_energies(a.continuation);
  ASSERT_EQ(e.size(), 2u) << a.continuation;
  ASSERT_GT(e[0] - e[1], one.refine.tol * e[0]) << a.continuation;
  EXPECT_NE(a.message.find("continuation not converged: its last stage (w_s = 0.01 rad/s)"),
            std::string::npos) << a.message;
  BatchOptions all = one;
  all.refine.continuation = BatchOptions().refine.continuation;
  all.refine.tol = BatchOptions().refine.tol;
  const TaskResult b = solve(task, all);
  ASSERT_EQ(b.status, "ok") << b.message;
  EXPECT_EQ(b.message.find("continuation not converged"), std::string::npos) << b.message;
}

TEST(Optimizer, PreconditionedSlsqpReachesTheSameOptimumInFewerEvaluations) {
  // a refined spline (45 control points, 78 variables) from the minimum-jerk start: SLSQP in
  // the variables that make the objective's Hessian at the start +-I ends at the optimum of the
  // plain solve in a fraction of its evaluations (counts are deterministic, no timing; the plain
  // solve's count moves with the model's last digits, hence a margin of 1.5, not more)
  const TaskSpec task = paper_tasks()[0];  // swing_left
  const TrajectoryProblem p = task_problem(task, 45, 8);
  const std::vector<double> x0 = p.motion().minimum_jerk();
  OptimizerOptions plain, pre;
  plain.precondition = false;
  // full solves, not cut by the stall test (which ends both early, at its own tolerance)
  plain.stall_rtol = pre.stall_rtol = 0;
  ASSERT_TRUE(pre.precondition);
  const OptimizeResult a = optimize(p, x0, plain), b = optimize(p, x0, pre);
  ASSERT_TRUE(a.solver.usable()) << a.solver.message;
  ASSERT_TRUE(b.solver.usable()) << b.solver.message;
  EXPECT_LE(b.max_node_constraint, 10 * pre.constraint_tol);
  EXPECT_LT(b.objective, a.objective * (1 + 1e-5)) << a.objective << " " << b.objective;
  EXPECT_LT(1.5 * b.evaluations, a.evaluations) << a.evaluations << " " << b.evaluations;
}

TEST(Refinement, LevelsUnderTheSmoothedLawThenTheContinuation) {
  // swing_right: refined under the first solve's smooth law, whose landscape has no kinks at
  // the reversals, the levels reach a lower basin than under the near-exact law (0.2644 J at 45
  // control points when the continuation ran first); the continuation then runs on the finest
  // spline and ends at the exact law's w_s
  const TaskSpec task = paper_tasks()[1];
  BatchOptions options;
  options.validate = false;
  options.refine.control_points = {25, 45};
  options.refine.tol = 1e-6;
  const TaskResult r = solve(task, options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_EQ(r.control_points, 45) << r.refinement;
  EXPECT_LT(r.dissipated_energy, 0.2638) << r.refinement << " " << r.continuation;
  EXPECT_EQ(r.refinement.find("10:"), 0u) << r.refinement;
  EXPECT_EQ(r.continuation.find("0.05:"), 0u) << r.continuation;
  EXPECT_EQ(r.smoothing_velocity, options.refine.continuation.back()) << r.continuation;
}

TEST(Refinement, StopsWhenTheEnergyChangesLessThanTheTolerance) {
  const TaskSpec task = paper_tasks()[0];  // swing_left
  BatchOptions options;
  options.validate = false;
  options.refine.continuation.clear();
  options.refine.control_points = {14, 20};
  options.refine.tol = 2e-2;  // 10 -> 14 changes the energy by about 1%: stop at 14
  const TaskResult r = solve(task, options);
  ASSERT_EQ(r.status, "ok") << r.message;
  EXPECT_EQ(r.control_points, 14) << r.refinement;
  EXPECT_LT(r.refinement_change, options.refine.tol);
  EXPECT_EQ(r.message.find("discretization not converged"), std::string::npos) << r.message;
  EXPECT_EQ(r.refinement.rfind("10:", 0), 0u) << r.refinement;
  // a tolerance no level meets: every level is solved, and the change says so
  options.refine.tol = 1e-6;
  const TaskResult all = solve(task, options);
  ASSERT_EQ(all.status, "ok") << all.message;
  EXPECT_EQ(all.control_points, 20) << all.refinement;
  EXPECT_GT(all.refinement_change, options.refine.tol);
  EXPECT_NE(all.message.find("discretization not converged"), std::string::npos) << all.message;
  EXPECT_LT(all.dissipated_energy, r.dissipated_energy);
}

// a level whose solve stopped at its evaluation limit can end within the tolerance of the level
// before and pass for converged; it shows nothing, and says so
TEST(Refinement, ALevelStoppedAtItsLimitDoesNotShowConvergence) {
  const TaskSpec task = paper_tasks()[0];  // swing_left
  BatchOptions options;
  options.validate = false;
  options.refine.continuation.clear();
  options.refine.control_points = {14};
  options.refine.tol = 0.5;  // any change passes: only the limit can keep it open
  options.optimizer.max_evaluations = 12;
  const TaskResult r = solve(task, options);
  ASSERT_TRUE(r.refinement_limited) << r.refinement << " " << r.message;
  EXPECT_TRUE(r.discretization_unsettled(options.refine.tol));
  EXPECT_NE(r.message.find("discretization not shown converged"), std::string::npos) << r.message;
}

TEST(WarmStart, FromANeighbouringDesign) {
  const TaskSpec task = paper_tasks()[2];  // reach_right, a Cartesian goal
  BatchOptions options;
  options.validate = false;
  options.refine.enabled = false;
  const TaskResult base = solve(task, options);
  ASSERT_EQ(base.status, "ok") << base.message;
  Params<double> p = paper_params();
  p.links[1].length = 0.052;  // the goal's joint angles move
  const TaskResult cold = solve(task, options, p), warm = solve(task, options, p, &base);
  ASSERT_EQ(warm.status, "ok") << warm.message;
  EXPECT_EQ(warm.initial_guess, "warm_start");
  EXPECT_NE(warm.goal[1], base.goal[1]);
  EXPECT_NEAR(warm.dissipated_energy, cold.dissipated_energy, 1e-3 * cold.dissipated_energy);
  EXPECT_LT(warm.evaluations, cold.evaluations);
}

TEST(DesignBox, FindsInteriorAndBoundMinima) {
  int calls = 0;
  auto f = [&](const std::vector<double>& x) {
    ++calls;
    return (x[0] - 0.3) * (x[0] - 0.3) + 2.0 * (x[1] - 1.5) * (x[1] - 1.5);
  };
  BoxOptions o;
  o.max_evaluations = 60;
  o.xtol = 1e-6;
  // the minimum in x[1] lies beyond the upper bound 1.0
  const BoxResult r = minimize_box(f, {0.0, 0.0}, {1.0, 1.0}, {0.8, 0.2}, o);
  ASSERT_TRUE(r.solver.usable()) << r.solver.message;
  EXPECT_NEAR(r.x[0], 0.3, 1e-3);
  EXPECT_NEAR(r.x[1], 1.0, 1e-6);
  EXPECT_EQ(r.evaluations, calls);
  EXPECT_LE(calls, o.max_evaluations);
}

}  // namespace
}  // namespace fivebar::trajectory
