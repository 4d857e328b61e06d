// One solve of a task (a stage): the optimization of one discretization under one smoothing of
// the friction law, its dense re-check and its exact-law objective; and the continuation and
// refinement that chain such stages (refine.cc). Internal to the library.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "fivebar/trajectory/batch.h"

namespace fivebar::trajectory {

struct Candidate {
  std::vector<double> x;
  int control_points = 0;
  double smoothing_velocity = 0;  ///< w_s of the problem solved [rad/s]
  SolverStatus solver;
  Status evaluation;              ///< not ok: even the start could not be evaluated
  ConstraintCheck check;          ///< dense grid, exact law
  int evaluations = 0, starts = 0, best_start = 0;
  double exact = NAN;             ///< exact-law objective of x [J]
  bool solved() const { return evaluation.ok() && !x.empty(); }
};

/// True when c is usable: solved, its solver's point usable, its check ok and within every limit
/// (BatchOptions::limit_rtol), its exact-law objective finite.
bool feasible(const Candidate& c, const BatchOptions& options);
/// The same within the looser feasibility_tol: a point the later stages may start from.
bool startable(const Candidate& c, const BatchOptions& options);

/// Optimizes `motion` under the smoothing velocity `ws` from x0 (the torque peak between the
/// nodes removed by re-solving with a lowered limit, at most twice), then re-checks it.
Candidate solve_stage(const Params<double>& params, const sim::LoadFunction& loads,
                      const RestToRest& motion, double ws, const std::vector<double>& x0,
                      const BatchOptions& options, double torque_limit,
                      const OptimizerOptions& optimizer);

/// The refinement of the control points of `first` under its smoothed law, then the
/// continuation of the finest spline kept towards the exact law (options.refine.continuation);
/// the best feasible candidate of all stages (`first` itself when it is not feasible). The
/// stages are described in r->continuation, r->refinement and r->refinement_change.
Candidate refine(const Params<double>& params, const sim::LoadFunction& loads,
                 const Candidate& first, const BatchOptions& options,
                 const OptimizerOptions& optimizer, TaskResult* r);

}  // namespace fivebar::trajectory
