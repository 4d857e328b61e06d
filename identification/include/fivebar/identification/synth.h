// Synthetic torque logs: simulate a scene, sample, add sensor noise and quantization.
#pragma once

#include <array>
#include <vector>
#include <cstdint>
#include <limits>

#include "fivebar/identification/torque_log.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::identification {

struct SynthOptions {
  double rate_hz = 1000;    ///< sampling rate [Hz]
  double duration = 10;     ///< [s]
  double torque_noise = 0;  ///< std of the Gaussian noise on tau1, tau2 [N m]
  double angle_noise = 0;   ///< std of the Gaussian noise on theta1, theta2 [rad]
  double rate_noise = 0;    ///< std of the Gaussian noise on omega1, omega2 [rad/s]
  double quantization = 0;  ///< encoder step [rad]: angles rounded to multiples (0: none)
  std::uint64_t seed = 1;   ///< std::mt19937_64 seed (same seed, same log)
  bool with_rates = false;  ///< write omega1, omega2, alpha1, alpha2 (exact, + rate_noise)
  bool multisine = false;   ///< replace the scene's M1, M2 by the multi-sine fitted (fit_multisine)
  /// the multi-sine's |M1|, |M2| at most this [N m] (fit_multisine; infinity: no limit)
  double torque_limit = std::numeric_limits<double>::infinity();
  sim::Options sim;         ///< solver settings (duration and output_step are overridden)
};

struct SynthResult {
  Status status;  ///< not ok: the simulation failed (log empty)
  TorqueLog log;
  sim::Stats stats;
  /// sign changes of each joint's relative rate: the five-bar's O, B, C, D, D0; the four-bar's
  /// O, B, C, D0 (slot 4 unused)
  std::array<int, kJoints> reversals{};
  double multisine_factor = 1;        ///< the multi-sine's scale (fit_multisine)
  bool multisine_holding_bias = false;  ///< its biases are the start pose's holding torques
};

/// Built-in excitation: the scene's M3, F, F_angle with M1, M2 replaced by sums of four sines
/// (0.3 to 3.1 Hz, Schroeder-like phases) around a bias that balances the paper scene's mean
/// load, so that both cranks swing back and forth and every joint's relative rate changes sign.
/// These are the paper scene's tones; synthesize_log fits them to other mechanisms
/// (fit_multisine).
sim::LoadFunction multisine_loads(const sim::LoadFunction& scene_loads);

/// Simulates `params` from `initial` under `loads` (or the multi-sine fitted to the mechanism and
/// torque_limit by fit_multisine: a mechanism it cannot run on at any scale fails), samples at
/// rate_hz, adds noise (torques: the applied M1, M2 plus noise; angles: plus noise, then
/// quantized). Comments of the log are left empty for the caller.
SynthResult synthesize_log(const Params<double>& params, const sim::LoadFunction& loads,
                           const sim::Initial& initial, const SynthOptions& options);

/// The four-bar's log (dof 1: t, theta1, tau1, and omega1, alpha1 with rates) of a run under the
/// scene's loads. The built-in multi-sine drives the five-bar's two cranks: options.multisine
/// fails here.
SynthResult synthesize_log(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                           const sim::Initial& initial, const SynthOptions& options);

/// The log a sensor records along `rows` (t, theta1..2, omega1..4, alpha1..2, M1, M2), into
/// out->log and out->reversals: noise in one fixed order of draws per row (tau1, tau2, theta1,
/// theta2, omega1, omega2, from opt.seed), torques plus the actuators' offsets, angles
/// quantized. Used by synthesize_log and for a given motion (`synth-log --motion`).
void sample_log(const Params<double>& params, const std::vector<sim::Row>& rows,
                const SynthOptions& opt, SynthResult* out);
/// The same for the four-bar's rows (crank in slot 0, M1): draws tau1, theta1, omega1 per row.
void sample_log(const FourBarParams& params, const std::vector<sim::Row>& rows,
                const SynthOptions& opt, SynthResult* out);

/// Sign changes of each joint's relative rate over a sequence of rate samples (zeros keep the
/// previous sign).
std::array<int, kJoints> count_reversals(const std::vector<std::array<double, kJoints>>& rates);

}  // namespace fivebar::identification
