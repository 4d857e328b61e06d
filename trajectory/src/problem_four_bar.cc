// The four-bar's trajectories, in one unit apart from the five-bar's: its trajectory problem
// (TrajectoryProblemT<FourBar>, whose Jet inverse dynamics compile here), its tasks (poses
// resolved to crank angles: theta1, or one coordinate of P) and one task's run over the steps
// run_task takes for the five-bar (stage.h).
#include <chrono>
#include <cmath>

#include "fivebar/model/format.h"
#include "fivebar/trajectory/four_bar_problem.h"
#include "fivebar/trajectory/four_bar_tasks.h"
#include "problem_impl.h"
#include "stage.h"

namespace fivebar::trajectory {

template class TrajectoryProblemT<FourBar>;

}  // namespace fivebar::trajectory

namespace fivebar::trajectory {
namespace {

// crank angles scanned per turn for the roots of a coordinate of P
constexpr int kScanSteps = 720;

// the coordinate of P named by `axis` ("x" or "y") minus `value` at theta1; NaN where the
// four-bar cannot close
double p_offset(const FourBarParams& params, const std::string& axis, double value, double th1) {
  std::array<double, 2> p{};
  if (!four_bar_point_p(params, th1, &p)) return NAN;
  return (axis == "x" ? p[0] : p[1]) - value;
}

// the crank angle within pi of `ref` nearest to it at which P's coordinate `axis` is `value`
// (the scene's assembly): sign changes on a grid, refined by bisection; false when none
bool crank_for_coordinate(const FourBarParams& params, const std::string& axis, double value,
                          double ref, double* th1) {
  bool found = false;
  double best = 0;
  double a = ref - M_PI, fa = p_offset(params, axis, value, a);
  for (int i = 1; i <= kScanSteps; ++i) {
    const double b = ref - M_PI + 2 * M_PI * i / kScanSteps;
    const double fb = p_offset(params, axis, value, b);
    if (std::isfinite(fa) && std::isfinite(fb) && (fa == 0.0 || (fa < 0.0) != (fb < 0.0))) {
      double lo = a, hi = b, flo = fa;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi), fm = p_offset(params, axis, value, mid);
        if ((fm < 0.0) == (flo < 0.0)) {
          lo = mid;
          flo = fm;
        } else {
          hi = mid;
        }
      }
      const double root = 0.5 * (lo + hi);
      if (!found || std::abs(root - ref) < std::abs(best - ref)) best = root;
      found = true;
    }
    a = b;
    fa = fb;
  }
  if (found) *th1 = best;
  return found;
}

}  // namespace

bool four_bar_point_p(const FourBarParams& params, double theta1, std::array<double, 2>* p) {
  FourBarKinematics k;
  if (!four_bar_kinematics(params, theta1, &k, 0.0).ok()) return false;
  *p = {k.P.x(), k.P.y()};
  return true;
}

bool validation_point(const FourBarParams& params, const std::array<double, 1>& q,
                      std::array<double, 2>* c) {
  return four_bar_point_p(params, q[0], c);
}

ResolvedFourBarTask resolve_four_bar_task(const FourBarParams& params, const TaskSpec& task,
                                          double initial_theta1, double singular_margin) {
  ResolvedFourBarTask r;
  if (!task_values_ok(task, &r.status, &r.message)) return r;
  auto fail = [&](const std::string& status, const std::string& message) {
    r.status = status;
    r.message = message;
    return false;
  };
  // the crank angle of a pose; a coordinate of P nearest to the reference angle
  auto solve = [&](const Pose& pose, double ref, const std::string& w, double* out) -> bool {
    const char* single = pose.single();
    if (!single) {
      return fail(w + "_invalid", w + ": a four-bar pose has one coordinate (theta1, x or y)");
    }
    const double v = pose.value();
    if (!(std::abs(v) <= kMaxTaskAngle)) {
      return fail(w + "_invalid", w + ": " + format_significant(v, 6) + " is beyond |" +
                                      format_significant(kMaxTaskAngle, 6) + "| (rad or m)");
    }
    if (std::string(single) == "theta1") {
      *out = v;
    } else if (!crank_for_coordinate(params, single, v, ref, out)) {
      return fail(w + "_out_of_workspace", w + ": no crank angle puts P at " + single + " = " +
                                               format_significant(v, 6) +
                                               " m in the scene's assembly");
    }
    FourBarKinematics k;
    Status st = four_bar_kinematics(params, *out, &k, 0.0);
    if (!st.ok()) return fail(w + "_cannot_assemble", w + ": " + st.message);
    st = four_bar_kinematics(params, *out, &k, singular_margin);
    if (!st.ok()) return fail(w + "_near_singular", w + ": " + st.message);
    return true;
  };
  if (!solve(task.start, initial_theta1, "start", &r.start)) return r;
  solve(task.goal, r.start, "goal", &r.goal);
  return r;
}

FourBarTrajectoryProblem four_bar_problem_of(const FourBarParams& params,
                                             const sim::FourBarLoadFunction& loads,
                                             const TaskResult& result,
                                             const BatchOptions& options) {
  const RestToRestT<1> motion(result_control_points(result, options), result.duration,
                              {result.start[0]}, {result.goal[0]},
                              options.problem.end_acceleration);
  return FourBarTrajectoryProblem(params, loads, motion, result_options(result, options));
}

Status four_bar_rows(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                     const TaskResult& result, const BatchOptions& options, bool baseline,
                     double step, std::vector<sim::Row>* out) {
  const FourBarTrajectoryProblem problem = four_bar_problem_of(params, loads, result, options);
  if (!baseline) return problem.rows(result.x.data(), step, out);
  const std::vector<double> x0 = problem.motion().minimum_jerk();
  return problem.rows(x0.data(), step, out);
}

namespace {

// Why the crank's sweep from a to b fails: the first angle where the four-bar cannot close
// (kinematics alone, on a grid of 1e-3 rad at most), else the dynamics' own reason
std::string sweep_failure(const FourBarParams& params, double a, double b, const Status& st) {
  const int n = std::max(2, static_cast<int>(std::ceil(std::abs(b - a) / 1e-3)));
  for (int i = 0; i <= n; ++i) {
    const double th = a + (b - a) * i / n;
    FourBarKinematics k;
    const Status closed = four_bar_close(params, th, &k, 0.0);
    if (!closed.ok()) {
      return "leaves the workspace at theta1 = " + format_significant(th, 6) + " rad (" +
             closed.message + ")";
    }
  }
  return "fails in the dynamics: " + st.message;
}

// the minimum-jerk start: its baseline and, when it keeps the margin on the dense grid, the
// initial_* fields; false (status unreachable) when it does not: with one degree of freedom
// every motion between the ends sweeps the same crank angles
bool minimum_jerk_start(const FourBarTrajectoryProblem& problem, const std::vector<double>& x0,
                        const BatchOptions& options, TaskResult* r) {
  evaluate_baseline(problem, x0, options, r);
  const ConstraintCheck c = problem.check(x0.data(), check_points(problem, options));
  const double margin = options.problem.singular_margin;
  if (!c.status.ok() || !(c.min_coupler_sine >= margin)) {
    r->status = "unreachable";
    r->add_note("the crank's sweep from theta1 = " + format_significant(r->start[0], 6) +
                " to " + format_significant(r->goal[0], 6) + " rad " +
                (c.status.ok() ? "comes to |" + std::string(FourBar::kSingularName) + "| = " +
                                     format_significant(c.min_coupler_sine, 4) +
                                     " < the singular margin " + format_significant(margin, 4)
                               : sweep_failure(problem.params(), r->start[0], r->goal[0],
                                               c.status)) +
                "; with one degree of freedom every motion between these ends sweeps it");
    return false;
  }
  r->initial_guess = "minimum_jerk";
  Energies e;
  if (problem.exact_energies(x0.data(), exact_points(options), &e).ok()) {
    r->initial_dissipated_energy = e.dissipated;
  }
  r->initial_peak_torque = c.peak_torque;
  r->initial_min_coupler_sine = c.min_coupler_sine;
  return true;
}

}  // namespace

TaskResult run_four_bar_task(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                             const TaskSpec& task, double initial_theta1,
                             const BatchOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  TaskResult r = begin_task(task, options);
  auto finish = [&]() {
    r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return r;
  };
  const ResolvedFourBarTask resolved =
      resolve_four_bar_task(params, task, initial_theta1, options.problem.singular_margin);
  if (!ends_resolved(resolved, &r)) return finish();
  r.start = {resolved.start, NAN};
  r.goal = {resolved.goal, NAN};
  try {
    const FourBarTrajectoryProblem problem = four_bar_problem_of(params, loads, r, options);
    const std::vector<double> x0 = problem.motion().minimum_jerk();
    if (!minimum_jerk_start(problem, x0, options, &r)) return finish();
    const StageFactoryT<FourBar> factory(params, loads, r.duration, {r.start[0]}, {r.goal[0]},
                                         options.problem.end_acceleration);
    SolverStatus solver;
    ConstraintCheck check;
    if (!solve_task(factory, problem, x0, options, &r, &solver, &check)) return finish();
    classify(solver, check, options, &r, FourBar::kSingularName);
    // the optimal torques simulated forward must bring P to the goal
    if (options.validate) {
      validate(four_bar_problem_of(params, loads, r, options), loads, options, &r);
    }
  } catch (const std::exception& e) {
    r.status = "failure";
    r.add_note(e.what());
  }
  return finish();
}

}  // namespace fivebar::trajectory
