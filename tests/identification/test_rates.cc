// Savitzky-Golay rates: exact on polynomials up to the order, accurate on smooth motion.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fivebar/identification/rates.h"

namespace fivebar::identification {
namespace {

TEST(SavitzkyGolay, ExactOnAQuinticIncludingTheEnds) {
  // order 5 reproduces a quintic exactly, at the ends too (shifted window); round-off only
  constexpr double kTol = 1e-6;
  std::vector<double> t, x;
  for (int i = 0; i < 200; ++i) {
    const double s = i * 1e-3;
    t.push_back(s);
    x.push_back(1 + 2 * s - 3 * s * s + 4 * std::pow(s, 3) - 5 * std::pow(s, 4) +
                6 * std::pow(s, 5));
  }
  std::vector<double> dx, ddx;
  savitzky_golay(t, x, SgOptions{0.010, 5}, &dx, &ddx);
  for (size_t i = 0; i < t.size(); ++i) {
    const double s = t[i];
    EXPECT_NEAR(dx[i], 2 - 6 * s + 12 * s * s - 20 * std::pow(s, 3) + 30 * std::pow(s, 4), kTol);
    EXPECT_NEAR(ddx[i], -6 + 24 * s - 60 * s * s + 120 * std::pow(s, 3), 1e3 * kTol);
  }
}

TEST(SavitzkyGolay, SineAtFourHertzWithUnevenSampling) {
  // 4 Hz (the paper's fastest forcing) sampled at ~1 kHz with 20 % jitter: relative errors of
  // the centred order-5 fit over 21 samples are ~ (w h)^6 / ... << 1e-3
  std::vector<double> t, x;
  double s = 0;
  for (int i = 0; i < 1000; ++i) {
    t.push_back(s);
    x.push_back(std::sin(8 * M_PI * s));
    s += 1e-3 * (1.0 + 0.2 * std::sin(1.7 * i));
  }
  std::vector<double> dx, ddx;
  savitzky_golay(t, x, SgOptions{}, &dx, &ddx);
  const double w = 8 * M_PI;
  for (size_t i = 20; i + 20 < t.size(); ++i) {
    EXPECT_NEAR(dx[i], w * std::cos(w * t[i]), 1e-3 * w);
    EXPECT_NEAR(ddx[i], -w * w * std::sin(w * t[i]), 1e-3 * w * w);
  }
}

}  // namespace
}  // namespace fivebar::identification
