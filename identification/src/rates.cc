// Savitzky-Golay differentiation by local least squares on the actual sample times.
#include "fivebar/identification/rates.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>

namespace fivebar::identification {

int sg_half_window(const SgOptions& options, double dt) {
  const int min_half = options.order / 2 + 1;
  return std::max(min_half, static_cast<int>(std::lround(options.half_window_s / dt)));
}

namespace {

/// The window of savitzky_golay_taps at sample i: its first sample, the polynomial's degree, the
/// mean step and the scaled offsets (t[lo + r] - t[i]) / dt (empty when t has fewer than 2).
struct TapWindow {
  int lo = 0, deg = 0;
  double dt = 1;
};

TapWindow tap_window(const std::vector<double>& t, int i, const SgOptions& options,
                     std::vector<double>* s) {
  TapWindow w;
  s->clear();
  const int n = static_cast<int>(t.size());
  if (n < 2) return w;
  w.dt = (t.back() - t.front()) / (n - 1);
  const int order = std::max(2, options.order);
  const int m = sg_half_window(options, w.dt);
  const int width = std::min(n, 2 * m + 1);
  w.deg = std::min(order, width - 1);
  w.lo = std::clamp(i - width / 2, 0, n - width);
  s->resize(width);
  for (int r = 0; r < width; ++r) (*s)[r] = (t[w.lo + r] - t[i]) / w.dt;
  return w;
}

/// The taps of a window (tap_window) from its offsets s
void taps_of(const TapWindow& w, const std::vector<double>& s, std::vector<double>* d1,
             std::vector<double>* d2) {
  const int width = static_cast<int>(s.size());
  const int deg = w.deg;
  const double dt = w.dt;
  Eigen::MatrixXd V(width, deg + 1);
  for (int r = 0; r < width; ++r) {
    double p = 1.0;
    for (int c = 0; c <= deg; ++c, p *= s[r]) V(r, c) = p;
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

}  // namespace

void savitzky_golay_taps(const std::vector<double>& t, int i, const SgOptions& options, int* lo,
                         std::vector<double>* d1, std::vector<double>* d2) {
  d1->clear();
  d2->clear();
  std::vector<double> s;
  const TapWindow w = tap_window(t, i, options, &s);
  *lo = w.lo;
  if (!s.empty()) taps_of(w, s, d1, d2);
}

SgTapCache::SgTapCache(const std::vector<double>& t, const SgOptions& options)
    : t_(t), options_(options) {}

void SgTapCache::taps(int i, int* lo, const std::vector<double>** d1,
                      const std::vector<double>** d2) {
  const TapWindow w = tap_window(t_, i, options_, &offsets_);
  *lo = w.lo;
  key_.resize(offsets_.size());
  if (!offsets_.empty()) std::memcpy(key_.data(), offsets_.data(), offsets_.size() * sizeof(double));
  auto it = memo_.find(key_);
  if (it == memo_.end()) {
    it = memo_.emplace(key_, Taps()).first;
    if (!offsets_.empty()) taps_of(w, offsets_, &it->second.d1, &it->second.d2);
  }
  *d1 = &it->second.d1;
  *d2 = &it->second.d2;
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
