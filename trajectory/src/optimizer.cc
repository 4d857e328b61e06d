// The NLopt driver (NLopt is included only in trajectory/src).
#include "fivebar/trajectory/optimizer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <nlopt.hpp>

#include "fivebar/model/names.h"
#include "nlopt_algorithm.h"
#include "precondition.h"

namespace fivebar::trajectory {
namespace {

// evaluations shared by the objective and constraint callbacks of one local solve
class Cache {
 public:
  Cache(const TrajectoryProblemBase& problem, double penalty) : problem_(problem), penalty_(penalty) {}

  const Evaluated& at(const double* x, bool grad) {
    const int n = problem_.num_variables();
    const bool same = valid_ && std::equal(x, x + n, x_.begin());
    if (same && (has_grad_ || !grad)) return value_;
    x_.assign(x, x + n);
    valid_ = true;
    has_grad_ = grad;
    ++evaluations_;
    const Status st = grad ? problem_.evaluate_local(x, &value_)
                           : problem_.evaluate(x, false, &value_);
    if (!st.ok()) {
      // outside the domain of the model (cannot assemble, friction loop failed): a large flat
      // penalty makes the line searches step back
      value_.objective = penalty_;
      value_.constraints.assign(problem_.num_constraints(), 1.0);
      value_.objective_grad.assign(n, 0.0);
      value_.constraints_grad_local.assign(
          static_cast<size_t>(problem_.num_constraints()) * problem_.local_variables(), 0.0);
    }
    return value_;
  }
  int evaluations() const { return evaluations_; }

 private:
  const TrajectoryProblemBase& problem_;
  double penalty_;
  std::vector<double> x_;
  bool valid_ = false, has_grad_ = false;
  Evaluated value_;
  int evaluations_ = 0;
};

// The stall test (OptimizerOptions::stall_rtol): the best point that satisfies the rows handed
// to NLopt, and the run stopped when the last `window` such iterations (evaluations with
// gradients) lowered the best objective by less than rtol of it. Iterations that violate the
// rows (SLSQP's rejected trial steps) are skipped, not counted against the run, as long as
// they are at most as many as the feasible ones: on the near-kinks of the law at small w_s
// SLSQP alternates a long trial step with a short accepted one, and a run of consecutive
// feasible iterations never came (the continuation's solves ran to their limit).
struct Stall {
  double rtol = 0, feasible_tol = 0;
  int window = 0;
  nlopt::opt* opt = nullptr;
  std::vector<double> best_x;
  double best_f = std::numeric_limits<double>::infinity();
  std::vector<double> history;   // best_f at each feasible iteration
  std::vector<int> feasible_at;  // the iteration count at each of them
  int iterations = 0;
  bool stalled = false;
  // screening (solve_screened): `screened` marks the rows handed to NLopt (null: all of
  // them); a new best point that violates a row left out ends the round there (`escaped`)
  const std::vector<char>* screened = nullptr;
  bool escaped = false;

  // true (and the run stopped) when the best point x violates a row NLopt does not see: the
  // rest of the round would converge to a point the next round rejects anyway
  bool escape(const Evaluated& e) {
    if (!screened || escaped) return escaped;
    for (size_t i = 0; i < screened->size(); ++i) {
      if (!(*screened)[i] && e.constraints[i] > 0.0) {
        escaped = true;
        if (opt) opt->force_stop();
        break;
      }
    }
    return escaped;
  }

  void record(const double* x, int n, const Evaluated& e, const std::vector<int>& rows,
              bool iteration) {
    double cv = -std::numeric_limits<double>::infinity();
    for (int r : rows) cv = std::max(cv, e.constraints[r]);
    const bool ok = cv <= feasible_tol && std::isfinite(e.objective);
    const bool improved = ok && e.objective < best_f;
    if (improved) {
      best_f = e.objective;
      best_x.assign(x, x + n);
    }
    if (!iteration || (improved && escape(e))) return;
    if (!(rtol > 0) || stalled) return;
    ++iterations;
    if (!ok) return;
    history.push_back(best_f);
    feasible_at.push_back(iterations);
    const size_t k = history.size(), w = static_cast<size_t>(window);
    if (k > w && iterations - feasible_at[k - 1 - w] <= 2 * window &&
        history[k - 1 - w] - best_f <= rtol * std::abs(best_f)) {
      stalled = true;
      if (opt) opt->force_stop();
    }
  }
};

// the variables NLopt sees: x itself, or y with x = origin + T y (a Preconditioner); and the
// constraint rows handed to it (all of them, or the screened subset)
struct View {
  Cache* cache;
  const std::vector<int>* rows;
  const Preconditioner* pre;  // null: x itself
  Eigen::VectorXd origin, x;
  Stall* stall;
  // the free variables of each node's local gradients, `local` per node
  // (TrajectoryProblemBase::node_variables_into), and the rows per node
  const std::vector<int>* node_vars;
  int local = 0, rows_per_node = 1;

  const Evaluated& at(const double* y, unsigned n, bool grad) {
    const double* px = y;
    if (pre) {
      x = origin + pre->T * Eigen::Map<const Eigen::VectorXd>(y, n);
      px = x.data();
    }
    const int before = cache->evaluations();
    const Evaluated& e = cache->at(px, grad);
    if (cache->evaluations() != before) stall->record(px, static_cast<int>(n), e, *rows, grad);
    return e;
  }
  // the local gradient of constraint row `row` (Evaluated::constraints_grad_local) as a dense
  // one with respect to the variables NLopt sees
  void chain_row(const Evaluated& e, int row, unsigned n, double* out) const {
    const int* vars = &(*node_vars)[static_cast<size_t>(row / rows_per_node) * local];
    const double* g = &e.constraints_grad_local[static_cast<size_t>(row) * local];
    std::fill(out, out + n, 0.0);
    Eigen::Map<Eigen::VectorXd> o(out, n);
    for (int l = 0; l < local; ++l) {
      if (vars[l] < 0 || g[l] == 0.0) continue;
      if (pre) {
        o += g[l] * pre->Tt.col(vars[l]);
      } else {
        out[vars[l]] += g[l];
      }
    }
  }
  // a gradient with respect to x (n values) as one with respect to the variables NLopt sees
  void chain(const double* g, unsigned n, double* out) const {
    if (!pre) {
      std::memcpy(out, g, n * sizeof(double));
      return;
    }
    // T^T g, by the columns of T^T (rows of T) where g is non-zero: a constraint row depends
    // on the 12 control points around its node only
    Eigen::Map<Eigen::VectorXd> o(out, n);
    o.setZero();
    for (unsigned k = 0; k < n; ++k) {
      if (g[k] != 0.0) o += g[k] * pre->Tt.col(k);
    }
  }
};

double objective_cb(unsigned n, const double* x, double* grad, void* data) {
  View& v = *static_cast<View*>(data);
  const Evaluated& e = v.at(x, n, grad != nullptr);
  if (grad) v.chain(e.objective_grad.data(), n, grad);
  return e.objective;
}

void constraints_cb(unsigned m, double* result, unsigned n, const double* x, double* grad,
                    void* data) {
  View& v = *static_cast<View*>(data);
  const Evaluated& e = v.at(x, n, grad != nullptr);
  for (unsigned i = 0; i < m; ++i) {
    const size_t row = static_cast<size_t>((*v.rows)[i]);
    result[i] = e.constraints[row];
    if (grad) v.chain_row(e, static_cast<int>(row), n, grad + i * n);
  }
}

struct Local {
  SolverStatus solver;
  std::vector<double> x;
  double objective = std::numeric_limits<double>::infinity();
  double max_constraint = std::numeric_limits<double>::infinity();
  int evaluations = 0;
  bool evaluated = false;
  std::vector<double> constraints;  ///< every constraint at x (when evaluated)
  bool escaped = false;  ///< ended early at x: it violates a row the screening left out
};

// the box of the variables: one turn beyond the span of the motion (MMA and CCSAQ want a
// bounded box); x is clamped into it
void box_of(const TrajectoryProblemBase& problem, std::vector<double>* lo, std::vector<double>* hi,
            std::vector<double>* x) {
  const int n = problem.num_variables(), nf = problem.free_per_joint();
  lo->resize(n);
  hi->resize(n);
  for (int j = 0; j < problem.dofs(); ++j) {
    const double a = problem.start_angle(j), b = problem.goal_angle(j);
    for (int v = 0; v < nf; ++v) {
      (*lo)[j * nf + v] = std::min(a, b) - M_PI;
      (*hi)[j * nf + v] = std::max(a, b) + M_PI;
      (*x)[j * nf + v] = std::clamp((*x)[j * nf + v], (*lo)[j * nf + v], (*hi)[j * nf + v]);
    }
  }
}

// the outcome of a run NLopt ended (code) or that threw (error); a run the stall test stopped
// ends at the stall's best point
void finish_run(const View& view, const Stall& stall, int code, std::exception_ptr error,
                const std::vector<double>& y, Local* out) {
  out->solver = error ? status_from_exception(error) : status_from_result(code);
  if (stall.escaped) {
    // the next round of the screening resumes from there
    out->solver = {SolverOutcome::kConverged,
                   "stopped: a constraint row left out by the screening was violated"};
    out->x = stall.best_x;
    out->escaped = true;
  } else if (stall.stalled && !stall.best_x.empty()) {
    out->solver = {SolverOutcome::kConverged,
                   "converged: objective lowered by less than the stall tolerance over the last "
                   "iterations"};
    out->x = stall.best_x;
  } else if (error) {
    return;
  } else if (view.pre) {
    const int n = static_cast<int>(y.size());
    const Eigen::VectorXd x =
        view.origin + view.pre->T * Eigen::Map<const Eigen::VectorXd>(y.data(), n);
    out->x.assign(x.data(), x.data() + n);
  } else {
    out->x = y;
  }
}

// one local solve under the constraint rows `rows` (indices into the problem's constraints)
Local solve_local(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                  const OptimizerOptions& options, double penalty, const std::vector<int>& rows,
                  const Preconditioner* pre, const std::vector<char>* screened = nullptr) {
  const int n = problem.num_variables(), m = static_cast<int>(rows.size());
  Cache cache(problem, penalty);
  Stall stall;
  stall.rtol = options.stall_rtol;
  stall.window = options.stall_iterations;
  stall.feasible_tol = options.stall_feasibility_tol;
  if (static_cast<int>(rows.size()) < problem.num_constraints()) stall.screened = screened;
  const int local = problem.local_variables();
  std::vector<int> node_vars(static_cast<size_t>(problem.num_nodes()) * local);
  for (int q = 0; q < problem.num_nodes(); ++q) {
    problem.node_variables_into(q, &node_vars[static_cast<size_t>(q) * local]);
  }
  View view{&cache, &rows, pre && pre->active ? pre : nullptr, {}, {}, &stall, &node_vars,
            local, problem.rows_per_node()};
  Local out;
  out.x = x0;
  int code = 0;
  std::exception_ptr error;
  std::vector<double> y;
  try {
    nlopt::opt opt(nlopt_algorithm(options.method), n);
    stall.opt = &opt;
    std::vector<double> lo, hi;
    box_of(problem, &lo, &hi, &out.x);
    y = out.x;
    if (view.pre) {
      // y = 0 at the start; the box (never reached by SLSQP's steps in practice) is left out
      view.origin = Eigen::Map<const Eigen::VectorXd>(out.x.data(), n);
      y.assign(n, 0.0);
    } else {
      opt.set_lower_bounds(lo);
      opt.set_upper_bounds(hi);
    }
    opt.set_min_objective(objective_cb, &view);
    if (m > 0) {
      opt.add_inequality_mconstraint(constraints_cb, &view,
                                     std::vector<double>(m, options.constraint_tol));
    }
    opt.set_ftol_rel(options.ftol_rel);
    opt.set_xtol_rel(options.xtol_rel);
    opt.set_maxeval(options.max_evaluations);
    double f = 0;
    code = static_cast<int>(opt.optimize(y, f));
  } catch (...) {
    error = std::current_exception();
  }
  finish_run(view, stall, code, error, y, &out);
  out.evaluations = cache.evaluations();
  // the returned point, evaluated afresh (NLopt may return a point it evaluated earlier)
  Evaluated e;
  if (problem.evaluate(out.x.data(), false, &e).ok()) {
    out.evaluated = true;
    out.objective = e.objective;
    out.max_constraint = *std::max_element(e.constraints.begin(), e.constraints.end());
    out.constraints = std::move(e.constraints);
  }
  return out;
}

// the preconditioner of a solve from x0, when the options ask for one (inactive otherwise); a
// solve whose objective is mostly winding heat is preconditioned at any size (its Gauss-Newton
// Hessian costs one evaluation)
Preconditioner preconditioner_of(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                                 const OptimizerOptions& options) {
  if (!options.precondition || options.method != Method::kSlsqp) return {};
  const bool gauss_newton = gauss_newton_preconditioning(problem, x0);
  if (problem.num_variables() < options.precondition_min_variables && !gauss_newton) return {};
  return objective_preconditioner(problem, x0, gauss_newton);
}

// A local solve under the constraints that matter (OptimizerOptions::screen): the rows with
// c > -screen at the start; every row that the result violates or nears is added and the solve
// resumed from there, until no row left out is violated (at most 4 rounds, the last with every
// row). The first round ends early at its first new best point that violates a row left out
// (it would otherwise converge to a point the next round rejects: swing_left's, reach_right's
// and lower_fast's refined levels spent 25 to 40 evaluations there). screen <= 0: every row
// from the start.
Local solve_screened(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                     const OptimizerOptions& options, double penalty) {
  const int m = problem.num_constraints();
  std::vector<int> all(m);
  for (int i = 0; i < m; ++i) all[i] = i;
  // one preconditioner for every round (its evaluations count in the limit)
  const Preconditioner pre = preconditioner_of(problem, x0, options);
  OptimizerOptions budget = options;
  budget.max_evaluations = std::max(1, options.max_evaluations - pre.evaluations);
  Evaluated e;
  if (!(options.screen > 0) || !problem.evaluate(x0.data(), false, &e).ok()) {
    Local out = solve_local(problem, x0, budget, penalty, all, &pre);
    out.evaluations += pre.evaluations;
    return out;
  }
  std::vector<char> in(m, 0);
  for (int i = 0; i < m; ++i) in[i] = e.constraints[i] > -options.screen;
  std::vector<double> x = x0;
  int evaluations = pre.evaluations;
  Local out;
  for (int round = 0; round < 4; ++round) {
    std::vector<int> rows;
    for (int i = 0; i < m; ++i) {
      if (in[i] || round == 3) rows.push_back(i);
    }
    budget.max_evaluations = std::max(1, options.max_evaluations - evaluations);  // shared
    out = solve_local(problem, x, budget, penalty, rows, &pre, round == 0 && options.screen_early_end ? &in : nullptr);
    evaluations += out.evaluations;
    if (!out.evaluated || static_cast<int>(rows.size()) == m) break;
    bool violated = out.escaped;
    for (int i = 0; i < m; ++i) {
      if (in[i] || !(out.constraints[i] > -options.screen)) continue;
      in[i] = 1;
      violated = violated || out.constraints[i] > options.constraint_tol;
    }
    if (!violated || evaluations >= options.max_evaluations) break;
    x = out.x;
  }
  out.evaluations = evaluations;
  return out;
}

// deterministic normal deviates: splitmix64 and Box-Muller (no std:: distributions, whose
// output differs between standard libraries)
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : state_(seed) {}
  double operator()() {
    const double u1 = (next() >> 11) * 0x1.0p-53, u2 = (next() >> 11) * 0x1.0p-53;
    return std::sqrt(-2.0 * std::log(1.0 - u1)) * std::cos(2.0 * M_PI * u2);
  }

 private:
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
};

}  // namespace

namespace {
constexpr Named<Method> kMethodNames[] = {
    {Method::kSlsqp, "slsqp"}, {Method::kMma, "mma"}, {Method::kCcsaq, "ccsaq"}};
}  // namespace

const char* method_name(Method m) { return name_in(kMethodNames, m, "slsqp"); }

bool parse_method(const std::string& name, Method* out) { return parse_in(kMethodNames, name, out); }

OptimizeResult optimize(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                        const OptimizerOptions& options) {
  OptimizeResult result;
  result.x = x0;
  double f0 = 0;
  result.evaluation = problem.objective(x0.data(), &f0);
  if (!result.evaluation.ok()) {
    result.solver = {SolverOutcome::kFailure, "start not evaluable: " + result.evaluation.message};
    return result;
  }
  const double penalty = 1e3 * (1.0 + std::abs(f0));
  const double tol = 10.0 * options.constraint_tol;

  // local solve from the given start
  Local best = solve_screened(problem, x0, options, penalty);
  result.starts = 1;
  result.evaluations = best.evaluations;

  // multi-start: seeded perturbations of the start, each polished by the local method
  if (options.global) {
    Normal normal(options.seed);
    const int nf = problem.free_per_joint();
    for (int s = 1; s < options.starts; ++s) {
      std::vector<double> xs = x0;
      for (int j = 0; j < problem.dofs(); ++j) {
        const double scale =
            options.spread * (std::abs(problem.goal_angle(j) - problem.start_angle(j)) + 0.1);
        for (int v = 0; v < nf; ++v) xs[j * nf + v] += scale * normal();
      }
      Local local = solve_screened(problem, xs, options, penalty);
      ++result.starts;
      result.evaluations += local.evaluations;
      if (better(local, best, tol)) {
        best = std::move(local);
        result.best_start = s;
      }
    }
  }
  result.solver = best.solver;
  if (best.evaluated) {
    result.x = best.x;
    result.objective = best.objective;
    result.max_node_constraint = best.max_constraint;
  } else {
    Evaluated e;
    problem.evaluate(x0.data(), false, &e);
    result.objective = f0;
    result.max_node_constraint = *std::max_element(e.constraints.begin(), e.constraints.end());
  }
  return result;
}

}  // namespace fivebar::trajectory
