// A general NLopt driver: minimize f(x) subject to c(x) <= 0 and box bounds, from several starts
// (multi-start), for problems that are not rest-to-rest trajectories (the excitation design of
// identification/excitation.h). NLopt itself stays out of this header.
#pragma once

#include <functional>
#include <vector>

#include "fivebar/trajectory/nlopt_status.h"
#include "fivebar/trajectory/optimizer.h"

namespace fivebar::trajectory {

/// Evaluates f, c (m values) and, when `grad`, df (n) and dc (m x n, row-major) at x. Returns
/// false where the point cannot be evaluated (the driver then steps back from it).
using EvaluateFunction =
    std::function<bool(const std::vector<double>& x, bool grad, double* f, std::vector<double>* df,
                       std::vector<double>* c, std::vector<double>* dc)>;

struct GeneralProblem {
  int n = 0, m = 0;
  std::vector<double> lower, upper;
  EvaluateFunction evaluate;
};

struct GeneralOptions {
  Method method = Method::kSlsqp;
  double ftol_rel = 1e-6, xtol_rel = 1e-6;
  int max_evaluations = 200;       ///< per local solve
  double constraint_tol = 1e-6;    ///< NLopt tolerance of each constraint
  double max_time_s = 0;           ///< per local solve; 0: none
};

struct GeneralResult {
  SolverStatus solver;       ///< of the local solve that gave x
  std::vector<double> x;     ///< the best point (a start when nothing usable came out)
  double objective = 0;
  double max_constraint = 0;  ///< max c(x) (<= tolerance: feasible)
  bool evaluated = false;     ///< x could be evaluated
  int evaluations = 0;        ///< all starts together
  int best_start = 0;
  std::vector<double> start_objectives;  ///< final objective of each start (NaN: failed)
  std::vector<double> start_max_constraint;  ///< max c at each start's result
  std::vector<bool> start_feasible;
};

/// Local solves from every start; the best feasible result wins (then the least infeasible).
GeneralResult minimize_multistart(const GeneralProblem& problem,
                                  const std::vector<std::vector<double>>& starts,
                                  const GeneralOptions& options);

}  // namespace fivebar::trajectory
