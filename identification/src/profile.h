// Internal to identification: 95 % intervals. The Wald interval value +- q std (q the normal or,
// for a covariance estimated from G independent windows, Student's t quantile with G - 1 degrees
// of freedom), and the profile-likelihood interval of a parameter whose cost is far from
// quadratic (the Stribeck law's static_coulomb and stribeck_velocity): docs/identification.md,
// "Intervals".
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <functional>
#include <limits>

namespace fivebar::identification::detail {

/// The 0.975 quantile of Student's t with `dof` degrees of freedom (the normal's 1.95996 for
/// dof <= 0, meaning infinitely many): the half-width of a 95 % interval in std.
double t_quantile_975(int dof);

/// A cost function of a reduced parameter vector z (B.cols() values): x = u theta + B z, wrapping
/// `inner` (one parameter block of x.size() values, not owned), theta read from `theta` at every
/// evaluation (the profiled parameter's fixed value, changed between solves).
class AffineCost : public ceres::CostFunction {
 public:
  AffineCost(const ceres::CostFunction* inner, Eigen::VectorXd u, Eigen::MatrixXd B,
             const double* theta);
  bool Evaluate(double const* const* z, double* residuals, double** jacobians) const override;

 private:
  const ceres::CostFunction* inner_;
  Eigen::VectorXd u_;
  Eigen::MatrixXd B_;
  const double* theta_;
};

/// One side's end of a profile interval.
struct ProfileEnd {
  double value = std::numeric_limits<double>::quiet_NaN();
  bool unbounded = false;  ///< the cost never rose enough before the search gave up (no end)
  bool failed = false;     ///< a refit failed (the Wald end is then kept)
};

struct ProfileInterval {
  ProfileEnd low, high;
  int refits = 0;
};

/// The profile-likelihood interval {theta: rise(theta) <= threshold} around `value`, searched on
/// each side from the Wald end (value -+ wald_half) outwards, doubling the step up to `max_doublings`
/// times (or to `lower_limit` / `upper_limit`, where the interval then ends), then narrowed by a
/// safeguarded secant on sqrt(rise) (linear in theta where the cost is quadratic) to `tol`.
/// rise(theta, side): the least cost with the parameter fixed at theta minus the least cost
/// overall (negative values count as 0), NaN when the refit fails; side -1 (low) or +1 (high)
/// lets the caller warm-start each refit from the last one on the same side.
ProfileInterval profile_interval(const std::function<double(double, int)>& rise, double value,
                                 double wald_half, double threshold, double lower_limit,
                                 double upper_limit, double tol, int max_doublings = 5);

}  // namespace fivebar::identification::detail
