// fivebar excite SCENE --duration S --torque-limit NM [--estimate friction,inertia,actuator]
//   [--per-joint] [--criterion d-optimal|condition] [--theta1-range LO:HI] [--theta2-range LO:HI]
//   [--out DIR] [--set KEY=VALUE]...
// Excitation design (docs/excite.md): a periodic Fourier motion of the cranks (the five-bar's
// two, the four-bar's one) that maximizes the information a torque log along it gives on the
// chosen parameters (D-optimal, or the condition number), within the torque limit, away from
// the singular poses, with every joint reversing; on the five-bar compared with the built-in
// multi-sine of synth-log, or designed as tone torques (--family torque).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <iostream>
#include <memory>
#include <optional>
#include <random>
#include <sstream>

#include "cli_options.h"
#include "fivebar/identification/excitation.h"
#include "fivebar/identification/synth.h"
#include "fivebar/identification/torque_excitation.h"
#include "fivebar/io/command.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/rest.h"
#include "fivebar/trajectory/nlopt_minimize.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::excite_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "design an excitation motion that identifies the parameters best (D-optimal)";

namespace id = fivebar::identification;

struct Args {
  SceneArgs scene;
  /// the design's settings bound to the options directly (the command's defaults below)
  id::ExcitationOptions design = [] {
    id::ExcitationOptions o;
    o.torque_limit = NAN;
    o.design_samples = 600;
    o.min_reversals = 6;
    return o;
  }();
  double spread = 2, drift_spread = 2;
  std::string estimate = "friction", criterion = "d-optimal", method = "mma", start = "swing";
  std::string family = "torque";
  std::vector<std::string> family_only;  ///< options given that apply to the other family
  /// the options given of each family only, and whether --family was given (a four-bar's
  /// default family is fourier: the torque family is the five-bar's)
  std::vector<std::string> fourier_given, torque_given;
  bool family_given = false;
  std::string theta1_range, theta2_range;
  bool per_joint = false, no_plots = false, no_baseline = false;
  int starts = 2, max_evaluations = 0, tones = 6;
  double search_tolerance = id::kSearchTolerance;
  int finalists = id::kFinalists;
  unsigned long long seed = 1;
};

const std::vector<std::string> kOutputs = {"excitation.csv", "predicted_std.csv", "excitation.json",
                                           "fig_motion.png", "fig_torques.png",   "fig_std.png",
                                           "plots.gnuplot",  "excitation.bin"};
const char* const kFlags = "command line";

// "LO:HI" -> (lo, hi), bad input otherwise
std::array<double, 2> parse_range(const std::string& text, const std::string& flag) {
  const size_t colon = text.find(':');
  double lo = NAN, hi = NAN;
  if (colon == std::string::npos || !parse_finite(text.substr(0, colon), &lo) ||
      !parse_finite(text.substr(colon + 1), &hi) || !(lo < hi)) {
    throw InputError(kFlags, flag, "expected LO:HI in radians with LO < HI, got '" + text + "'");
  }
  return {lo, hi};
}

// the checks of bad input (exit 2) that need the scene
void check_input(const Args& a, const Scene& scene, id::ExcitationOptions* o) {
  if (!(a.design.duration > 0) || !std::isfinite(a.design.duration)) {
    throw InputError(kFlags, "--duration", "must be > 0, got " + format_double(a.design.duration));
  }
  if (!(a.design.torque_limit > 0) || !std::isfinite(a.design.torque_limit)) {
    throw InputError(kFlags, "--torque-limit", "must be > 0 N m, got " + format_double(a.design.torque_limit));
  }
  if (!(a.design.torque_noise > 0)) throw InputError(kFlags, "--torque-noise", "must be > 0");
  if (!(a.design.rate_hz > 0) || !std::isfinite(a.design.rate_hz)) {
    throw InputError(kFlags, "--rate", "must be > 0, got " + format_double(a.design.rate_hz));
  }
  // the designed motion's log is sampled at --rate: simulate's and synth-log's row limit
  const std::string rows = log_rows_problem(a.design.duration, a.design.rate_hz);
  if (!rows.empty()) {
    throw InputError(kFlags, "--duration, --rate",
                     "duration " + format_double(a.design.duration) + " s at --rate " +
                         format_double(a.design.rate_hz) + " Hz " + rows);
  }
  if (!(a.design.singular_margin >= 0 && a.design.singular_margin < 1)) {
    throw InputError(kFlags, "--singular-margin",
                     "expected a number in [0, 1), got " + format_double(a.design.singular_margin));
  }
  if (a.design.min_reversals < 0) {
    throw InputError(kFlags, "--min-reversals", "must be >= 0, got " + std::to_string(a.design.min_reversals));
  }
  // (below 1e-6 rad/s no log tells a rate from rest; above 1e5 rad/s no machine turns)
  if (!(a.design.reversal_rate >= 1e-6 && a.design.reversal_rate <= 1e5)) {
    throw InputError(kFlags, "--reversal-rate",
                     "must be in [1e-6, 1e5] rad/s, got " + format_double(a.design.reversal_rate));
  }
  if (a.design.periods < 1) throw InputError(kFlags, "--periods", "must be >= 1");
  if (a.design.harmonics < 1) throw InputError(kFlags, "--harmonics", "must be >= 1");
  if (a.design.design_samples < 16) throw InputError(kFlags, "--design-samples", "must be >= 16");
  if (a.starts < 1) throw InputError(kFlags, "--starts", "must be >= 1");
  if (!(a.family == "torque" || (a.design.ramp >= 0 && a.design.ramp < a.design.duration))) {
    throw InputError(kFlags, "--ramp",
                     "must be in [0, duration), got " + format_double(a.design.ramp));
  }
  const std::array<double, 2> start = {scene.initial.theta1, scene.initial.theta2};
  const std::string* ranges[2] = {&a.theta1_range, &a.theta2_range};
  for (int j = 0; j < kDof; ++j) {
    if (ranges[j]->empty()) continue;
    const std::string flag = "--theta" + std::to_string(j + 1) + "-range";
    const std::array<double, 2> r = parse_range(*ranges[j], flag);
    if (start[j] < r[0] || start[j] > r[1]) {
      throw InputError(kFlags, flag,
                       "the range " + *ranges[j] + " excludes the start pose theta" +
                           std::to_string(j + 1) + " = " + format_double(start[j]) + " rad");
    }
    o->theta_lo[j] = r[0];
    o->theta_hi[j] = r[1];
  }
}

// the start pose: the five-bar's cranks, the four-bar's crank (theta2 unused)
std::array<double, 2> start_pose(const Scene& scene) {
  return {scene.initial.theta1, scene.type == MechanismType::kFourBar ? 0.0 : scene.initial.theta2};
}

// the motion starts at rest at the start pose: the motors must at least hold it there (bad
// input otherwise)
void check_holding(const Args& a, const Scene& scene, const LoadExpressions& loads,
                   const id::ExcitationMechanism& mech, const id::ExcitationOptions& o) {
  const std::array<double, 2> start = start_pose(scene);
  // a start within the singular margin: no design can keep the margin from its first sample
  const bool four_bar = scene.type == MechanismType::kFourBar;
  const double sine = four_bar ? four_bar_sine(scene.four_bar, start[0])
                               : coupler_sine(scene.params, start[0], start[1]);
  if (sine < o.singular_margin) {
    throw InputError(scene.path, "initial",
                     "the start pose (theta1 = " + format_double(start[0]) +
                         (four_bar ? "" : ", theta2 = " + format_double(start[1])) + ") is " +
                         (sine < 0 ? "one the mechanism cannot assemble"
                                   : "within the design's singular margin (its singular measure " +
                                         format_significant(sine, 3) + " < " +
                                         format_significant(o.singular_margin, 3) + ")") +
                         ": start the design away from the singular pose");
  }
  Holding<double> h;
  Status st;
  if (four_bar) {
    id::SampleTerms rest;  // inverse dynamics at rest: no joint slips
    st = mech.terms(0.0, {start[0], start[1], 0, 0, 0, 0}, nullptr, &rest);
    h.M1 = rest.M1;
    h.M2 = 0;
  } else {
    st = holding_torques(scene.params, loads(0.0), start[0], start[1], EvalOptions{}, &h);
  }
  if (!st.ok()) throw InputError(scene.path, "initial", st.message);
  const double need = std::max(std::abs(h.M1), std::abs(h.M2));
  if (!std::isfinite(need)) {
    throw InputError(scene.path, "loads",
                     "holding the start pose needs torques that are not finite (M1 = " +
                         format_double(h.M1) + ", M2 = " + format_double(h.M2) + " N m)");
  }
  if (need >= a.design.torque_limit * (1.0 - o.torque_margin)) {
    const std::string torques = "M1 = " + format_double(h.M1) +
                                (mech.dof() > 1 ? ", M2 = " + format_double(h.M2) : std::string());
    throw InputError(kFlags, "--torque-limit",
                     format_double(a.design.torque_limit) +
                         " N m is below what holding the start pose needs (" + torques +
                         " N m at rest, plus the design's " + format_double(100 * o.torque_margin) +
                         " % margin)");
  }
}

// the options a four-bar's design does not have: bad input naming the option and the type
void refuse_four_bar_options(const Args& a, const id::ExcitationOptions& o) {
  const std::string type = " (mechanism.type four_bar)";
  if (a.family == "torque") {
    throw InputError(kFlags, "--family",
                     "torque drives the five-bar's two motors by tone torques; a four-bar's design "
                     "is --family fourier" +
                         type);
  }
  if (!a.theta2_range.empty()) {
    throw InputError(kFlags, "--theta2-range", "a four-bar has one crank, theta1" + type);
  }
  if (a.start == "multisine") {
    throw InputError(kFlags, "--start",
                     "multisine: the multi-sine drives the five-bar's two cranks" + type);
  }
}

id::ExcitationOptions options_of(const Args& a, const Scene& scene) {
  id::ExcitationOptions o = a.design;
  parse_estimate(a.estimate, &o.groups);
  o.groups.per_joint = a.per_joint;
  if (a.start != "multisine" && a.start != "rest" && a.start != "swing") {
    throw InputError(kFlags, "--start", "expected swing, multisine or rest, got " + a.start);
  }
  if (a.criterion == "d-optimal") {
    o.criterion = id::Criterion::kDOptimal;
  } else if (a.criterion == "condition") {
    o.criterion = id::Criterion::kCondition;
  } else if (a.criterion == "worst-std") {
    o.criterion = id::Criterion::kWorstStd;
  } else {
    throw InputError(kFlags, "--criterion",
                     "expected d-optimal, condition or worst-std, got " + a.criterion);
  }
  if (a.family != "fourier" && a.family != "torque") {
    throw InputError(kFlags, "--family", "expected fourier or torque, got " + a.family);
  }
  // a four-bar's refusals first: `--family torque --starts 1` names the family the four-bar
  // lacks, not --starts
  if (scene.type == MechanismType::kFourBar) refuse_four_bar_options(a, o);
  if (!a.family_only.empty()) {
    throw InputError(kFlags, a.family_only.front(),
                     "applies to --family " + std::string(a.family == "torque" ? "fourier" : "torque") +
                         " only (this design uses --family " + a.family + ")");
  }
  if (a.tones < 1 || a.max_evaluations < 0) {
    throw InputError(kFlags, "--tones/--max-evaluations", "need tones >= 1, max evaluations >= 0");
  }
  o.singular_margin = std::max(a.design.singular_margin, scene.options.singular_margin);
  check_input(a, scene, &o);
  // at rest the motion carries no information (the criterion is not finite there), so a local
  // solve started there alone cannot leave it; the other starts perturb rest
  if (a.start == "rest" && a.starts == 1) {
    throw InputError(kFlags, "--start",
                     "rest with --starts 1: a motion at rest carries no information, so the design "
                     "cannot leave it; give --starts 2 or more (the others perturb rest) or "
                     "--start swing");
  }
  return o;
}

// seeded starts: the first is `base` (the multi-sine's motion fitted by the basis, or rest),
// the others base plus normal perturbations (drift: drift_spread rad/s; harmonic l: spread / l rad)
std::vector<std::vector<double>> make_starts(const id::FourierMotion& m, const Args& a,
                                             const std::vector<double>& base) {
  std::mt19937_64 rng(a.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<std::vector<double>> starts = {base};
  const int pj = m.per_joint();
  for (int s = 1; s < a.starts; ++s) {
    std::vector<double> x = base;
    for (int j = 0; j < m.dof(); ++j) {
      for (int v = 0; v < pj; ++v) {
        const int l = m.harmonic_of(v);
        x[j * pj + v] += l == 0 ? a.drift_spread * gauss(rng) : a.spread * gauss(rng) / l;
      }
    }
    starts.push_back(x);
  }
  return starts;
}

// the states of the designed motion on the log's grid t = i / rate
void design_grid(const id::FourierMotion& m, const std::vector<double>& x, double duration,
                 double rate, std::vector<double>* t, std::vector<id::MotionState>* s) {
  const long n = std::lround(std::floor(duration * rate + 1e-9));
  for (long i = 0; i <= n; ++i) {
    t->push_back(i / rate);
    s->push_back(m.state(x, t->back()));
  }
}

// the built-in multi-sine of synth-log (noise-free, exact rates) on the same grid, fitted to the
// mechanism and the torque limit as synth-log --torque-limit does; `failure` says why there is
// none (a failed baseline: the design is evaluated and reported without it)
struct Multisine {
  id::TorqueLog log;
  id::ExcitationReport report;
  double factor = 1;
  bool holding_bias = false;
  std::string failure;
};

Multisine multisine(const Scene& scene, const LoadExpressions& loads, const id::DesignParameters& dp,
                    const id::ExcitationOptions& o) {
  id::SynthOptions so;
  so.rate_hz = o.rate_hz;
  so.duration = o.duration;
  so.with_rates = true;
  so.multisine = true;
  so.torque_limit = o.torque_limit;
  so.sim = scene.options;
  id::SynthResult res = id::synthesize_log(scene.params, loads.function(), scene.initial, so);
  Multisine m;
  if (!res.status.ok()) {
    m.failure = res.status.message;
    return m;
  }
  m.factor = res.multisine_factor;
  m.holding_bias = res.multisine_holding_bias;
  m.log = std::move(res.log);
  const id::TorqueLog& log = m.log;
  std::vector<id::MotionState> states;
  for (int i = 0; i < log.size(); ++i) {
    states.push_back({log.theta1[i], log.theta2[i], log.omega1[i], log.omega2[i], log.alpha1[i],
                      log.alpha2[i]});
  }
  Status st = id::evaluate_motion(scene.params, dp, loads, log.t, states, o.torque_noise, &m.report);
  if (st.ok()) {
    st = id::predict_identified_std(scene.params, dp, loads, o.torque_noise, o.angle_noise, &m.report);
  }
  if (!st.ok()) m.failure = st.message;
  // the multi-sine's peak is that of its applied torques (the log's, noise-free)
  m.report.peak_torque = 0;
  for (int i = 0; i < log.size(); ++i) {
    m.report.peak_torque = std::max({m.report.peak_torque, std::abs(log.tau1[i]), std::abs(log.tau2[i])});
  }
  return m;
}

double worst(const std::vector<double>& v, int begin, int end) {
  double w = 0;
  for (int i = begin; i < end; ++i) {
    if (std::isfinite(v[i]) || std::isinf(v[i])) w = std::max(w, v[i]);
  }
  return w;
}

// the motion and its torques: the five-bar's two cranks, or the four-bar's one (the columns of
// its motion files, t,theta1,omega1,alpha1, then M1)
void write_excitation_csv(const std::string& path, const id::ExcitationReport& r) {
  std::ostringstream s;
  s << (r.dof > 1 ? "t,theta1,theta2,omega1,omega2,alpha1,alpha2,M1,M2\n"
                  : "t,theta1,omega1,alpha1,M1\n");
  for (size_t i = 0; i < r.t.size(); ++i) {
    const id::MotionState& m = r.states[i];
    s << format_grid_value(r.t[i]);
    if (r.dof > 1) {
      for (double v : {m.th1, m.th2, m.w1, m.w2, m.a1, m.a2, r.M1[i], r.M2[i]}) {
        s << ',' << format_double(v);
      }
    } else {
      for (double v : {m.th1, m.w1, m.a1, r.M1[i]}) s << ',' << format_double(v);
    }
    s << '\n';
  }
  write_text_file(path, s.str());
}

void write_std_csv(const std::string& path, const id::DesignParameters& dp,
                   const id::ExcitationReport& r, const id::ExcitationReport* base) {
  std::ostringstream s;
  s << "name,value,std,relative_std,multisine_std,multisine_relative_std,torque_noise_std,"
       "multisine_torque_noise_std\n";
  auto at = [](const std::vector<double>& v, int i) { return i < static_cast<int>(v.size()) ? v[i] : NAN; };
  for (int i = 0; i < dp.size(); ++i) {
    s << dp.names[i] << ',' << format_double(dp.nominal[i]) << ',' << format_double(r.std_dev[i])
      << ',' << format_double(r.relative_std[i]) << ','
      << format_double(base ? base->std_dev[i] : NAN) << ','
      << format_double(base ? base->relative_std[i] : NAN) << ','
      << format_double(at(r.torque_only_std, i)) << ','
      << format_double(base ? at(base->torque_only_std, i) : NAN) << '\n';
  }
  write_text_file(path, s.str());
}

Json report_json(const id::DesignParameters& dp, const id::ExcitationReport& r) {
  Json j = Json::object();
  j.set("peak_torque", r.peak_torque);
  j.set("peak_torque_time", r.peak_time);
  j.set("min_coupler_sine", r.min_sine);
  Json rev = Json::array_of(std::vector<int>(r.reversals.begin(), r.reversals.begin() + r.joints));
  j.set("reversals", rev);
  j.set("theta1_range", Json::array().push(r.theta_min[0]).push(r.theta_max[0]));
  if (r.dof > 1) j.set("theta2_range", Json::array().push(r.theta_min[1]).push(r.theta_max[1]));
  j.set("log_det_scaled_fisher", r.log_det_scaled);
  j.set("condition_number_scaled", r.condition_number);
  j.set("worst_relative_std_friction", worst(r.relative_std, 0, dp.friction));
  j.set("worst_relative_std", worst(r.relative_std, 0, dp.size()));
  j.set("std_method", r.sg_half_window > 0 ? "errors-in-variables" : "torque-noise");
  if (r.sg_half_window > 0) {
    j.set("sg_half_window_samples", r.sg_half_window);
    j.set("window_choice", r.window_choice);
  }
  Json params = Json::array();
  for (int i = 0; i < dp.size(); ++i) {
    params.push(Json::object()
                    .set("name", dp.names[i])
                    .set("value", dp.nominal[i])
                    .set("std", r.std_dev[i])
                    .set("relative_std", r.relative_std[i])
                    .set("torque_noise_std",
                         i < static_cast<int>(r.torque_only_std.size()) ? r.torque_only_std[i] : NAN));
  }
  j.set("parameters", params);
  return j;
}

struct Design {
  trajectory::GeneralResult solve;
  id::ExcitationReport report;
  double seconds = 0;
  int rounds = 0;           // local solves with a tightened torque margin after the first
  double torque_margin = 0;  // the margin of the last round
  /// the torque family: the peak of the applied (clipped) tone torques [N m]; NaN otherwise
  double peak_applied = NAN;
  /// the torque family with --min-reversals > 0: the worst relative std (torque noise alone,
  /// design grid) and the reversals of the best motion found that misses the constraints, when
  /// it beats the design (NaN otherwise): what the constraints cost
  double unconstrained_std = NAN;
  std::array<int, kJoints> unconstrained_reversals{};
  bool torque_family = false;
  /// the torque family: the status of the std identify would report, already in `report`
  std::optional<Status> predicted;
  /// the torque family: the search objectives of the finalists evaluated at the scene's
  /// settings (the search's best first) and the chosen one's index
  std::vector<double> finalist_objectives;
  int finalist = 0;
};

trajectory::GeneralResult solve_design(const id::ExcitationProblem& problem, const Args& a,
                                       const std::vector<std::vector<double>>& starts) {
  trajectory::GeneralProblem gp;
  gp.n = problem.num_variables();
  gp.m = problem.num_constraints();
  const int pj = problem.motion().per_joint();
  for (int v = 0; v < gp.n; ++v) {
    const int l = problem.motion().harmonic_of(v % pj);
    const double bound = l == 0 ? 60.0 : 40.0 / l;  // drift [rad/s], amplitude [rad]
    gp.lower.push_back(-bound);
    gp.upper.push_back(bound);
  }
  gp.evaluate = [&problem](const std::vector<double>& x, bool grad, double* f,
                           std::vector<double>* df, std::vector<double>* c,
                           std::vector<double>* dc) {
    id::DesignValue v;
    if (!problem.evaluate(x, grad, &v).ok()) return false;
    *f = v.objective;
    *df = std::move(v.objective_grad);
    *c = std::move(v.constraints);
    *dc = std::move(v.constraints_grad);
    return std::isfinite(*f);
  };
  trajectory::GeneralOptions go;
  if (!trajectory::parse_method(a.method, &go.method)) {
    throw InputError(kFlags, "--method", "expected slsqp, mma or ccsaq, got " + a.method);
  }
  go.max_evaluations = a.max_evaluations > 0 ? a.max_evaluations : 80;
  go.ftol_rel = 1e-6;
  go.xtol_rel = 1e-6;
  go.constraint_tol = 1e-6;
  return trajectory::minimize_multistart(gp, starts, go);
}

// the designed motion on the log's grid, with its Fisher information
id::ExcitationReport on_grid(const Scene& scene, const id::ExcitationProblem& problem,
                             const std::vector<double>& x) {
  const id::ExcitationOptions& o = problem.options();
  std::vector<double> t;
  std::vector<id::MotionState> states;
  design_grid(problem.motion(), x, o.duration, o.rate_hz, &t, &states);
  id::ExcitationReport r;
  const Status st = id::evaluate_motion(problem.mechanism(), t, states, o.torque_noise, &r);
  if (!st.ok()) throw NumericalError(scene.path, "excite", "designed motion: " + st.message);
  return r;
}

// a start scaled towards the torque and singularity limits: the largest factor in (0, 1] (by
// bisection) at which the per-sample constraints hold, so that no local solve starts far outside
std::vector<double> scaled_start(const id::ExcitationProblem& problem, const std::vector<double>& x) {
  const int per_samples = problem.num_constraints() - problem.reversal_constraints();
  auto fits = [&](double s) {
    std::vector<double> xs = x;
    for (double& v : xs) v *= s;
    id::DesignValue val;
    if (!problem.evaluate(xs, false, &val).ok()) return false;
    return *std::max_element(val.constraints.begin(), val.constraints.begin() + per_samples) <= 0;
  };
  if (fits(1.0)) return x;
  double lo = 0, hi = 1;
  for (int it = 0; it < 10; ++it) (fits(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
  std::vector<double> xs = x;
  for (double& v : xs) v *= lo;
  return xs;
}

// the largest motor torque per unit acceleration of both cranks together at the start pose, at
// rest [kg m^2] (the torque at rest subtracted: loads and friction do not count)
double swing_inertia(const id::ExcitationMechanism& mech, const std::array<double, 2>& start) {
  const double th1 = start[0], th2 = start[1];
  id::SampleTerms rest, unit;
  if (!mech.terms(0.0, {th1, th2, 0, 0, 0, 0}, nullptr, &rest).ok() ||
      !mech.terms(0.0, {th1, th2, 0, 0, 1, 1}, nullptr, &unit).ok()) {
    return 1e-300;  // no swing: the start stays at rest
  }
  return std::max({std::abs(unit.M1 - rest.M1), std::abs(unit.M2 - rest.M2), 1e-300});
}

// multi-start design; while the log's grid shows a torque peak above the limit (between the
// design samples), the margin is tightened by the excess and the best design solved again
Design design(const Scene& scene, const std::shared_ptr<const id::ExcitationMechanism>& mech,
              id::ExcitationOptions o, const Args& a, const Multisine* ms) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::array<double, 2> start = start_pose(scene);
  Design d;
  const id::FourierMotion motion(o.harmonics, o.duration / o.periods, o.ramp, start, mech->dof());
  std::vector<double> base(motion.num_variables(), 0.0);
  if (a.start == "multisine") {
    if (!ms || !ms->failure.empty()) {
      throw NumericalError(scene.path, "excite",
                           "--start multisine: the multi-sine cannot run on this mechanism (" +
                               (ms ? ms->failure : std::string("skipped")) + ")");
    }
    base = motion.fit(ms->log.t, ms->log.theta1, ms->log.theta2);
  } else if (a.start == "swing") {
    // both cranks swing together through a large angle once per period: peak rate 30 rad/s, or
    // less where the torque the swing's acceleration needs (the mechanism's inertia) would
    // exceed half the limit; then the start is scaled to the limits
    const double w = 2 * M_PI / motion.period();
    const double amplitude =
        std::min(30.0 / w, 0.5 * o.torque_limit / (swing_inertia(*mech, start) * w * w));
    for (int j = 0; j < mech->dof(); ++j) {
      base[j * motion.per_joint() + motion.harmonics() + 1] = -amplitude;
    }
  }
  std::vector<std::vector<double>> starts = make_starts(motion, a, base);
  for (int round = 0; round < 4; ++round) {
    const id::ExcitationProblem problem(mech, start, o);
    if (round == 0) {
      for (std::vector<double>& x : starts) x = scaled_start(problem, x);
    }
    trajectory::GeneralResult r = solve_design(problem, a, starts);
    if (!r.evaluated) {
      throw NumericalError(scene.path, "excite",
                           "no start could be evaluated (" + r.solver.message + ")");
    }
    if (round > 0) r.evaluations += d.solve.evaluations;
    d.solve = r;
    d.report = on_grid(scene, problem, r.x);
    d.rounds = round;
    d.torque_margin = o.torque_margin;
    if (d.report.peak_torque <= o.torque_limit) break;
    // constrain where the torque peaked between design samples, and tighten the margin a little
    const id::ExcitationReport& g = d.report;
    for (size_t i = 1; i + 1 < g.t.size(); ++i) {
      const double m = std::max(std::abs(g.M1[i]), std::abs(g.M2[i]));
      const double before = std::max(std::abs(g.M1[i - 1]), std::abs(g.M2[i - 1]));
      const double after = std::max(std::abs(g.M1[i + 1]), std::abs(g.M2[i + 1]));
      if (m > o.torque_limit * (1 - o.torque_margin) && m >= before && m >= after) {
        o.extra_times.push_back(g.t[i]);
      }
    }
    o.torque_margin = 1.0 - (1.0 - o.torque_margin) * std::sqrt(o.torque_limit / g.peak_torque);
    starts = {r.x};
  }
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

// the starts of the torque family: the nine of tone_starts from the multi-sine as fitted to the
// mechanism; when it was scaled down (its biases were tuned on the paper scene's loads, and a
// bias no load balances spins the cranks one way), the nine again with the start pose's holding
// torques as biases
std::vector<std::vector<double>> torque_starts(const Scene& scene, const sim::LoadFunction& loads,
                                               const id::ToneTorques& tones,
                                               const id::FittedMultisine& fit, int k) {
  const std::vector<double> x0 = id::resize_tones(fit.tones, 4, k);
  std::vector<std::vector<double>> starts = id::tone_starts(tones, x0);
  if (fit.factor >= 1 && !fit.holding_bias) return starts;
  Holding<double> h;
  if (!holding_torques(scene.params, loads(0.0), scene.initial.theta1, scene.initial.theta2,
                       EvalOptions{}, &h).ok()) {
    return starts;
  }
  std::vector<double> held = x0;
  held[0] = h.M1;
  held[tones.per_motor()] = h.M2;
  if (held == x0) return starts;
  for (std::vector<double>& x : id::tone_starts(tones, held)) starts.push_back(std::move(x));
  return starts;
}

// the torque family's search as the solver summary of excitation.json: the chosen finalist's
// tones and search objective, its constraints at the scene's settings
trajectory::GeneralResult torque_solve_summary(const id::TorqueDesignResult& r,
                                               const id::FinishedTorqueDesign& f,
                                               bool searched_again) {
  trajectory::GeneralResult s;
  s.solver.outcome = trajectory::SolverOutcome::kMaxEvaluations;
  s.solver.message = "evolution strategy: " + std::to_string(r.evaluations) + " simulations" +
                     (searched_again ? " at the scene's settings (none of the finalists of the "
                                       "search at --search-tolerance met the constraints there)"
                                     : "") +
                     ", " + std::to_string(r.improvements) + " improving generations; its best " +
                     std::to_string(f.evaluated) + " at the scene's settings, number " +
                     std::to_string(f.finalist + 1) + " chosen";
  s.x = r.finalists[static_cast<size_t>(f.finalist)];
  s.objective = r.finalist_objectives[static_cast<size_t>(f.finalist)];
  s.evaluated = true;
  s.evaluations = r.evaluations;
  s.best_start = r.best_start;
  s.start_objectives = r.start_objectives;
  for (bool ok : r.start_feasible) s.start_max_constraint.push_back(ok ? 0.0 : 1.0);
  s.max_constraint = f.design.feasible ? 0.0 : 1.0;
  return s;
}

// the torque-driven design (--family torque): an evolution strategy over tone torques from the
// multi-sine's, then its finalists at the scene's settings on the log's grid
Design design_torque(const Scene& scene, const LoadExpressions& loads, const id::ExcitationOptions& o,
                     const Args& a) {
  const auto t0 = std::chrono::steady_clock::now();
  id::TorqueDesignOptions to;
  to.excitation = o;
  to.tones = a.tones;
  to.max_evaluations = a.max_evaluations > 0 ? a.max_evaluations : 160;
  to.seed = a.seed;
  to.sim = scene.options;
  to.search_tolerance = a.search_tolerance;
  to.finalists = a.finalists;
  const std::array<double, 2> start = {scene.initial.theta1, scene.initial.theta2};
  // M3 and F compiled once for every call; the tones replace M1 and M2 (the scene's
  // expressions for them are not evaluated)
  const std::array<std::string, 4>& e = loads.expressions();
  const sim::LoadFunction scene_loads =
      LoadExpressions({"0", "0", e[LoadExpressions::kM3], e[LoadExpressions::kF]},
                      loads(0.0).F_angle, scene.path)
          .function();
  // the multi-sine fitted to the mechanism and the limit, as the baseline (its last try when it
  // cannot run: the search's other starts may)
  id::MultisineFitOptions mo;
  mo.torque_limit = o.torque_limit;
  mo.duration = o.duration;
  mo.singular_margin = o.singular_margin;
  mo.sim = scene.options;
  sim::Initial rest;
  rest.theta1 = start[0];
  rest.theta2 = start[1];
  const id::FittedMultisine fit = id::fit_multisine(scene.params, scene_loads, rest, mo);
  const id::ToneTorques tones(a.tones, o.torque_limit);
  const std::vector<std::vector<double>> starts =
      torque_starts(scene, scene_loads, tones, fit, a.tones);
  id::TorqueDesignResult r =
      id::design_torque_excitation(scene.params, scene_loads, start, to, starts);
  // the search's best few again at the scene's settings, on the log's grid, with their std
  id::FinishedTorqueDesign f =
      id::finish_torque_design(scene.params, scene_loads, start, to, r.finalists);
  const bool searched_again =
      to.search_tolerance > 0 && !(f.design.status.ok() && f.design.feasible);
  if (searched_again) {
    // none of the finalists runs within the constraints at the scene's settings: the search's
    // tolerance has misled it near a constraint, so the search is repeated at the scene's
    to.search_tolerance = 0;
    r = id::design_torque_excitation(scene.params, scene_loads, start, to, starts);
    f = id::finish_torque_design(scene.params, scene_loads, start, to, r.finalists);
  }
  if (!r.best.status.ok()) {
    throw NumericalError(scene.path, "excite",
                         "no start of the search ran (the multi-sine's tones x " +
                             format_double(fit.factor) + ", their amplitudes x 3 and 10, frequencies "
                             "x 0.7 and 0.5): " + r.best.status.message);
  }
  id::TorqueCandidate& g = f.design;
  if (!g.status.ok()) throw NumericalError(scene.path, "excite", "designed motion: " + g.status.message);
  Design d;
  d.report = std::move(g.report);
  d.predicted = f.predicted;
  d.peak_applied = g.peak_applied;
  d.torque_family = true;
  const id::TorqueCandidate& u = r.best_unconstrained;
  if (o.min_reversals > 0 && u.status.ok() && u.objective < r.best.objective) {
    // its report is on the design grid: each sample stands for rate * duration / samples
    const double samples = static_cast<double>(u.report.t.size());
    d.unconstrained_std = worst(u.report.relative_std, 0, static_cast<int>(u.report.relative_std.size())) *
                          std::sqrt(samples / (o.rate_hz * o.duration));
    d.unconstrained_reversals = u.report.reversals;
  }
  d.solve = torque_solve_summary(r, f, searched_again);
  d.finalist_objectives.assign(r.finalist_objectives.begin(),
                               r.finalist_objectives.begin() + f.evaluated);
  d.finalist = f.finalist;
  d.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

/// A design that predicts a parameter's std above its value is no design: a log along it does
/// not determine that parameter (identify leaves it near its bound 0, or at the bound, where its
/// std is no longer meaningful: a light mechanism's design at a relative std of 2.2 gave logs
/// with one coefficient at its bound 0 and the other 4.4 std off)
constexpr double kUndeterminedRelativeStd = 1;
/// ... nor one whose worst predicted relative std is this many times the baseline's (that
/// design's 179 against the multi-sine's 0.093)
constexpr double kWorseThanBaseline = 10;

/// A peak torque this far above the limit at most (relative) is an excess of the final check
/// alone: the design met the limit where it was computed
constexpr double kSlightExcess = 1e-3;

/// Why a design's peak torque (on the log's grid) is above `limit`, by how much, and, when the
/// excess is slight (kSlightExcess), where it comes from
std::string torque_excess(const Design& d, double limit) {
  const double peak = d.report.peak_torque, excess = peak / limit - 1;
  std::string why = "peaks at " + format_significant(peak, 6) + " N m, " +
                    format_significant(100 * excess, 2) + " % above the limit " +
                    format_significant(limit, 6) + " N m";
  if (!(excess < kSlightExcess)) return why;
  if (d.peak_applied <= limit * (1 + 1e-9)) {
    return why + " (less than " + format_significant(100 * kSlightExcess) +
           " %: the applied tone torques are clipped at the limit, peak " +
           format_significant(d.peak_applied, 6) +
           " N m; the excess is in the inverse dynamics of the simulated motion on the log's "
           "grid, which differs from the applied torques by this much)";
  }
  return why + " (less than " + format_significant(100 * kSlightExcess) +
         " %: the design met the limit at the samples it was computed on, and the torque "
         "peaks between them on the log's grid)";
}

// what to change for a design whose std is too large: what --min-reversals costs it (the torque
// family: the best motion found that reverses fewer times, when it carries more information),
// else the settings that may give more
// (`torque_family`: whether the mechanism has the torque family, the five-bar)
std::string reversal_cost(const Design& d, const id::ExcitationOptions& o,
                          const id::DesignParameters& dp, bool torque_family) {
  const std::string n = std::to_string(o.min_reversals);
  double own = 0;  // the design's, torque noise alone (comparable with the search's)
  for (size_t i = 0; i < d.report.torque_only_std.size(); ++i) {
    if (dp.nominal[i] != 0) own = std::max(own, d.report.torque_only_std[i] / std::abs(dp.nominal[i]));
  }
  // no comparison (the Fourier family's local solves give none), no reversal constraint, or one
  // that costs little (the motions that reverse fewer times predict about as much)
  if (!std::isfinite(d.unconstrained_std) || o.min_reversals == 0 ||
      d.unconstrained_std > 0.5 * own) {
    return std::string("; ") +
           (o.min_reversals > 0 ? "a lower --min-reversals (" + n + "), " : "") +
           "a higher --torque-limit, a longer --duration" +
           (d.torque_family || !torque_family
                ? ""
                : " or --family torque (free motions, faster within the same limit)") +
           " may give more";
  }
  std::string rev;
  for (int k : d.unconstrained_reversals) rev += (rev.empty() ? "" : ", ") + std::to_string(k);
  return ". --min-reversals " + n + " costs it: within --torque-limit " +
         format_significant(o.torque_limit, 6) + " N m the motions found that reverse every joint " +
         n + " times are small, while the best motion found that reverses fewer (O, B, C, D, D0: " +
         rev + ") predicts a worst relative std of " + format_significant(d.unconstrained_std, 3) +
         " for the torque noise alone, where this design predicts " + format_significant(own, 3) +
         ": a lower --min-reversals (0 accepts any) or a higher --torque-limit gives a usable design";
}

// the design's own checks on the log's grid: status "ok" or what it misses; `base`: the
// multi-sine baseline's report, when it ran
std::string design_status(const Design& d, const id::ExcitationOptions& o,
                          const id::ExcitationMechanism& mech, const id::ExcitationReport* base,
                          std::string* why) {
  const id::DesignParameters& dp = mech.parameters();
  const id::ExcitationReport& r = d.report;
  // a predicted std of 0, NaN or none is no prediction: the information matrix is singular or
  // was not formed (a light mechanism once reported "worst predicted relative std 0")
  for (int i = 0; i < dp.size(); ++i) {
    const double sd = i < static_cast<int>(r.std_dev.size()) ? r.std_dev[i] : NAN;
    if (!(sd > 0) || !std::isfinite(sd)) {
      *why = "predicts no usable std for " + dp.names[i] + " (" + format_double(sd) +
             "): the information matrix of the motion is singular or not finite";
      return "std_not_determined";
    }
  }
  for (int k = 0; k < mech.joints(); ++k) {
    if (r.reversals[k] < o.min_reversals) {
      *why = "joint " + mech.joint_name(k) + " reverses " + std::to_string(r.reversals[k]) +
             " times, fewer than --min-reversals " + std::to_string(o.min_reversals) +
             " (the search found no motion within --torque-limit that does; a lower "
             "--min-reversals accepts fewer)";
      return "reversals_not_met";
    }
  }
  if (r.peak_torque > o.torque_limit * (1 + 1e-9)) {
    *why = torque_excess(d, o.torque_limit);
    return "torque_limit_exceeded";
  }
  if (r.min_sine < o.singular_margin * (1 - 1e-3)) {
    *why = "min coupler sine " + format_double(r.min_sine) + " below the singularity margin";
    return "singular_margin_violated";
  }
  for (int j = 0; j < mech.dof(); ++j) {
    if (std::isfinite(o.theta_lo[j]) &&
        (r.theta_min[j] < o.theta_lo[j] - 1e-9 || r.theta_max[j] > o.theta_hi[j] + 1e-9)) {
      *why = "theta" + std::to_string(j + 1) + " leaves its range";
      return "angle_range_violated";
    }
  }
  // the information of a design that meets its constraints (one that misses one is named for it
  // above: its large std is the cost of the search's compromise)
  const double worst = worst_relative_std(r);
  if (worst > kUndeterminedRelativeStd) {
    int i = 0;
    while (i + 1 < dp.size() && !(r.relative_std[i] == worst)) ++i;
    *why = "predicts a std of " + dp.names[i] + " " + format_significant(worst, 4) +
           " times its value: a log along it would not determine " + dp.names[i];
    // the angle noise through the estimated rates, when it is what makes the std large
    const double torque_only = i < static_cast<int>(r.torque_only_std.size()) && dp.nominal[i] != 0
                                   ? r.torque_only_std[i] / std::abs(dp.nominal[i])
                                   : NAN;
    if (torque_only < 0.5 * worst) {
      *why += " (the angle noise through the rates estimated from the angles dominates: the "
              "torque noise alone predicts " + format_significant(torque_only, 3) +
              "); a smaller --angle-noise (finer encoders), logged rates, a longer --duration or "
              "a higher --torque-limit give more";
    } else {
      *why += reversal_cost(d, o, dp, mech.dof() > 1);
    }
    return "std_too_large";
  }
  if (base && worst > kWorseThanBaseline * worst_relative_std(*base)) {
    *why = "predicts a worst relative std of " + format_significant(worst, 4) + ", more than " +
           format_significant(kWorseThanBaseline) + " times the multi-sine baseline's " +
           format_significant(worst_relative_std(*base), 3) + reversal_cost(d, o, dp, true);
    return "worse_than_baseline";
  }
  return "ok";
}

Json summary_json(const Args& a, const id::ExcitationOptions& o, const id::DesignParameters& dp,
                  const Design& d, const std::string& status, const Multisine* ms) {
  const id::ExcitationReport* base = ms && !a.no_baseline && ms->failure.empty() ? &ms->report : nullptr;
  Json j = Json::object({{"status", status},
                          {"estimate", a.estimate},
                          {"per_joint", a.per_joint},
                          {"criterion", a.criterion},
                          {"duration_s", o.duration},
                          {"rate_hz", o.rate_hz},
                          {"torque_limit", o.torque_limit},
                          {"torque_noise", o.torque_noise},
                          {"singular_margin", o.singular_margin},
                          {"min_reversals", o.min_reversals},
                          {"family", a.family}});
  if (a.family == "torque") {
    j.set("basis", "free motion under tone torques clipped at the limit, " + std::to_string(a.tones) +
                       " tones per motor (bias, amplitude, frequency, phase)");
  } else {
    j.set("basis", "drift plus finite Fourier series, " + std::to_string(o.harmonics) +
                       " harmonics, " + std::to_string(o.periods) + " periods, faded in from rest over " +
                       format_double(o.ramp) + " s");
  }
  Json solver =
      Json::object({{"method", a.family == "torque" ? "evolution_strategy" : a.method},
                    {"outcome", trajectory::outcome_name(d.solve.solver.outcome)},
                    {"message", d.solve.solver.message},
                    {"objective", d.solve.objective},
                    {"max_design_constraint", d.solve.max_constraint},
                    {"evaluations", d.solve.evaluations},
                    {"starts", a.starts},
                    {"best_start", d.solve.best_start},
                    {"start_objectives", Json::array_of(d.solve.start_objectives)},
                    {"start_max_constraint", Json::array_of(d.solve.start_max_constraint)},
                    {"design_time_s", d.seconds},
                    {"margin_rounds", d.rounds},
                    {"final_torque_margin", d.torque_margin}});
  if (d.torque_family) {
    solver.set("finalist_objectives", Json::array_of(d.finalist_objectives));
    solver.set("finalist", d.finalist);
  }
  j.set("solver", solver);
  Json coeffs = Json::array_of(d.solve.x);
  j.set(a.family == "torque" ? "torque_tones" : "fourier_coefficients", coeffs);
  j.set("designed", report_json(dp, d.report));
  Json baseline = Json::object({{"status", std::string(a.no_baseline || !ms ? "skipped"
                                                       : base               ? "ok"
                                                                            : "failed")}});
  if (!ms && !a.no_baseline)
    baseline.set("reason", "the multi-sine drives the five-bar's two cranks");
  if (ms && !a.no_baseline) {
    if (!base) baseline.set("reason", ms->failure);
    baseline.set("tones_factor", ms->factor);
    baseline.set("holding_bias", ms->holding_bias);
  }
  j.set("multisine_baseline", baseline);
  if (base) {
    j.set("multisine", report_json(dp, *base));
    const double wd = worst(d.report.relative_std, 0, dp.friction);
    const double wb = worst(base->relative_std, 0, dp.friction);
    j.set("worst_friction_relative_std_ratio_multisine_over_designed", wb / wd);
    j.set("worst_relative_std_ratio_multisine_over_designed",
          worst(base->relative_std, 0, dp.size()) / worst(d.report.relative_std, 0, dp.size()));
  }
  return j;
}

// the mechanism of the scene as the design sees it
std::shared_ptr<const id::ExcitationMechanism> mechanism_of(const Scene& scene,
                                                            const LoadExpressions& loads,
                                                            const id::ExcitationOptions& o) {
  if (scene.type == MechanismType::kFourBar) {
    return id::four_bar_excitation(scene.four_bar, loads.four_bar_function(), o.groups.per_joint,
                                   o.groups.inertia, o.groups.actuator);
  }
  return id::five_bar_excitation(scene.params, id::design_parameters(scene.params, o.groups),
                                 loads);
}

// the scene key of a friction parameter of the design ("coulomb" -> friction.coulomb, a
// per-joint "coulomb_3" -> friction.coulomb.2)
std::string friction_key(const std::string& name) {
  const size_t u = name.rfind('_');
  const bool joint = u != std::string::npos && u + 1 < name.size() &&
                     std::isdigit(static_cast<unsigned char>(name[u + 1]));
  if (!joint) return "friction." + name;
  return "friction." + name.substr(0, u) + "." + std::to_string(std::stoi(name.substr(u + 1)) - 1);
}

// A design makes each parameter's std small against its value (`ok`: every relative std at most
// 1): a scene without a friction law, or whose parameters are all 0, leaves nothing to design
// for, and a friction coefficient of 0 has no relative std to judge the design by.
void check_values(const Scene& scene, const id::DesignParameters& dp) {
  const FrictionParams<double>& f =
      scene.type == MechanismType::kFourBar ? scene.four_bar.friction : scene.params.friction;
  if (!f.active()) {
    throw InputError(scene.path, "friction.model",
                     "none: there is no friction to identify; excite designs a motion for the "
                     "coefficients of a friction law (give friction.model and the values you "
                     "expect)");
  }
  bool any = false;
  for (double v : dp.nominal) any = any || v != 0;
  if (!any) {
    throw InputError(scene.path, "friction",
                     "every parameter to design for is 0 (" + std::to_string(dp.size()) +
                         " of them): excite makes their std small against their values; give "
                         "the scene the friction you expect");
  }
  for (int i = 0; i < dp.friction; ++i) {
    if (dp.nominal[i] != 0) continue;
    throw InputError(scene.path, friction_key(dp.names[i]),
                     "0: excite judges a design by each coefficient's std against its value, "
                     "which a 0 does not have; give the value you expect (> 0)");
  }
}

// the family of the design (a four-bar's default: fourier) and the options given that it does
// not use
Args resolved(const Args& given, const Scene& scene) {
  Args a = given;
  if (scene.type == MechanismType::kFourBar && !a.family_given) a.family = "fourier";
  a.family_only = a.family == "torque" ? a.fourier_given : a.torque_given;
  return a;
}

// an ok design's outputs (excitation.csv, predicted_std.csv, excitation.json, the figures) and
// its line on the console
void write_design(const Args& a, const Scene& scene, const id::ExcitationOptions& o,
                  const id::ExcitationMechanism& mech, const Design& d, const Multisine* ms,
                  const id::ExcitationReport* base, OutputDir* out) {
  const id::DesignParameters& dp = mech.parameters();
  write_excitation_csv(out->file("excitation.csv"), d.report);
  write_std_csv(out->file("predicted_std.csv"), dp, d.report, base);
  write_json_file(out->file("excitation.json"), summary_json(a, o, dp, d, "ok", ms));
  if (!a.no_plots) {
    ExcitationFigures f;
    f.torque_limit = o.torque_limit;
    f.title = scene.path;
    f.baseline = base != nullptr;
    f.cranks = mech.dof();
    const std::string w = plot_excitation(out->staging(), f);
    if (!w.empty()) warn(w);
  }
  const double wd = worst(d.report.relative_std, 0, dp.size());
  std::cout << "fivebar excite: ok in " << format_double(std::round(d.seconds * 100) / 100)
            << " s; worst predicted relative std " << format_significant(wd, 4);
  if (base) {
    std::cout << " (multi-sine " << format_significant(worst(base->relative_std, 0, dp.size()), 4)
              << ")";
  }
  if (ms && !a.no_baseline && !base) std::cout << " (multi-sine baseline failed)";
  std::cout << "; peak torque " << format_significant(d.report.peak_torque, 6) << " N m"
            << std::endl;
  print_written(out->dir(), out->commit());
}

// the design is for identify's default law: a scene of another law is told what its std are
void warn_other_law(const Scene& scene) {
  const FrictionLaw law = friction_of(scene).law;
  if (law == FrictionLaw::kCoulombViscous || law == FrictionLaw::kNone) return;
  const std::string name = id::law_name(law);
  const std::string other =
      id::law_is_identifiable(law_descriptor(law))
          ? ": a fit with --law " + name +
                " reports other std (a power_viscous scene's viscous read 0.23 times the "
                "prediction)"
          : " (identify fits it as coulomb_viscous or stribeck only)";
  warn(
      "the design and its predicted std are those of a coulomb_viscous fit (identify's default "
      "law); the scene's law is " +
      name + other);
}

int run(const Args& given) {
  OutputDir::remove_previous(given.scene.out, kOutputs);  // a refused run leaves none of them
  Scene scene = load_scene(given.scene.scene, given.scene.sets, /*four_bar_ok=*/true);
  for (const std::string& w : scene.warnings) warn(w);
  const Args a = resolved(given, scene);
  const id::ExcitationOptions o = options_of(a, scene);  // (the options checked first)
  warn_other_law(scene);
  const LoadExpressions loads(scene);
  loads.require_finite(a.design.duration, 1 / a.design.rate_hz);
  const std::shared_ptr<const id::ExcitationMechanism> mech = mechanism_of(scene, loads, o);
  check_values(scene, mech->parameters());
  check_holding(a, scene, loads, *mech, o);
  // a trigonometric polynomial of degree H changes sign at most 2 H times per period
  const int most = 2 * o.harmonics * o.periods;
  if (a.family == "fourier" && o.min_reversals > most) {
    throw NumericalError(kFlags, "--min-reversals",
                         "status reversals_unreachable: " + std::to_string(o.min_reversals) +
                             " reversals cannot be met by " + std::to_string(o.harmonics) +
                             " harmonics over " + std::to_string(o.periods) +
                             " periods (at most " + std::to_string(most) + ")");
  }
  OutputDir out(a.scene.out, kOutputs);
  const id::DesignParameters& dp = mech->parameters();
  std::unique_ptr<Multisine> ms;  // the five-bar's
  // the torque family does not start from the baseline: it is evaluated beside the design's
  // search (a thread of its own; the load expressions are safe to share)
  std::future<Multisine> baseline;
  if (mech->dof() > 1 && (!a.no_baseline || a.start == "multisine")) {
    baseline = std::async(std::launch::async, [&] { return multisine(scene, loads, dp, o); });
  }
  const auto take_baseline = [&] {
    if (!baseline.valid()) return;
    ms = std::make_unique<Multisine>(baseline.get());
    if (!ms->failure.empty()) {
      warn("the multi-sine baseline failed (" + ms->failure +
           "): the design is evaluated without the comparison");
    }
  };
  if (a.family != "torque") take_baseline();
  Design d = a.family == "torque"
                 ? design_torque(scene, loads, o, a)
                 : design(scene, mech, o, a, a.start == "multisine" ? ms.get() : nullptr);
  take_baseline();
  // the std identify will report for a log along it: the angle noise through the rates too
  const Status eiv =
      d.predicted ? *d.predicted
                  : id::predict_identified_std(*mech, o.torque_noise, o.angle_noise, &d.report);
  std::string why = "predicts no std identify could report: " + eiv.message;
  const id::ExcitationReport* base =
      !ms || a.no_baseline || !ms->failure.empty() ? nullptr : &ms->report;
  const std::string status =
      eiv.ok() ? design_status(d, o, *mech, base, &why) : "std_not_determined";
  if (base && base->peak_torque > o.torque_limit * (1 + 1e-9)) {
    warn("the multi-sine baseline peaks at " + format_double(base->peak_torque) +
         " N m, above --torque-limit " + format_double(o.torque_limit) +
         " N m: the comparison is with a motion this limit does not allow");
  }
  if (status != "ok") {
    // only the summary, which says what was missed; no excitation that could be mistaken for one
    write_json_file(out.file("excitation.json"), summary_json(a, o, dp, d, status, ms.get()));
    out.commit();
    throw NumericalError(scene.path, "excite", "status " + status + ": the design " + why +
                                                   " (solver: " + d.solve.solver.message +
                                                   "; excitation.json written)");
  }
  write_design(a, scene, o, *mech, d, ms.get(), base, &out);
  return 0;
}

RunFunction setup(CLI::App* app) {
  auto a = std::make_shared<Args>();
  add_scene_options(app, &a->scene, "excite");
  add_plots_flag(app, &a->no_plots, "the figures");
  app->option_defaults()->always_capture_default();  // the options below show their defaults
  app->add_option("--duration", a->design.duration, "length of the motion [s]");
  app->add_option("--torque-limit", a->design.torque_limit, "|M1|, |M2| at most this [N m]")
      ->default_str("")
      ->required();
  app->add_option("--estimate", a->estimate, "parameter groups: friction,inertia,actuator");
  app->add_flag("--per-joint", a->per_joint,
                "one friction coefficient of each kind per joint (five-bar 5, four-bar 4)");
  app->add_option("--criterion", a->criterion, "d-optimal | condition | worst-std");
  CLI::Option* family = app->add_option(
      "--family", a->family,
      "fourier: position-controlled Fourier motion (gradient, NLopt) | torque: free "
      "motion under tone torques clipped at the limit (evolution strategy from the "
      "multi-sine; five-bars only). Default: torque, on a four-bar fourier");
  std::vector<CLI::Option*> fourier, torque;  // the options of one family only
  torque.push_back(app->add_option("--tones", a->tones, "torque family: tones per motor"));
  torque.push_back(app->add_option("--search-tolerance", a->search_tolerance,
                                   "torque family: rtol = atol of the search's simulations where "
                                   "the scene's are tighter, with arkode_erk45 unless the friction "
                                   "law is lugre (0: the scene's settings); its finalists are "
                                   "evaluated at the scene's")
                       ->check(nonnegative_number()));
  torque.push_back(app->add_option("--finalists", a->finalists,
                                   "torque family: the search's best motions simulated again at "
                                   "the scene's settings; the design is the one of the lowest "
                                   "worst predicted std (other criteria: objective)")
                       ->check(CLI::PositiveNumber));
  app->add_option("--theta1-range", a->theta1_range, "allowed theta1 [rad], LO:HI");
  app->add_option("--theta2-range", a->theta2_range, "allowed theta2 [rad], LO:HI");
  app->add_option("--singular-margin", a->design.singular_margin,
                  "least |sin(theta4 - theta3)| (four-bar: |sin(theta3 - theta2)|)");
  app->add_option("--min-reversals", a->design.min_reversals, "sign changes of every joint's rate");
  fourier.push_back(app->add_option("--reversal-rate", a->design.reversal_rate,
                                    "fourier: every joint reaches +- this [rad/s]"));
  app->add_option("--torque-noise", a->design.torque_noise, "std of the logged torques [N m]");
  app->add_option("--angle-noise", a->design.angle_noise,
                  "std of the logged angles [rad] (the rates identify estimates from them)")
      ->check(within_a_turn());
  app->add_option("--rate", a->design.rate_hz, "sampling rate of the log [Hz]");
  fourier.push_back(app->add_option("--periods", a->design.periods, "periods of the motion"));
  fourier.push_back(
      app->add_option("--harmonics", a->design.harmonics, "Fourier harmonics per crank"));
  app->add_option("--design-samples", a->design.design_samples, "samples of the design objective");
  fourier.push_back(app->add_option("--starts", a->starts, "multi-start: local solves"));
  app->add_option("--seed", a->seed, "seed of the starts")->check(nonnegative_number());
  fourier.push_back(
      app->add_option("--spread", a->spread, "Fourier amplitudes of the random starts [rad]")
          ->check(positive_number()));
  fourier.push_back(
      app->add_option("--drift-spread", a->drift_spread, "drifts of the random starts [rad/s]")
          ->check(nonnegative_number()));
  fourier.push_back(app->add_option("--ramp", a->design.ramp, "fade-in from rest [s]"));
  fourier.push_back(app->add_option("--start", a->start,
                                    "first start: swing (both cranks swing together) | multisine "
                                    "(its motion fitted) | rest"));
  fourier.push_back(app->add_option("--method", a->method, "slsqp | mma | ccsaq"));
  app->add_option("--max-evaluations", a->max_evaluations,
                  "fourier: per local solve (0: 80); torque: simulations in the search (0: 160)");
  app->add_flag("--no-baseline", a->no_baseline, "skip the multi-sine comparison");
  // the options a user gave that the chosen family does not use: bad input, not ignored
  return [a, fourier, torque, family] {
    for (const CLI::Option* o : fourier) {
      if (o->count() > 0) a->fourier_given.push_back(o->get_name());
    }
    for (const CLI::Option* o : torque) {
      if (o->count() > 0) a->torque_given.push_back(o->get_name());
    }
    a->family_given = family->count() > 0;
    return run(*a);
  };
}

const bool kRegistered = register_command({"excite", kSummary, setup});

}  // namespace
}  // namespace fivebar::io::excite_command
