// Internal to identification: the covariance of a least-squares fit whose residuals are
// correlated within blocks and independent between them (the output-error method's windows,
// each restarted from the logged state). docs/identification.md, "Output-error standard
// deviations", says why the blocks and not a lag window (Newey-West).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace fivebar::identification::detail {

/// A block-robust (cluster) sandwich covariance and what it was made from.
struct BlockCovariance {
  Eigen::MatrixXd covariance;  ///< P x P; empty when it cannot be formed
  int blocks = 0;              ///< blocks that carried residuals
  /// per parameter: the sandwich std over the std that treats every residual as independent
  /// (s^2 (J^T J)^-1, s^2 the residual variance): how much the correlation within a block costs
  std::vector<double> inflation;
};

/// The covariance of the least-squares estimate from the Jacobian J (m x P, full column rank)
/// and the residuals r at the fit, residual rows grouped in consecutive blocks of `sizes` rows
/// (summing to m):
///   C = H^-1 (sum_b J_b^T A_b r_b r_b^T A_b J_b) H^-1,   H = J^T J,
///   A_b = (I - J_b H^-1 J_b^T)^(-1/2)
/// (the "CR2" small-sample correction of Bell and McCaffrey: the residuals at the fit are smaller
/// than the errors by the block's leverage; with it, E[C] is exact for independent errors of
/// equal variance, and nearly so otherwise). Whatever the correlation inside a block, the score
/// of a block is then estimated by its own residuals. Returns an empty covariance when the
/// sizes do not match m, or when fewer than P + 1 blocks carry residuals.
BlockCovariance block_sandwich(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                               const std::vector<int>& sizes);

}  // namespace fivebar::identification::detail
