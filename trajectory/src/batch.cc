#include "fivebar/trajectory/batch.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include "fivebar/model/format.h"
#include "fivebar/sim/bytes.h"
#include "stage.h"

namespace fivebar::trajectory {
namespace {

ProblemOptions task_problem_options(const BatchOptions& options, double torque_limit) {
  ProblemOptions o = options.problem;
  o.torque_limit = torque_limit;
  return o;
}

constexpr const char* kTruncated = "decode: truncated TaskResult";

}  // namespace

double objective_value(const TaskResult& r, Objective o) {
  switch (o) {
    case Objective::kDissipatedEnergy: return r.dissipated_energy;
    case Objective::kInputEnergy: return r.input_energy;
    case Objective::kTotalDissipation: return r.total_dissipation;
    case Objective::kSupplyEnergy: return r.supply_energy;
  }
  return r.dissipated_energy;
}

std::uint64_t task_seed(const std::string& name, std::uint64_t seed) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : name) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h ^ (seed * 0x9e3779b97f4a7c15ULL);
}

int result_control_points(const TaskResult& result, const BatchOptions& options) {
  return result.control_points > 0 ? result.control_points : options.problem.control_points;
}

ProblemOptions result_options(const TaskResult& result, const BatchOptions& options) {
  ProblemOptions o = task_problem_options(options, result.torque_limit);
  if (result.smoothing_velocity > 0) o.smoothing_velocity = result.smoothing_velocity;
  return o;
}

TrajectoryProblem problem_of(const Params<double>& params, const sim::LoadFunction& loads,
                             const TaskResult& result, const BatchOptions& options) {
  const RestToRest motion(result_control_points(result, options), result.duration, result.start,
                          result.goal, options.problem.end_acceleration);
  return TrajectoryProblem(params, loads, motion, result_options(result, options));
}

bool validation_point(const Params<double>& params, const std::array<double, 2>& q,
                      std::array<double, 2>* c) {
  return point_c(params, q[0], q[1], c);
}

int check_points(const TrajectoryProblemBase& problem, const BatchOptions& options) {
  return options.check_factor * problem.num_nodes() + 1;
}

int exact_points(const BatchOptions& options) { return 4 * options.problem.quadrature_points; }

void evaluate_baseline(const TrajectoryProblemBase& problem, const std::vector<double>& x0,
                       const BatchOptions& options, TaskResult* r) {
  Energies e;
  const Status s = problem.energies(x0.data(), options.problem.quadrature_points, &e);
  if (!s.ok()) {
    r->baseline_status =
        s.code == StatusCode::kCannotAssemble ? "cannot_assemble" : "evaluation_failed";
    r->add_note("minimum-jerk baseline: " + s.message);
    return;
  }
  r->baseline_dissipated_energy_smoothed = e.dissipated;
  r->baseline_input_energy_smoothed = e.input_smoothed;
  if (problem.exact_energies(x0.data(), exact_points(options), &e).ok()) {
    r->baseline_dissipated_energy = r->baseline_dissipated_energy_exact = e.dissipated;
    r->baseline_input_energy = e.input;
    r->baseline_winding_heat = e.winding_heat;
    r->baseline_total_dissipation = e.total();
    r->baseline_supply_energy = e.supply;
  }
  const ConstraintCheck c = problem.check(x0.data(), check_points(problem, options));
  if (!c.status.ok()) {
    r->baseline_status = "evaluation_failed";
    r->add_note("minimum-jerk baseline check: " + c.status.message);
    return;
  }
  r->baseline_peak_torque = c.peak_torque;
  // a NaN violation is no pass
  r->baseline_status = c.max_violation <= options.feasibility_tol ? "ok" : "violates_constraints";
}

namespace {

// the detour: the path search, then the fewest control points whose spline keeps the margin
bool detour_start(const Params<double>& params, const sim::LoadFunction& loads,
                  const BatchOptions& options, TaskResult* r,
                  std::optional<TrajectoryProblem>* problem, std::vector<double>* x) {
  PathSearchOptions po = options.path;
  po.margin = options.problem.singular_margin;
  const JointPath path = find_joint_path(params, r->start, r->goal, po);
  if (!path.ok()) {
    r->status = path.status;
    r->add_note(path.message);
    return false;
  }
  std::vector<int> counts = {options.problem.control_points};
  for (int n : options.path_control_points) {
    if (n > counts.back()) counts.push_back(n);
  }
  double best = -2;
  for (int n : counts) {
    const RestToRest motion(n, r->duration, r->start, r->goal, options.problem.end_acceleration);
    const std::vector<double> guess = follow_path(motion, path);
    const int points = options.check_factor * motion.basis().spans() *
                           options.problem.quadrature_points + 1;
    const double sine = min_coupler_sine(params, motion, guess, points);
    if (sine <= best) continue;
    best = sine;
    r->control_points = n;
    *x = guess;
    if (sine >= options.problem.singular_margin) break;
  }
  problem->emplace(problem_of(params, loads, *r, options));
  r->initial_guess = "path_search";
  r->add_note("started from a detour of " + std::to_string(path.waypoints.size() - 2) +
                  " via points found by the path search");
  return true;
}

// a warm start: the same task's optimum for another design, its joint motion moved to this
// design's ends (minimum-jerk blend of the end offsets), when it keeps the margin
bool warm_start(const Params<double>& params, const sim::LoadFunction& loads,
                const BatchOptions& options, const TaskResult& warm, TaskResult* r,
                std::optional<TrajectoryProblem>* problem, std::vector<double>* x) {
  if (!warm.solved() || warm.control_points < 7 || warm.duration != r->duration) return false;
  const EndAcceleration ends = options.problem.end_acceleration;
  const RestToRest from(warm.control_points, warm.duration, warm.start, warm.goal, ends);
  const RestToRest to(warm.control_points, r->duration, r->start, r->goal, ends);
  std::vector<double> guess = to.fit([&](double t) {
    std::array<double, 2> th = from.state(warm.x.data(), t)[0];
    const double b = minimum_jerk_blend(t / r->duration)[0];
    for (int j = 0; j < kDof; ++j) {
      th[j] += (r->start[j] - warm.start[j]) * (1.0 - b) + (r->goal[j] - warm.goal[j]) * b;
    }
    return th;
  });
  const int points = options.check_factor * to.basis().spans() *
                         options.problem.quadrature_points + 1;
  if (min_coupler_sine(params, to, guess, points) < options.problem.singular_margin) return false;
  r->control_points = warm.control_points;
  problem->emplace(problem_of(params, loads, *r, options));
  *x = std::move(guess);
  r->initial_guess = "warm_start";
  return true;
}

// where the optimization starts: the warm start when given and usable, else the minimum-jerk
// motion when it closes with the margin kept, else a detour; false when no path joins start
// and goal (status and message say why)
bool choose_start(const Params<double>& params, const sim::LoadFunction& loads,
                  const BatchOptions& options, const TaskResult* warm, TaskResult* r,
                  std::optional<TrajectoryProblem>* problem, std::vector<double>* x) {
  problem->emplace(problem_of(params, loads, *r, options));
  *x = (*problem)->motion().minimum_jerk();
  evaluate_baseline(**problem, *x, options, r);
  const double sine = min_coupler_sine(params, (*problem)->motion(), *x,
                                       check_points(**problem, options));
  if (warm && warm_start(params, loads, options, *warm, r, problem, x)) {
    // started from the neighbouring design's optimum
  } else if (sine >= options.problem.singular_margin) {
    r->initial_guess = "minimum_jerk";
  } else if (!detour_start(params, loads, options, r, problem, x)) {
    return false;
  }
  const TrajectoryProblem& p = **problem;
  Energies e;
  if (p.exact_energies(x->data(), exact_points(options), &e).ok()) {
    r->initial_dissipated_energy = e.dissipated;
  }
  const ConstraintCheck c = p.check(x->data(), check_points(p, options));
  if (c.status.ok()) {
    r->initial_peak_torque = c.peak_torque;
    r->initial_min_coupler_sine = c.min_coupler_sine;
  }
  return true;
}

// the energies of r->x: smoothed (the law of its stage) and exact
void record_energies(const TrajectoryProblemBase& problem, const BatchOptions& options,
                     TaskResult* r) {
  const Objective o = options.problem.objective;
  Energies e;
  if (problem.energies(r->x.data(), options.problem.quadrature_points, &e).ok()) {
    r->dissipated_energy_smoothed = e.dissipated;
    r->input_energy_smoothed = e.input_smoothed;
    r->objective = o == Objective::kSupplyEnergy  ? e.supply_smoothed
                   : o == Objective::kInputEnergy ? e.input_smoothed
                                                  : e.of(o);
  }
  if (problem.exact_energies(r->x.data(), exact_points(options), &e).ok()) {
    r->dissipated_energy = r->dissipated_energy_exact = e.dissipated;
    r->input_energy = e.input;
    r->winding_heat = e.winding_heat;
    r->total_dissipation = e.total();
    r->supply_energy = e.supply;
  }
}

}  // namespace

bool solve_task(const StageFactory& factory, const TrajectoryProblemBase& problem,
                const std::vector<double>& x0, const BatchOptions& options, TaskResult* r,
                SolverStatus* solver, ConstraintCheck* check) {
  OptimizerOptions oo = options.optimizer;
  oo.seed = task_seed(r->task, options.optimizer.seed);
  const Candidate first = solve_stage(factory, problem.control_points(),
                                      problem.options().smoothing_velocity, x0, options,
                                      r->torque_limit, oo);
  r->evaluations = first.evaluations;
  r->starts = first.starts;
  r->best_start = first.best_start;
  if (!first.evaluation.ok()) {
    r->solver_status = outcome_name(first.solver.outcome);
    r->status = "evaluation_failed";
    r->add_note(first.solver.message);
    return false;
  }
  oo.global = false;  // the later stages polish from a warm start
  const Candidate best = options.refine.enabled && startable(first, options)
                             ? refine(factory, first, options, oo, r)
                             : first;
  // a later stage that improved on a converged first solve but stopped at a limit keeps the
  // task ok (it is feasible and better); its outcome is noted
  const bool later = best.control_points != first.control_points ||
                     best.smoothing_velocity != first.smoothing_velocity;
  *solver = best.solver;
  if (later && first.solver.outcome == SolverOutcome::kConverged &&
      best.solver.outcome != SolverOutcome::kConverged) {
    *solver = first.solver;
    r->add_note("the last stage (" + std::to_string(best.control_points) +
                    " control points) ended: " + best.solver.message);
  }
  *check = best.check;
  r->solver_status = outcome_name(best.solver.outcome);
  r->x = best.x;
  r->control_points = best.control_points;
  r->smoothing_velocity = best.smoothing_velocity;
  record_energies(*factory.problem(result_control_points(*r, options), result_options(*r, options)),
                  options, r);
  if (!check->status.ok()) {
    r->status = "evaluation_failed";
    r->add_note("constraint re-check: " + check->status.message);
    return false;
  }
  r->peak_torque = check->peak_torque;
  r->max_constraint_violation = check->max_violation;
  r->min_coupler_sine = check->min_coupler_sine;
  return true;
}

void classify(const SolverStatus& solver, const ConstraintCheck& check,
              const BatchOptions& options, TaskResult* r, const char* singular_name) {
  std::string status = "ok", message = solver.message;
  // the checks are written so that a NaN fails them (a NaN compares false)
  if (!solver.usable()) {
    status = r->solver_status;
  } else if (!(check.max_violation <= options.feasibility_tol)) {
    status = "infeasible";
    message = "constraints violated on the check grid (relative " +
              std::to_string(check.max_violation) + "; peak torque " +
              std::to_string(check.peak_torque) + " N m, min |" + singular_name + "| " +
              std::to_string(check.min_coupler_sine) + ")";
  } else if (!(check.max_violation <= options.limit_rtol)) {
    status = "violates_constraints";
    message = "over a limit on the check grid by " + std::to_string(check.max_violation) +
              " (relative; peak torque " + std::to_string(check.peak_torque) +
              " N m, min |" + singular_name + "| " + std::to_string(check.min_coupler_sine) + ")";
  } else if (solver.limited()) {
    status = r->solver_status;
  }
  if (status == "ok" && !(std::isfinite(r->objective) &&
                          std::isfinite(objective_value(*r, options.problem.objective)))) {
    status = "evaluation_failed";  // a NaN total would rank designs in study and design
    message = "the objective of the result is not finite under the smoothed or the exact law";
  }
  r->status = status;
  const std::string notes = r->message;
  r->message = message;
  if (!notes.empty()) r->add_note(notes);
}

void judge_validation(const BatchOptions& options, TaskResult* r) {
  if (r->status != "ok") return;
  const double miss = std::max(r->miss_distance, r->miss_distance_exact);
  if (std::isnan(r->miss_distance) || std::isnan(r->miss_distance_exact) ||
      !(miss <= options.miss_tol)) {
    r->status = "validation_failed";  // the reason first, the solve's notes after it
    const std::string notes = r->message;
    r->message = "the optimal torques simulated forward miss the goal by " +
                 format_significant(r->miss_distance) + " m (smoothed law) and " +
                 format_significant(r->miss_distance_exact) + " m (exact law), tolerance " +
                 format_significant(options.miss_tol) + " m";
    r->add_note(notes);
  }
}

TaskResult run_task(const Params<double>& params, const sim::LoadFunction& loads,
                    const TaskSpec& task, const sim::Initial& initial,
                    const BatchOptions& options, const TaskResult* warm) {
  const auto t0 = std::chrono::steady_clock::now();
  TaskResult r = begin_task(task, options);
  auto finish = [&]() {
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };

  // joint angles of both ends, or why the task cannot be done by this design
  const ResolvedTask resolved =
      resolve_task(params, task, initial, options.problem.singular_margin);
  if (!ends_resolved(resolved, &r)) return finish();
  r.start = resolved.start;
  r.goal = resolved.goal;

  try {
    std::optional<TrajectoryProblem> problem;
    std::vector<double> x0;
    if (!choose_start(params, loads, options, warm, &r, &problem, &x0)) return finish();
    SolverStatus solver;
    ConstraintCheck check;
    const StageFactoryT<FiveBar> factory(params, loads, r.duration, r.start, r.goal,
                                         options.problem.end_acceleration);
    if (!solve_task(factory, *problem, x0, options, &r, &solver, &check)) return finish();
    classify(solver, check, options, &r, "sin(th4 - th3)");

    // validation: the optimal torques simulated forward must bring C to the goal (the problem
    // of the result: refinement may have changed its control points)
    if (options.validate) validate(problem_of(params, loads, r, options), loads, options, &r);
  } catch (const std::exception& e) {
    r.status = "failure";
    r.add_note(e.what());
  }
  return finish();
}

std::vector<TaskResult> run_parallel(int count, int threads,
                                     const std::function<TaskResult(int)>& work,
                                     const std::function<void(int, int)>& progress) {
  std::vector<TaskResult> results(count);
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::max(1, std::min(threads, count));
  std::atomic<int> next{0};
  std::mutex mutex;
  int done = 0;
  std::exception_ptr error;
  auto worker = [&]() {
    for (int i = next++; i < count; i = next++) {
      try {
        results[i] = work(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      ++done;
      if (progress) progress(done, count);
    }
  };
  if (threads == 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k) pool.emplace_back(worker);
    for (std::thread& t : pool) t.join();
  }
  if (error) std::rethrow_exception(error);
  return results;
}

namespace {

// the codec of one field (visit_fields)
struct FieldWriter {
  sim::ByteWriter* w;
  void operator()(const char*, const std::string& v) const { w->put_string(v); }
  void operator()(const char*, double v) const { w->put(v); }
  void operator()(const char*, int v) const { w->put(static_cast<long long>(v)); }
  void operator()(const char*, bool v) const { w->put(static_cast<long long>(v)); }
  void operator()(const char*, const std::vector<double>& v) const {
    w->put(static_cast<long long>(v.size()));
    for (double x : v) w->put(x);
  }
};

struct FieldReader {
  sim::ByteReader* rd;
  void operator()(const char*, std::string& v) const { v = rd->take_string(kTruncated); }
  void operator()(const char*, double& v) const { v = rd->take<double>(kTruncated); }
  void operator()(const char*, int& v) const {
    v = static_cast<int>(rd->take<long long>(kTruncated));
  }
  void operator()(const char*, bool& v) const { v = rd->take<long long>(kTruncated) != 0; }
  void operator()(const char*, std::vector<double>& v) const {
    v.resize(static_cast<size_t>(rd->take<long long>(kTruncated)));
    for (double& x : v) x = rd->take<double>(kTruncated);
  }
};

}  // namespace

std::string encode(const TaskResult& r) {
  sim::ByteWriter w;
  visit_fields(r, FieldWriter{&w});
  return w.bytes();
}

TaskResult decode(const std::string& bytes) {
  sim::ByteReader rd(bytes);
  TaskResult r;
  visit_fields(r, FieldReader{&rd});
  return r;
}

}  // namespace fivebar::trajectory
