// Internal to identification: a cheap check of the model behind a fit. One linearized refit with
// further parameters freed (the links' inertial parameters) tells whether the log asks for them:
// identify() warns when the fitted friction would move by more than its noise allows (the
// scene's masses do not match).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace fivebar::identification::detail {

/// One Gauss-Newton step from a fit with extra parameters freed. J: the Jacobian of the residual
/// r at the fit, rows whitened to unit noise, over the fitted parameters (columns `fitted`) and
/// the extra ones (columns `extra`, with prior information prior(k) = 1 / prior variance on
/// extra[k] in whitened units; 0: none). `bias` (empty: none; else one entry per column of J):
/// the score J' r's expectation when the model holds, taken off it (errors in variables: noise
/// that enters both the columns and the residual). The step, the move of the fitted parameters
/// and the drop are those beyond the restricted refit (the fitted parameters alone), which is
/// nothing when J' r is 0 on them and there is no bias.
struct FreedStep {
  bool ok = false;  ///< false: the augmented normal matrix is singular
  /// the step of the fitted parameters, and its covariance when the extra parameters are at
  /// their values (the augmented minus the restricted covariance: the test of Hausman)
  Eigen::VectorXd fitted_step;
  Eigen::MatrixXd fitted_cov;
  /// the step of the extra parameters and their (augmented, posterior) std
  Eigen::VectorXd extra_step, extra_std;
  /// the decrease of the whitened cost |r|^2 (+ the extras' prior) by the step, and its mean and
  /// std when r is white noise of unit deviation (the score statistic: g' (S + P)^-1 g' with S
  /// the information on the extras left by the fitted ones, P the prior; mean tr M, variance
  /// 2 tr M^2 for M = (S + P)^-1 S; without a prior chi-square with as many degrees of freedom as
  /// extras)
  double drop = 0, drop_mean = 0, drop_sd = 0;
};
/// Which causes the log evidences, from freed steps at one fit: each candidate cause's
/// parameters freed alone (`alone[k]`: the links' inertial parameters, the two angle offsets,
/// the torque readings' offsets and gains), all of them together (`all`) and all but cause k
/// (`all_but[k]`; with one cause, neither is used). A cause is evidenced when freeing its
/// parameters lowers the cost by more than kCauseZ std above what noise alone gives (drop_mean,
/// drop_sd), and also beyond what the other causes' parameters lower it by (all minus all_but;
/// a step not ok there: the causes cannot be told apart, none is named).
inline constexpr double kCauseZ = 8.0;
/// A fall `drop` of the whitened cost in std of what noise alone gives the parameters `fs` frees
/// ((drop - mean) / sd; 0 when the step is not ok).
inline double evidence(const FreedStep& fs, double drop) {
  return fs.ok && fs.drop_sd > 0 ? (drop - fs.drop_mean) / fs.drop_sd : 0.0;
}
struct Causes {
  std::vector<bool> named;
  /// (drop - mean) / sd alone, and given the other causes
  std::vector<double> z, z_given;
};
Causes model_causes(const std::vector<FreedStep>& alone, const FreedStep& all,
                    const std::vector<FreedStep>& all_but);

FreedStep freed_step(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                     const std::vector<int>& fitted, const std::vector<int>& extra,
                     const Eigen::VectorXd& prior, const Eigen::VectorXd& bias = {});

}  // namespace fivebar::identification::detail
