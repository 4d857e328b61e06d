// One linearized refit with further parameters freed (misfit.h).
#include "misfit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace fivebar::identification::detail {
namespace {

/// Inverse of a symmetric positive definite matrix; false when it is not (numerically). The
/// test is on A with its diagonal scaled to 1, so that parameters in units far apart (a torque
/// offset in N m and a gain of a crane's torques of 1e6 N m: 1e12 apart in A) are not taken for
/// a rank deficiency.
bool spd_inverse(const Eigen::MatrixXd& A, Eigen::MatrixXd* inv) {
  if (A.size() == 0 || !(A.diagonal().minCoeff() > 0)) return false;
  const Eigen::VectorXd d = A.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd As = d.asDiagonal() * A * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(As);
  if (es.info() != Eigen::Success) return false;
  const Eigen::VectorXd ev = es.eigenvalues();
  if (!(ev.minCoeff() > 1e-12 * ev.maxCoeff()) || !(ev.maxCoeff() > 0)) return false;
  *inv = d.asDiagonal() *
         (es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose()) *
         d.asDiagonal();
  return inv->allFinite();
}

}  // namespace

FreedStep freed_step(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                     const std::vector<int>& fitted, const std::vector<int>& extra,
                     const Eigen::VectorXd& prior, const Eigen::VectorXd& bias) {
  FreedStep out;
  const int nf = static_cast<int>(fitted.size()), ne = static_cast<int>(extra.size());
  Eigen::MatrixXd Ja(J.rows(), nf + ne);
  Eigen::VectorXd ba = Eigen::VectorXd::Zero(nf + ne);
  for (int k = 0; k < nf + ne; ++k) {
    const int c = k < nf ? fitted[k] : extra[k - nf];
    Ja.col(k) = J.col(c);
    if (bias.size() > 0) ba(k) = bias(c);
  }
  Eigen::MatrixXd A = Ja.transpose() * Ja;
  for (int k = 0; k < ne; ++k) A(nf + k, nf + k) += prior(k);
  Eigen::MatrixXd C, Cf;
  if (!spd_inverse(A, &C) || !spd_inverse(A.topLeftCorner(nf, nf), &Cf)) return out;
  // the centred score, the augmented step and the restricted one (fitted parameters alone)
  const Eigen::VectorXd g = Ja.transpose() * r - ba;
  const Eigen::VectorXd step = -C * g, step_f = -Cf * g.head(nf);
  out.fitted_step = step.head(nf) - step_f;
  out.fitted_cov = C.topLeftCorner(nf, nf) - Cf;
  out.extra_step = step.tail(ne);
  out.extra_std = C.bottomRightCorner(ne, ne).diagonal().cwiseMax(0.0).cwiseSqrt();
  out.drop = -step.dot(g) + step_f.dot(g.head(nf));
  // S = (A_ee - P) - A_ef A_ff^-1 A_fe; (S + P)^-1 is the extras' block of C
  const Eigen::MatrixXd Afe = A.topRightCorner(nf, ne);
  Eigen::MatrixXd S = A.bottomRightCorner(ne, ne) - Afe.transpose() * Cf * Afe;
  S.diagonal() -= prior;
  const Eigen::MatrixXd M = C.bottomRightCorner(ne, ne) * S;
  out.drop_mean = M.trace();
  out.drop_sd = std::sqrt(std::max(0.0, 2.0 * (M * M).trace()));
  out.ok = true;
  return out;
}

Causes model_causes(const std::vector<FreedStep>& alone, const FreedStep& all,
                    const std::vector<FreedStep>& all_but) {
  const size_t n = alone.size();
  Causes c;
  c.named.assign(n, false);
  c.z.assign(n, 0.0);
  c.z_given.assign(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    c.z[k] = evidence(alone[k], alone[k].drop);
    // with other causes in the check, each must also show beyond their parameters
    if (n == 1) {
      c.z_given[k] = c.z[k];
    } else if (all.ok && k < all_but.size() && all_but[k].ok) {
      c.z_given[k] = evidence(alone[k], all.drop - all_but[k].drop);
    }
    c.named[k] = c.z[k] > kCauseZ && c.z_given[k] > kCauseZ;
  }
  return c;
}

}  // namespace fivebar::identification::detail
