// The excitation design's gradients against central differences: the objective's and every
// constraint's, in each variable (the five-bar's and the four-bar's design tests).
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fivebar/identification/excitation.h"

namespace fivebar::testing {

/// The small Fourier design of the gradient tests: 2 s, one period of 3 harmonics, a 0.5 s ramp,
/// 40 design samples, within `torque_limit`
inline identification::ExcitationOptions small_design(double torque_limit) {
  identification::ExcitationOptions o;
  o.duration = 2;
  o.periods = 1;
  o.harmonics = 3;
  o.ramp = 0.5;
  o.design_samples = 40;
  o.torque_limit = torque_limit;
  return o;
}

inline void expect_design_gradients(const identification::ExcitationProblem& problem,
                                    const std::vector<double>& x) {
  identification::DesignValue v;
  ASSERT_TRUE(problem.evaluate(x, true, &v).ok());
  const int n = problem.num_variables(), m = problem.num_constraints();
  for (int i = 0; i < n; ++i) {
    std::vector<double> xp = x, xm = x;
    const double h = 1e-6;
    xp[i] += h;
    xm[i] -= h;
    identification::DesignValue vp, vm;
    ASSERT_TRUE(problem.evaluate(xp, false, &vp).ok());
    ASSERT_TRUE(problem.evaluate(xm, false, &vm).ok());
    const double fd = (vp.objective - vm.objective) / (2 * h);
    EXPECT_NEAR(v.objective_grad[i], fd, 1e-4 * (1 + std::abs(fd))) << "variable " << i;
    for (int r = 0; r < m; ++r) {
      const double cfd = (vp.constraints[r] - vm.constraints[r]) / (2 * h);
      EXPECT_NEAR(v.constraints_grad[static_cast<size_t>(r) * n + i], cfd,
                  1e-4 * (1 + std::abs(cfd)))
          << "constraint " << r << " variable " << i;
    }
  }
}

}  // namespace fivebar::testing
