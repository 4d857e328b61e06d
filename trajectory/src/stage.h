// One solve of a task (a stage): the optimization of one discretization under one smoothing of
// the friction law, its dense re-check and its exact-law objective; and the continuation and
// refinement that chain such stages (refine.cc). Internal to the library.
#pragma once

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fivebar/model/four_bar_params.h"
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

/// A task's mechanism as the stages see it: the problem of a spline of n control points per
/// joint between the task's ends, and a candidate's motion refitted onto n control points.
class StageFactory {
 public:
  virtual ~StageFactory() = default;
  virtual std::unique_ptr<TrajectoryProblemBase> problem(int n, const ProblemOptions& o) const = 0;
  virtual std::vector<double> refit(const Candidate& c, int n) const = 0;
  /// the scene's own law is smoothed (no continuation towards it)
  virtual bool smooth_law() const = 0;
};

/// The factory of mechanism M for one task (duration, start and goal angles).
template <class M>
class StageFactoryT : public StageFactory {
 public:
  using Problem = TrajectoryProblemT<M>;
  using Angles = std::array<double, M::kDof>;
  StageFactoryT(const typename Problem::ParamsD& params,
                const typename Problem::LoadFunction& loads, double duration, Angles start,
                Angles goal, EndAcceleration ends)
      : params_(params), loads_(loads), duration_(duration), start_(start), goal_(goal),
        ends_(ends) {}
  typename Problem::Motion motion(int n) const {
    return typename Problem::Motion(n, duration_, start_, goal_, ends_);
  }
  std::unique_ptr<TrajectoryProblemBase> problem(int n, const ProblemOptions& o) const override {
    return std::make_unique<Problem>(params_, loads_, motion(n), o);
  }
  std::vector<double> refit(const Candidate& c, int n) const override {
    const typename Problem::Motion from = motion(c.control_points), to = motion(n);
    return to.fit([&](double t) { return from.state(c.x.data(), t)[0]; });
  }
  bool smooth_law() const override { return params_.friction.smoothing_velocity > 0.0; }

 private:
  const typename Problem::ParamsD& params_;
  const typename Problem::LoadFunction& loads_;
  double duration_;
  Angles start_, goal_;
  EndAcceleration ends_;
};

/// True when c is usable: solved, its solver's point usable, its check ok and within every limit
/// (BatchOptions::limit_rtol), its exact-law objective finite.
bool feasible(const Candidate& c, const BatchOptions& options);
/// The same within the looser feasibility_tol: a point the later stages may start from.
bool startable(const Candidate& c, const BatchOptions& options);

/// Optimizes the spline of n control points under the smoothing velocity `ws` from x0 (the
/// torque peak between the nodes removed by re-solving with a lowered limit, at most twice),
/// then re-checks it.
Candidate solve_stage(const StageFactory& factory, int n, double ws,
                      const std::vector<double>& x0, const BatchOptions& options,
                      double torque_limit, const OptimizerOptions& optimizer);

/// The refinement of the control points of `first` under its smoothed law, then the
/// continuation of the finest spline kept towards the exact law (options.refine.continuation);
/// the best feasible candidate of all stages (`first` itself when it is not feasible). The
/// stages are described in r->continuation, r->refinement and r->refinement_change.
Candidate refine(const StageFactory& factory, const Candidate& first, const BatchOptions& options,
                 const OptimizerOptions& optimizer, TaskResult* r);

// The steps of a task's run that do not depend on the mechanism (batch.cc): run_task (the
// five-bar) and run_four_bar_task (problem_four_bar.cc) chain them.

/// control points per joint of a result's spline (the options' when it has none)
/// A task's result before it is set up: the task's name, duration, torque limit and the
/// options' control points
inline TaskResult begin_task(const TaskSpec& task, const BatchOptions& options) {
  TaskResult r;
  r.task = task.name;
  r.duration = task.duration;
  r.torque_limit = task.torque_limit;
  r.control_points = options.problem.control_points;
  return r;
}

/// False, with r's status and message, when the task's ends could not be resolved (any
/// mechanism's resolved task: ok(), status, message)
template <class Resolved>
bool ends_resolved(const Resolved& resolved, TaskResult* r) {
  if (resolved.ok()) return true;
  r->status = resolved.status;
  r->message = resolved.message;
  r->control_points = 0;
  return false;
}

int result_control_points(const TaskResult& result, const BatchOptions& options);
/// the problem options of a result: its torque limit, the smoothing velocity of its stage
ProblemOptions result_options(const TaskResult& result, const BatchOptions& options);
/// points of the dense check grid of a problem
int check_points(const TrajectoryProblemBase& problem, const BatchOptions& options);
/// Gauss-Legendre points per span of the exact-law energies
int exact_points(const BatchOptions& options);
/// the minimum-jerk baseline x0 on `problem` (the problem's own control points): energies,
/// checks and baseline_status; a baseline that does not close is a note, not a failure of the
/// task
void evaluate_baseline(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                       const BatchOptions& options, TaskResult* r);
/// the first solve from x0 on `problem` (multi-start when asked), then the refinement and the
/// continuation to the exact law; the best stage's point and energies go into r. False (status
/// set) when nothing usable came out.
bool solve_task(const StageFactory& factory, const TrajectoryProblemBase& problem,
                const std::vector<double>& x0, const BatchOptions& options, TaskResult* r,
                SolverStatus* solver, ConstraintCheck* check);
/// the status of a solved task (`singular_name`: the mechanism's singular measure, in messages)
void classify(const SolverStatus& solver, const ConstraintCheck& check,
              const BatchOptions& options, TaskResult* r, const char* singular_name);
/// an ok task whose validation failed (a simulation that did not finish: miss NaN) or missed
/// the goal by more than BatchOptions::miss_tol becomes `validation_failed`
void judge_validation(const BatchOptions& options, TaskResult* r);

/// The point of the mechanism whose miss the validation measures at pose q: the five-bar's C,
/// the four-bar's P (problem_four_bar.cc); false where the mechanism cannot close.
bool validation_point(const Params<double>& params, const std::array<double, 2>& q,
                      std::array<double, 2>* c);
bool validation_point(const FourBarParams& params, const std::array<double, 1>& q,
                      std::array<double, 2>* c);

/// the drive torques M into loads L (NaN where the inverse dynamics failed)
inline void set_drives(Loads<double>* L, double M1, double M2) {
  L->M1 = M1;
  L->M2 = M2;
}
inline void set_drives(FourBarLoads* L, double M1, double) { L->M1 = M1; }

/// the exact-law validation ends this fraction of the duration before the end
constexpr double kValidationEndGap = 1e-4;

/// The miss of the validation point at the end of the optimal torques simulated forward from
/// rest at the start: with the smoothed law the optimizer works on (its torques; consistent with
/// the optimization), or with the scene's exact law and stick-slip (the exact-law torques of
/// trajectory.csv). NaN (and a note) when the simulation fails or ends where the mechanism
/// cannot close.
template <class M>
double miss_distance(const TrajectoryProblemT<M>& problem,
                     const typename TrajectoryProblemT<M>::LoadFunction& loads,
                     const std::vector<double>& x, const BatchOptions& options, bool exact,
                     std::string* note) {
  constexpr int n = M::kDof;
  const auto& m = problem.motion();
  const typename TrajectoryProblemT<M>::LoadFunction drive = [&](double t) {
    typename TrajectoryProblemT<M>::LoadsD L = loads(t);
    // the optimal torques, from the inverse dynamics of the spline at t (no sampling error)
    double M1 = 0, M2 = 0;
    const Status s = exact ? problem.torques(x.data(), t, &M1, &M2)
                           : problem.smoothed_torques(x.data(), t, &M1, &M2);
    if (!s.ok()) M1 = M2 = NAN;
    set_drives(&L, M1, M2);
    return L;
  };
  sim::Options so;
  // the exact law stops a fraction short of the end: there every joint comes to rest at once
  // and the simulator's joint modes are degenerate (docs/optimize.md, "Validation")
  so.duration = exact ? m.duration() * (1.0 - kValidationEndGap) : m.duration();
  so.output_step = so.duration / 50;
  so.rtol = options.validation_rtol;
  so.atol = options.validation_rtol;
  sim::Initial init;
  init.theta1 = m.start()[0];
  if constexpr (n > 1) init.theta2 = m.start()[1];
  const sim::Result run =
      sim::simulate(exact ? problem.exact_params() : problem.params(), drive, init, so);
  if (!run.status.ok() || run.rows.empty()) {
    *note = std::string(exact ? "exact-law " : "") + "validation simulation failed: " +
            run.status.message;
    return NAN;
  }
  const sim::Row& last = run.rows.back();
  // the planned pose at the end of the run (the goal itself when it runs to the end)
  const std::array<double, n> planned = m.state(x.data(), last.t)[0];
  std::array<double, n> reached;
  for (int j = 0; j < n; ++j) reached[j] = last.theta[j];
  std::array<double, 2> c{}, goal{};
  if (!validation_point(problem.params(), reached, &c) ||
      !validation_point(problem.params(), planned, &goal)) {
    *note = "validation simulation ended where the mechanism cannot close";
    return NAN;
  }
  return std::hypot(c[0] - goal[0], c[1] - goal[1]);
}

/// Both validations of r->x (miss_distance, miss_distance_exact), then judge_validation.
template <class M>
void validate(const TrajectoryProblemT<M>& problem,
              const typename TrajectoryProblemT<M>::LoadFunction& loads,
              const BatchOptions& options, TaskResult* r) {
  std::string note;
  r->miss_distance = miss_distance(problem, loads, r->x, options, false, &note);
  if (!note.empty()) r->add_note(note);
  note.clear();
  r->miss_distance_exact = miss_distance(problem, loads, r->x, options, true, &note);
  if (!note.empty()) r->add_note(note);
  judge_validation(options, r);
}

}  // namespace fivebar::trajectory
