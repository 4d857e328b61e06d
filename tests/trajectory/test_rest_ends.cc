// A rest-to-rest trajectory starts and ends held still. Its trajectory rows there are
// at rest (both cranks stuck) with the holding torques of `fivebar hold`, and the optimizer's own
// torques (its torque constraint) agree with them.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "fivebar/model/rest.h"
#include "fivebar/model/rest_rule.h"
#include "fivebar/trajectory/bspline.h"
#include "fivebar/trajectory/problem.h"

#include "paper.h"

namespace fivebar::trajectory {
namespace {

// the required tolerance on holding torques
constexpr double kTorqueTol = 1e-9;

TEST(RestEnds, TrajectoryEndsAreHeldWithTheHoldingTorques) {
  const sim::LoadFunction loads = [](double) { return testing::paper_static_loads(); };
  const std::array<double, 2> start = {M_PI / 2, M_PI / 2}, goal = {2.4, 2.0};
  const double duration = 0.5;
  const TrajectoryProblem problem(paper_params(), loads, RestToRest(10, duration, start, goal),
                                  ProblemOptions{});
  const std::vector<double> x = problem.motion().minimum_jerk();
  std::vector<sim::Row> rows;
  ASSERT_TRUE(problem.rows(x.data(), 1e-3, &rows).ok());
  const std::array<double, 2> poses[2] = {start, goal};
  const sim::Row* ends[2] = {&rows.front(), &rows.back()};
  for (int e = 0; e < 2; ++e) {
    const sim::Row& r = *ends[e];
    Holding<double> h;
    ASSERT_TRUE(holding_torques(paper_params(), loads(r.t), poses[e][0], poses[e][1],
                                EvalOptions{}, &h)
                    .ok());
    EXPECT_EQ(r.mode[0], kStuck) << "end " << e;
    EXPECT_EQ(r.mode[4], kStuck) << "end " << e;
    EXPECT_NEAR(r.M1, h.M1, kTorqueTol) << "end " << e;
    EXPECT_NEAR(r.M2, h.M2, kTorqueTol) << "end " << e;
    EXPECT_NEAR(r.hold_range[0], h.M1_min, kTorqueTol) << "end " << e;
    EXPECT_NEAR(r.hold_range[3], h.M2_max, kTorqueTol) << "end " << e;
    double M1 = 0, M2 = 0;
    ASSERT_TRUE(problem.torques(x.data(), r.t, &M1, &M2).ok());
    EXPECT_NEAR(M1, h.M1, kTorqueTol) << "end " << e;
    EXPECT_NEAR(M2, h.M2, kTorqueTol) << "end " << e;
  }
  // in between, the cranks move: no row is at rest
  for (size_t i = 1; i + 1 < rows.size(); ++i) {
    ASSERT_FALSE(rows[i].mode[0] == kStuck && rows[i].mode[4] == kStuck) << "t = " << rows[i].t;
  }
}

// An oscillating planned motion like swing_right's optimum (85 control points over
// 0.5 s, rows every 1 ms): its control points oscillate 0.05 rad about the straight line with a
// period of 8 control points (20 Hz); the first two and last two free ones stay at the ends, so
// the rows next to the ends move slowly (1e-4 rad/s), as swing_right's last rows do.
struct OscillatingSpline {
  RestToRest motion{85, 0.5, {M_PI / 2, M_PI / 2}, {0.7, 0.6}};
  std::vector<double> x;
  OscillatingSpline() {
    const int m = motion.free_per_joint();
    for (int j = 0; j < 2; ++j) {
      const double a = motion.start()[j], b = motion.goal()[j];
      for (int v = 0; v < m; ++v) {
        const double u = (v + 1.0) / (m + 1.0);
        x.push_back(v <= 1       ? a
                    : v >= m - 2 ? b
                                 : a + u * (b - a) + 0.05 * std::sin(2 * M_PI * v / 8));
      }
    }
  }
  // series q (0 angle, 1 rate, 2 acceleration) of joint j on the 1 ms grid
  std::vector<double> series(int q, int j) const {
    std::vector<double> f;
    for (int i = 0; i <= 500; ++i) f.push_back(motion.state(x.data(), 1e-3 * i)[q][j]);
    return f;
  }
};

// the simpler estimate series_noise improves on: fourth differences only
// (median |d4| / (0.6745 sqrt 70))
double fourth_difference_noise(const std::vector<double>& f) {
  std::vector<double> d;
  for (size_t i = 0; i + 4 < f.size(); ++i) {
    d.push_back(std::abs(f[i] - 4 * f[i + 1] + 6 * f[i + 2] - 4 * f[i + 3] + f[i + 4]));
  }
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2] / 0.6745 / std::sqrt(70.0);
}

TEST(RestNoise, FinelySampledSplineIsNotNoiseAndWhiteNoiseIsMeasured) {
  const OscillatingSpline spline;
  std::mt19937_64 rng(12);
  for (int q = 0; q < 2; ++q) {
    const std::vector<double> f = spline.series(q, 0);
    // the motion's own high-order content: what the fourth differences read as noise
    EXPECT_GT(fourth_difference_noise(f), q == 0 ? 1e-7 : 1e-4) << "series " << q;
    EXPECT_LT(series_noise(f), q == 0 ? 1e-9 : 1e-5) << "series " << q;
    // white noise of real logs' size (angles 1e-5 rad, rates 1e-3 rad/s in datasets/logs)
    for (double sigma : q == 0 ? std::vector<double>{1e-6, 1e-5, 1e-4}
                               : std::vector<double>{1e-4, 1e-3, 1e-2}) {
      std::normal_distribution<double> noise(0.0, sigma);
      std::vector<double> g = f;
      for (double& v : g) v += noise(rng);
      EXPECT_NEAR(series_noise(g) / sigma, 1.0, 0.2) << "series " << q << ", sigma " << sigma;
    }
  }
}

// optimize's trajectory rows equal `fivebar inverse` on the same motion: inverse derives its
// rest thresholds from the noise it estimates in the given rates and accelerations
TEST(RestNoise, PlannedRowsEqualInverseWithThresholdsFromTheirNoise) {
  const OscillatingSpline spline;
  const sim::LoadFunction loads = [](double) { return testing::paper_static_loads(); };
  const TrajectoryProblem problem(paper_params(), loads, spline.motion, ProblemOptions{});
  std::vector<sim::Row> rows, inverse;
  ASSERT_TRUE(problem.rows(spline.x.data(), 1e-3, &rows).ok());
  const double h = 1e-3, rounding = rounding_noise(spline.series(0, 0)) / h;
  const auto noise = [&](int q, double floor, bool fourth) {
    double worst = floor;
    for (int j = 0; j < 2; ++j) {
      const std::vector<double> f = spline.series(q, j);
      worst = std::max(worst, fourth ? fourth_difference_noise(f) : series_noise(f));
    }
    return worst;
  };
  for (bool fourth : {true, false}) {
    const RestThresholds rest =
        rest_thresholds(noise(1, rounding, fourth), noise(2, rounding / h, fourth));
    ASSERT_TRUE(sim::inverse_rows(paper_params(), loads, rows, &inverse, rest)
                    .ok());
    double gap = 0.0;
    for (size_t i = 0; i < rows.size(); ++i) {
      gap = std::max({gap, std::abs(inverse[i].M1 - rows[i].M1),
                      std::abs(inverse[i].M2 - rows[i].M2)});
    }
    // the fourth differences (the estimate before) put slow rows near the ends at rest
    if (fourth) {
      EXPECT_GT(gap, 1e-3);
    } else {
      EXPECT_LE(gap, kTorqueTol);
    }
  }
}

}  // namespace
}  // namespace fivebar::trajectory
