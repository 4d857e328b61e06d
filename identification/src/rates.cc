// Savitzky-Golay differentiation by local least squares on the actual sample times.
#include "fivebar/identification/rates.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace fivebar::identification {

int sg_half_window(const SgOptions& options, double dt) {
  const int min_half = options.order / 2 + 1;
  return std::max(min_half, static_cast<int>(std::lround(options.half_window_s / dt)));
}

void savitzky_golay_taps(const std::vector<double>& t, int i, const SgOptions& options, int* lo,
                         std::vector<double>* d1, std::vector<double>* d2) {
  const int n = static_cast<int>(t.size());
  d1->clear();
  d2->clear();
  *lo = 0;
  if (n < 2) return;
  const double dt = (t.back() - t.front()) / (n - 1);
  const int order = std::max(2, options.order);
  const int m = sg_half_window(options, dt);
  const int width = std::min(n, 2 * m + 1);
  const int deg = std::min(order, width - 1);
  *lo = std::clamp(i - width / 2, 0, n - width);
  Eigen::MatrixXd V(width, deg + 1);
  for (int r = 0; r < width; ++r) {
    const double s = (t[*lo + r] - t[i]) / dt;
    double p = 1.0;
    for (int c = 0; c <= deg; ++c, p *= s) V(r, c) = p;
  }
  // rows of the pseudo-inverse: the polynomial coefficients as weights of the samples
  const Eigen::MatrixXd pinv =
      V.colPivHouseholderQr().solve(Eigen::MatrixXd::Identity(width, width));
  d1->assign(width, 0.0);
  d2->assign(width, 0.0);
  for (int r = 0; r < width; ++r) {
    if (deg >= 1) (*d1)[r] = pinv(1, r) / dt;
    if (deg >= 2) (*d2)[r] = 2.0 * pinv(2, r) / (dt * dt);
  }
}

void savitzky_golay(const std::vector<double>& t, const std::vector<double>& x,
                    const SgOptions& options, std::vector<double>* dx, std::vector<double>* ddx,
                    int step) {
  const int n = static_cast<int>(t.size());
  dx->assign(n, 0.0);
  ddx->assign(n, 0.0);
  if (n < 2) return;
  const double dt = (t.back() - t.front()) / (n - 1);
  const int order = std::max(2, options.order);
  int m = sg_half_window(options, dt);
  const int width = std::min(n, 2 * m + 1);
  const int deg = std::min(order, width - 1);
  Eigen::MatrixXd V(width, deg + 1);
  Eigen::VectorXd y(width);
  for (int i = 0; i < n; i += std::max(1, step)) {
    // window [lo, lo + width) centred on i, shifted inside the log at the ends
    const int lo = std::clamp(i - width / 2, 0, n - width);
    // powers of the scaled time offset (t - t_i) / dt keep the normal equations well conditioned
    for (int r = 0; r < width; ++r) {
      const double s = (t[lo + r] - t[i]) / dt;
      double p = 1.0;
      for (int c = 0; c <= deg; ++c, p *= s) V(r, c) = p;
      y(r) = x[lo + r];
    }
    const Eigen::VectorXd coef = V.colPivHouseholderQr().solve(y);
    (*dx)[i] = deg >= 1 ? coef(1) / dt : 0.0;
    (*ddx)[i] = deg >= 2 ? 2.0 * coef(2) / (dt * dt) : 0.0;
  }
}

}  // namespace fivebar::identification
