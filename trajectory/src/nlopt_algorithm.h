// Internal: what the trajectory optimizer and the general multi-start driver share about NLopt
// local solves: the algorithm of each method and the ranking of their results (NLopt is included
// only in trajectory/src).
#pragma once

#include <nlopt.hpp>

#include "fivebar/trajectory/optimizer.h"

namespace fivebar::trajectory {

inline nlopt::algorithm nlopt_algorithm(Method m) {
  switch (m) {
    case Method::kMma:
      return nlopt::LD_MMA;
    case Method::kCcsaq:
      return nlopt::LD_CCSAQ;
    case Method::kSlsqp:
      break;
  }
  return nlopt::LD_SLSQP;
}

/// Ranking of two local results (any type with evaluated, solver, max_constraint, objective): a
/// feasible result beats an infeasible one; then the lower objective, or the smaller violation.
template <typename Local>
bool better(const Local& a, const Local& b, double tol) {
  if (!a.evaluated) return false;
  if (!b.evaluated) return true;
  const bool fa = a.solver.usable() && a.max_constraint <= tol;
  const bool fb = b.solver.usable() && b.max_constraint <= tol;
  if (fa != fb) return fa;
  if (!fa) return a.max_constraint < b.max_constraint;
  return a.objective < b.objective;
}

}  // namespace fivebar::trajectory
