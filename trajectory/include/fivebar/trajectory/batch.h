// Batch runs: every task of a tasks file optimized for one design, on a pool of threads, with the
// minimum-jerk baseline beside each result and a forward-simulation check of the optimal torques.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/optimizer.h"
#include "fivebar/trajectory/path_search.h"
#include "fivebar/trajectory/problem.h"
#include "fivebar/trajectory/tasks.h"

namespace fivebar::trajectory {

/// The refinement of the discretization and the continuation to the scene's exact friction law
/// that follow the first solve of a task: the refinement levels are solved under the first
/// solve's smoothed law (no kinks where a joint reverses: the levels find lower basins than
/// under the near-exact law), then the continuation runs on the finest spline kept. Each solve
/// is warm-started from the best point so far;
/// a stage replaces it only when it is feasible on the dense check grid and its exact-law
/// objective is lower, so no stage can make the result worse.
/// The refinement levels of `fivebar optimize`: from the first solve's 10 control points (5
/// knot spans) to 40, then 80 spans, so that every coarser spline lies in the finer space and
/// the warm start of a level is the last optimum itself (knot insertion: the least-squares
/// refit reproduces it to rounding). A level of 20 spans in between (25 control points) cost
/// more than it saved in the 45-point solves (docs/dev/figures-optimization.md).
inline const std::vector<int> kRefineLevels = {45, 85};
/// The levels for the smooth objectives (total_dissipation, supply_energy), whose optimum is
/// smooth: 10, 20, 40, 80 knot spans (each space holds the coarser ones), stopped as soon as the
/// objective settles.
inline const std::vector<int> kSmoothRefineLevels = {15, 25, 45, 85};
/// The refinement's tolerance (RefineOptions::tol) for the smooth objectives: their refinement
/// runs to a 0.01% change (docs/optimize.md).
inline constexpr double kSmoothRefineTol = 1e-4;

struct RefineOptions {
  bool enabled = true;
  /// smoothing velocities w_s [rad/s] solved after the refinement, on its finest spline, in
  /// order (continuation on w_s towards the exact law, w_s = 0), until a stage lowers the
  /// exact-law objective by less than `tol`: on reach_left (paper_motors.yaml), whose optimum
  /// holds a joint at rest, a single stage at 4e-4 stalled 0.46% above the optimum these four
  /// stages reach (they lower it by 0.35%, 0.18%, 0.05% and 0.0096%).
  std::vector<double> continuation = {1e-2, 2e-3, 4e-4, 8e-5};
  /// evaluation limit of each solve of the continuation (at most OptimizerOptions::
  /// max_evaluations): a polish of an optimum whose smoothed and exact-law energies differ by
  /// 1e-4 to 1e-3 (relative), where SLSQP crawls on the near-kinks of the law (docs/optimize.md)
  int continuation_max_evaluations = 100;
  /// stall tolerance of the continuation's solves (OptimizerOptions::stall_rtol, when larger)
  double continuation_stall_rtol = 1e-5;
  /// and its window (OptimizerOptions::stall_iterations, when smaller): 5 instead of 10 took
  /// the five shipped tasks from 1067 to 938 evaluations, their energies up by 0 to 0.017%
  /// (docs/dev/figures-optimization.md)
  int continuation_stall_iterations = 5;
  /// control points per joint tried after the first solve's count (only the larger ones),
  /// until the exact-law objective changes by less than `tol` (relative) from one to the next;
  /// empty: no refinement (`fivebar optimize` uses kRefineLevels)
  std::vector<int> control_points;
  double tol = 1e-3;
  /// Gauss-Legendre points per knot span of a refined spline: as many nodes in all as the
  /// first solve's, but at least this many per span
  int min_quadrature_points = 6;
};

struct BatchOptions {
  ProblemOptions problem;      ///< its torque_limit is replaced by each task's
  OptimizerOptions optimizer;  ///< its seed is combined with a hash of each task's name
  /// constraints re-checked after the solve on a grid this many times denser than the nodes
  int check_factor = 10;
  /// relative violation (ConstraintCheck::max_violation) above which a result is "infeasible"
  double feasibility_tol = 1e-3;
  /// relative violation above which a result is not `ok` (violates_constraints): the dense
  /// check's peak torque within limit (1 + limit_rtol), its |sin C| within margin (1 - limit_rtol);
  /// a stage whose peak exceeds it is re-solved with a lowered limit first
  double limit_rtol = 1e-6;
  /// simulate the optimal torques forward from the start state and measure the miss of C
  bool validate = true;
  double validation_rtol = 1e-9;  ///< CVODE tolerances of that simulation
  /// largest miss of C [m] (either law) of an `ok` task; a larger or NaN miss (a simulation
  /// that did not finish) makes it `validation_failed`. Shipped tasks miss by 1e-10 to 1e-8 m.
  double miss_tol = 1e-4;
  /// the search for a feasible initial guess when the minimum-jerk motion leaves the workspace
  /// or comes nearer than the singular margin to a singular pose (its margin is the problem's)
  PathSearchOptions path;
  /// control points tried, in order, for the spline that follows the path found (the first
  /// whose fit keeps the margin wins); the problem's own count is tried first
  std::vector<int> path_control_points = {14, 20, 28, 40};
  /// after the first solve (smoothed law, problem.smoothing_velocity): the continuation to the
  /// exact law and the refinement of the control points (docs/optimize.md)
  RefineOptions refine;
};

/// The outcome of one task (one row of summary.csv). Energies are NaN when not computed.
struct TaskResult {
  std::string task;
  /// ok | max_evaluations | max_time | infeasible | violates_constraints (over a limit by more
  /// than BatchOptions::limit_rtol, within feasibility_tol) | a solver outcome (roundoff_limited ...) |
  /// a resolution status (goal_out_of_workspace, invalid_duration, ...) | unreachable (no
  /// path of assemblable, non-singular poses joins start and goal) | evaluation_failed |
  /// validation_failed (solved within the limits, but the forward simulation of its torques
  /// failed or missed the goal by more than BatchOptions::miss_tol)
  std::string status;
  std::string message;
  std::string solver_status;  ///< outcome_name() of the solve, "" when none ran
  double duration = 0, torque_limit = 0;
  std::array<double, 2> start{}, goal{};  ///< resolved joint angles [rad]
  /// under the scene's exact friction law (sign(w), not the optimizer's smooth tanh(w / w_s)),
  /// by a Gauss-Legendre rule 4x denser than the optimizer's (the integrand has kinks where a
  /// joint reverses) [J]
  double dissipated_energy = NAN, baseline_dissipated_energy = NAN;
  double input_energy = NAN, baseline_input_energy = NAN;
  /// the same as dissipated_energy / baseline_dissipated_energy (columns kept for scripts)
  double dissipated_energy_exact = NAN, baseline_dissipated_energy_exact = NAN;
  /// under the smoothed law the optimizer minimizes, on its own rule [J]
  double dissipated_energy_smoothed = NAN, baseline_dissipated_energy_smoothed = NAN;
  double input_energy_smoothed = NAN, baseline_input_energy_smoothed = NAN;
  /// exact law, same rule as dissipated_energy [J]: the motors' winding heat int sum_a c_a M_a^2
  /// dt, joint friction plus winding heat, and the electrical energy drawn from the supply
  /// (exact max(0, p), ProblemOptions::regeneration); winding heat 0 without winding data
  double winding_heat = NAN, baseline_winding_heat = NAN;
  double total_dissipation = NAN, baseline_total_dissipation = NAN;
  double supply_energy = NAN, baseline_supply_energy = NAN;
  /// the minimized quantity, under the smoothed law of the winning stage and as minimized
  /// (kSupplyEnergy: with the softplus) [J]
  double objective = NAN;
  double peak_torque = NAN, baseline_peak_torque = NAN;  ///< dense grid [N m]
  /// dense grid, relative (ConstraintCheck); the baseline's decides its baseline_status
  double max_constraint_violation = NAN;
  double min_coupler_sine = NAN;  ///< dense grid
  /// |C(T) simulated - C goal| [m], the smoothed-law torques simulated with the smoothed law
  /// (the model the optimizer solved)
  double miss_distance = NAN;
  /// the same for the exact-law torques (trajectory.csv) simulated with the scene's exact law
  /// and stick-slip, open loop [m]
  double miss_distance_exact = NAN;
  int evaluations = 0, starts = 0, best_start = 0;
  double wall_time_s = 0;
  int control_points = 0;  ///< per joint, of the spline solved (0: none)
  /// the minimum-jerk baseline: ok (within every constraint on the check grid),
  /// violates_constraints (closes everywhere, but the torque limit or the singular margin is
  /// exceeded), cannot_assemble (some pose does not close: no baseline energies),
  /// evaluation_failed (the inverse dynamics failed otherwise); "" when not evaluated
  std::string baseline_status;
  /// where the optimization started: minimum_jerk, or path_search (the minimum-jerk motion left
  /// the workspace or the margin; a detour through a grid of feasible poses)
  std::string initial_guess;
  double initial_dissipated_energy = NAN;  ///< of that start, exact law [J] (the detour's energy)
  double initial_peak_torque = NAN;        ///< of that start, dense grid [N m]
  double initial_min_coupler_sine = NAN;   ///< of that start, dense grid
  std::vector<double> x;  ///< optimal free control points (empty when no solve ran)
  /// w_s [rad/s] of the smoothed law of the stage that gave x (its *_smoothed energies)
  double smoothing_velocity = NAN;
  /// the continuation, "w_s:E" per stage (E: exact-law objective of the stage's optimum [J],
  /// "x" after it when the stage did not improve the result), ';'-separated
  std::string continuation;
  /// the refinement, "n:E" per control-point count solved, ';'-separated
  std::string refinement;
  /// relative change of the exact-law objective between the last two counts solved (< the
  /// tolerance: converged); NaN when no refinement ran
  double refinement_change = NAN;

  /// the last level's solve stopped at its evaluation (or time) limit: its change shows nothing
  bool refinement_limited = false;

  bool solved() const { return !x.empty(); }
  /// Appends a note to `message` ("; " between notes).
  void add_note(const std::string& note) { message += (message.empty() ? "" : "; ") + note; }
  /// the refinement's levels ran out before the energy changed by less than `tol` (its
  /// RefineOptions::tol), or the last one stopped at its limit: the result is the optimum of
  /// the finest basis at best, not yet shown to be the problem's
  bool discretization_unsettled(double tol) const {
    return refinement_change >= tol || refinement_limited;
  }
};

/// The exact-law value of objective o of a result (dissipated_energy, input_energy,
/// total_dissipation or supply_energy) [J].
double objective_value(const TaskResult& r, Objective o);

/// Optimizes one task for one design. Never throws for numerical trouble: everything ends up in
/// the status. `loads` gives M3, F, F_angle (M1, M2 ignored) and must be callable from the
/// calling thread. `warm` (optional): the same task solved for a neighbouring design, whose
/// optimum, moved to this design's ends, starts the solve when it keeps the singular margin
/// (initial_guess "warm_start").
TaskResult run_task(const Params<double>& params, const sim::LoadFunction& loads,
                    const TaskSpec& task, const sim::Initial& initial,
                    const BatchOptions& options, const TaskResult* warm = nullptr);

/// The problem a result was solved on (to recompute its trajectory rows or torques).
TrajectoryProblem problem_of(const Params<double>& params, const sim::LoadFunction& loads,
                             const TaskResult& result, const BatchOptions& options);

/// Hash of a task name (FNV-1a), mixed into the optimizer seed so that every task has its own
/// perturbations whatever the order or thread it runs in.
std::uint64_t task_seed(const std::string& name, std::uint64_t seed);

/// Runs work(i) for i in [0, count) on `threads` threads (<= 0: all cores) and returns the
/// results in index order. `progress(done, count)` (optional) is called after each item, under a
/// lock. Each result depends only on i, so the output does not depend on the thread count.
std::vector<TaskResult> run_parallel(int count, int threads,
                                     const std::function<TaskResult(int)>& work,
                                     const std::function<void(int, int)>& progress = {});

/// Visits every field of a TaskResult once, as visit(name, member): the one list of its fields,
/// from which the codec (encode, decode) and summary.csv (io::summary_fields) are derived.
/// Members are std::string, double, int, bool or std::vector<double>; `name` is the field's
/// summary.csv column (start and goal as theta1_start ... theta2_goal), and "x" is the one
/// field summary.csv leaves out. The order is that of summary.csv (new fields at the end).
template <typename Result, typename Visit>
void visit_fields(Result& r, Visit&& visit) {
  visit("task", r.task);
  visit("status", r.status);
  visit("dissipated_energy", r.dissipated_energy);
  visit("baseline_dissipated_energy", r.baseline_dissipated_energy);
  visit("input_energy", r.input_energy);
  visit("peak_torque", r.peak_torque);
  visit("max_constraint_violation", r.max_constraint_violation);
  visit("wall_time_s", r.wall_time_s);
  visit("baseline_input_energy", r.baseline_input_energy);
  visit("baseline_peak_torque", r.baseline_peak_torque);
  visit("miss_distance", r.miss_distance);
  visit("min_coupler_sine", r.min_coupler_sine);
  visit("solver_status", r.solver_status);
  visit("evaluations", r.evaluations);
  visit("starts", r.starts);
  visit("best_start", r.best_start);
  visit("duration", r.duration);
  visit("torque_limit", r.torque_limit);
  visit("theta1_start", r.start[0]);
  visit("theta2_start", r.start[1]);
  visit("theta1_goal", r.goal[0]);
  visit("theta2_goal", r.goal[1]);
  visit("dissipated_energy_exact", r.dissipated_energy_exact);
  visit("baseline_dissipated_energy_exact", r.baseline_dissipated_energy_exact);
  visit("baseline_status", r.baseline_status);
  visit("initial_guess", r.initial_guess);
  visit("initial_dissipated_energy", r.initial_dissipated_energy);
  visit("initial_peak_torque", r.initial_peak_torque);
  visit("initial_min_coupler_sine", r.initial_min_coupler_sine);
  visit("control_points", r.control_points);
  visit("dissipated_energy_smoothed", r.dissipated_energy_smoothed);
  visit("baseline_dissipated_energy_smoothed", r.baseline_dissipated_energy_smoothed);
  visit("input_energy_smoothed", r.input_energy_smoothed);
  visit("baseline_input_energy_smoothed", r.baseline_input_energy_smoothed);
  visit("miss_distance_exact", r.miss_distance_exact);
  visit("smoothing_velocity", r.smoothing_velocity);
  visit("refinement_change", r.refinement_change);
  visit("continuation", r.continuation);
  visit("refinement", r.refinement);
  visit("message", r.message);
  visit("winding_heat", r.winding_heat);
  visit("baseline_winding_heat", r.baseline_winding_heat);
  visit("total_dissipation", r.total_dissipation);
  visit("baseline_total_dissipation", r.baseline_total_dissipation);
  visit("supply_energy", r.supply_energy);
  visit("baseline_supply_energy", r.baseline_supply_energy);
  visit("objective", r.objective);
  visit("refinement_limited", r.refinement_limited);
  visit("x", r.x);
}

/// Serialization of a result (for MPI transfer): decode(encode(r)) == r, bit for bit.
std::string encode(const TaskResult& result);
TaskResult decode(const std::string& bytes);

}  // namespace fivebar::trajectory
