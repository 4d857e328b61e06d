// Savitzky-Golay rates: exact on polynomials up to the order, accurate on smooth motion.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "fivebar/identification/rates.h"
#include "smoothing_bias.h"

namespace fivebar::identification {
namespace {

/// A 1 kHz grid whose times are rounded as a log's are (i * 1e-3), with a jittered stretch whose
/// windows are all distinct, and a smooth motion on it
void rounded_grid(std::vector<double>* t, std::vector<double>* x) {
  for (int i = 0; i < 600; ++i) {
    const double jitter = i > 250 && i < 320 ? 2e-5 * std::sin(1.3 * i) : 0.0;
    t->push_back(i * 1e-3 + jitter);
    x->push_back(std::sin(5.0 * t->back()) + 0.3 * std::cos(11.0 * t->back()));
  }
}

TEST(SavitzkyGolay, CachedTapsAndRatesAreTheDirectOnesBitForBit) {
  // the cache and the filter factorize each distinct window once: the same taps and rates as
  // one least-squares solve per sample, at the ends, on the jittered stretch and between
  std::vector<double> t, x;
  rounded_grid(&t, &x);
  const SgOptions sg{0.012, 5};
  SgTapCache cache(t, sg);
  std::vector<double> dx, ddx;
  savitzky_golay(t, x, sg, &dx, &ddx);
  const int n = static_cast<int>(t.size());
  const double dt = (t.back() - t.front()) / (n - 1);
  for (int i = 0; i < n; ++i) {
    int lo = -1, lo_direct = -2;
    const std::vector<double>*d1 = nullptr, *d2 = nullptr;
    std::vector<double> e1, e2;
    cache.taps(i, &lo, &d1, &d2);
    savitzky_golay_taps(t, i, sg, &lo_direct, &e1, &e2);
    ASSERT_EQ(lo, lo_direct) << i;
    EXPECT_EQ(*d1, e1) << i;
    EXPECT_EQ(*d2, e2) << i;
    // the rates: the order-5 polynomial through the window, solved at this sample alone
    const int width = static_cast<int>(e1.size());
    Eigen::MatrixXd V(width, 6);
    Eigen::VectorXd y(width);
    // the offsets as the filter reads them: whole steps where every one is within 1e-9 of one
    std::vector<double> offsets(width);
    bool whole = true;
    for (int r = 0; r < width; ++r) {
      offsets[r] = (t[lo + r] - t[i]) / dt;
      whole = whole && std::abs(offsets[r] - std::nearbyint(offsets[r])) <= 1e-9;
    }
    for (int r = 0; r < width; ++r) {
      const double s = whole ? std::nearbyint(offsets[r]) : offsets[r];
      double p = 1.0;
      for (int c = 0; c <= 5; ++c, p *= s) V(r, c) = p;
      y(r) = x[lo + r];
    }
    const Eigen::VectorXd coef = V.colPivHouseholderQr().solve(y);
    EXPECT_EQ(dx[i], coef(1) / dt) << i;
    EXPECT_EQ(ddx[i], 2.0 * coef(2) / (dt * dt)) << i;
  }
}

TEST(SavitzkyGolay, AUniformGridsWindowsAreOneWindowJitteredOnesAreTheirOwn) {
  // the rounded stamps of a uniform grid give every centred window the same taps bit for bit (one
  // factorization); a jitter of 2e-5 s (2 % of a step) is read as it is
  std::vector<double> t, x;
  rounded_grid(&t, &x);
  const SgOptions sg{0.012, 5};
  int lo = 0;
  std::vector<double> d1_ref, d2_ref, d1, d2;
  savitzky_golay_taps(t, 100, sg, &lo, &d1_ref, &d2_ref);
  int same = 0, jittered_differ = 0;
  for (int i = 20; i < 580; ++i) {
    savitzky_golay_taps(t, i, sg, &lo, &d1, &d2);
    const bool in_jitter = lo + static_cast<int>(d1.size()) > 251 && lo < 320;
    if (in_jitter) {
      jittered_differ += d1 != d1_ref;
    } else {
      EXPECT_EQ(d1, d1_ref) << i;
      EXPECT_EQ(d2, d2_ref) << i;
      ++same;
    }
  }
  EXPECT_GT(same, 400);
  EXPECT_GT(jittered_differ, 60);
}

TEST(SmoothingBias, HighOrderCacheIsTheDirectReconstructionBitForBit) {
  // the reconstruction's terms of two motions and its weights, windows cut short at the ends
  // and off-centre as the reversals cut them
  std::vector<double> t, x;
  rounded_grid(&t, &x);
  std::vector<double> x2(x.size());
  for (size_t i = 0; i < x.size(); ++i) x2[i] = std::cos(3.0 * t[i]);
  const double dt = (t.back() - t.front()) / (t.size() - 1);
  const int n = static_cast<int>(t.size()), reach = 24;
  detail::HighOrderCache cache(t, dt, 5);
  for (int i = 0; i < n; ++i) {
    const int a = std::max(0, i - reach - (i % 3 == 0 ? 0 : -5)), b = std::min(n - 1, i + reach);
    EXPECT_EQ(cache.terms(x, i, a, b), detail::high_order_terms(t, x, i, a, b, dt, 5)) << i;
    EXPECT_EQ(cache.terms(x2, i, a, b), detail::high_order_terms(t, x2, i, a, b, dt, 5)) << i;
    EXPECT_EQ(cache.weights(i, a, b), detail::high_order_weights(t, i, a, b, dt, 5)) << i;
  }
}

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
