// Speed of trajectory optimization: one evaluation of the problem (objective,
// constraints and their gradients) for several spline sizes, and whole tasks of the paper scene
// (the first solve with the continuation; the refined default). Nothing here is asserted.
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>

#include "fivebar/model/dynamics.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/problem.h"
#include "paper_fixture.h"

namespace {

using namespace fivebar::trajectory;
namespace fixture = fivebar::trajectory::testing;
using fivebar::paper_params;

// the problem of swing_right with n control points at the last continuation stage, and the
// minimum-jerk start
struct Setup {
  explicit Setup(int n, int quadrature_points, int threads = 1) {
    ProblemOptions o;
    o.control_points = n;
    o.quadrature_points = quadrature_points;
    o.threads = threads;
    o.torque_limit = 30.0;
    o.smoothing_velocity = 4e-4;
    const TaskSpec task = fixture::paper_tasks()[1];
    const ResolvedTask rt = resolve_task(paper_params(), task, fixture::paper_initial(), 0.1);
    const RestToRest motion(n, task.duration, rt.start, rt.goal);
    problem = std::make_unique<TrajectoryProblem>(paper_params(), fixture::paper_loads(), motion, o);
    x = motion.minimum_jerk();
  }
  std::unique_ptr<TrajectoryProblem> problem;
  std::vector<double> x;
};

// args: control points, Gauss-Legendre points per knot span
void BM_Evaluate(benchmark::State& state) {
  const Setup s(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  Evaluated e;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.problem->evaluate(s.x.data(), true, &e));
  }
  state.counters["nodes"] = s.problem->num_nodes();
}
BENCHMARK(BM_Evaluate)->Args({10, 12})->Args({25, 6})->Args({45, 6})->Args({85, 6})
    ->Unit(benchmark::kMicrosecond);

void BM_EvaluateValueOnly(benchmark::State& state) {
  const Setup s(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  Evaluated e;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.problem->evaluate(s.x.data(), false, &e));
  }
}
BENCHMARK(BM_EvaluateValueOnly)->Args({10, 12})->Args({85, 6})->Unit(benchmark::kMicrosecond);

// the optimizer's form (constraint gradients local); args: control points, GL points, threads
void BM_EvaluateLocal(benchmark::State& state) {
  const Setup s(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
                static_cast<int>(state.range(2)));
  Evaluated e;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.problem->evaluate_local(s.x.data(), &e));
  }
}
BENCHMARK(BM_EvaluateLocal)->Args({85, 6, 1})->Args({85, 6, 2})->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// the objective's Hessian of the preconditioner (node by node)
void BM_Hessian(benchmark::State& state) {
  const Setup s(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::vector<double> h;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.problem->objective_hessian(s.x.data(), &h));
  }
}
BENCHMARK(BM_Hessian)->Args({45, 6})->Args({85, 6})->Unit(benchmark::kMicrosecond);

// a whole task (arg: index in paper_tasks.yaml); arg 1: 0 first solve and continuation,
// 1 the refined default of `fivebar optimize`
void BM_Task(benchmark::State& state) {
  const TaskSpec task = fixture::paper_tasks()[state.range(0)];
  BatchOptions o;
  o.validate = false;
  if (state.range(1) == 1) o.refine.control_points = kRefineLevels;
  double energy = 0;
  for (auto _ : state) {
    const TaskResult r =
        run_task(paper_params(), fixture::paper_loads(), task, fixture::paper_initial(), o);
    energy = r.dissipated_energy;
  }
  state.counters["energy_J"] = energy;
}
BENCHMARK(BM_Task)->ArgsProduct({{0, 1, 2, 3, 4}, {0}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Task)->ArgsProduct({{0, 1, 2, 3, 4}, {1}})->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
