// Internal to identification: how sensor noise reaches the inverse-dynamics torque residual when
// rates and accelerations are estimated from the angles (or accelerations from logged rates):
// the expected residual level, the data-driven Savitzky-Golay window, and the errors-in-variables
// covariance.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "fivebar/identification/parameters.h"
#include "fivebar/identification/rates.h"
#include "fivebar/identification/residual.h"
#include "fivebar/model/dynamics.h"
#include "jet_dynamics.h"  // identify.cc and noise_model.cc: the Jet inverse dynamics compiled once

namespace fivebar::identification::detail {

/// Where the rates and accelerations of the fit come from.
enum class RateSource { kLogged, kAccelsFromRates, kFromAngles };

/// Sensor noise std of the logged columns (robust estimates from the log).
struct SensorNoise {
  double angle[2] = {0, 0}, rate[2] = {0, 0}, torque[2] = {0, 0};
};

/// d M / d (theta1, theta2, omega1, omega2, alpha1, alpha2) at one sample (2 x 6), friction
/// coefficients x laid out by `layout`; false where the inverse dynamics fails.
bool kinematic_jacobian(const Params<double>& scene, const ParameterLayout& layout, const double* x,
                        const Sample& s, const EvalOptions& eval, Eigen::Matrix<double, 2, 6>* D);

/// kinematic_jacobian at many samples of one parameter vector: the scene's Jet parameters at x
/// formed once (the same Jacobians bit for bit).
class KinematicJacobians {
 public:
  KinematicJacobians(const Params<double>& scene, const ParameterLayout& layout, const double* x);
  bool operator()(const Sample& s, const EvalOptions& eval, Eigen::Matrix<double, 2, 6>* D) const;

 private:
  using J6 = ceres::Jet<double, 6>;
  Params<J6> p_;
};

/// One sample's noise sensitivities: for each noise channel (0, 1: the differentiated or direct
/// angle or rate of crank 1, 2; 2, 3: the direct angle when rates are logged) the samples it
/// comes from and d r / d n (2 rows, one per actuator) for each.
struct Sensitivity {
  int lo[4] = {0, 0, 0, 0};
  std::vector<Eigen::Vector2d> coef[4];
  double sigma[4] = {0, 0, 0, 0};
};

/// Sensitivities of the residual at log sample i (kinematic Jacobian D) to the sensor noise.
Sensitivity sensitivity(const std::vector<double>& t, int i, RateSource source, const SgOptions& sg,
                        const SensorNoise& noise, const Eigen::Matrix<double, 2, 6>& D);

/// The same with the filter's taps at i given (savitzky_golay_taps: the window starts at log
/// index lo; unused for logged rates): on a uniform grid every centred window has the same taps.
Sensitivity sensitivity(int i, int lo, const std::vector<double>& d1, const std::vector<double>& d2,
                        RateSource source, const SensorNoise& noise,
                        const Eigen::Matrix<double, 2, 6>& D);

/// The same with the filter's taps at i from `taps` (a cache over the log's t and the filter).
Sensitivity sensitivity(SgTapCache* taps, int i, RateSource source, const SensorNoise& noise,
                        const Eigen::Matrix<double, 2, 6>& D);

/// Variance of the residual of each actuator that the noise in `s` produces.
Eigen::Vector2d propagated_variance(const Sensitivity& s);

/// Errors-in-variables score covariance J^T Sigma J: torque noise at every sample plus each noise
/// sample's effect through all the residuals whose rates it enters. `J` has 2 rows per used
/// sample (log index `index[u]`), `sens[u]` the sensitivities of used sample u, `n` the log size.
Eigen::MatrixXd score_covariance(const Eigen::MatrixXd& J, const std::vector<Sensitivity>& sens,
                                 const SensorNoise& noise, int n);

/// diag(Q S Q^T) for S = score_covariance(J, sens, noise, n) and Q (k x P), without forming S:
/// the variances of k combinations of the score (the same up to rounding).
Eigen::VectorXd projected_score_variance(const Eigen::MatrixXd& Q, const Eigen::MatrixXd& J,
                                         const std::vector<Sensitivity>& sens,
                                         const SensorNoise& noise, int n);

/// One noise channel's share of the score covariance: S += sigma^2 G G^T over G's columns
/// [first, last] (G: P x n, column l the score's response to noise sample l; the columns outside
/// the range are zero). Nothing where sigma is not > 0 or the range is empty.
void add_channel_covariance(const Eigen::MatrixXd& G, int first, int last, double sigma,
                            Eigen::MatrixXd* S);

}  // namespace fivebar::identification::detail

namespace fivebar::identification::stages {

/// The Savitzky-Golay half-windows [samples] identify's window choice tries on a log of n
/// samples of step dt: from the polynomial's minimum to 50 ms, growing by 25 %, each fitting in
/// the n samples (at least the minimum). Defined in stage_window.cc; declared here, beside the
/// noise model, for the excitation design's prediction of that choice too (no Ceres needed).
std::vector<int> window_candidates(int n, double dt, int order);

/// Window choice: a residual/noise ratio this much above the least one is smoothing bias
/// (stage_window.cc; the excitation design predicts the same choice).
constexpr double kWindowExcess = 0.04;

/// The largest predicted smoothing bias of a friction coefficient, in its std, that a window may
/// carry: a bias b moves the coverage of a 95 % interval from 0.95 to 0.945 at b = 0.2, 0.943 at
/// 0.25 and 0.92 at 0.5 (stage_smoothing_bias.cc; the excitation design predicts the same choice)
constexpr double kBiasFraction = 0.2;

/// Where no window keeps the predicted bias within kBiasFraction, the largest predicted |bias| /
/// std of a friction coefficient at the window kept beyond which the fit is not to be used
/// (unbiased_window_check, stage_smoothing_bias.cc): the prediction is taken off the estimates,
/// but its own error grows with it (a fast per-joint design at 1 kHz, predicted 2.4 std at its
/// least: errors of 3-6 std left after the correction, 67 of 100 intervals covering)
constexpr double kUnusableBias = 1.0;

/// The walk of the window choice by predicted bias (choose_window_by_bias, mechanism_stages.h),
/// over candidates 1 .. K - 1 from `start` (clamped into them): worst(k) gives candidate k's
/// predicted largest |bias| / std of a friction coefficient (NaN: not predicted there), false when
/// its inputs cannot be formed (then no choice). Within kBiasFraction at the start: down while
/// within, the smallest so; else up until within, or until the ratio exceeds twice the least (or
/// twice kBiasFraction), then the least. Shared by identify and the excitation design's
/// prediction of identify's window.
struct BiasWalk {
  int pick = -1;              ///< the candidate chosen (-1: none)
  bool within = false;        ///< whether it is within kBiasFraction
  std::vector<double> ratio;  ///< per candidate: -1 not evaluated, NaN not predicted
};
BiasWalk walk_window_by_bias(int K, int start, const std::function<bool(int, double*)>& worst);

}  // namespace fivebar::identification::stages
