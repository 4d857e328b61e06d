// Local (SLSQP, MMA, CCSAQ) and multi-start global minimization of a TrajectoryProblem by NLopt.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fivebar/trajectory/nlopt_status.h"
#include "fivebar/trajectory/problem.h"

namespace fivebar::trajectory {

/// NLopt algorithms offered (all gradient-based, all handle the inequality constraints).
enum class Method : int {
  kSlsqp = 0,  ///< "slsqp": NLOPT_LD_SLSQP, sequential quadratic programming (default)
  kMma,        ///< "mma": NLOPT_LD_MMA, method of moving asymptotes
  kCcsaq,      ///< "ccsaq": NLOPT_LD_CCSAQ, conservative convex separable quadratic
};
const char* method_name(Method m);
bool parse_method(const std::string& name, Method* out);

struct OptimizerOptions {
  Method method = Method::kSlsqp;
  /// Multi-start: the local method from the given start and from starts - 1 seeded random
  /// perturbations of it (each a full local solve); the best feasible result wins.
  bool global = false;
  int starts = 8;
  /// Perturbation of the inner control points [rad]: normal with standard deviation
  /// spread * (|goal - start| + 0.1 rad) per joint.
  double spread = 0.5;
  std::uint64_t seed = 1;   ///< seed of the perturbations (results depend on it, never on time)
  double ftol_rel = 1e-10;  ///< relative objective change that stops a local solve
  double xtol_rel = 1e-8;   ///< relative step that stops a local solve
  int max_evaluations = 500;  ///< per local solve
  double constraint_tol = 1e-8;  ///< NLopt tolerance of each constraint (dimensionless)
  /// Constraint screening: NLopt sees only the rows with c > -screen at the start (c of
  /// TrajectoryProblem, dimensionless: 0.75 keeps the torques above half the limit); rows the
  /// result violates or nears are added and the solve resumed (the answer satisfies every row).
  /// 0: every row from the start. (0.5 made round 0 of swing_right's refined solves leave out
  /// rows whose torques then reached 1.9 times the limit, and cost a resumed solve of 50-120
  /// evaluations.)
  double screen = 0.75;
  /// the first screening round ends at its first new best point that violates a row left out
  /// (it would converge to a point the next round rejects); false: it runs to its end
  bool screen_early_end = true;
  /// SLSQP on problems of at least precondition_min_variables variables works in y,
  /// x = x0 + T y, where T^T H T = +-I for the Hessian H of the objective at the start
  /// (TrajectoryProblem::objective_hessian, node by node, about 7 evaluations): SLSQP's
  /// quasi-Newton matrix starts at the identity, which in x is far from H on a refined spline.
  /// A solve whose objective is mostly winding heat at the start is preconditioned at any size,
  /// by the Gauss-Newton form of the heat (one evaluation; precondition.h): without it each
  /// full SLSQP step of the 10-point solves overshot.
  bool precondition = true;
  int precondition_min_variables = 30;
  /// Stall test of a local solve: it stops when the last stall_iterations iterations
  /// (evaluations with gradients) that satisfied the rows handed to NLopt within
  /// stall_feasibility_tol together lowered the best such objective by less than stall_rtol of
  /// it, and the others among them were no more than as many; the best such point is returned. ftol_rel (1e-10) asks for far more
  /// than the refinement's 0.1 % and the 0.3 % of the figures: the last iterations of a refined
  /// solve spent hundreds of evaluations on changes below 1e-6. 0: no stall test.
  double stall_rtol = 1e-5;
  int stall_iterations = 10;
  double stall_feasibility_tol = 1e-6;
};

struct OptimizeResult {
  SolverStatus solver;          ///< of the local solve that gave x
  std::vector<double> x;        ///< the best point (the start when nothing usable came out)
  double objective = 0;         ///< [J]
  double max_node_constraint = 0;  ///< max c(x) at the quadrature nodes (<= 0: feasible)
  int evaluations = 0;          ///< objective evaluations, all starts together
  int starts = 0;               ///< local solves run
  int best_start = 0;           ///< which one gave x (0: the given start)
  Status evaluation;            ///< not ok: even the start could not be evaluated
};

/// Minimizes problem.objective subject to its constraints, from x0.
OptimizeResult optimize(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                        const OptimizerOptions& options);

}  // namespace fivebar::trajectory
