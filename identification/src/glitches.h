// The glitch passes of log conditioning (condition.cc): what glitch_repair.cc and
// glitch_checks.cc share.
#pragma once

#include "fivebar/identification/condition.h"
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include "fivebar/identification/rates.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"

namespace fivebar::identification {

namespace glitches {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// The median of |v| (a non-finite value counts as infinite).
inline double median_abs(std::vector<double> v) {
  if (v.empty()) return 0;
  for (double& x : v) x = std::isfinite(x) ? std::abs(x) : kInf;
  return median_of(std::move(v));
}

/// One column beyond the cubic of a local fit: its value at sample k, u the sample's scaled time.
using FitColumn = std::function<double(int k, double u)>;

/// A local least-squares cubic (fit_cubic): its coefficients, residuals and frame.
struct LocalCubic {
  Eigen::VectorXd coef;      ///< of 1, u, u^2, u^3, then the extra column if any
  Eigen::VectorXd residual;  ///< fit minus sample, one per fitted sample in order of index
  double t0 = 0, step = 1, x0 = 0;
  /// the cubic (extra column left out) at sample k of `t`, in the column's units
  double at(const std::vector<double>& t, int k) const {
    const double u = (t[k] - t0) / step;
    return Eigen::RowVector4d(1, u, u * u, u * u * u).dot(coef.head<4>()) + x0;
  }
};

/// A burst of up to this many samples that leaves the trend and returns is a glitch run (a step
/// of an angle, glitch_run; adjacent glitches of any column, run_hits).
constexpr int kMaxRun = 3;

// ---- glitch_repair.cc ----

/// Indices of the four neighbours the leave-one-out cubic of sample i uses.
std::array<int, 4> neighbours(int i, int n);

/// Glitch signature at an interior sample: the deviations of both neighbours have the other sign
/// and about 2/3 of its size (the cubic gives them weight 4/6); a step between two samples does
/// not have it (its neighbours deviate by 1/6 and 1/2 of the step).
bool glitch_signature(const std::vector<double>& z, int i);

/// The least-squares fit of samples lo..hi of `x`, less those in `out`, by a cubic in
/// u = (t - t[centre]) / (mean sample step over lo..hi), plus `column` when given. Fitted to
/// x - x[ref]: the offset keeps multi-turn angles exact.
LocalCubic fit_cubic(const std::vector<double>& t, const std::vector<double>& x, int lo, int hi,
                     const std::vector<int>& out, int centre, int ref,
                     const FitColumn& column = {});

/// The glitch of sample i of column `name` (values `x`, before repair), with its expected value.
Glitch make_glitch(const TorqueLog& log, const char* name, const std::vector<double>& x, int i,
                   double expected, double noise);

/// Rejects isolated glitches of one column in place; returns the glitches found.
std::vector<Glitch> reject_column(const TorqueLog& log, const char* name, double sigmas,
                                  std::vector<double>* x, double* noise, double min_threshold);

// ---- glitch_checks.cc ----

/// Absurd values: samples farther from the column's median than 1000 times its interquartile
/// range (at least 1 in the column's unit), or jumping away and back by more than 1000 median
/// steps. No cubic can judge them (a 1e300 spike overflows every
/// leave-one-out fit that uses it, and near the ends it drowns the sample that is really wrong),
/// so they are replaced first, by linear interpolation between the nearest sane samples.
std::vector<Glitch> reject_absurd(const TorqueLog& log, const char* name, std::vector<double>* x);

/// Frozen encoder: three or more equal samples of a moving angle, then a catch-up jump of more
/// than twice the steps around the run. A real mechanism cannot stop dead and resume, and a
/// quantized encoder's runs end with a one-count step, not a jump. The run is interpolated
/// linearly and its samples are rejected, named.
std::vector<Glitch> reject_frozen(const TorqueLog& log, const char* name, std::vector<double>* x);

std::string line_list(const std::vector<Glitch>& g, size_t max_shown = 5);

/// Median |tau - M| (frictionless inverse dynamics of `scene`) over up to 400 samples of the
/// angles `th1, th2` (rates by Savitzky-Golay); failed poses count as infinite.
double torque_mismatch(const Params<double>& scene, const sim::LoadFunction& loads,
                       const TorqueLog& log, const std::vector<double>& th1,
                       const std::vector<double>& th2, double* median_rate);

/// White-noise std of leave-one-out deviations: the rms of those within 4 robust std (efficient
/// like the rms, robust like the median), corrected for the truncation of a Gaussian at 4 std.
double noise_std(const std::vector<double>& z);

/// Steps of the angle column `x` (find_steps): a short run that leaves the trend and returns
/// (glitch_run) is rejected like a glitch, in place; any other step throws LogError naming its
/// line (which side is right cannot be told, and either side fitted with the other gives the
/// rates a spike and the poses an offset).
std::vector<Glitch> runs_or_steps(const TorqueLog& log, const char* name, std::vector<double>* x,
                                  double sigmas);

}  // namespace glitches
}  // namespace fivebar::identification
