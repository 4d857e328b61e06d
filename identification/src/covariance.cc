// Block-robust sandwich covariance (see covariance.h).
#include "covariance.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace fivebar::identification::detail {

namespace {

/// A_b r_b = (I - G G^T)^(-1/2) r_b, G = J_b L^-T (H = L L^T): with the thin SVD G = U s V^T
/// the block's leverage is U s^2 U^T, so only its P directions are rescaled. A direction that
/// the block alone determines (leverage ~1) is left as it is: no correction is defined there.
Eigen::VectorXd leverage_corrected(const Eigen::MatrixXd& G, const Eigen::VectorXd& r) {
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(G, Eigen::ComputeThinU);
  const Eigen::MatrixXd& U = svd.matrixU();
  const Eigen::VectorXd s = svd.singularValues();
  Eigen::VectorXd scale(s.size());
  for (int k = 0; k < s.size(); ++k) {
    const double lev = s(k) * s(k);
    scale(k) = lev < 1 - 1e-9 ? 1.0 / std::sqrt(1.0 - lev) - 1.0 : 0.0;
  }
  return r + U * scale.cwiseProduct(U.transpose() * r);
}

}  // namespace

BlockCovariance block_sandwich(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                               const std::vector<int>& sizes) {
  BlockCovariance out;
  const int m = static_cast<int>(J.rows()), P = static_cast<int>(J.cols());
  if (std::accumulate(sizes.begin(), sizes.end(), 0) != m || r.size() != m || P == 0) return out;
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() != Eigen::Success || !H.allFinite() || !r.allFinite()) return out;
  const Eigen::MatrixXd Hinv = llt.solve(Eigen::MatrixXd::Identity(P, P));
  // G_b = J_b L^-T, from L G_b^T = J_b^T
  const Eigen::MatrixXd Gall = llt.matrixL().solve(J.transpose()).transpose();
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(P, P);
  int row = 0;
  for (int n : sizes) {
    if (n > 0) {
      const Eigen::VectorXd a = leverage_corrected(Gall.middleRows(row, n), r.segment(row, n));
      const Eigen::VectorXd u = J.middleRows(row, n).transpose() * a;
      S += u * u.transpose();
      ++out.blocks;
    }
    row += n;
  }
  if (out.blocks < P + 1) return out;
  out.covariance = Hinv * S * Hinv;
  const double s2 = r.squaredNorm() / std::max(1, m - P);
  out.inflation.resize(P);
  for (int i = 0; i < P; ++i) {
    out.inflation[i] = std::sqrt(out.covariance(i, i) / (s2 * Hinv(i, i)));
  }
  return out;
}

}  // namespace fivebar::identification::detail
