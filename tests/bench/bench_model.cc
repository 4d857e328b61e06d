// Speed of the model's right-hand side (with and without friction) and of the paper scene.
//   build/tests/bench/bench_model --benchmark_repetitions=5 --benchmark_report_aggregates_only
#include <benchmark/benchmark.h>
#include <ceres/jet.h>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

/// One right-hand side as the integrator calls it: forward dynamics with the reaction/friction
/// loop resolved (friction) or no reaction solve at all (frictionless), loads included.
void RightHandSide(benchmark::State& state, bool friction, bool actuators = false) {
  Params<double> p = paper_params();
  if (!friction) p.friction.law = FrictionLaw::kNone;
  if (actuators) p.actuators.coulomb = p.actuators.viscous = {0.03, 0.002};  // the motors' friction
  EvalOptions opt;
  opt.want_reactions = false;
  opt.want_angles = false;  // as the simulator's right-hand side
  opt.singular_margin = 1e-3;
  const JointModes slip = {JointMode::kSlipPositive, JointMode::kSlipNegative, JointMode::kSlipPositive, JointMode::kSlipPositive, JointMode::kSlipNegative};
  double th1 = 1.3, th2 = 2.0, t = 0.31;
  for (auto _ : state) {
    Evaluation<double> ev;
    const Loads<double> L = testing::paper_loads(t);
    const Status st = forward_dynamics(p, L, th1, th2, 23.0, -31.0, friction ? &slip : nullptr,
                                       opt, &ev);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(ev.thdd);
    benchmark::ClobberMemory();
  }
}
BENCHMARK_CAPTURE(RightHandSide, friction, true);
BENCHMARK_CAPTURE(RightHandSide, frictionless, false);
BENCHMARK_CAPTURE(RightHandSide, actuators, true, true);

/// One node of trajectory optimization: inverse dynamics of the paper scene with the state
/// (th1, th2, w1, w2, a1, a2) seeded in Jet<6>, as trajectory/src/problem.cc evaluates it.
/// arg 0: value only (double); 1: Jets, implicit loop derivative (default); 2: Jets, the whole
/// loop iterated in Jets (the former path).
void InverseNode(benchmark::State& state) {
  using Jet6 = ceres::Jet<double, 6>;
  const Params<double> p = paper_params();
  const Params<Jet6> pj = p.cast<Jet6>();
  const Loads<double> L = testing::paper_loads(0.31);
  const Loads<Jet6> Lj = L.cast<Jet6>();
  EvalOptions opt;
  opt.implicit_loop_derivative = state.range(0) != 2;
  const double s[6] = {1.3, 2.0, 3.1, -4.2, 20.0, -12.0};
  for (auto _ : state) {
    if (state.range(0) == 0) {
      Evaluation<double> ev;
      benchmark::DoNotOptimize(
          inverse_dynamics(p, L, s[0], s[1], s[2], s[3], s[4], s[5], nullptr, opt, &ev));
      benchmark::DoNotOptimize(ev.M1);
    } else {
      Evaluation<Jet6> ev;
      benchmark::DoNotOptimize(inverse_dynamics(pj, Lj, Jet6(s[0], 0), Jet6(s[1], 1),
                                                Jet6(s[2], 2), Jet6(s[3], 3), Jet6(s[4], 4),
                                                Jet6(s[5], 5), nullptr, opt, &ev));
      benchmark::DoNotOptimize(ev.M1);
    }
    benchmark::ClobberMemory();
  }
}
BENCHMARK(InverseNode)->Arg(0)->Arg(1)->Arg(2);

/// The paper scene, 2 s on the 1 ms grid, at default settings (no plots, no file output).
void PaperScene(benchmark::State& state, bool friction) {
  Params<double> p = paper_params();
  if (!friction) p.friction.law = FrictionLaw::kNone;
  const sim::LoadFunction loads = testing::paper_loads;
  long rhs = 0;
  for (auto _ : state) {
    const sim::Result r = sim::simulate(p, loads, testing::paper_initial(), sim::Options{});
    rhs = r.stats.rhs_evaluations;
    benchmark::DoNotOptimize(r.rows.data());
  }
  state.counters["rhs_evaluations"] = static_cast<double>(rhs);
}
BENCHMARK_CAPTURE(PaperScene, friction, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(PaperScene, frictionless, false)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace fivebar

BENCHMARK_MAIN();
