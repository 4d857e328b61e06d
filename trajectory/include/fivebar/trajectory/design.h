// The outer loop of `fivebar design`: a derivative-free minimization over a box of design
// values (NLopt BOBYQA on the box scaled to [0, 1]^k). The objective (a sum of inner optima,
// each a function of the design only through a solve) has no cheap gradient and is noisy at
// the level of the inner solver's tolerance, and a design that cannot do a task has no
// gradient at all; BOBYQA's quadratic models of sampled values need neither.
#pragma once

#include <functional>
#include <vector>

#include "fivebar/trajectory/nlopt_status.h"

namespace fivebar::trajectory {

struct BoxOptions {
  int max_evaluations = 40;    ///< designs evaluated at most (the start included)
  double initial_step = 0.4;  ///< first trust-region radius, as a fraction of each range
  double xtol = 1e-3;          ///< stop when a step changes every value by < xtol of its range
  double ftol_rel = 1e-6;      ///< stop when the objective changes by < this (relative)
};

struct BoxResult {
  SolverStatus solver;
  std::vector<double> x;  ///< the best point evaluated
  double value = 0;       ///< its objective
  int evaluations = 0;
};

/// Minimizes f over lo <= x <= hi from x0 (clamped into the box). f is called once per design,
/// in sequence, and must be deterministic for the result to be. Requires lo[i] < hi[i].
BoxResult minimize_box(const std::function<double(const std::vector<double>&)>& f,
                       const std::vector<double>& lo, const std::vector<double>& hi,
                       const std::vector<double>& x0, const BoxOptions& options);

}  // namespace fivebar::trajectory
