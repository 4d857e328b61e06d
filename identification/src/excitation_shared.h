// What the excitation design (excitation.cc) and its prediction of identify's std
// (excitation_prediction.cc) share (identify's rest rule of a sample: setup_shared.h).
#pragma once

#include <algorithm>
#include <limits>
#include <thread>

namespace fivebar::identification {

namespace detail {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
