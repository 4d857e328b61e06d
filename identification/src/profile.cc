// 95 % intervals: Student's t quantile and profile likelihood (see profile.h).
#include "profile.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace fivebar::identification::detail {

namespace {

constexpr double kNormal975 = 1.959963984540054;

/// The regularized incomplete beta function I_x(a, b) by its continued fraction (modified
/// Lentz), for 0 <= x <= 1.
double incomplete_beta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  // the fraction converges fast for x < (a + 1) / (a + b + 2); else use the symmetry
  if (x > (a + 1) / (a + b + 2)) return 1 - incomplete_beta(b, a, 1 - x);
  const double front =
      std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) +
               b * std::log1p(-x)) / a;
  constexpr double kTiny = 1e-300;
  double f = 1, c = 1, d = 0;
  for (int i = 0; i <= 400; ++i) {
    const int m = i / 2;
    double num = 1;
    if (i > 0) {
      num = i % 2 == 0 ? m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m))
                       : -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
    }
    d = 1 + num * d;
    d = std::abs(d) < kTiny ? 1 / kTiny : 1 / d;
    c = 1 + num / c;
    c = std::abs(c) < kTiny ? kTiny : c;
    f *= c * d;
    if (std::abs(1 - c * d) < 1e-14) break;
  }
  return front * (f - 1);
}

}  // namespace

double t_quantile_975(int dof) {
  if (dof <= 0) return kNormal975;
  // P(|T| > t) = I_{dof / (dof + t^2)}(dof / 2, 1 / 2) = 0.05, decreasing in t: bisection
  const double nu = dof;
  double lo = kNormal975, hi = 2000;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    const double t = 0.5 * (lo + hi);
    (incomplete_beta(0.5 * nu, 0.5, nu / (nu + t * t)) > 0.05 ? lo : hi) = t;
  }
  return 0.5 * (lo + hi);
}

AffineCost::AffineCost(const ceres::CostFunction* inner, Eigen::VectorXd u, Eigen::MatrixXd B,
                       const double* theta)
    : inner_(inner), u_(std::move(u)), B_(std::move(B)), theta_(theta) {
  set_num_residuals(inner->num_residuals());
  mutable_parameter_block_sizes()->push_back(static_cast<int>(B_.cols()));
}

bool AffineCost::Evaluate(double const* const* z, double* residuals, double** jacobians) const {
  const int P = static_cast<int>(B_.rows()), n = static_cast<int>(B_.cols());
  const int m = num_residuals();
  const Eigen::VectorXd x = u_ * *theta_ + B_ * Eigen::Map<const Eigen::VectorXd>(z[0], n);
  const double* xs[] = {x.data()};
  if (jacobians == nullptr || jacobians[0] == nullptr) {
    return inner_->Evaluate(xs, residuals, nullptr);
  }
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  RowMajor Jx(m, P);
  double* jx[] = {Jx.data()};
  if (!inner_->Evaluate(xs, residuals, jx)) return false;
  Eigen::Map<RowMajor>(jacobians[0], m, n) = Jx * B_;
  return true;
}

namespace {

/// One end of the profile interval on `side` (-1 low, +1 high).
ProfileEnd search_side(const std::function<double(double, int)>& rise, double value,
                       double wald_half, double threshold, double limit, int side, double tol,
                       int max_doublings, int* refits) {
  ProfileEnd end;
  const double s = std::sqrt(threshold);
  // g(theta) = sqrt(rise) - sqrt(threshold): < 0 inside, >= 0 outside, linear in theta where
  // the cost is quadratic
  const auto g = [&](double theta, double* out) {
    ++*refits;
    const double r = rise(theta, side);
    if (std::isnan(r)) return false;
    *out = std::sqrt(std::max(0.0, r)) - s;
    return true;
  };
  double a = value, ga = -s, b = value, gb = 0;
  bool bracketed = false;
  double h = wald_half;
  for (int k = 0; k <= max_doublings && !bracketed; ++k, h *= 2) {
    const bool at_limit = side > 0 ? value + h >= limit : value - h <= limit;
    const double theta = at_limit ? limit : value + side * h;
    double gt = 0;
    if (!g(theta, &gt)) {
      end.failed = true;
      return end;
    }
    if (gt >= 0) {
      b = theta, gb = gt, bracketed = true;
    } else {
      a = theta, ga = gt;
      if (at_limit) {  // the interval reaches the parameter's limit
        end.value = limit;
        return end;
      }
    }
  }
  if (!bracketed) {
    end.unbounded = true;
    end.value = side * std::numeric_limits<double>::infinity();
    return end;
  }
  // safeguarded secant (regula falsi kept inside the bracket) to |g| < 1 % of sqrt(threshold)
  for (int it = 0; it < 8 && std::abs(b - a) > tol && gb > 0.01 * s; ++it) {
    const double w = std::clamp(-ga / (gb - ga), 0.05, 0.95);
    const double c = a + w * (b - a);
    double gc = 0;
    if (!g(c, &gc)) {
      end.failed = true;
      return end;
    }
    if (gc < 0) {
      a = c, ga = gc;
    } else {
      b = c, gb = gc;
    }
  }
  end.value = a + (-ga / (gb - ga)) * (b - a);
  return end;
}

}  // namespace

ProfileInterval profile_interval(const std::function<double(double, int)>& rise, double value,
                                 double wald_half, double threshold, double lower_limit,
                                 double upper_limit, double tol, int max_doublings) {
  ProfileInterval out;
  out.low = search_side(rise, value, wald_half, threshold, lower_limit, -1, tol, max_doublings,
                        &out.refits);
  out.high = search_side(rise, value, wald_half, threshold, upper_limit, +1, tol, max_doublings,
                         &out.refits);
  return out;
}

}  // namespace fivebar::identification::detail
