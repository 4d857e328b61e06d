// The general multi-start NLopt driver (NLopt is included only in trajectory/src).
#include "fivebar/trajectory/nlopt_minimize.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <nlopt.hpp>

#include "nlopt_algorithm.h"

namespace fivebar::trajectory {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// one evaluation shared by the objective and constraint callbacks at the same point
class Cache {
 public:
  Cache(const GeneralProblem& p, double penalty, double tol) : p_(p), penalty_(penalty), tol_(tol) {}
  void at(const double* x, bool grad) {
    const bool same = valid_ && std::equal(x, x + p_.n, x_.begin());
    if (same && (has_grad_ || !grad)) return;
    x_.assign(x, x + p_.n);
    valid_ = true;
    has_grad_ = grad;
    ++evaluations;
    if (!p_.evaluate(x_, grad, &f, &df, &c, &dc)) {
      f = penalty_;  // outside the model's domain: a flat penalty makes line searches step back
      df.assign(p_.n, 0.0);
      c.assign(p_.m, 1.0);
      dc.assign(static_cast<size_t>(p_.m) * p_.n, 0.0);
      return;
    }
    // the best point evaluated: feasible (within tol) before infeasible, then the lower objective
    // (infeasible: the smaller violation)
    const double worst = c.empty() ? 0.0 : *std::max_element(c.begin(), c.end());
    const bool feasible = worst <= tol_, best_feasible = best_c <= tol_;
    if (best_x.empty() || (feasible && (!best_feasible || f < best_f)) ||
        (!feasible && !best_feasible && worst < best_c)) {
      best_x = x_;
      best_f = f;
      best_c = worst;
    }
  }
  double f = 0;
  std::vector<double> df, c, dc;
  int evaluations = 0;
  std::vector<double> best_x;  ///< empty: no point could be evaluated
  double best_f = kNaN, best_c = kNaN;

 private:
  const GeneralProblem& p_;
  double penalty_, tol_;
  std::vector<double> x_;
  bool valid_ = false, has_grad_ = false;
};

double objective_cb(unsigned n, const double* x, double* grad, void* data) {
  Cache* cache = static_cast<Cache*>(data);
  cache->at(x, grad != nullptr);
  if (grad) std::memcpy(grad, cache->df.data(), n * sizeof(double));
  return cache->f;
}

void constraints_cb(unsigned m, double* result, unsigned n, const double* x, double* grad,
                    void* data) {
  Cache* cache = static_cast<Cache*>(data);
  cache->at(x, grad != nullptr);
  std::memcpy(result, cache->c.data(), m * sizeof(double));
  if (grad) std::memcpy(grad, cache->dc.data(), static_cast<size_t>(m) * n * sizeof(double));
}

struct Local {
  SolverStatus solver;
  std::vector<double> x;
  double objective = kNaN, max_constraint = kNaN;
  bool evaluated = false;
  int evaluations = 0;
};

Local solve_local(const GeneralProblem& p, std::vector<double> x, const GeneralOptions& o,
                  double penalty) {
  Cache cache(p, penalty, 10.0 * o.constraint_tol);
  Local out;
  for (int i = 0; i < p.n; ++i) x[i] = std::clamp(x[i], p.lower[i], p.upper[i]);
  try {
    nlopt::opt opt(nlopt_algorithm(o.method), p.n);
    opt.set_lower_bounds(p.lower);
    opt.set_upper_bounds(p.upper);
    opt.set_min_objective(objective_cb, &cache);
    opt.add_inequality_mconstraint(constraints_cb, &cache,
                                   std::vector<double>(p.m, o.constraint_tol));
    opt.set_ftol_rel(o.ftol_rel);
    opt.set_xtol_rel(o.xtol_rel);
    opt.set_maxeval(o.max_evaluations);
    if (o.max_time_s > 0) opt.set_maxtime(o.max_time_s);
    double f = 0;
    out.solver = status_from_result(static_cast<int>(opt.optimize(x, f)));
  } catch (...) {
    out.solver = status_from_exception(std::current_exception());
  }
  out.x = x;
  out.evaluations = cache.evaluations;
  // the returned point, evaluated afresh (NLopt may return a point it evaluated earlier); when
  // the solver stopped at a point outside the model's domain, the best point it evaluated
  double f = 0;
  std::vector<double> df, c, dc;
  bool ok = p.evaluate(x, false, &f, &df, &c, &dc);
  if (!ok && !cache.best_x.empty()) {
    out.x = x = cache.best_x;
    ok = p.evaluate(x, false, &f, &df, &c, &dc);
  }
  if (ok) {
    out.evaluated = true;
    out.objective = f;
    out.max_constraint = c.empty() ? 0.0 : *std::max_element(c.begin(), c.end());
  }
  return out;
}

}  // namespace

GeneralResult minimize_multistart(const GeneralProblem& problem,
                                  const std::vector<std::vector<double>>& starts,
                                  const GeneralOptions& options) {
  GeneralResult result;
  if (starts.empty()) {
    result.solver = {SolverOutcome::kInvalidArgument, "no start given"};
    return result;
  }
  result.x = starts.front();
  double f0 = 0;
  std::vector<double> df, c, dc;
  const bool ok0 = problem.evaluate(starts.front(), false, &f0, &df, &c, &dc);
  const double penalty = 1e3 * (1.0 + (ok0 ? std::abs(f0) : 1.0));
  const double tol = 10.0 * options.constraint_tol;
  Local best;
  for (size_t s = 0; s < starts.size(); ++s) {
    Local local = solve_local(problem, starts[s], options, penalty);
    result.evaluations += local.evaluations;
    result.start_objectives.push_back(local.evaluated ? local.objective : kNaN);
    result.start_max_constraint.push_back(local.max_constraint);
    result.start_feasible.push_back(local.evaluated && local.solver.usable() &&
                                    local.max_constraint <= tol);
    if (s == 0 || better(local, best, tol)) {
      best = std::move(local);
      result.best_start = static_cast<int>(s);
    }
  }
  result.solver = best.solver;
  result.evaluated = best.evaluated;
  if (best.evaluated) {
    result.x = best.x;
    result.objective = best.objective;
    result.max_constraint = best.max_constraint;
  }
  return result;
}

}  // namespace fivebar::trajectory
