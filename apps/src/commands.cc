#include "fivebar/io/commands.h"

#include <algorithm>
#include <cmath>

#include "fivebar/identification/degrees.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/tasks_file.h"
#include "fivebar/io/torque_log_file.h"
#include "fivebar/trajectory/four_bar_tasks.h"

namespace fivebar::io {

namespace id = fivebar::identification;

namespace {
const char* const kFlags = "command line";

/// The largest Savitzky-Golay half-window --sg-window may ask for [samples]: each sample's
/// filter is a least-squares solve whose cost grows as the window squared (1 s at 1 kHz, 1000
/// samples, ran for minutes), and the data-driven choice never goes beyond a few tens
constexpr double kMaxSgHalfWindow = 200;

/// A half-window given with --sg-window that the log cannot hold, or one beyond
/// kMaxSgHalfWindow samples, is bad input (a huge value overflowed to the smallest window)
void check_sg_window(const id::IdentifyOptions& options, const id::TorqueLog& log) {
  const double dt = id::median_time_step(log);
  if (options.auto_window || !(dt > 0)) return;
  const double half = options.sg.half_window_s / dt;
  const std::string asked = format_shortest(options.sg.half_window_s) + " s is " +
                            format_significant(half, 3) + " samples of the log's step " +
                            format_significant(dt, 3) + " s";
  if (std::lround(half) < 1) {
    throw InputError(kFlags, "--sg-window",
                     asked + ": less than one sample (its half-window holds whole samples)");
  }
  if (!(2 * std::lround(std::min(half, 1e9)) + 1 <= log.size())) {
    throw InputError(kFlags, "--sg-window",
                     asked + ": the window (2 x " + format_significant(half, 3) +
                         " + 1 samples) must fit in the log's " + std::to_string(log.size()) +
                         " samples");
  }
  if (half > kMaxSgHalfWindow) {
    throw InputError(kFlags, "--sg-window",
                     asked + ": more than " + format_significant(kMaxSgHalfWindow) +
                         " (the filter's cost grows as the window squared; smooth less, or "
                         "resample the log)");
  }
}

/// A --window longer than the log holds no window: bad input naming the log's duration
void check_window(const id::IdentifyOptions& options, const id::TorqueLog& log) {
  if (!(options.window_s > 0) || log.size() < 2) return;
  const double span = log.t.back() - log.t.front();
  const double dt = id::median_time_step(log);
  if (dt > 0 && options.window_s < 2 * dt) {
    throw InputError(kFlags, "--window",
                     format_shortest(options.window_s) + " s holds fewer than 2 samples of the " +
                         "log's step " + format_significant(dt, 3) + " s");
  }
  if (options.window_s <= span) return;
  throw InputError(kFlags, "--window",
                   format_shortest(options.window_s) + " s is longer than the log (" +
                       format_significant(span, 4) + " s from t = " +
                       format_significant(log.t.front(), 6) + "): at most its duration");
}

/// The log's largest joint rate [rad/s]: the logged rates, else the angles' differences (one
/// turn's jumps left in: an unwrapped log reads a rate no larger than its true one)
double largest_rate(const id::TorqueLog& log) {
  double w = 0;
  for (const std::vector<double>* o : {&log.omega1, &log.omega2}) {
    for (double v : *o) w = std::max(w, std::abs(v));
  }
  if (log.has_rates) return w;
  for (const std::vector<double>* th : {&log.theta1, &log.theta2}) {
    for (size_t i = 1; i < th->size() && i < log.t.size(); ++i) {
      const double dt = log.t[i] - log.t[i - 1], d = std::abs((*th)[i] - (*th)[i - 1]);
      if (dt > 0 && d < M_PI) w = std::max(w, d / dt);
    }
  }
  return w;
}

/// A smoothing velocity beyond the log's largest rate is bad input: tanh(w / w_s) is then nearly
/// linear over the whole log, so Coulomb friction cannot be told from viscous friction (1e19
/// left coulomb at its start, with no std). The fit's: --smooth-sign, else the scene's
/// friction.smoothing_velocity (named as the key it came from).
void check_smooth_sign(const id::IdentifyOptions& options, const Scene& scene,
                       const id::TorqueLog& log) {
  const bool given = options.smoothing_velocity >= 0;
  const double ws = given ? options.smoothing_velocity : friction_of(scene).smoothing_velocity;
  const double w = largest_rate(log);
  if (!(ws > 0) || !(w > 0) || ws <= w) return;
  const std::string why = format_shortest(ws) + " rad/s is beyond the log's largest rate, " +
                          format_significant(w, 3) +
                          " rad/s: the sign would be linear in the rate (no Coulomb friction to "
                          "fit); use at most a fraction of it (0: the exact sign)";
  if (given) throw InputError(kFlags, "--smooth-sign", why);
  throw InputError(scene.path, "friction.smoothing_velocity", why + " or --smooth-sign 0");
}

/// --smooth-sign's value before the log is read: >= 0, and where positive not below the scene
/// reader's range (the fitted scene carries it; a value above the log's largest rate is refused
/// once the log is read: check_smooth_sign). The default's -1 (the scene's) is not for users:
/// the command line rejects negative values.
void check_smooth_sign_value(double v) {
  if (!std::isfinite(v) || (v < 0 && v != -1)) {
    throw InputError(kFlags, "--smooth-sign",
                     "must be >= 0 [rad/s] (0: the exact sign), got " + format_shortest(v));
  }
  const SceneLimit* smooth = scene_limit("friction.smoothing_velocity");
  if (v > 0 && smooth != nullptr && v < smooth->low) {
    throw InputError(kFlags, "--smooth-sign",
                     "must be at least " + format_double(smooth->low) +
                         " rad/s (the plausible range of a machine, docs/scene.md; 0: the exact "
                         "sign), got " +
                         format_double(v));
  }
}

/// The scene's friction as the start of a fit of `law`: the coefficients the scene's law
/// identifies or requires keep their values (a LuGre scene identifies none, and requires its
/// coulomb); of the others, one that defaults to another takes its value (static_coulomb:
/// coulomb) and one that only the fitted law identifies its neutral start
/// (CoefficientInfo::start: the Stribeck velocity 0.2 rad/s).
FrictionParams<double> start_from(FrictionParams<double> fp, FrictionLaw law) {
  const LawDescriptor& scene_law = law_descriptor(fp.law);
  for (const CoefficientInfo& c : kCoefficientInfo) {  // coulomb before static_coulomb
    const LawCoefficient* use = law_coefficient(scene_law, c.id);
    if (use && (use->identifiable || use->required)) continue;
    if (c.same_as != c.id) {
      coefficient(fp, c.id) = coefficient(fp, c.same_as);
    } else if (identifies(law_descriptor(law), c.id)) {
      coefficient(fp, c.id).fill(c.start);
    }
  }
  return fp;
}
}  // namespace

namespace {
template <class Groups>
void parse_estimate_into(const std::string& list, Groups* groups) {
  std::string bad;
  if (id::parse_groups(list, groups, &bad)) return;
  throw InputError(kFlags, "--estimate",
                   bad.empty() ? "an empty value in '" + list +
                                     "' (a list is values separated by commas)"
                               : "'" + bad + "' is not a group or is given twice (expected "
                                 "friction, inertia, actuator, each at most once, comma-separated)");
}
}  // namespace

void parse_estimate(const std::string& list, id::ParameterLayout* layout) {
  parse_estimate_into(list, layout);
}
void parse_estimate(const std::string& list, id::DesignGroups* groups) {
  parse_estimate_into(list, groups);
}

id::IdentifyOptions identify_options(const IdentifySettings& a, const Scene& scene) {
  id::IdentifyOptions opt;
  if (!id::parse_law(a.law, &opt.layout.law)) {
    throw InputError(kFlags, "--law", "expected " + id::identifiable_law_names() + ", got " + a.law);
  }
  opt.layout.per_joint = a.per_joint;
  parse_estimate(a.estimate, &opt.layout);
  // a relative std below 1e-6 holds the inertias at the scene's values (--estimate friction
  // does that); above 1e3 it is no prior
  if (!(a.inertia_prior >= 1e-6 && a.inertia_prior <= 1e3)) {
    throw InputError(
        kFlags, "--inertia-prior",
        "must be in [1e-6, 1e3] (a relative std, e.g. 0.2), got " + format_double(a.inertia_prior));
  }
  opt.inertia_prior = a.inertia_prior;
  if (!id::parse_method(a.method, &opt.method)) {
    throw InputError(kFlags, "--method",
                     "expected inverse-dynamics or output-error, got " + a.method);
  }
  if (!id::parse_loss(a.loss, &opt.loss)) {
    throw InputError(kFlags, "--loss", "expected none, huber or cauchy, got " + a.loss);
  }
  if ((opt.layout.inertia || opt.layout.actuator) && opt.method != id::Method::kInverseDynamics) {
    throw InputError(kFlags, "--estimate",
                     std::string("group ") + (opt.layout.inertia ? "inertia" : "actuator") +
                         " needs --method inverse-dynamics");
  }
  if (!(a.loss_scale >= 0) || !std::isfinite(a.loss_scale)) {
    throw InputError(kFlags, "--loss-scale", "must be > 0 (0: from the noise floor, the default)");
  }
  if (!(a.sg_window > 0) || !std::isfinite(a.sg_window)) {
    throw InputError(kFlags, "--sg-window", "must be > 0 [s], got " + format_shortest(a.sg_window));
  }
  if (a.sg_order < 2 || a.sg_order > 10) {
    throw InputError(kFlags, "--sg-order", "must be in [2, 10], got " + std::to_string(a.sg_order));
  }
  if (!(a.window >= 0) || !std::isfinite(a.window)) {
    throw InputError(kFlags, "--window", "must be > 0 (0: the default)");
  }
  check_smooth_sign_value(a.smooth_sign);
  if (!(a.min_rate >= 0) || !std::isfinite(a.min_rate)) {
    // the command line's shared rule words it the same (command.cc, nonnegative_number)
    throw InputError(kFlags, "--min-rate", "must be >= 0, got " + format_shortest(a.min_rate));
  }
  opt.loss_scale = a.loss_scale;
  opt.smoothing_velocity = a.smooth_sign;
  opt.estimate_rates = a.estimate_rates;
  opt.min_rate = a.min_rate;
  opt.rest_rate_threshold = scene.rest_rate_threshold;  // rest rule; < 0: derived
  opt.rest_acceleration_threshold = scene.rest_acceleration_threshold;
  opt.sg.half_window_s = a.sg_window;
  opt.sg.order = a.sg_order;
  opt.auto_window = !a.sg_window_given;
  opt.condition.unwrap = !a.no_unwrap;
  opt.condition.reject_glitches = !a.keep_glitches;
  opt.exclude_reversals = !a.keep_reversals;
  opt.errors_in_variables = !a.classical_std;
  opt.estimate_delay = !a.no_delay;
  opt.num_threads = std::max(1, a.threads);
  opt.window_s = a.window;
  if (scene.type == MechanismType::kFourBar) opt.layout.set_four_bar();
  if (a.start_from_scene) {
    opt.initial = opt.layout.extract(start_from(friction_of(scene), opt.layout.law));
  }
  return opt;
}

id::TorqueLog read_log(const std::string& path, int dof) {
  try {
    return io::read_torque_log(path, dof);
  } catch (const id::LogError& e) {
    // the file itself (cannot open, a directory): the option that named it
    throw InputError(e.file(), e.key() == "(file)" ? "--log" : e.key(), e.reason());
  }
}

std::string start_looks_like_degrees(const std::vector<double>& starts) {
  double first = 0.0;
  std::string at;
  for (double s : starts) {
    first = std::max(first, std::abs(s));
    at += (at.empty() ? "" : ", ") + format_significant(s, 4);
  }
  if (!(first > id::kDegreesBeyond && first <= 360)) return "";
  return "angles look like degrees (" + std::string(starts.size() > 1 ? "they start" : "it starts") +
         " at " + at + "), expected radians";
}

std::string start_looks_like_degrees(double theta1, double theta2) {
  return start_looks_like_degrees(std::vector<double>{theta1, theta2});
}

namespace {

/// A fit whose fitted scene the scene reader refuses (a value beyond the plausible range of a
/// machine: coulomb 30 from a scene whose pin radius is 150 times too small) is not to be used,
/// naming the key: a scene `simulate` would refuse is not a result.
void reject_implausible_fit(const Scene& scene, id::IdentifyResult* res) {
  try {
    parse_scene(scene_to_yaml(fitted_scene(scene, *res)), "scene_fitted.yaml", {},
                /*four_bar_ok=*/true);
  } catch (const InputError& e) {
    const std::string why = "the fitted scene is refused by the scene reader (" + e.key() + ": " +
                            e.reason() +
                            "): check the scene's pin radii, masses and lengths, and the log's "
                            "units";
    res->warnings.push_back(why);
    if (res->unusable.empty()) res->unusable = why;
  }
}

}  // namespace

id::IdentifyResult identify_scene(const Scene& scene, const sim::LoadFunction& loads,
                                  const id::TorqueLog& log, const id::IdentifyOptions& options) {
  check_sg_window(options, log);
  check_window(options, log);
  check_smooth_sign(options, scene, log);
  LoadExpressions(scene).require_finite(log.t);
  id::IdentifyResult res;
  try {
    res = id::identify(scene.params, loads, log, options);
  } catch (const id::LogError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
  if (!res.status.ok()) {
    const std::string degrees =
        options.check_degrees && log.size() > 0
            ? start_looks_like_degrees(log.theta1[0], log.theta2[0])
            : "";
    if (!degrees.empty()) {
      throw InputError(log.path, "columns theta1, theta2",
                       degrees + ": the model failed on them: " + res.status.message);
    }
    throw NumericalError(log.path, "identify", res.status.message);
  }
  reject_implausible_fit(scene, &res);
  return res;
}

id::IdentifyResult identify_four_bar_scene(const Scene& scene, const id::TorqueLog& log,
                                           const id::IdentifyOptions& options) {
  check_sg_window(options, log);
  check_window(options, log);
  check_smooth_sign(options, scene, log);
  if (options.check_degrees && log.has_rates) {
    const std::string why = id::rates_look_like_degrees(log.t, log.theta1, log.omega1);
    if (!why.empty()) {
      throw InputError(log.path, "column theta1",
                       "angles look like degrees, expected radians (" + why + ")");
    }
  }
  // without rates, a start in degrees is named where the model fails on the angles
  const std::string degrees = options.check_degrees && log.size() > 0
                                  ? start_looks_like_degrees(std::vector<double>{log.theta1[0]})
                                  : "";
  const LoadExpressions expressions(scene);
  expressions.require_finite(log.t);
  id::IdentifyResult res;
  try {
    res = id::identify(scene.four_bar, expressions.four_bar_function(), log, options);
  } catch (const id::LogError& e) {
    // identify names the unit itself where the motion tells it (angle_units_from_motion)
    const bool named = e.reason().rfind("angles look like", 0) == 0;
    if (!degrees.empty() && !named) {
      throw InputError(log.path, "column theta1", degrees + ": " + e.reason());
    }
    throw InputError(e.file(), e.key(), e.reason());
  }
  if (!res.status.ok()) {
    if (!degrees.empty()) {
      throw InputError(log.path, "column theta1",
                       degrees + ": the model failed on them: " + res.status.message);
    }
    throw NumericalError(log.path, "identify", res.status.message);
  }
  reject_implausible_fit(scene, &res);
  return res;
}

Scene fitted_scene(const Scene& scene, const id::IdentifyResult& result) {
  Scene fitted = scene;
  if (scene.type == MechanismType::kFourBar) {
    fitted.four_bar = result.fitted_four_bar;
    return fitted;
  }
  fitted.params.friction = result.fitted.friction;
  fitted.params.links = result.fitted.links;
  fitted.params.actuators = result.fitted.actuators;
  return fitted;
}

OptimizeSettings optimize_defaults() {
  OptimizeSettings s;
  s.refine = true;  // the optimum of the problem, not of the basis
  return s;
}

namespace {

// the scene keys of the motors' winding data
constexpr char kWindingKeys[] =
    "actuators.M1.winding_resistance, actuators.M1.torque_constant, "
    "actuators.M2.winding_resistance, actuators.M2.torque_constant (and gear_ratio, default 1)";
// the four-bar's (one motor)
constexpr char kFourBarWindingKeys[] =
    "actuators.M1.winding_resistance, actuators.M1.torque_constant (and gear_ratio, default 1)";

// --objective, --regeneration, --end-acceleration and the refinement that suits the objective
void objective_options(const OptimizeSettings& a, const MotorWindings& windings, int motors,
                       trajectory::BatchOptions* o) {
  const bool winding = windings.present(motors);
  const std::string keys = motors == 1 ? kFourBarWindingKeys : kWindingKeys;
  o->problem.winding_heat = windings.heat_coefficients();
  const std::string name =
      a.objective.empty() ? (winding ? "total_dissipation" : "dissipated_energy") : a.objective;
  if (!trajectory::parse_objective(name, &o->problem.objective)) {
    throw InputError(kFlags, "--objective",
                     "'" + name + "' is not one of " + trajectory::objective_names());
  }
  if (trajectory::needs_winding(o->problem.objective) && !winding) {
    throw InputError(kFlags, "--objective",
                     name + " needs the motors' winding data; add to the scene: " +
                         keys);
  }
  if (!trajectory::parse_regeneration(a.regeneration, &o->problem.regeneration)) {
    throw InputError(kFlags, "--regeneration",
                     "'" + a.regeneration + "' is not one of none, shared_bus");
  }
  if (!trajectory::parse_end_acceleration(a.end_acceleration, &o->problem.end_acceleration)) {
    throw InputError(kFlags, "--end-acceleration",
                     "'" + a.end_acceleration + "' is not one of free, zero");
  }
  const bool smooth = trajectory::needs_winding(o->problem.objective);
  const double tol = !std::isnan(a.refine_tol) ? a.refine_tol
                     : smooth                   ? trajectory::kSmoothRefineTol
                                                : trajectory::RefineOptions().tol;
  // a relative change of the energy below 1e-12 cannot be told from rounding
  if (!(tol >= 1e-12 && tol < 1)) {
    throw InputError(kFlags, "--refine-tol",
                     "expected a number in [1e-12, 1), got " + format_double(tol));
  }
  o->refine.tol = tol;
  if (a.refine) {
    o->refine.control_points =
        !a.refine_levels.empty()
            ? a.refine_levels
            : (smooth ? trajectory::kSmoothRefineLevels : trajectory::kRefineLevels);
  }
}

}  // namespace

std::string objective_note(const trajectory::BatchOptions& options, int motors) {
  if (options.problem.objective != trajectory::Objective::kDissipatedEnergy) return "";
  const std::string why =
      "the optimum of dissipated_energy switches the motors between their torque limits (a "
      "chattering limit no discretization converges); ";
  const std::array<double, 2>& c = options.problem.winding_heat;
  if (c[0] > 0 && (motors < 2 || c[1] > 0)) {
    return why + "the scene gives the motors' winding data: minimize total_dissipation (the "
                 "default) for a motion a machine can run";
  }
  return why + "add the motors' winding data to the scene (" +
         (motors == 1 ? kFourBarWindingKeys : kWindingKeys) +
         ") to minimize total_dissipation instead";
}

trajectory::BatchOptions with_windings(trajectory::BatchOptions options,
                                       const MotorWindings& windings) {
  options.problem.winding_heat = windings.heat_coefficients();
  return options;
}

std::vector<BoundHit> bounds_hit(const std::vector<std::string>& keys,
                                 const std::vector<double>& values, const std::vector<double>& lo,
                                 const std::vector<double>& hi) {
  constexpr double kOnBound = 1e-6;  // relative to the range
  std::vector<BoundHit> hits;
  for (size_t k = 0; k < keys.size(); ++k) {
    if (hi[k] <= lo[k]) continue;  // a fixed value is no bound of a search
    const double tol = kOnBound * (hi[k] - lo[k]);
    if (values[k] <= lo[k] + tol) hits.push_back({keys[k], "lower", lo[k]});
    if (values[k] >= hi[k] - tol) hits.push_back({keys[k], "upper", hi[k]});
  }
  return hits;
}

std::string bounds_advice(const std::vector<BoundHit>& hits) {
  std::string s;
  for (const BoundHit& h : hits) {
    s += "the best design lies on the " + h.side + " bound of " + h.key + " (" +
         format_double(h.bound) + "): the optimum may lie outside the range; widen it\n";
  }
  return s;
}

void add_objective_note(const trajectory::BatchOptions& options,
                        std::vector<trajectory::TaskResult>* results, int motors) {
  const std::string note = objective_note(options, motors);
  if (note.empty()) return;
  for (trajectory::TaskResult& r : *results) {
    if (r.solved()) r.add_note(note);
  }
}

trajectory::BatchOptions batch_options(const OptimizeSettings& a, const MotorWindings& windings,
                                       int motors) {
  trajectory::BatchOptions o;
  if (!trajectory::parse_method(a.method, &o.optimizer.method)) {
    throw InputError(kFlags, "--method", "'" + a.method + "' is not slsqp, mma or ccsaq");
  }
  if (a.control_points < 7 || a.control_points > 60) {
    throw InputError(kFlags, "--control-points", "expected an integer in [7, 60]");
  }
  if (a.quadrature_points < 2 || a.quadrature_points > 64) {
    throw InputError(kFlags, "--quadrature-points", "expected an integer in [2, 64]");
  }
  if (!(a.singular_margin >= 0 && a.singular_margin < 1)) {
    throw InputError(kFlags, "--singular-margin", "expected a number in [0, 1)");
  }
  if (a.starts < 1) throw InputError(kFlags, "--starts", "expected an integer >= 1");
  if (a.max_evaluations < 10) {
    throw InputError(kFlags, "--max-evaluations", "expected an integer >= 10");
  }
  o.optimizer.max_evaluations = a.max_evaluations;
  if (a.node_threads < 1 || a.node_threads > 64) {
    throw InputError(kFlags, "--node-threads", "expected an integer in [1, 64]");
  }
  o.problem.threads = a.node_threads;
  if (!(a.path_step >= 1e-3 && a.path_step <= 0.5)) {
    throw InputError(kFlags, "--path-step", "expected a number in [0.001, 0.5] rad");
  }
  for (size_t i = 0; i < a.refine_levels.size(); ++i) {
    if (a.refine_levels[i] < 8 || a.refine_levels[i] > 400 ||
        (i > 0 && a.refine_levels[i] <= a.refine_levels[i - 1])) {
      throw InputError(kFlags, "--refine-levels",
                       "expected increasing integers in [8, 400], comma-separated");
    }
  }
  objective_options(a, windings, motors, &o);
  if (!a.continuation) o.refine.continuation.clear();
  o.refine.enabled = a.refine || a.continuation;
  o.path.step = a.path_step;
  o.optimizer.global = a.global;
  o.optimizer.starts = a.starts;
  o.problem.control_points = a.control_points;
  o.problem.quadrature_points = a.quadrature_points;
  o.problem.singular_margin = a.singular_margin;
  o.validate = a.validate;
  return o;
}

std::vector<trajectory::TaskSpec> read_tasks(const std::string& path, bool four_bar) {
  return load_tasks(path, four_bar);
}

trajectory::TaskResult run_scene_task(const Scene& scene, const trajectory::TaskSpec& task,
                                      const trajectory::BatchOptions& options,
                                      const trajectory::TaskResult* warm) {
  if (scene.type == MechanismType::kFourBar) {
    const sim::FourBarLoadFunction loads = LoadExpressions(scene).four_bar_function();
    return trajectory::run_four_bar_task(scene.four_bar, loads, task, scene.initial.theta1,
                                         options);
  }
  const sim::LoadFunction loads = LoadExpressions(scene).function();
  return trajectory::run_task(scene.params, loads, task, scene.initial, options, warm);
}

Status task_rows(const Scene& scene, const trajectory::TaskResult& r,
                 const trajectory::BatchOptions& options, std::vector<sim::Row>* optimal,
                 std::vector<sim::Row>* baseline) {
  const double step = std::min(scene.options.output_step, r.duration / 10);
  // rows(base, out): the rows of the result's motion, or of its minimum-jerk baseline
  auto rows_of = [&](const auto& rows) {
    const Status s1 = rows(false, optimal);
    if (!s1.ok()) return s1;
    baseline->clear();
    if (r.baseline_status != "ok" && r.baseline_status != "violates_constraints") {
      return Status::Ok();  // the baseline does not close: no rows
    }
    return rows(true, baseline);
  };
  if (scene.type == MechanismType::kFourBar) {
    const sim::FourBarLoadFunction loads = LoadExpressions(scene).four_bar_function();
    return rows_of([&](bool base, std::vector<sim::Row>* out) {
      return trajectory::four_bar_rows(scene.four_bar, loads, r, options, base, step, out);
    });
  }
  const sim::LoadFunction loads = LoadExpressions(scene).function();
  const trajectory::TrajectoryProblem problem =
      trajectory::problem_of(scene.params, loads, r, options);
  return rows_of([&](bool base, std::vector<sim::Row>* out) {
    if (!base) return problem.rows(r.x.data(), step, out);
    const std::vector<double> x0 = problem.motion().minimum_jerk();
    return problem.rows(x0.data(), step, out);
  });
}

}  // namespace fivebar::io
