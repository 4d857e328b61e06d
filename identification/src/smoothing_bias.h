// Internal to identification: the bias that Savitzky-Golay smoothing puts on the fitted
// coefficients, predicted deterministically. The filter of order p keeps polynomials up to degree
// p exactly, so its error on a smooth motion comes from the motion's higher terms. These are read
// off a local polynomial reconstruction of degree p + kReconExtra over a wider window (where the
// angle noise averages out), the filter is applied to them (equivalently: the filter applied to
// the reconstruction minus the reconstruction's exact derivatives), and the rate and acceleration
// errors are propagated through the inverse dynamics to the coefficients (one Gauss-Newton step
// from the truth). Nothing is refitted, so the prediction has no window-to-window noise; its own
// noise comes from the angle noise through the reconstruction: small against the std where the
// torques are large (the paper scene), but not where the angle noise dominates the residual (a
// light mechanism's clean logs: 1-14 std at half-windows 10-15). It is linear in the angles, so
// its std is propagated exactly (smoothing_bias's `spread`).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <vector>

#include "fivebar/identification/rates.h"
#include "noise_model.h"

namespace fivebar::identification::detail {

/// Degrees above the filter's order that the reconstruction carries: one, the term of the
/// acceleration's leading error (order 5: degree 6; the rate's, degree 7, is smaller by two
/// powers of the window). Measured on the paper log (2 s, 1 kHz, angle noise 1e-5 rad, predicted
/// viscous bias at half-window 12 samples, noise-free -9.55e-6 by refitting): with degree 6 over
/// +-2 times the residual rule's window, -9.70e-6 noise-free and -7.8e-6, -8.1e-6 on two noisy
/// logs; with degree 8 the noise-free prediction is as good (-9.65e-6) but the noisy logs scatter
/// by +-1.5e-5 (the two extra coefficients cost far more in noise than they gain in bias;
/// docs/dev/figures-logs.md, round bias16).
constexpr int kReconExtra = 1;

/// The reconstruction of the motion for the bias prediction reaches this many times the residual
/// rule's half-window each side (the polynomial of degree order + kReconExtra then averages the
/// angle noise far below the filter's own noise, while following the motion over the filter's
/// span)
constexpr double kReconSpan = 2.0;

/// The terms of degree order + 1 .. order + extra of the least-squares polynomial of degree
/// order + extra through x over the samples [a, b] (fewer where b - a is too short), as
/// coefficients of ((t - t_i) / dt)^k.
Eigen::VectorXd high_order_terms(const std::vector<double>& t, const std::vector<double>& x, int i,
                                 int a, int b, double dt, int order, int extra = kReconExtra);

/// high_order_terms as weights of the samples: terms = W x[a..b] (extra x (b - a + 1); rows of
/// zeros where b - a is too short for a term).
Eigen::MatrixXd high_order_weights(const std::vector<double>& t, int i, int a, int b, double dt,
                                   int order, int extra = kReconExtra);

/// high_order_terms and high_order_weights at many samples of one grid t: each distinct window
/// (its offsets (t - t_i) / reach, bit for bit, and its reach each side) factorized once, the
/// factorization shared by the terms of every angle and the weights (the centred windows of a
/// uniform grid repeat up to the rounding of t); the same results bit for bit.
class HighOrderCache {
 public:
  /// t must outlive the cache
  HighOrderCache(const std::vector<double>& t, double dt, int order, int extra = kReconExtra);
  ~HighOrderCache();
  /// high_order_terms(t, x, i, a, b, dt, order, extra)
  Eigen::VectorXd terms(const std::vector<double>& x, int i, int a, int b);
  /// high_order_weights(t, i, a, b, dt, order, extra)
  const Eigen::MatrixXd& weights(int i, int a, int b);

 private:
  struct Window;
  Window& window(int i, int a, int b);
  const std::vector<double>& t_;
  double dt_;
  int order_, extra_;
  std::map<std::vector<std::uint64_t>, std::unique_ptr<Window>> memo_;
  std::vector<std::uint64_t> key_;
};

/// The filter's rate (r1) and acceleration (r2) response to ((t - t_i) / dt)^k for k = order + 1
/// .. order + extra, on a uniform grid of step dt (it reproduces lower degrees exactly).
void filter_response(const SgOptions& sg, double dt, Eigen::VectorXd* r1, Eigen::VectorXd* r2,
                     int extra = kReconExtra);

/// What the prediction needs about the samples of a fit, at its parameters.
struct BiasInputs {
  std::vector<int> index;  ///< log index of each sample
  Eigen::MatrixXd J;       ///< d residual / d x (internal layout), 2 rows per sample
  std::vector<Eigen::Matrix<double, 2, 6>> D;  ///< kinematic Jacobians (noise_model.h)
  std::vector<Eigen::VectorXd> terms[2];       ///< high_order_terms of each crank's angle
  /// the same as weights of the angles (high_order_weights) from log sample recon_lo[u] (empty:
  /// the prediction's own noise is not propagated)
  std::vector<Eigen::MatrixXd> weights[2];
  std::vector<int> recon_lo;
  Eigen::MatrixXd Hp;  ///< prior information (J^T J units) and its score scale s2
  double s2 = 0;
  Eigen::MatrixXd T;  ///< internal to public parameters
  int friction_size = 0;
  /// the public parameters, from the first, whose bias smoothing_bias predicts and the window
  /// rules judge (0: the friction coefficients; the four-bar with its links' inertial parameters
  /// judges them all)
  int judged = 0;
  RateSource source = RateSource::kFromAngles;
  SensorNoise noise;
};

/// What the noise of estimated rates and accelerations does to the fit at each of its samples u
/// (errors in variables), for one filter: with A = d torques / d x and n that noise,
/// shift[u] = E[torques(u + n)] - torques(u) (the reactions' norms, and with them the friction,
/// are convex in the accelerations) and score[u] = E[(A(u + n) - A(u))^T (torques(u + n) -
/// torques(u))] (the friction's columns move with the same noise as the residual: the larger
/// part).
struct NoiseBias {
  std::vector<Eigen::Vector2d> shift;
  std::vector<Eigen::VectorXd> score;
};

/// The covariance of the noise of (theta, omega, alpha) of one crank at log sample `at`, its
/// rate and acceleration from the filter's taps d1, d2 over the window from log sample lo, the
/// angles of noise std `sigma`.
Eigen::Matrix3d filtered_noise_covariance(int at, int lo, const std::vector<double>& d1,
                                          const std::vector<double>& d2, double sigma);

/// The drive torques (2; a mechanism of one crank leaves the second 0) and their derivatives in
/// the parameters (2 x P) at a sample's motion with (theta, omega, alpha) of its first crank moved
/// by dn; false where the model fails.
using PerturbedTorques =
    std::function<bool(const Eigen::Vector3d& dn, Eigen::Vector2d* torques, Eigen::MatrixXd* A)>;

/// One sample's NoiseBias (shift and score) for the noise of covariance C of the first crank's
/// (theta, omega, alpha): a 3-point Gauss-Hermite rule along each principal axis of C, exact for
/// quadratic torques, and bounded where a reaction passes through zero (its norm's kink) as a
/// Taylor term is not; false where an evaluation fails.
bool noise_bias_at(const Eigen::Matrix3d& C, const PerturbedTorques& torques,
                   Eigen::Vector2d* shift, Eigen::VectorXd* score);

/// The Gauss-Hermite points of one crank's noise for the filter `sg` at a centred sample of the
/// uniform grid t: sqrt(3 lambda_k) v_k for each eigenpair of the covariance of (angle, filtered
/// rate, filtered acceleration) per unit angle noise. A 3-point rule along each axis (weights
/// 1/6 at +-, 2/3 at 0) is exact for quadratic torques, and bounded where a reaction passes
/// through zero (its norm's kink) as a Taylor term is not.
std::array<Eigen::Vector3d, 3> noise_axes(const std::vector<double>& t, const SgOptions& sg);

/// smoothing_bias's prediction for one filter over the samples kept, before the noise's bias:
/// what the bias with the noise's (noisy_bias) shares with it.
struct BiasPrediction {
  Eigen::MatrixXd J;       ///< the kept samples' rows of BiasInputs::J
  Eigen::VectorXd dM;      ///< the smoothing's torque error at them (2 per sample)
  Eigen::MatrixXd Hinv;    ///< (J^T J + Hp)^-1
  Eigen::VectorXd bias;    ///< the smoothing's (public parameters judged)
  Eigen::VectorXd std;     ///< errors in variables (public parameters judged)
  Eigen::VectorXd spread;  ///< with_spread: as smoothing_bias's `spread`
};

/// smoothing_bias without the noise's bias, into *out (false when too few samples or singular;
/// spread only `with_spread`).
bool predict_smoothing_bias(const std::vector<double>& t, const BiasInputs& in,
                            const std::vector<char>& keep, const SgOptions& sg, bool with_spread,
                            BiasPrediction* out);

/// The bias of the smoothing and of the noise (NoiseBias of the same filter) from the prediction
/// p of the same samples: the same as smoothing_bias with `noise` (false where not finite).
bool noisy_bias(const BiasInputs& in, const std::vector<char>& keep, const NoiseBias& noise,
                const BiasPrediction& p, Eigen::VectorXd* bias);

/// Predicted smoothing bias and errors-in-variables std of the public parameters judged
/// (BiasInputs:: judged: by default the friction coefficients) for the filter `sg`, over the
/// samples u with keep[u] (false when too few or singular). With `noise` (NoiseBias at sg), the
/// bias is that of the smoothing and of the noise. With `spread` and in.weights: the std of the
/// smoothing's prediction from the angle noise through the reconstruction (0 without weights).
bool smoothing_bias(const std::vector<double>& t, const BiasInputs& in,
                    const std::vector<char>& keep, const SgOptions& sg, Eigen::VectorXd* bias,
                    Eigen::VectorXd* std, const NoiseBias* noise = nullptr,
                    Eigen::VectorXd* spread = nullptr);

}  // namespace fivebar::identification::detail
