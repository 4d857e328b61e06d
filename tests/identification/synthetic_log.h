// A synthetic torque log of the paper scene's loads and start (the fixture of tests/common),
// for the identification tests.
#pragma once

#include <gtest/gtest.h>

#include "fivebar/identification/synth.h"
#include "paper.h"

namespace fivebar::testing {

/// The sampling and noise of a test log: `duration` s at 1 kHz, Gaussian noise on the torques
/// and angles, the seed.
inline identification::SynthOptions log_options(double duration, double torque_noise,
                                                double angle_noise, std::uint64_t seed) {
  identification::SynthOptions so;
  so.duration = duration;
  so.torque_noise = torque_noise;
  so.angle_noise = angle_noise;
  so.seed = seed;
  return so;
}

/// The paper scene under the Stribeck law of the tests and `coverage-angles --case stribeck`:
/// static Coulomb 0.2 (kinetic 0.12), Stribeck velocity 0.5 rad/s.
inline Params<double> stribeck_truth() {
  return with_law(paper_params(), FrictionLaw::kStribeck,
                  {{Coefficient::kStaticCoulomb, 0.2}, {Coefficient::kStribeckVelocity, 0.5}});
}

/// synth-log of `truth` under the paper loads from the paper start; a failed synthesis fails
/// the calling test (and returns what was made).
inline identification::TorqueLog synthetic_paper_log(const Params<double>& truth,
                                                     const identification::SynthOptions& so,
                                                     const char* path) {
  identification::SynthResult r =
      identification::synthesize_log(truth, paper_loads, paper_initial(), so);
  EXPECT_TRUE(r.status.ok()) << r.status.message;
  r.log.path = path;
  return r.log;
}

}  // namespace fivebar::testing
