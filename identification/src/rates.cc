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

/// The window of the filter at one sample: its first sample, the polynomial's degree and the
/// log's mean step.
struct TapWindow {
  int lo = 0, deg = 0;
  double dt = 1;
};

/// Offsets within this of whole steps are whole steps: the rounding of a uniform grid's stamps
/// (t up to 1e4 s carries about 1e-12 s, 1e-9 of a 1 ms step), not a sampling jitter.
constexpr double kWholeStep = 1e-9;

/// The window at sample i, its scaled offsets (t[lo + r] - t[i]) / dt into s (empty when t has
/// fewer than 2 samples). Where every offset is within kWholeStep of a whole number of steps,
/// the offsets are those whole numbers, so that the windows of a uniform grid repeat bit for bit
/// (the callers factor each distinct window once).
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
  bool whole = true;
  for (int r = 0; r < width; ++r) {
    const double offset = (t[w.lo + r] - t[i]) / w.dt;
    whole = whole && std::abs(offset - std::nearbyint(offset)) <= kWholeStep;
    (*s)[r] = offset;
  }
  if (whole) {
    for (double& offset : *s) offset = std::nearbyint(offset);
  }
  return w;
}

/// The window's least-squares basis: the powers of its offsets s up to its degree
Eigen::MatrixXd powers(const TapWindow& w, const std::vector<double>& s) {
  Eigen::MatrixXd V(s.size(), w.deg + 1);
  for (size_t r = 0; r < s.size(); ++r) {
    double p = 1.0;
    for (int c = 0; c <= w.deg; ++c, p *= s[r]) V(r, c) = p;
  }
  return V;
}

/// The bit patterns of s (a map key that tells every double apart)
void bit_key(const std::vector<double>& s, std::vector<std::uint64_t>* key) {
  key->resize(s.size());
  if (!s.empty()) std::memcpy(key->data(), s.data(), s.size() * sizeof(double));
}

/// The taps of a window (tap_window) from its offsets s
void taps_of(const TapWindow& w, const std::vector<double>& s, std::vector<double>* d1,
             std::vector<double>* d2) {
  const int width = static_cast<int>(s.size());
  const int deg = w.deg;
  const double dt = w.dt;
  const Eigen::MatrixXd V = powers(w, s);
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
  bit_key(offsets_, &key_);
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
  // each distinct window (its offsets, bit for bit) factorized once: the centred windows of a
  // uniform grid repeat up to the rounding of t
  std::map<std::vector<std::uint64_t>, Eigen::ColPivHouseholderQR<Eigen::MatrixXd>> memo;
  std::vector<double> s;
  std::vector<std::uint64_t> key;
  Eigen::VectorXd y;
  for (int i = 0; i < n; i += std::max(1, step)) {
    // window [lo, lo + width) centred on i, shifted inside the log at the ends
    const TapWindow w = tap_window(t, i, options, &s);
    const int width = static_cast<int>(s.size());
    bit_key(s, &key);
    auto it = memo.find(key);
    if (it == memo.end()) {
      // powers of the scaled time offset (t - t_i) / dt keep the normal equations well
      // conditioned
      it = memo.emplace(key, Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(powers(w, s))).first;
    }
    y.resize(width);
    for (int r = 0; r < width; ++r) y(r) = x[w.lo + r];
    const Eigen::VectorXd coef = it->second.solve(y);
    (*dx)[i] = w.deg >= 1 ? coef(1) / w.dt : 0.0;
    (*ddx)[i] = w.deg >= 2 ? 2.0 * coef(2) / (w.dt * w.dt) : 0.0;
  }
}

}  // namespace fivebar::identification
