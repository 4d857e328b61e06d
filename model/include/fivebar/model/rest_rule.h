// The thresholds of the rest rule (rest.h) and the noise estimate they are derived from. Kept
// apart from rest.h so that the simulator's header needs no Eigen.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace fivebar {

/// Thresholds of the rest rule. The defaults serve motions whose rates are computed, not
/// measured (a simulation's output, an optimized spline): rounding leaves ~1e-14 rad/s there.
/// Measured or differentiated motions derive them from their noise (rest_thresholds).
struct RestThresholds {
  double rate = 1e-9;          ///< [rad/s]: |w_k| at or below is at rest
  double acceleration = 1e-7;  ///< [rad/s^2]: at rest and |dw_k/dt| at or below is stuck
};

/// Thresholds are this many standard deviations of the estimate's noise: a sample at rest
/// passes with probability 1 - 6e-7 per value for Gaussian noise.
inline constexpr double kRestSigmas = 5.0;

/// The thresholds for rate and acceleration estimates with noise standard deviations
/// `rate_noise` [rad/s] and `acceleration_noise` [rad/s^2].
inline RestThresholds rest_thresholds(double rate_noise, double acceleration_noise) {
  return {kRestSigmas * rate_noise, kRestSigmas * acceleration_noise};
}

/// Rounding of the values of f: eps max(1, max |f|). A rate or acceleration given with a motion
/// cannot be known better than the rounding of its angles over one sample step h:
/// rounding_noise(theta) / h, / h^2 (the floors the apps put under the given series' noise).
inline double rounding_noise(const std::vector<double>& f) {
  double largest = 1.0;
  for (double x : f) largest = std::max(largest, std::abs(x));
  return std::numeric_limits<double>::epsilon() * largest;
}

/// Noise standard deviation of a uniformly sampled series f, robustly from its fourth
/// differences: for white noise of deviation s, d4 = f[i] - 4 f[i+1] + 6 f[i+2] - 4 f[i+3] +
/// f[i+4] has deviation sqrt(70) s, and the median absolute d4 is 0.6745 of that. A smooth signal
/// adds h^4 f'''' to d4 (an overestimate where the motion is fast, harmless: the rule only looks
/// at samples that are nearly at rest). Floored at the rounding of the values, eps max(1, |f|).
inline double series_noise(const std::vector<double>& f) {
  const double floor = rounding_noise(f);
  if (f.size() < 9) return floor;
  std::vector<double> d(f.size() - 4);
  for (size_t i = 0; i + 4 < f.size(); ++i) {
    d[i] = std::abs(f[i] - 4.0 * f[i + 1] + 6.0 * f[i + 2] - 4.0 * f[i + 3] + f[i + 4]);
  }
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return std::max(floor, d[d.size() / 2] / 0.6745 / std::sqrt(70.0));
}

}  // namespace fivebar
