// Rates and accelerations from sampled angles: local polynomial least squares (Savitzky-Golay).
#pragma once

#include <cstdint>
#include <map>
#include <vector>

namespace fivebar::identification {

/// Savitzky-Golay settings. Each sample's derivatives come from the least-squares polynomial of
/// degree `order` through the 2 * half_window + 1 samples centred on it (the actual times are
/// used, so uneven sampling is handled); near the ends the window is shifted inside the log and
/// the polynomial evaluated off-centre.
///
/// Why SG and these defaults: SG is a zero-phase FIR differentiator that keeps polynomials up
/// to `order` exactly, so it adds no lag (lag would bias friction against inertia) and bias and
/// noise trade off through one window length. The motion of a five-bar with Coulomb friction has
/// acceleration kinks at every slip reversal (up to 400 rad/s^2 on the paper scene), so the
/// smoothing bias, not the encoder noise, dominates: order 5 over 21 samples (half-window 10 ms
/// at 1 kHz) gave the smallest torque residual on the paper-scene log (angle noise 1e-5 rad):
/// rms 0.06 N m against 0.33 N m for order 3 over the same window and 0.12 N m for order 3 over
/// 11 samples, with coulomb and viscous within 0.1 % of the truth (order 3: 1 to 4 %).
struct SgOptions {
  double half_window_s = 0.010;  ///< half-width of the window [s]; at least order/2 + 1 samples
  int order = 5;                 ///< polynomial degree (>= 2 for accelerations)
};

/// Half-width in samples for a log of mean sample step dt.
int sg_half_window(const SgOptions& options, double dt);

/// First and second derivatives of x(t) by Savitzky-Golay (see SgOptions); with `step` > 1
/// only at the samples 0, step, 2 step, ... (the others left 0), for a caller that reads no
/// others.
void savitzky_golay(const std::vector<double>& t, const std::vector<double>& x,
                    const SgOptions& options, std::vector<double>* dx, std::vector<double>* ddx,
                    int step = 1);

/// The weights that savitzky_golay applies at sample i: dx[i] = sum_r d1[r] x[lo + r] and
/// ddx[i] = sum_r d2[r] x[lo + r] (the filter is linear in x; used to propagate sensor noise).
void savitzky_golay_taps(const std::vector<double>& t, int i, const SgOptions& options, int* lo,
                         std::vector<double>* d1, std::vector<double>* d2);

/// savitzky_golay_taps of one filter over one grid t, each computed once per distinct window:
/// the taps are a function of the window's scaled offsets (t[lo + r] - t[i]) / dt alone, so the
/// windows met again (the centred windows of a uniform grid, whose offsets repeat bit for bit up
/// to the rounding of t) get the same taps bit for bit, without another factorization.
class SgTapCache {
 public:
  /// t must outlive the cache
  SgTapCache(const std::vector<double>& t, const SgOptions& options);
  /// savitzky_golay_taps(t, i, options, lo, ...), the taps owned by the cache
  void taps(int i, int* lo, const std::vector<double>** d1, const std::vector<double>** d2);

 private:
  struct Taps {
    std::vector<double> d1, d2;
  };
  const std::vector<double>& t_;
  SgOptions options_;
  std::map<std::vector<std::uint64_t>, Taps> memo_;  ///< by the offsets' bit patterns
  std::vector<double> offsets_;
  std::vector<std::uint64_t> key_;
};

}  // namespace fivebar::identification
