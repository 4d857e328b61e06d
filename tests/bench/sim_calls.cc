// n runs of the paper scene at arkode_erk45, rtol = atol = 1e-10 (2 s, the 1 ms output grid), for
// profiles of the simulator's time per step (perf record, valgrind --tool=callgrind; the
// difference of two counts n1, n2 over n2 - n1 is one run, without the program's start):
//   valgrind --tool=callgrind build/release/tests/bench/sim_calls 3
// The loads are the scene's as a C++ function (paper_loads), not parsed expressions.
#include <cstdio>
#include <cstdlib>

#include "fivebar/sim/simulator.h"
#include "paper.h"

int main(int argc, char** argv) {
  using namespace fivebar;
  const long n = argc == 2 ? std::atol(argv[1]) : 0;
  if (n < 1) {
    std::fprintf(stderr, "usage: sim_calls N\n");
    return 2;
  }
  const Params<double> p = paper_params();
  sim::Options o;
  o.method = sim::Method::kArkodeErk45;
  o.rtol = o.atol = 1e-10;
  double sum = 0.0;
  long steps = 0, rhs = 0;
  for (long i = 0; i < n; ++i) {
    const sim::Result r = sim::simulate(p, paper_loads, testing::paper_initial(), o);
    if (!r.status.ok()) return 3;
    sum += r.rows.back().theta[0];
    steps = r.stats.steps;
    rhs = r.stats.rhs_evaluations;
  }
  std::printf("%.17g (steps %ld, right-hand sides %ld per run)\n", sum / static_cast<double>(n),
              steps, rhs);
  return 0;
}
