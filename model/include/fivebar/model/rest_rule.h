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

/// Highest difference order series_noise looks at, and the ratio of successive orders' estimates
/// at or above which it takes them as consistent with white noise.
inline constexpr int kNoiseMaxOrder = 8;
inline constexpr double kNoiseFlatRatio = 0.9;

/// Noise standard deviation of a uniformly sampled series f, robustly from its differences. For
/// white noise of deviation s, the k-th difference d_k has deviation sqrt(C(2k, k)) s and the
/// median |d_k| is 0.6745 of that, so s_k = median |d_k| / (0.6745 sqrt(C(2k, k))) estimates s
/// at every order k. A deterministic signal adds to every s_k (median |d + n| >= median |n| for
/// symmetric unimodal noise), by about h^k |f^(k)| / sqrt(C(2k, k)): a finely sampled motion's
/// share falls by a large factor from one order to the next (to zero within the pieces of a
/// polynomial of degree < k), white noise's stays put. So the estimate is s_k at the first order
/// k (1..8) whose successor does not fall below kNoiseFlatRatio s_k: the lowest order that is
/// consistent with white noise, where the motion's share has gone. White noise gives s_1 (no
/// bias); the rates of a quintic spline at 1 ms (quartic pieces) give s_5, 6.6e-7 rad/s on the
/// swing_right optimum where s_4 reads 9.2e-5 (docs/hold.md, docs/dev/figures-optimization.md).
/// Noise whose spectrum falls toward the Nyquist frequency (filtered rates) is read lower than
/// its deviation, at any order. Orders with fewer than 5 differences are not used. Floored at
/// the rounding of the values, eps max(1, |f|).
inline double series_noise(const std::vector<double>& f) {
  const double floor = rounding_noise(f);
  if (f.size() < 9) return floor;
  std::vector<double> d = f, work;
  double previous = 0.0, binomial = 1.0;  // s_(k-1); C(2k, k)
  for (int k = 1; k <= kNoiseMaxOrder && d.size() >= 6; ++k) {
    for (size_t i = 0; i + 1 < d.size(); ++i) d[i] = d[i + 1] - d[i];
    d.pop_back();
    binomial *= 2.0 * (2 * k - 1) / k;
    work = d;  // the median |d_k| (the upper one for an even count)
    for (double& x : work) x = std::abs(x);
    std::nth_element(work.begin(), work.begin() + work.size() / 2, work.end());
    const double s = work[work.size() / 2] / 0.6745 / std::sqrt(binomial);
    if (k > 1 && s >= kNoiseFlatRatio * previous) break;
    previous = s;
  }
  return std::max(floor, previous);
}

}  // namespace fivebar
