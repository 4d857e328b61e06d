// Stages of a task's solve: the first (smoothed) solve, the continuation on the smoothing
// velocity towards the scene's exact friction law, and the refinement of the control points.
#include <algorithm>
#include <cmath>
#include <string>

#include "fivebar/model/format.h"
#include "stage.h"

namespace fivebar::trajectory {
namespace {

// re-solves with a lowered torque limit when the dense check finds a peak between the nodes
constexpr int kTightenRounds = 4;
// the limit is lowered by the overshoot raised to this power: lowered by the overshoot itself,
// the re-solve peaked again 0.3% to 0.4% over the limit (a tenth of the first overshoot of 2% to
// 4%), and a second re-solve followed on 3 of the 8 stages that needed one
constexpr double kTightenGain = 1.3;

// the problem of a stage: finer splines get fewer quadrature points per knot span (as many
// nodes in all as the first solve's, at least options.refine.min_quadrature_points per span)
ProblemOptions stage_options(const BatchOptions& options, int control_points, double ws,
                             double torque_limit) {
  ProblemOptions o = options.problem;
  o.smoothing_velocity = ws;
  o.torque_limit = torque_limit;
  const int base_spans = std::max(1, options.problem.control_points - kDegree);
  const int spans = control_points - kDegree;
  if (spans > base_spans) {
    const int q = (o.quadrature_points * base_spans + spans - 1) / spans;
    o.quadrature_points = std::max(std::min(options.refine.min_quadrature_points,
                                            o.quadrature_points), q);
  }
  return o;
}

// exact-law value of the objective the problem minimizes, Gauss-Legendre 4x denser than its rule
double exact_objective(const TrajectoryProblemBase& problem, const std::vector<double>& x,
                       const BatchOptions& options) {
  Energies e;
  if (!problem.exact_energies(x.data(), 4 * options.problem.quadrature_points, &e).ok()) {
    return NAN;
  }
  return e.of(options.problem.objective);
}

// a is better than b: feasible beats infeasible, then the lower exact-law objective
bool better(const Candidate& a, const Candidate& b, const BatchOptions& options) {
  const bool fa = feasible(a, options), fb = feasible(b, options);
  if (fa != fb) return fa;
  return fa && a.exact < b.exact;
}

// "key:E" (exact-law objective), "x" appended when the stage did not improve the result
void log_stage(std::string* log, double key, const Candidate& c, bool kept) {
  *log += (log->empty() ? "" : ";") + format_significant(key, 7) + ":" +
          format_significant(c.exact, 7) + (kept ? "" : "x");
}

// why a candidate is not feasible (feasible() below)
std::string why_infeasible(const Candidate& c, const BatchOptions& options) {
  if (!c.solved()) return "not solved";
  if (!c.solver.usable()) return "solver: " + c.solver.message;
  if (!c.check.status.ok()) return "check: " + c.check.status.message;
  if (c.check.max_violation > options.limit_rtol) {
    return "violation " + format_significant(c.check.max_violation, 7) +
           " on the check grid (peak " + format_significant(c.check.peak_torque, 7) +
           " N m, min sine " + format_significant(c.check.min_coupler_sine, 7) + ")";
  }
  return "exact-law energy not finite";
}

}  // namespace

bool startable(const Candidate& c, const BatchOptions& options) {
  return c.solved() && c.solver.usable() && c.check.status.ok() &&
         c.check.max_violation <= options.feasibility_tol && std::isfinite(c.exact);
}

bool feasible(const Candidate& c, const BatchOptions& options) {
  return c.solved() && c.solver.usable() && c.check.status.ok() &&
         c.check.max_violation <= options.limit_rtol && std::isfinite(c.exact);
}

Candidate solve_stage(const StageFactory& factory, int n, double ws,
                      const std::vector<double>& x0, const BatchOptions& options,
                      double torque_limit, const OptimizerOptions& optimizer) {
  Candidate c;
  c.control_points = n;
  c.smoothing_velocity = ws;
  const std::unique_ptr<TrajectoryProblemBase> owned =
      factory.problem(n, stage_options(options, n, ws, torque_limit));
  const TrajectoryProblemBase& problem = *owned;
  const OptimizeResult opt = optimize(problem, x0, optimizer);
  c.solver = opt.solver;
  c.evaluation = opt.evaluation;
  c.evaluations = opt.evaluations;
  c.starts = opt.starts;
  c.best_start = opt.best_start;
  if (!opt.evaluation.ok()) return c;
  c.x = opt.x;
  const int grid = options.check_factor * problem.num_nodes() + 1;
  c.check = problem.check(c.x.data(), grid);
  // a torque peak between the nodes: re-solve with the limit lowered by the overshoot (and a
  // margin, kTightenGain)
  double limit = torque_limit;
  for (int round = 0; round < kTightenRounds && c.check.status.ok() && opt.solver.usable() &&
                      c.check.torque_excess > options.limit_rtol * torque_limit;
       ++round) {
    limit *= std::pow(torque_limit / c.check.peak_torque, kTightenGain) *
             (1.0 - 0.1 * std::max(options.limit_rtol, c.check.torque_excess / torque_limit));
    const std::unique_ptr<TrajectoryProblemBase> tightened =
        factory.problem(n, stage_options(options, n, ws, limit));
    const OptimizeResult again = optimize(*tightened, c.x, optimizer);
    c.evaluations += again.evaluations;
    if (!again.solver.usable()) break;
    const ConstraintCheck c2 = problem.check(again.x.data(), grid);
    if (!c2.status.ok()) break;
    c.x = again.x;
    c.check = c2;
  }
  if (c.check.status.ok()) c.exact = exact_objective(problem, c.x, options);
  return c;
}

namespace {

// the message's note when the last stage of the continuation still lowered the exact-law
// objective by more than the refinement's tolerance: the optimum holds a joint near rest, where
// the smoothing of the friction law still matters, and a smaller w_s may lower it further
void note_continuation_unsettled(double ws, double lowered, const BatchOptions& options,
                                 TaskResult* r) {
  r->add_note("continuation not converged: its last stage (w_s = " + format_significant(ws, 2) +
              " rad/s) lowered the exact-law energy by " + format_significant(100.0 * lowered, 2) +
              "% (tolerance " + format_significant(100.0 * options.refine.tol, 2) +
              "%): a joint creeps near rest, where the friction law's smoothing still matters");
}

// the continuation on w_s from `best`, each stage warm-started from the last usable point
Candidate continuation(const StageFactory& factory, Candidate best, const BatchOptions& options,
                       const OptimizerOptions& optimizer, TaskResult* r) {
  const int n = best.control_points;
  std::vector<double> warm = best.x;
  log_stage(&r->continuation, best.smoothing_velocity, best, true);
  // a polish: its solves get the continuation's own evaluation limit
  OptimizerOptions polish = optimizer;
  polish.max_evaluations =
      std::min(optimizer.max_evaluations, options.refine.continuation_max_evaluations);
  polish.stall_rtol = std::max(optimizer.stall_rtol, options.refine.continuation_stall_rtol);
  polish.stall_iterations =
      std::min(optimizer.stall_iterations, options.refine.continuation_stall_iterations);
  // a stage that lowers the exact-law objective by less than the refinement's tolerance ends
  // the continuation: the smoothing no longer matters (on reach_left, whose optimum holds a
  // joint at rest, the stages lowered it by 0.35%, 0.18%, 0.05% and 0.0096%; on the other
  // shipped tasks the first by less than 2e-5)
  const std::vector<double>& stages = options.refine.continuation;
  for (size_t k = 0; k < stages.size(); ++k) {
    const double before = best.exact;
    Candidate c = solve_stage(factory, n, stages[k], warm, options, r->torque_limit, polish);
    r->evaluations += c.evaluations;
    if (c.solved() && c.solver.usable()) warm = c.x;
    const bool kept = better(c, best, options);
    log_stage(&r->continuation, stages[k], c, kept);
    if (kept) best = std::move(c);
    const double lowered = (before - best.exact) / std::abs(before);
    if (!(lowered > options.refine.tol)) break;
    if (k + 1 == stages.size()) note_continuation_unsettled(stages[k], lowered, options, r);
  }
  return best;
}

}  // namespace

namespace {

// the message's note when the levels ran out before the energy settled: the answer is then the
// optimum of the finest basis, not yet of the problem (on the shipped swing_right task the
// energy still fell 0.43% from 85 to 165 control points: docs/dev/figures-optimization.md)
void note_unconverged(const BatchOptions& options, TaskResult* r) {
  if (!r->discretization_unsettled(options.refine.tol)) return;  // converged, or no level solved
  if (r->refinement_limited) {
    r->add_note(
        "discretization not shown converged: the finest level stopped at its evaluation limit "
        "(raise --max-evaluations)");
    return;
  }
  r->add_note("discretization not converged: the exact-law energy changed by " +
              format_significant(100.0 * r->refinement_change, 2) +
              "% at the last refinement (tolerance " +
              format_significant(100.0 * options.refine.tol, 2) +
              "%): the result is the optimum of the finest basis solved; add a finer level with "
              "--refine-levels");
}

// the refinement of the control points of `best` (options.refine.control_points), every level
// solved under the smoothed law of `best`
Candidate refinement(const StageFactory& factory, Candidate best, const BatchOptions& options,
                     const OptimizerOptions& optimizer, TaskResult* r) {
  const double ws = best.smoothing_velocity;
  double previous = best.exact;
  log_stage(&r->refinement, best.control_points, best, true);
  for (int n : options.refine.control_points) {
    if (n <= best.control_points) continue;
    Candidate c = solve_stage(factory, n, ws, factory.refit(best, n), options, r->torque_limit,
                              optimizer);
    r->evaluations += c.evaluations;
    const bool kept = better(c, best, options);
    log_stage(&r->refinement, n, c, kept);
    if (!feasible(c, options)) {
      r->add_note("refinement level " + std::to_string(n) + " not kept: " +
                  why_infeasible(c, options));
      continue;
    }
    r->refinement_change = std::abs(c.exact - previous) / std::abs(previous);
    // a level stopped at its limit may sit anywhere above its basis's optimum (deg12: a
    // 325-point level ended 1.5e-6 from the 165-point one and passed for converged)
    r->refinement_limited = c.solver.limited();
    previous = c.exact;
    if (kept) best = std::move(c);
    if (r->refinement_change < options.refine.tol && !r->refinement_limited) break;
  }
  note_unconverged(options, r);
  return best;
}

}  // namespace

Candidate refine(const StageFactory& factory, const Candidate& first,
                 const BatchOptions& options, const OptimizerOptions& optimizer, TaskResult* r) {
  // the levels under the first solve's smoothed law, whose landscape has no kinks at the
  // reversals, then the continuation to the exact law on the finest spline kept (a scene whose
  // own law is smoothed is solved exactly by the first law)
  if (!startable(first, options)) return first;
  Candidate best = refinement(factory, first, options, optimizer, r);
  if (!factory.smooth_law()) best = continuation(factory, best, options, optimizer, r);
  return best;
}

}  // namespace fivebar::trajectory
