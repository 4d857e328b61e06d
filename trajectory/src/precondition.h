// A linear change of variables x = origin + T y that makes the Hessian of the objective of a
// TrajectoryProblem near the identity at the start of a solve (internal to the library).
//
// SLSQP starts its quasi-Newton matrix at the identity. On a refined spline (80 to 160
// variables) the Hessian is far from it (control points of a fine spline act on the
// accelerations through 1/h^2), and SLSQP spends hundreds of iterations rebuilding it, again at
// every restart (each refinement level, each screening round, each tightened re-solve). In y
// the start is close to Newton's step.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "fivebar/trajectory/problem.h"

namespace fivebar::trajectory {

struct Preconditioner {
  bool active = false;
  Eigen::MatrixXd T;   ///< x - origin = T y (nv x nv)
  Eigen::MatrixXd Tt;  ///< T transposed (its columns are the rows of T)
  int evaluations = 0;  ///< problem evaluations spent to build it
};

/// T = V |D|^(-1/2) of the symmetric eigen-decomposition V D V^T of the Hessian of the
/// objective at x0 (TrajectoryProblem::objective_hessian: node by node, the 6 x 6 Hessian of
/// the integrand by differences of its exact gradient, mapped through the spline basis; about 7
/// evaluations with gradients, counted as 7). |D| is floored at 1e-8 max |D|. The
/// constraints' curvature is left out: with multipliers estimated at the start (least squares on
/// the near-active rows) the refined solves took more iterations, not fewer. Inactive when x0
/// cannot be evaluated. With `gauss_newton`, the winding heat's Gauss-Newton Hessian instead
/// (one evaluation; TrajectoryProblem::objective_hessian).
Preconditioner objective_preconditioner(const TrajectoryProblemBase& problem,
                                         const std::vector<double>& x0, bool gauss_newton);

/// Whether a solve from x0 is preconditioned by the winding heat's Gauss-Newton Hessian: when
/// the heat is at least kGaussNewtonShare of the objective there. On the shipped tasks with
/// paper_motors.yaml (c = 0.0765 W/(N m)^2, heat 55-65% of the objective) the 10-point solves
/// took 2 to 3 times fewer evaluations than unpreconditioned; with c = 5e-4 (heat ~1%) the
/// form, blind to the friction's curvature, made the five tasks 1.6 times slower, with c = 5e-5
/// 2.3 times; with c = 1e-2 (heat ~20%) neither gained.
constexpr double kGaussNewtonShare = 0.3;
bool gauss_newton_preconditioning(const TrajectoryProblemBase& problem,
                                  const std::vector<double>& x0);

}  // namespace fivebar::trajectory
