// Test helpers shared by the identification tests: random samples of the paper mechanism, and
// synthetic logs of it.
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "fivebar/identification/residual.h"
#include "fivebar/identification/synth.h"
#include "fivebar/model/dynamics.h"
#include "paper.h"

namespace fivebar::identification::testing {

using ::fivebar::testing::paper_loads;

/// Random samples: poses, rates (away from 0 so exact sign is fixed), accelerations; torques
/// from the inverse dynamics at `truth` plus an offset so the residual is not zero.
inline std::vector<Sample> random_samples(const Params<double>& truth, int n,
                                          std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(0.5, 2.5), rate(-8, 8), acc(-50, 50);
  std::vector<Sample> out;
  while (static_cast<int>(out.size()) < n) {
    Sample s;
    s.t = 0.1 * out.size();
    s.th1 = angle(rng);
    s.th2 = angle(rng);
    s.w1 = rate(rng);
    s.w2 = rate(rng);
    s.a1 = acc(rng);
    s.a2 = acc(rng);
    s.loads = paper_loads(s.t);
    Evaluation<double> ev;
    if (!inverse_dynamics(truth, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr,
                          EvalOptions{}, &ev)
             .ok()) {
      continue;
    }
    s.tau1 = ev.M1 + 0.3;
    s.tau2 = ev.M2 - 0.2;
    out.push_back(s);
  }
  return out;
}

/// A paper-loads log of `truth` with rates logged: torque noise 0.02 N m, angle noise 1e-5 rad
/// (multisine: the built-in excitation, which reverses both cranks, replaces M1, M2).
inline TorqueLog rated_log(const Params<double>& truth, double duration, std::uint64_t seed,
                           const char* path, bool multisine = false) {
  SynthOptions so;
  so.multisine = multisine;
  so.duration = duration;
  so.torque_noise = 0.02;
  so.angle_noise = 1e-5;
  so.with_rates = true;
  so.seed = seed;
  SynthResult r = synthesize_log(truth, paper_loads, {M_PI / 2, M_PI / 2, 0, 0}, so);
  r.log.path = path;
  return r.status.ok() ? r.log : TorqueLog{};
}

}  // namespace fivebar::identification::testing
