// Logs as encoders and loggers write them: unwrapping of wrapped angles, rejection of isolated
// glitches, degrees told from radians by the motion, and robust white-noise levels. Everything
// here is data: the caller (identify, and through it the app) reports it. docs/identification.md
// describes the rules for users.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fivebar/identification/torque_log.h"
#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::identification {

struct ConditionOptions {
  bool unwrap = true;           ///< undo jumps of one turn (2 pi) between consecutive samples
  bool reject_glitches = true;  ///< interpolate isolated glitches and leave their samples out
  /// a sample is a glitch when it leaves the cubic through its four neighbours by more than this
  /// many robust standard deviations of that leave-one-out deviation (and more than the floor
  /// of the motion's own curvature, for noise-free logs)
  double glitch_sigmas = 12.0;
  /// more glitches than this fraction of one column is not "isolated glitches": LogError
  double max_glitch_fraction = 0.01;
  /// samples already rejected (by index; a refit of a log conditioned before, whose glitches
  /// were interpolated and no longer show): left out of the fit like glitches
  std::vector<int> rejected_before;
  /// > 0: the torques' white-noise std as measured before they were shifted for a delay (the
  /// shift's interpolation smooths the noise, which the leave-one-out estimate then finds too
  /// small); torque_variance_factor: what is left of its variance per sample (the sum of the
  /// interpolation's squared weights), 1 for a log as logged
  double torque_noise[2] = {0, 0};
  double torque_variance_factor = 1;
};

/// One rejected sample.
struct Glitch {
  int index = 0;        ///< sample index (0-based, log order)
  int line = 0;         ///< line of the file (1-based)
  std::string column;   ///< theta1, theta2, tau1, tau2 (omega1/2, alpha1/2 when logged)
  double value = 0;     ///< as in the file (angles: before unwrapping)
  double expected = 0;  ///< from its four neighbours (angles: in the same turn as value)
  double sigmas = 0;    ///< |value - expected| in robust standard deviations
};

/// The first step of an angle series between two samples that is no motion (an encoder slip or
/// reset, a gap, a glitch): the check identify applies to each logged angle (an isolated spike of
/// the first differences beyond `sigmas` robust std of their leave-one-out deviation and beyond
/// the floor of the motion's own third differences). Returns the index of the first sample
/// after the step, with its size beyond the trend in *size [the series' unit]; -1 when none.
int first_angle_step(const std::vector<double>& t, const std::vector<double>& x, double* size,
                     double sigmas = ConditionOptions{}.glitch_sigmas);

/// The log after conditioning, and what was done to it.
struct ConditionedLog {
  TorqueLog log;               ///< unwrapped angles, glitches replaced by their interpolation
  std::vector<char> rejected;  ///< per sample: 1 if one of its values was a glitch
  int unwrapped[2] = {0, 0};   ///< one-turn jumps undone in theta1, theta2
  std::vector<Glitch> glitches;
  /// robust white-noise std of the logged columns (leave-one-out cubic deviation, MAD-based)
  double angle_noise[2] = {0, 0}, torque_noise[2] = {0, 0}, rate_noise[2] = {0, 0};
  double accel_noise[2] = {0, 0};  ///< of logged accelerations (their glitches are rejected too)
  /// per-sample variance of the torque noise over torque_noise^2 (ConditionOptions)
  double torque_variance_factor = 1;
  std::vector<std::string> notes;  ///< one sentence per thing done (unwrapping, rejections)
};

/// Unwraps and cleans `log` (see ConditionOptions): single glitches, then adjacent pairs of bad
/// samples (predicted from the two samples on each side), in every logged column. Throws
/// LogError naming the column and the first lines when a column has more glitches than
/// max_glitch_fraction allows, and naming the line when an angle steps between two samples and
/// stays there (an encoder slip or reset: which side is right cannot be told).
ConditionedLog condition_log(const TorqueLog& log, const ConditionOptions& options);

/// Jumps of one turn undone in place: a step that differs from the previous step by 2 pi within
/// pi/2 is a wrap (encoders that report (-pi, pi] or [0, 2 pi)); returns how many were undone.
int unwrap_angles(std::vector<double>* theta);

/// Leave-one-out deviation of every sample from the cubic through its four nearest neighbours
/// (two on each side inside the log, one-sided at the ends), divided by the deviation's noise
/// gain so that white noise of std s gives deviations of std s. Non-finite results are +inf.
std::vector<double> loo_deviation(const std::vector<double>& t, const std::vector<double>& x,
                                  std::vector<double>* expected = nullptr);

/// 1.4826 times the median of |v| (robust std of zero-mean values); 0 for an empty vector.
double robust_std(std::vector<double> v);

/// The reading of angle_units_from_motion whose columns theta1 and theta2 are each other's.
inline constexpr const char* kSwappedAngles = "radians with theta1 and theta2 swapped";

/// Empty if the log's angles read as radians explain its torques, else the evidence that they
/// are in another unit, which is set in `unit` (degrees, turns, gradians, the counts of a
/// common encoder resolution, or kSwappedAngles: radians in each other's column): with rates
/// estimated from the angles, the scene's frictionless inverse dynamics is compared with the logged
/// torques for each reading (median |tau - M| over the log, and the median crank rate); another
/// unit is reported only when its reading explains the torques four times better than radians and
/// to within half their median size.
std::string angle_units_from_motion(const Params<double>& scene, const sim::LoadFunction& loads,
                                    const TorqueLog& log, std::string* unit);

/// A reading of a log's crank angles (theta1, and theta2 for two cranks; radians) against its
/// torques: the median over the log of the largest |logged - frictionless inverse torque| of its
/// cranks [N m], and the median crank rate [rad/s] in *median_rate.
using TorqueMismatch = std::function<double(
    const std::vector<double>& theta1, const std::vector<double>& theta2, double* median_rate)>;

/// angle_units_from_motion over any mechanism, its readings judged by `mismatch`; a log of one
/// crank has no swapped reading.
std::string angle_units_from_motion(const TorqueLog& log, const TorqueMismatch& mismatch,
                                    std::string* unit);

}  // namespace fivebar::identification
