// What the excitation design (excitation.cc) and its prediction of identify's std
// (excitation_prediction.cc) share.
#pragma once

#include <algorithm>
#include <limits>
#include <thread>

#include "fivebar/identification/residual.h"
#include "fivebar/model/rest_rule.h"

namespace fivebar::identification {

namespace stages {
/// identify's rest rule on the five-bar (stage_samples.cc; declared in identify_stages.h, whose
/// Ceres stages this unit does not need)
bool held_sample(const Params<double>& p, const Sample& s, const RestThresholds& rest,
                 double angle_noise);
}  // namespace stages

namespace detail {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Runs f(i) for i in [0, n) on up to two threads (the machine's budget), in contiguous chunks.
template <typename F>
void parallel_for(int n, F&& f) {
  const int workers = std::min(2, std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
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
