#include "precondition.h"

#include <algorithm>
#include <cmath>

namespace fivebar::trajectory {
namespace {

constexpr int kBand = kDegree;       // control points more than kBand apart share no knot span
constexpr double kStep = 1e-7;       // difference step of the control points [rad]
constexpr double kFloor = 1e-8;      // smallest |eigenvalue| kept, relative to the largest

// T = V |D|^(-1/2) of the symmetric part of H
bool scaling_of(const Eigen::MatrixXd& H, Eigen::MatrixXd* T) {
  const Eigen::MatrixXd S = 0.5 * (H + H.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  if (eig.info() != Eigen::Success) return false;
  const Eigen::VectorXd d = eig.eigenvalues().cwiseAbs();
  const double top = d.maxCoeff();
  if (!(top > 0) || !std::isfinite(top)) return false;
  const Eigen::VectorXd s = d.cwiseMax(kFloor * top).cwiseSqrt().cwiseInverse();
  *T = eig.eigenvectors() * s.asDiagonal();
  return T->allFinite();
}

}  // namespace

Preconditioner objective_preconditioner(const TrajectoryProblem& problem,
                                         const std::vector<double>& x0) {
  Preconditioner p;
  const int nv = problem.num_variables(), nf = problem.motion().free_per_joint();
  Evaluated e;
  p.evaluations = 1;
  if (nv == 0 || !problem.evaluate(x0.data(), true, &e).ok()) return p;
  const Eigen::Map<const Eigen::VectorXd> g0(e.objective_grad.data(), nv);
  const int groups = std::min(nf, 2 * kBand + 1);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nv, nv);
  for (int j = 0; j < 2; ++j) {
    for (int group = 0; group < groups; ++group) {
      std::vector<double> x = x0;
      for (int i = group; i < nf; i += groups) x[j * nf + i] += kStep;
      Evaluated ep;
      ++p.evaluations;
      if (!problem.evaluate(x.data(), true, &ep).ok()) return p;
      const Eigen::VectorXd d =
          (Eigen::Map<const Eigen::VectorXd>(ep.objective_grad.data(), nv) - g0) / kStep;
      // row r sees the one perturbed control point of this group within the band around it
      for (int r = 0; r < nv; ++r) {
        const int ir = r % nf;
        const int below = ir - ((ir - group) % groups + groups) % groups;
        for (int i : {below, below + groups}) {
          if (i >= 0 && i < nf && std::abs(i - ir) <= kBand) H(r, j * nf + i) = d[r];
        }
      }
    }
  }
  p.active = scaling_of(H, &p.T);
  if (p.active) p.Tt = p.T.transpose();
  return p;
}

}  // namespace fivebar::trajectory
