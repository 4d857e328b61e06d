// Issue 14: a rest-to-rest trajectory starts and ends held still. Its trajectory rows there are
// at rest (both cranks stuck) with the holding torques of `fivebar hold`, and the optimizer's own
// torques (its torque constraint) agree with them.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "fivebar/model/rest.h"
#include "fivebar/trajectory/bspline.h"
#include "fivebar/trajectory/problem.h"

#include "paper.h"

namespace fivebar::trajectory {
namespace {

// the tolerance on holding torques
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

}  // namespace
}  // namespace fivebar::trajectory
