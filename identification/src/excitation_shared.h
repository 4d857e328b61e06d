// What the excitation design (excitation.cc) and its prediction of identify's std
// (excitation_prediction.cc) share (identify's rest rule of a sample: setup_shared.h).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <thread>

#include "fivebar/identification/excitation.h"

namespace fivebar::identification {

namespace detail {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// The prior's information on the parameters of dp (DesignParameters::prior_std: 1 / std^2 on
/// the diagonal, 0 where there is none), in the units of the Fisher information.
inline Eigen::MatrixXd prior_fisher(const DesignParameters& dp) {
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(dp.size(), dp.size());
  for (int i = 0; i < static_cast<int>(dp.prior_std.size()); ++i) {
    if (dp.prior_std[i] > 0) F(i, i) = 1.0 / (dp.prior_std[i] * dp.prior_std[i]);
  }
  return F;
}

/// The actuator columns in closed form, after the Jet parameters: tau_j = M_j + offset_j +
/// Fc_j sign(w_j) + Fv_j w_j for the dp.actuator / kActuatorPerMotor motors (the five-bar's two,
/// the four-bar's crank).
inline void actuator_columns(const DesignParameters& dp, const MotionState& s, SampleTerms* out) {
  const int c0 = dp.friction + dp.inertial;
  const double w[2] = {s.w1, s.w2};
  for (int j = 0; j < dp.actuator / kActuatorPerMotor; ++j) {
    const int c = c0 + kActuatorPerMotor * j;
    out->J(j, c) = 1.0;
    out->J(j, c + 1) = (w[j] > 0) - (w[j] < 0);
    out->J(j, c + 2) = w[j];
  }
}

/// Runs f(i) for i in [0, n) on up to two threads (the machine's budget), in contiguous chunks.
template <typename F>
void parallel_for(int n, F&& f) {
  const int workers =
      std::min(2, std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  if (workers == 1 || n < 64) {
    for (int i = 0; i < n; ++i) f(i);
    return;
  }
  const int half = n / 2;
  std::thread other([&] {
    for (int i = half; i < n; ++i) f(i);
  });
  for (int i = 0; i < half; ++i) f(i);
  other.join();
}

}  // namespace detail
}  // namespace fivebar::identification
