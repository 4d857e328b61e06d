#include "fivebar/trajectory/batch.h"

#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace fivebar::trajectory {
namespace {

ProblemOptions task_problem_options(const BatchOptions& options, double torque_limit) {
  ProblemOptions o = options.problem;
  o.torque_limit = torque_limit;
  return o;
}

// |C(T) - C goal| of the optimal torques simulated forward from rest at the start
double miss_distance(const TrajectoryProblem& problem, const sim::LoadFunction& loads,
                     const std::vector<double>& x, const BatchOptions& options,
                     std::string* note) {
  const RestToRest& m = problem.motion();
  const sim::LoadFunction drive = [&](double t) {
    Loads<double> L = loads(t);
    // the optimal torques, from the inverse dynamics of the spline at t (no sampling error)
    if (!problem.torques(x.data(), t, &L.M1, &L.M2).ok()) L.M1 = L.M2 = NAN;
    return L;
  };
  sim::Options so;
  so.duration = m.duration();
  so.output_step = m.duration() / 50;
  so.rtol = options.validation_rtol;
  so.atol = options.validation_rtol;
  so.singular_margin = 1e-3;
  const sim::Initial init{m.start()[0], m.start()[1], 0.0, 0.0};
  const sim::Result run = sim::simulate(problem.params(), drive, init, so);
  if (!run.status.ok() || run.rows.empty()) {
    *note = "validation simulation failed: " + run.status.message;
    return NAN;
  }
  const sim::Row& last = run.rows.back();
  std::array<double, 2> c{}, goal{};
  if (!point_c(problem.params(), last.theta[0], last.theta[1], &c) ||
      !point_c(problem.params(), m.goal()[0], m.goal()[1], &goal)) {
    *note = "validation simulation ended where the mechanism cannot close";
    return NAN;
  }
  return std::hypot(c[0] - goal[0], c[1] - goal[1]);
}

// byte writer and reader for encode / decode
struct Writer {
  std::string out;
  void num(double v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void integer(long long v) { out.append(reinterpret_cast<const char*>(&v), sizeof v); }
  void text(const std::string& s) {
    integer(static_cast<long long>(s.size()));
    out += s;
  }
};
struct Reader {
  const std::string& in;
  size_t pos = 0;
  void need(size_t n) {
    if (pos + n > in.size()) throw std::runtime_error("decode: truncated TaskResult");
  }
  double num() {
    double v;
    need(sizeof v);
    std::memcpy(&v, in.data() + pos, sizeof v);
    pos += sizeof v;
    return v;
  }
  long long integer() {
    long long v;
    need(sizeof v);
    std::memcpy(&v, in.data() + pos, sizeof v);
    pos += sizeof v;
    return v;
  }
  std::string text() {
    const size_t n = static_cast<size_t>(integer());
    need(n);
    std::string s = in.substr(pos, n);
    pos += n;
    return s;
  }
};

// shortest text that reads back exactly (0.3, not %.17g's 0.29999999999999999); the apps'
// format_double does the same, but this library does not depend on the apps layer
std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out + "\"";
}

}  // namespace

const std::vector<std::string>& summary_columns() {
  static const std::vector<std::string> columns = {
      "task", "status", "dissipated_energy", "baseline_dissipated_energy", "input_energy",
      "peak_torque", "max_constraint_violation", "wall_time_s", "baseline_input_energy",
      "baseline_peak_torque", "saving_percent", "miss_distance", "min_coupler_sine",
      "solver_status", "evaluations", "starts", "best_start", "duration", "torque_limit",
      "theta1_start", "theta2_start", "theta1_goal", "theta2_goal",
      "dissipated_energy_exact", "baseline_dissipated_energy_exact", "message"};
  return columns;
}

std::vector<std::string> summary_fields(const TaskResult& r) {
  const double saving = 100.0 * (1.0 - r.dissipated_energy / r.baseline_dissipated_energy);
  const bool resolved = r.solved() || !std::isnan(r.baseline_dissipated_energy);
  auto angle = [&](double v) { return resolved ? num(v) : std::string("nan"); };
  return {r.task, r.status, num(r.dissipated_energy), num(r.baseline_dissipated_energy),
          num(r.input_energy), num(r.peak_torque), num(r.max_constraint_violation),
          num(r.wall_time_s), num(r.baseline_input_energy), num(r.baseline_peak_torque),
          num(saving), num(r.miss_distance), num(r.min_coupler_sine), r.solver_status,
          std::to_string(r.evaluations), std::to_string(r.starts), std::to_string(r.best_start),
          num(r.duration), num(r.torque_limit), angle(r.start[0]), angle(r.start[1]),
          angle(r.goal[0]), angle(r.goal[1]), num(r.dissipated_energy_exact),
          num(r.baseline_dissipated_energy_exact), quoted(r.message)};
}

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + fields[i];
  return line + "\n";
}

std::uint64_t task_seed(const std::string& name, std::uint64_t seed) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : name) {
    h ^= c;
    h *= 0x100000001b3ULL;
  }
  return h ^ (seed * 0x9e3779b97f4a7c15ULL);
}

TrajectoryProblem problem_of(const Params<double>& params, const sim::LoadFunction& loads,
                             const TaskResult& result, const BatchOptions& options) {
  const RestToRest motion(options.problem.control_points, result.duration, result.start,
                          result.goal);
  return TrajectoryProblem(params, loads, motion,
                           task_problem_options(options, result.torque_limit));
}

TaskResult run_task(const Params<double>& params, const sim::LoadFunction& loads,
                    const TaskSpec& task, const sim::Initial& initial,
                    const BatchOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  TaskResult r;
  r.task = task.name;
  r.duration = task.duration;
  r.torque_limit = task.torque_limit;
  r.control_points = options.problem.control_points;
  auto finish = [&]() {
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };

  // joint angles of both ends, or why the task cannot be done by this design
  const ResolvedTask resolved =
      resolve_task(params, task, initial, options.problem.singular_margin);
  if (!resolved.ok()) {
    r.status = resolved.status;
    r.message = resolved.message;
    return finish();
  }
  r.start = resolved.start;
  r.goal = resolved.goal;

  try {
    const TrajectoryProblem problem = problem_of(params, loads, r, options);
    const int grid = options.check_factor * problem.num_nodes() + 1;

    // the minimum-jerk baseline (exactly representable by the spline)
    const std::vector<double> x0 = problem.motion().minimum_jerk();
    double bd = NAN, bi = NAN;
    const Status bs = problem.energies(x0.data(), options.problem.quadrature_points, &bd, &bi);
    if (!bs.ok()) {
      r.status = "evaluation_failed";
      r.message = "minimum-jerk baseline: " + bs.message;
      return finish();
    }
    r.baseline_dissipated_energy = bd;
    r.baseline_input_energy = bi;
    const ConstraintCheck bc = problem.check(x0.data(), grid);
    if (bc.status.ok()) {
      r.baseline_peak_torque = bc.peak_torque;
      r.baseline_max_constraint_violation = bc.max_violation;
    }

    // the optimization
    OptimizerOptions oo = options.optimizer;
    oo.seed = task_seed(task.name, options.optimizer.seed);
    const OptimizeResult opt = optimize(problem, x0, oo);
    r.solver_status = outcome_name(opt.solver.outcome);
    r.evaluations = opt.evaluations;
    r.starts = opt.starts;
    r.best_start = opt.best_start;
    if (!opt.evaluation.ok()) {
      r.status = "evaluation_failed";
      r.message = opt.solver.message;
      return finish();
    }
    r.x = opt.x;
    r.objective = opt.objective;
    double d = NAN, in = NAN;
    const Status es = problem.energies(r.x.data(), options.problem.quadrature_points, &d, &in);
    if (es.ok()) {
      r.dissipated_energy = d;
      r.input_energy = in;
    }

    // constraints re-checked on a denser grid; a torque peak between the nodes above the limit
    // is removed by re-solving with the limit lowered by the overshoot (at most twice)
    ConstraintCheck check = problem.check(r.x.data(), grid);
    double limit = r.torque_limit;
    for (int round = 0; round < 2 && check.status.ok() && opt.solver.usable() &&
                        check.torque_excess > options.feasibility_tol * r.torque_limit;
         ++round) {
      limit *= r.torque_limit / check.peak_torque * (1.0 - 0.1 * options.feasibility_tol);
      const RestToRest motion(options.problem.control_points, r.duration, r.start, r.goal);
      const TrajectoryProblem tightened(params, loads, motion,
                                        task_problem_options(options, limit));
      const OptimizeResult again = optimize(tightened, r.x, oo);
      r.evaluations += again.evaluations;
      if (!again.solver.usable()) break;
      const ConstraintCheck c2 = problem.check(again.x.data(), grid);
      if (!c2.status.ok()) break;
      r.x = again.x;
      check = c2;
      if (problem.energies(r.x.data(), options.problem.quadrature_points, &d, &in).ok()) {
        r.dissipated_energy = d;
        r.input_energy = in;
      }
      r.objective = options.problem.objective == Objective::kInputEnergy ? in : d;
    }
    if (!check.status.ok()) {
      r.status = "evaluation_failed";
      r.message = "constraint re-check: " + check.status.message;
      return finish();
    }
    r.peak_torque = check.peak_torque;
    r.max_constraint_violation = check.max_violation;
    r.min_coupler_sine = check.min_coupler_sine;

    // energies under the scene's own (exact-sign) friction, for the record: the integrand has
    // kinks where a joint reverses, hence the denser rule
    {
      ProblemOptions exact_options = task_problem_options(options, r.torque_limit);
      exact_options.smoothing_velocity = params.friction.smoothing_velocity;
      exact_options.quadrature_points = 4 * options.problem.quadrature_points;
      const TrajectoryProblem exact(params, loads, problem.motion(), exact_options);
      double e = NAN, unused = NAN;
      if (exact.energies(r.x.data(), exact_options.quadrature_points, &e, &unused).ok()) {
        r.dissipated_energy_exact = e;
      }
      if (exact.energies(x0.data(), exact_options.quadrature_points, &e, &unused).ok()) {
        r.baseline_dissipated_energy_exact = e;
      }
    }

    if (!opt.solver.usable()) {
      r.status = r.solver_status;
      r.message = opt.solver.message;
    } else if (check.max_violation > options.feasibility_tol) {
      r.status = "infeasible";
      r.message = "constraints violated on the check grid (relative " +
                  std::to_string(check.max_violation) + "; peak torque " +
                  std::to_string(check.peak_torque) + " N m, min |sin(th4 - th3)| " +
                  std::to_string(check.min_coupler_sine) + ")";
    } else if (opt.solver.outcome == SolverOutcome::kMaxEvaluations ||
               opt.solver.outcome == SolverOutcome::kMaxTime) {
      r.status = r.solver_status;
      r.message = opt.solver.message;
    } else {
      r.status = "ok";
      r.message = opt.solver.message;
    }

    // validation: the optimal torques simulated forward must bring C to the goal
    if (options.validate) {
      std::string note;
      r.miss_distance = miss_distance(problem, loads, r.x, options, &note);
      if (!note.empty()) r.message += "; " + note;
    }
  } catch (const std::exception& e) {
    r.status = "failure";
    r.message = e.what();
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

std::string encode(const TaskResult& r) {
  Writer w;
  for (const std::string* s : {&r.task, &r.status, &r.message, &r.solver_status}) w.text(*s);
  for (double v : {r.duration, r.torque_limit, r.start[0], r.start[1], r.goal[0], r.goal[1],
                   r.dissipated_energy, r.baseline_dissipated_energy, r.input_energy,
                   r.baseline_input_energy, r.objective, r.peak_torque, r.baseline_peak_torque,
                   r.max_constraint_violation, r.baseline_max_constraint_violation,
                   r.min_coupler_sine, r.miss_distance, r.wall_time_s,
                   r.dissipated_energy_exact, r.baseline_dissipated_energy_exact}) {
    w.num(v);
  }
  for (long long v : {r.evaluations, r.starts, r.best_start, r.control_points}) w.integer(v);
  w.integer(static_cast<long long>(r.x.size()));
  for (double v : r.x) w.num(v);
  return w.out;
}

TaskResult decode(const std::string& bytes) {
  Reader rd{bytes};
  TaskResult r;
  for (std::string* s : {&r.task, &r.status, &r.message, &r.solver_status}) *s = rd.text();
  for (double* v : {&r.duration, &r.torque_limit, &r.start[0], &r.start[1], &r.goal[0],
                    &r.goal[1], &r.dissipated_energy, &r.baseline_dissipated_energy,
                    &r.input_energy, &r.baseline_input_energy, &r.objective, &r.peak_torque,
                    &r.baseline_peak_torque, &r.max_constraint_violation,
                    &r.baseline_max_constraint_violation, &r.min_coupler_sine,
                    &r.miss_distance, &r.wall_time_s, &r.dissipated_energy_exact,
                    &r.baseline_dissipated_energy_exact}) {
    *v = rd.num();
  }
  for (int* v : {&r.evaluations, &r.starts, &r.best_start, &r.control_points}) {
    *v = static_cast<int>(rd.integer());
  }
  r.x.resize(static_cast<size_t>(rd.integer()));
  for (double& v : r.x) v = rd.num();
  return r;
}

}  // namespace fivebar::trajectory
