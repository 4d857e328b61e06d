// The library side of the `identify` and `optimize` subcommands: their settings as plain values,
// turned into library options with the command line's checks and one-line messages, and the
// readers that turn library file errors into InputError. The command line (cmd_identify.cc,
// cmd_optimize.cc) and the Python module (python/) both call these.
#pragma once

#include <string>
#include <vector>

#include "fivebar/identification/excitation.h"
#include "fivebar/identification/identify.h"
#include "fivebar/identification/torque_log.h"
#include "fivebar/io/scene.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/tasks.h"

namespace fivebar::io {

/// `fivebar identify` options (see `fivebar identify --help`), with the command line's defaults:
/// those of identification::IdentifyOptions.
struct IdentifySettings {
  std::string method = identification::method_name(defaults().method);
  std::string law = identification::law_name(defaults().layout.law);
  std::string loss = identification::loss_name(defaults().loss);
  /// --estimate: parameter groups, comma-separated (friction, inertia)
  std::string estimate = "friction";
  /// --inertia-prior: relative std of the inertial prior
  double inertia_prior = defaults().inertia_prior;
  bool per_joint = false, estimate_rates = false, start_from_scene = false;
  /// log conditioning and error bars (docs/identification.md): --sg-window given (else the
  /// window is chosen from the log), --no-unwrap, --keep-glitches, --classical-std, --no-delay
  bool sg_window_given = false, no_unwrap = false, keep_glitches = false;
  bool keep_reversals = false;
  bool classical_std = false, no_delay = false;
  /// loss_scale 0: the robust loss's scale follows the residual's noise floor (IdentifyOptions)
  double loss_scale = defaults().loss_scale;
  double smooth_sign = defaults().smoothing_velocity;  ///< -1: the scene's
  double min_rate = defaults().min_rate;
  double sg_window = defaults().sg.half_window_s;
  double window = defaults().window_s;  ///< 0: chosen from the log
  int sg_order = defaults().sg.order, threads = defaults().num_threads;

 private:
  static const identification::IdentifyOptions& defaults() {
    static const identification::IdentifyOptions d;
    return d;
  }
};

/// The identification options of `settings` for `scene`. Throws
/// InputError(`command line: --law: ...`) and the like for a value the command line refuses.
identification::IdentifyOptions identify_options(const IdentifySettings& settings,
                                                 const Scene& scene);

/// The groups of `--estimate` (identification::parse_group_list); throws
/// InputError(`command line: --estimate: ...`) naming the group that is unknown, repeated or empty.
void parse_estimate(const std::string& list, identification::ParameterLayout* layout);
void parse_estimate(const std::string& list, identification::DesignGroups* groups);

/// Reads a torque log of `dof` cranks (torque_log_file.h); a log that cannot be used throws
/// InputError (the LogError's message).
identification::TorqueLog read_log(const std::string& path, int dof = 2);

/// "" or why angles that start at (theta1, theta2) look like degrees: a start beyond
/// identification::kDegreesBeyond (two turns), within 360. Read where the model failed on them,
/// to name the cause first, and on motions without rates.
std::string start_looks_like_degrees(double theta1, double theta2);
/// The same for the starts of any number of cranks.
std::string start_looks_like_degrees(const std::vector<double>& starts);

/// identification::identify for a scene: a log that does not fit the scene throws InputError,
/// failed numerics NumericalError(`<log>: identify: ...`), or InputError naming the angles when
/// the log starts where degrees would (start_looks_like_degrees).
identification::IdentifyResult identify_scene(const Scene& scene, const sim::LoadFunction& loads,
                                              const identification::TorqueLog& log,
                                              const identification::IdentifyOptions& options);

/// identification::identify of a four_bar scene (its loads M3, F, F_angle from the scene), with
/// identify_scene's errors. Options the four-bar's fit does not support are refused before
/// (identification::four_bar_unsupported).
identification::IdentifyResult identify_four_bar_scene(
    const Scene& scene, const identification::TorqueLog& log,
    const identification::IdentifyOptions& options);

/// The scene with what identify fitted: the friction, the links (group inertia) and the motors
/// (group actuator). scene_fitted.yaml and fivebar.identify's 'fitted_scene'.
Scene fitted_scene(const Scene& scene, const identification::IdentifyResult& result);

/// `fivebar optimize` options (see `fivebar optimize --help`), with the command line's defaults:
/// those of trajectory::BatchOptions, but the refinement (optimize_defaults).
struct OptimizeSettings {
  std::string method = trajectory::method_name(defaults().optimizer.method);
  /// --objective; "" (the default): total_dissipation when the scene has winding data, else
  /// dissipated_energy
  std::string objective;
  /// --regeneration (supply_energy): none | shared_bus
  std::string regeneration = trajectory::regeneration_name(defaults().problem.regeneration);
  /// --end-acceleration: free | zero
  std::string end_acceleration =
      trajectory::end_acceleration_name(defaults().problem.end_acceleration);
  bool global = false, validate = true;
  int starts = defaults().optimizer.starts;
  int control_points = defaults().problem.control_points;
  int quadrature_points = defaults().problem.quadrature_points;
  int max_evaluations = defaults().optimizer.max_evaluations;  ///< per local solve
  /// threads of one evaluation inside a task (--node-threads; trajectory::ProblemOptions::
  /// threads): the results do not depend on it
  int node_threads = defaults().problem.threads;
  double singular_margin = defaults().problem.singular_margin;
  /// grid step of the path search for a feasible start [rad]
  double path_step = defaults().path.step;
  /// the continuation to the exact law and the refinement of the control points after the
  /// first solve (`optimize` turns refine on: --no-refine; --no-continuation)
  bool refine = false, continuation = true;
  /// relative change of the objective that stops the refinement (--refine-tol); NaN:
  /// trajectory::kSmoothRefineTol for the smooth objectives (total_dissipation, supply_energy),
  /// RefineOptions::tol for the others
  double refine_tol = NAN;
  /// control points per joint of the refinement levels (--refine-levels; empty: the default
  /// trajectory::kSmoothRefineLevels or kRefineLevels, by the objective)
  std::vector<int> refine_levels;

 private:
  static const trajectory::BatchOptions& defaults() {
    static const trajectory::BatchOptions d;
    return d;
  }
};

/// The defaults of `fivebar optimize` (and Python's optimize): OptimizeSettings with the
/// refinement on.
OptimizeSettings optimize_defaults();

/// The batch options of `settings` for a scene with motor winding data `windings` of its
/// `motors` motors (which choose the default objective and give the winding heat); throws
/// InputError(`command line: --method: ...`) and the like, also for an objective that needs
/// winding data the scene does not give.
trajectory::BatchOptions batch_options(const OptimizeSettings& settings,
                                       const MotorWindings& windings, int motors = kActuators);

/// `options` with the winding heat of `windings` (a design of `study` or `design` may vary the
/// motors' keys).
trajectory::BatchOptions with_windings(trajectory::BatchOptions options,
                                       const MotorWindings& windings);

/// A varied key whose best value lies on a bound of its range.
struct BoundHit {
  std::string key;
  std::string side;  ///< "lower" or "upper"
  double bound = 0;
};
/// The keys whose value lies on (within 1e-6 of the range of) the lower or upper bound.
std::vector<BoundHit> bounds_hit(const std::vector<std::string>& keys,
                                 const std::vector<double>& values, const std::vector<double>& lo,
                                 const std::vector<double>& hi);
/// One line per hit: "the best design lies on the <side> bound of <key> (<bound>): the optimum
/// may lie outside the range; widen it".
std::string bounds_advice(const std::vector<BoundHit>& hits);

/// The note of an objective whose optimum a machine should not run (dissipated_energy: it
/// switches the motors between their limits), naming the scene keys to add; "" for the others.
std::string objective_note(const trajectory::BatchOptions& options, int motors = kActuators);
/// Appends objective_note() (when there is one) to the message of every solved result (not to
/// a task the design cannot do, whose message says why).
void add_objective_note(const trajectory::BatchOptions& options,
                        std::vector<trajectory::TaskResult>* results, int motors = kActuators);

/// Reads a tasks file (io::load_tasks) for a scene of that mechanism (`four_bar`: one-coordinate
/// poses); a malformed one throws InputError.
std::vector<trajectory::TaskSpec> read_tasks(const std::string& path, bool four_bar = false);

/// One task solved on the scene's mechanism (trajectory::run_task, or run_four_bar_task for a
/// four-bar), under the scene's loads (built here: call it from the thread that runs the task).
/// `warm`: the same task solved for a neighbouring design (run_task's warm start; a four-bar
/// starts from its minimum-jerk motion).
trajectory::TaskResult run_scene_task(const Scene& scene, const trajectory::TaskSpec& task,
                                      const trajectory::BatchOptions& options,
                                      const trajectory::TaskResult* warm = nullptr);

/// The trajectory rows of a solved task and of its minimum-jerk baseline, on the scene's output
/// step (at most a tenth of the task's duration). `baseline` is left empty when the baseline
/// cannot close (TaskResult::baseline_status neither ok nor violates_constraints).
Status task_rows(const Scene& scene, const trajectory::TaskResult& result,
                 const trajectory::BatchOptions& options, std::vector<sim::Row>* optimal,
                 std::vector<sim::Row>* baseline);

}  // namespace fivebar::io
