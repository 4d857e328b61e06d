// 95 % intervals (identification/src/profile.h): Student's t quantile, and the profile-likelihood
// search on cost profiles whose ends are known.
#include <gtest/gtest.h>

#include <cmath>

#include "profile.h"

namespace fivebar::identification::detail {
namespace {

TEST(Intervals, StudentQuantileMatchesTheTables) {
  EXPECT_NEAR(t_quantile_975(0), 1.959964, 1e-6);  // the normal
  EXPECT_NEAR(t_quantile_975(1), 12.7062, 1e-4);
  EXPECT_NEAR(t_quantile_975(2), 4.3027, 1e-4);
  EXPECT_NEAR(t_quantile_975(9), 2.2622, 1e-4);
  EXPECT_NEAR(t_quantile_975(19), 2.0930, 1e-4);
  EXPECT_NEAR(t_quantile_975(1000), 1.9623, 1e-4);
}

TEST(Intervals, ProfileOfAQuadraticCostIsTheWaldInterval) {
  // cost rise (theta - v)^2 / (2 s^2), threshold q^2 / 2: the ends are v -+ q s, found with one
  // re-fit per side
  const double v = 0.3, s = 0.05, q = 1.96;
  int calls = 0;
  const auto rise = [&](double th, int) { return ++calls, 0.5 * std::pow((th - v) / s, 2); };
  const ProfileInterval pi = profile_interval(rise, v, q * s, 0.5 * q * q, 0.0, INFINITY, 1e-4);
  EXPECT_NEAR(pi.low.value, v - q * s, 1e-9);
  EXPECT_NEAR(pi.high.value, v + q * s, 1e-9);
  EXPECT_EQ(pi.refits, 2);
  EXPECT_EQ(calls, 2);
}

TEST(Intervals, ProfileFollowsASkewedCostAndStopsAtLimitsAndPlateaus) {
  // quadratic in log(theta): the ends are v exp(-+ q s), not v -+ q (v s)
  const double v = 0.5, s = 0.4, q = 1.96;
  const auto log_rise = [&](double th, int) {
    return th > 0 ? 0.5 * std::pow(std::log(th / v) / s, 2) : INFINITY;
  };
  ProfileInterval pi = profile_interval(log_rise, v, q * v * s, 0.5 * q * q, 1e-4, INFINITY, 1e-5);
  EXPECT_NEAR(pi.low.value, v * std::exp(-q * s), 2e-4);
  EXPECT_NEAR(pi.high.value, v * std::exp(q * s), 2e-3);
  EXPECT_FALSE(pi.high.unbounded);
  // a cost that levels off below the threshold on the high side (a parameter the data do not
  // bound there), and that stays low down to the parameter's limit on the low side
  const auto plateau = [&](double th, int) { return th > v ? 1.0 - std::exp(v - th) : 0.01; };
  pi = profile_interval(plateau, v, 0.1, 0.5 * q * q, 0.2, INFINITY, 1e-5);
  EXPECT_TRUE(pi.high.unbounded);
  EXPECT_TRUE(std::isinf(pi.high.value));
  EXPECT_DOUBLE_EQ(pi.low.value, 0.2);
  EXPECT_FALSE(pi.low.unbounded);
  // a failed re-fit is reported, not turned into an end
  const auto fails = [&](double th, int) { return th > v ? NAN : 0.0; };
  pi = profile_interval(fails, v, 0.1, 0.5 * q * q, 0.0, INFINITY, 1e-5);
  EXPECT_TRUE(pi.high.failed);
}

}  // namespace
}  // namespace fivebar::identification::detail
