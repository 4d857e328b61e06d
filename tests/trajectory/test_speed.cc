// The solve time: the node-wise Hessian of the preconditioner, the local form of the
// constraint gradients, evaluations on several threads, and the stall test of local solves.
// Counts and numbers only (deterministic), no timing.
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "fivebar/model/dynamics.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/tasks.h"
#include "paper_fixture.h"

namespace fivebar::trajectory {
namespace {

using testing::paper_initial;
using testing::paper_loads;
using testing::paper_tasks;

// swing_right with n control points under the smoothing w_s, and a start off the minimum-jerk
// motion (so that joints reverse and the friction law's curvature enters)
struct Swing {
  Swing(int n, double ws, int threads = 1) {
    const TaskSpec task = paper_tasks()[1];
    const ResolvedTask rt = resolve_task(paper_params(), task, paper_initial(), 0.1);
    ProblemOptions o;
    o.torque_limit = task.torque_limit;
    o.quadrature_points = 6;
    o.smoothing_velocity = ws;
    o.threads = threads;
    problem = std::make_unique<TrajectoryProblem>(paper_params(), paper_loads(),
                                                  RestToRest(n, task.duration, rt.start, rt.goal),
                                                  o);
    x = problem->motion().minimum_jerk();
    for (size_t i = 0; i < x.size(); ++i) x[i] += 0.05 * std::sin(1.7 * static_cast<double>(i));
  }
  std::unique_ptr<TrajectoryProblem> problem;
  std::vector<double> x;
};

TEST(Hessian, MatchesDifferencesOfTheExactGradient) {
  const Swing s(14, 0.05);
  const int nv = s.problem->num_variables();
  std::vector<double> h;
  ASSERT_TRUE(s.problem->objective_hessian(s.x.data(), &h).ok());
  Evaluated e0;
  ASSERT_TRUE(s.problem->evaluate(s.x.data(), true, &e0).ok());
  double scale = 0;
  for (double v : h) scale = std::max(scale, std::abs(v));
  ASSERT_GT(scale, 0);
  for (int c = 0; c < nv; ++c) {
    // central differences of the gradient along variable c: column c of the Hessian
    std::vector<double> xp = s.x, xm = s.x;
    const double step = 1e-5;
    xp[c] += step;
    xm[c] -= step;
    Evaluated ep, em;
    ASSERT_TRUE(s.problem->evaluate(xp.data(), true, &ep).ok());
    ASSERT_TRUE(s.problem->evaluate(xm.data(), true, &em).ok());
    for (int r = 0; r < nv; ++r) {
      const double fd = (ep.objective_grad[r] - em.objective_grad[r]) / (2 * step);
      EXPECT_NEAR(h[static_cast<size_t>(r) * nv + c], fd, 1e-4 * scale) << r << ", " << c;
      EXPECT_NEAR(h[static_cast<size_t>(r) * nv + c], h[static_cast<size_t>(c) * nv + r],
                  1e-12 * scale);
    }
  }
}

TEST(Evaluation, LocalGradientsAreTheDenseOnes) {
  const Swing s(25, 4e-4);
  const int nv = s.problem->num_variables();
  Evaluated dense, local;
  ASSERT_TRUE(s.problem->evaluate(s.x.data(), true, &dense).ok());
  ASSERT_TRUE(s.problem->evaluate_local(s.x.data(), &local).ok());
  EXPECT_EQ(dense.objective, local.objective);
  EXPECT_EQ(dense.objective_grad, local.objective_grad);
  EXPECT_EQ(dense.constraints, local.constraints);
  for (int r = 0; r < s.problem->num_constraints(); ++r) {
    std::vector<double> row(nv, 0.0);
    const auto vars = s.problem->node_variables(r / 3);
    for (int l = 0; l < kLocalVariables; ++l) {
      if (vars[l] >= 0) row[vars[l]] += local.constraints_grad_local[r * kLocalVariables + l];
    }
    for (int v = 0; v < nv; ++v) {
      ASSERT_EQ(row[v], dense.constraints_grad[static_cast<size_t>(r) * nv + v]) << r << " " << v;
    }
  }
}

TEST(Evaluation, ThreadsGiveTheSameNumbers) {
  // 85 control points, 480 nodes: 1, 2 and 3 threads, bit for bit
  Evaluated e[3];
  for (int t = 1; t <= 3; ++t) {
    const Swing s(85, 4e-4, t);
    ASSERT_TRUE(s.problem->evaluate(s.x.data(), true, &e[t - 1]).ok());
  }
  for (int t = 1; t < 3; ++t) {
    EXPECT_EQ(e[t].objective, e[0].objective);
    EXPECT_EQ(e[t].objective_grad, e[0].objective_grad);
    EXPECT_EQ(e[t].constraints, e[0].constraints);
    EXPECT_EQ(e[t].constraints_grad, e[0].constraints_grad);
  }
}

TEST(Optimizer, StallTestEndsNearTheFullSolveInFewerEvaluations) {
  // swing_left at 45 control points from the minimum-jerk start: the solve stopped when ten
  // feasible iterations lowered the objective by < 1e-5 of it ends within 1e-5 of the solve to
  // ftol
  const TaskSpec task = paper_tasks()[0];
  const ResolvedTask rt = resolve_task(paper_params(), task, paper_initial(), 0.1);
  ProblemOptions po;
  po.torque_limit = task.torque_limit;
  po.quadrature_points = 6;
  const TrajectoryProblem p(paper_params(), paper_loads(),
                            RestToRest(45, task.duration, rt.start, rt.goal), po);
  OptimizerOptions full, stall;
  full.stall_rtol = 0;
  ASSERT_GT(stall.stall_rtol, 0);
  const std::vector<double> x0 = p.motion().minimum_jerk();
  const OptimizeResult a = optimize(p, x0, full), b = optimize(p, x0, stall);
  ASSERT_TRUE(a.solver.usable()) << a.solver.message;
  ASSERT_TRUE(b.solver.usable()) << b.solver.message;
  EXPECT_LE(b.max_node_constraint, stall.stall_feasibility_tol);
  EXPECT_LT(b.objective, a.objective * (1 + 1e-5)) << a.objective << " " << b.objective;
  EXPECT_LT(b.evaluations, a.evaluations) << a.evaluations << " " << b.evaluations;
}

TEST(Optimizer, ScreeningEndsItsFirstRoundEarlyAtTheSameOptimum) {
  // reach_right at 45 control points from the first solve's optimum (10 control points, knot
  // insertion): the first screening round hands NLopt no row and drives the torques past the
  // limit; ended at its first best point that violates a row left out, the solve reaches the
  // same optimum in fewer evaluations than with the round run to its end
  const TaskSpec task = paper_tasks()[2];
  BatchOptions o;
  o.validate = false;
  o.refine.enabled = false;
  o.problem.end_acceleration = EndAcceleration::kZero;  // the splines below
  const TaskResult first = run_task(paper_params(), paper_loads(), task, paper_initial(), o);
  ASSERT_EQ(first.status, "ok") << first.message;
  ASSERT_EQ(first.control_points, 10);
  const RestToRest coarse(10, task.duration, first.start, first.goal);
  const RestToRest fine(45, task.duration, first.start, first.goal);
  const std::vector<double> x0 =
      fine.fit([&](double t) { return coarse.state(first.x.data(), t)[0]; });
  ProblemOptions po;
  po.torque_limit = task.torque_limit;
  po.quadrature_points = 6;  // as the refinement's 45-point level
  const TrajectoryProblem p(paper_params(), paper_loads(), fine, po);
  OptimizerOptions early, late;
  late.screen_early_end = false;
  const OptimizeResult a = optimize(p, x0, late), b = optimize(p, x0, early);
  ASSERT_TRUE(a.solver.usable()) << a.solver.message;
  ASSERT_TRUE(b.solver.usable()) << b.solver.message;
  EXPECT_LE(b.max_node_constraint, 10 * early.constraint_tol);
  EXPECT_LT(b.objective, a.objective * (1 + 1e-4)) << a.objective << " " << b.objective;
  EXPECT_LT(b.evaluations, a.evaluations) << a.evaluations << " " << b.evaluations;
}

TEST(Batch, NodeThreadsGiveTheSameResult) {
  // a whole refined task (levels 25, 45 to keep it short) on 1 and 2 threads per evaluation
  BatchOptions o;
  o.validate = false;
  o.refine.control_points = {25, 45};
  const TaskSpec task = paper_tasks()[3];  // reach_left
  const TaskResult a = run_task(paper_params(), paper_loads(), task, paper_initial(), o);
  o.problem.threads = 2;
  const TaskResult b = run_task(paper_params(), paper_loads(), task, paper_initial(), o);
  ASSERT_EQ(a.status, "ok") << a.message;
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.dissipated_energy, b.dissipated_energy);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.refinement, b.refinement);
  EXPECT_EQ(a.continuation, b.continuation);
}

}  // namespace
}  // namespace fivebar::trajectory
