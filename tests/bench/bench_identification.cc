// Identification: parameter error against wall time as the log length and the method vary.
// Each benchmark synthesizes a paper-scene log (torque noise 0.02 N m, angle noise 1e-5 rad,
// seed 1) once, outside the timed loop, and times identify(); the counters report the relative
// errors of the shared coefficients and the error in reported standard deviations.
#include <benchmark/benchmark.h>

#include <cmath>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"

#include "paper.h"

namespace fivebar::identification {
namespace {

using testing::paper_loads;

// args: log duration [s], with rates (1) or angles only (0), method (0 inverse dynamics, 1 output
// error)
void BM_Identify(benchmark::State& state) {
  const double duration = static_cast<double>(state.range(0));
  SynthOptions so;
  so.duration = duration;
  so.torque_noise = 0.02;
  so.angle_noise = 1e-5;
  so.with_rates = state.range(1) != 0;
  const Params<double> truth = paper_params();
  const SynthResult log = synthesize_log(truth, paper_loads, testing::paper_initial(), so);
  IdentifyOptions opt;
  opt.method = state.range(2) ? Method::kOutputError : Method::kInverseDynamics;
  IdentifyResult res;
  for (auto _ : state) {
    res = identify(truth, paper_loads, log.log, opt);
    benchmark::DoNotOptimize(res.parameters.data());
  }
  const double tc = 0.12, tv = 0.02;
  state.counters["coulomb_rel_err"] = std::abs(res.parameters[0].value - tc) / tc;
  state.counters["viscous_rel_err"] = std::abs(res.parameters[1].value - tv) / tv;
  state.counters["coulomb_err_std"] =
      std::abs(res.parameters[0].value - tc) / res.parameters[0].std;
  state.counters["viscous_err_std"] =
      std::abs(res.parameters[1].value - tv) / res.parameters[1].std;
  state.counters["samples"] = res.samples_used;
}
BENCHMARK(BM_Identify)
    ->ArgsProduct({{1, 2, 5, 10}, {1, 0}, {0}})
    ->ArgsProduct({{1, 2, 5}, {1}, {1}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace
}  // namespace fivebar::identification

BENCHMARK_MAIN();
