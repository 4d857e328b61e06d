#include "precondition.h"

#include <algorithm>
#include <cmath>

namespace fivebar::trajectory {
namespace {

// the cost of TrajectoryProblemBase::objective_hessian in evaluations with gradients, counted in
// the evaluation limit: 3 dofs + 1 Jet passes over the nodes by differences (7 for the
// five-bar), 1 for the winding heat's Gauss-Newton form
int hessian_evaluations(const TrajectoryProblemBase& problem) {
  return 3 * problem.dofs() + 1;
}
constexpr int kGaussNewtonHessianEvaluations = 1;
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

bool gauss_newton_preconditioning(const TrajectoryProblemBase& problem,
                                  const std::vector<double>& x0) {
  return problem.heat_share(x0.data()) >= kGaussNewtonShare;  // false for NaN
}

Preconditioner objective_preconditioner(const TrajectoryProblemBase& problem,
                                         const std::vector<double>& x0, bool gauss_newton) {
  Preconditioner p;
  const int nv = problem.num_variables();
  p.evaluations = gauss_newton ? kGaussNewtonHessianEvaluations : hessian_evaluations(problem);
  std::vector<double> h;
  if (nv == 0 || !problem.objective_hessian(x0.data(), &h, gauss_newton).ok()) return p;
  const Eigen::MatrixXd H = Eigen::Map<const Eigen::MatrixXd>(h.data(), nv, nv);
  p.active = scaling_of(H, &p.T);
  if (p.active) p.Tt = p.T.transpose();
  return p;
}

}  // namespace fivebar::trajectory
