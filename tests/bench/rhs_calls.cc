// n right-hand sides as bench_model's RightHandSide benchmarks evaluate them, for instruction
// counts (valgrind --tool=callgrind; the difference of two counts n1, n2 over n2 - n1 is the cost
// of one evaluation, without the program's start):
//   valgrind --tool=callgrind --callgrind-out-file=/dev/null build/release/tests/bench/rhs_calls
//   friction 1000
// Modes: friction, frictionless, actuators (the benchmark's state, the loop started cold), and
// friction_warm (states 1e-5 s apart along the benchmark's velocities, 200 in a cycle, the loop
// warm-started from the previous evaluation as in the simulator), friction_path (the same
// states and loads, the loop started cold: what friction_warm saves is the difference; the other
// modes' loads are at one time, which the compiler evaluates once), and frictionless_path (the
// same states and loads without friction: friction_warm / frictionless_path is the ratio in the
// simulator's conditions).
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "fivebar/model/dynamics.h"
#include "paper.h"

int main(int argc, char** argv) {
  using namespace fivebar;
  const char* modes[] = {"friction",      "frictionless",  "actuators",
                         "friction_warm", "friction_path", "frictionless_path"};
  int mode = -1;
  for (int m = 0; m < 6 && argc == 3; ++m) mode = std::strcmp(argv[1], modes[m]) == 0 ? m : mode;
  const long n = argc == 3 ? std::atol(argv[2]) : 0;
  if (mode < 0 || n < 1) {
    std::fprintf(stderr,
                 "usage: rhs_calls friction|frictionless|actuators|friction_warm|friction_path|"
                 "frictionless_path N\n");
    return 2;
  }
  Params<double> p = paper_params();
  const bool frictionless = mode == 1 || mode == 5;
  if (frictionless) p.friction.law = FrictionLaw::kNone;
  if (mode == 2) p.actuators.coulomb = p.actuators.viscous = {0.03, 0.002};
  EvalOptions opt;
  opt.want_reactions = false;
  opt.want_angles = false;
  opt.singular_margin = 1e-3;
  const JointModes slip = {JointMode::kSlipPositive, JointMode::kSlipNegative,
                           JointMode::kSlipPositive, JointMode::kSlipPositive,
                           JointMode::kSlipNegative};
  FrictionWarmStart warm;
  double sum = 0.0;
  for (long i = 0; i < n; ++i) {
    const double dt = mode >= 3 ? 1e-5 * static_cast<double>(i % 200) : 0.0;
    Evaluation<double> ev;
    const Loads<double> L = testing::paper_loads(0.31 + dt);
    const Status st = forward_dynamics(
        p, L, 1.3 + 23.0 * dt, 2.0 - 31.0 * dt, 23.0, -31.0, frictionless ? nullptr : &slip, opt,
        &ev, static_cast<const std::array<double, kJoints>*>(nullptr), mode == 3 ? &warm : nullptr);
    sum += st.ok() ? ev.thdd[0] + ev.thdd[1] : 0.0;
  }
  std::printf("%.17g\n", sum / static_cast<double>(n));  // (keeps the evaluations)
  return 0;
}
