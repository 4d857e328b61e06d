// fivebar synth-log SCENE --out LOG.csv [--rate HZ] [--duration S] [--torque-noise NM]
//   [--angle-noise RAD] [--seed N] [--quantization RAD] [--excitation scene|multisine]
//   [--with-rates] [--law coulomb_viscous|stribeck] [--motion MOTION.csv] [--set KEY=VALUE]...
//   [--torque-offset A,B] [--actuator-coulomb A,B] [--actuator-viscous A,B] (a four-bar: A)
// A synthetic torque log (interfaces.md, "Torque log CSV") for testing identification: the scene
// simulated, sampled, with seeded Gaussian sensor noise and optional encoder quantization. The
// `#` header of the log holds the true friction values and the command that made it. With
// --motion (e.g. the excitation.csv of `fivebar excite`), the log is that of a position-controlled
// mechanism following the given motion: the torques by inverse dynamics, plus the noise. A
// four-bar scene's log has one crank (t,theta1,tau1; docs/formats.md).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "cli_options.h"
#include "fivebar/identification/excitation.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/identification/synth.h"
#include "fivebar/io/command.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/log_truth.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/torque_log_file.h"
#include "fivebar/model/actuator.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/inertial.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::synth_log_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] = "write a synthetic torque log of a scene (true friction in its header)";

struct Args {
  std::string scene, out;
  std::vector<std::string> sets;
  /// sampling, noise and seed, bound to the options directly (the command's defaults below)
  identification::SynthOptions so = [] {
    identification::SynthOptions o;
    o.torque_noise = 0.02;
    o.angle_noise = 1e-5;
    return o;
  }();
  std::string excitation = "scene", law, motion;
  double static_coulomb = 0.18, stribeck_velocity = 0.1, stribeck_exponent = 2.0;
  /// actuator terms (tau1, tau2), overriding the scene's `actuators:` when given
  std::vector<double> torque_offset, actuator_coulomb, actuator_viscous;
  std::string command_line;
  /// --rate and --duration as given on the command line (a motion's grid replaces their defaults)
  const CLI::Option* rate_option = nullptr;
  const CLI::Option* duration_option = nullptr;
  /// the motion's first seconds to follow: --duration when given, else all of it
  double motion_duration() const {
    return duration_option && duration_option->count() ? so.duration
                                                       : std::numeric_limits<double>::infinity();
  }
};

// Writes the log to `path`, creating its directory.
void write_log(const std::string& path, const identification::TorqueLog& log) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec) throw InputError(path, "--out", "cannot create the directory: " + ec.message());
  }
  try {
    io::write_torque_log(path, log);
  } catch (const identification::LogError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
}

// The rows of a motion up to `duration` seconds after its first (all of them for infinity; at
// least two); a motion shorter than that by more than half a step is refused, naming its length.
std::vector<sim::Row> first_seconds(const std::string& path, std::vector<sim::Row> rows,
                                    double duration) {
  if (!std::isfinite(duration)) return rows;
  const double t0 = rows.front().t, length = rows.back().t - t0;
  const double half_step = rows.size() > 1 ? 0.5 * length / double(rows.size() - 1) : 0.0;
  if (duration > length + half_step) {
    throw InputError(
        path, "--duration",
        format_double(duration) + " s is longer than the motion (" + format_double(length) + " s)");
  }
  // the rows up to the duration (rounding of t apart), at least two
  size_t n = 0;
  while (n < rows.size() && rows[n].t - t0 <= duration + 1e-9 * half_step) ++n;
  n = std::min(rows.size(), std::max<size_t>(n, 2));
  rows.resize(n);
  return rows;
}

// The rows of MOTION.csv (columns t, theta<j>, omega<j>, alpha<j> of the mechanism's `dof`
// cranks, as excitation.csv of `fivebar excite`), t strictly increasing, up to `duration`
// seconds after its first row.
std::vector<sim::Row> motion_rows(const CsvTable& table, int dof, double duration) {
  const std::string& path = table.path;
  // a motion of the other mechanism: a four-bar's has theta3 and no theta4, a five-bar's theta2
  // without theta3 (excitation.csv) or theta4
  const bool four_bar_file = table.has("theta3") && !table.has("theta4");
  const bool five_bar_file = table.has("theta4") || (table.has("theta2") && !table.has("theta3"));
  if (dof == 2 && four_bar_file) {
    throw InputError(path, "column theta3",
                     "a four-bar's motion (theta3 without theta4); the scene is a five_bar");
  }
  if (dof == 1 && five_bar_file) {
    throw InputError(path, table.has("theta4") ? "column theta4" : "column theta2",
                     "a five-bar's motion; the scene is a four_bar (its motion: t,theta1,omega1,"
                     "alpha1)");
  }
  const std::vector<double> t = table.column("t");
  if (t.empty()) throw InputError(path, "(file)", "no data rows after the header");
  std::vector<sim::Row> rows(t.size());
  for (int j = 0; j < dof; ++j) {
    const std::string n = std::to_string(j + 1);
    const std::vector<double> th = table.column("theta" + n), w = table.column("omega" + n),
                              al = table.column("alpha" + n);
    for (size_t i = 0; i < t.size(); ++i) {
      rows[i].theta[j] = th[i];
      rows[i].omega[j] = w[i];
      rows[i].alpha[j] = al[i];
    }
  }
  for (size_t i = 0; i < t.size(); ++i) {
    if (i > 0 && !(t[i] > t[i - 1])) {
      throw InputError(path, "line " + std::to_string(table.lines[i]) + ", column t",
                       "t must increase strictly");
    }
    rows[i].t = t[i];
  }
  return first_seconds(path, std::move(rows), duration);
}

// the times of a motion's rows
std::vector<double> row_times(const std::vector<sim::Row>& rows) {
  std::vector<double> t;
  for (const sim::Row& r : rows) t.push_back(r.t);
  return t;
}

// The log of a position-controlled five-bar following MOTION.csv: inverse dynamics of the
// scene at every row, then the same noise as a simulated log.
identification::SynthResult motion_log(const Scene& scene, const LoadExpressions& expressions,
                                       const std::string& path, double duration,
                                       const identification::SynthOptions& so) {
  const CsvTable table = read_csv(path, "--motion");
  std::vector<sim::Row> rows = motion_rows(table, kDof, duration);
  expressions.require_finite(row_times(rows));
  const sim::LoadFunction loads = expressions.function();
  for (size_t i = 0; i < rows.size(); ++i) {
    sim::Row& r = rows[i];
    Evaluation<double> ev;
    const Status st = inverse_dynamics(scene.params, loads(r.t), r.theta[0], r.theta[1],
                                       r.omega[0], r.omega[1], r.alpha[0], r.alpha[1], nullptr,
                                       EvalOptions{}, &ev);
    if (!st.ok()) {
      throw NumericalError(path, "line " + std::to_string(table.lines[i]),
                           "inverse dynamics: " + st.message);
    }
    r.omega[2] = ev.bias.w3;
    r.omega[3] = ev.bias.w4;
    r.M1 = ev.M1;
    r.M2 = ev.M2;
  }
  identification::SynthResult out;
  identification::sample_log(scene.params, rows, so, &out);  // the sensors, as synthesize_log's
  return out;
}

// The same for a four-bar (columns t, theta1, omega1, alpha1): sim::inverse_rows of the crank.
identification::SynthResult four_bar_motion_log(const Scene& scene,
                                                const LoadExpressions& expressions,
                                                const std::string& path, double duration,
                                                const identification::SynthOptions& so) {
  const CsvTable table = read_csv(path, "--motion");
  const std::vector<sim::Row> motion = motion_rows(table, 1, duration);
  expressions.require_finite(row_times(motion));
  std::vector<sim::Row> rows;
  const Status st =
      sim::inverse_rows(scene.four_bar, expressions.four_bar_function(), motion, &rows);
  if (!st.ok()) throw NumericalError(path, "inverse dynamics", st.message);
  identification::SynthResult out;
  identification::sample_log(scene.four_bar, rows, so, &out);
  return out;
}

// header: provenance and the truth (fivebar/io/log_truth.h, which identify reads back)
std::vector<std::string> truth_header(const Args& a, const Scene& scene) {
  std::vector<std::string> out = {" fivebar synth-log: synthetic torque log (format: docs/formats.md)",
                                  " command: " + a.command_line, " scene: " + scene.path};
  const std::vector<std::string> truth = scene.type == MechanismType::kFourBar
                                             ? truth_lines(scene.four_bar)
                                             : truth_lines(scene.params);
  out.insert(out.end(), truth.begin(), truth.end());
  return out;
}

/// `s` as one POSIX shell word: as is when it is made of safe characters, else in single quotes
/// (load expressions such as `loads.M1=2 + t` hold spaces), so that the `# command:` line re-runs.
std::string shell_word(const std::string& s) {
  const bool safe = !s.empty() && s.find_first_not_of(
                                      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                      "0123456789_-+=.,/:@%") == std::string::npos;
  if (safe) return s;
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

/// The actuator options: one value per actuator each (a five-bar's tau1, tau2; a four-bar's tau1),
/// in the order of set_actuators' targets.
struct ActuatorOption {
  const char* flag;
  std::vector<double> Args::*values;
  const char* help;
};
const ActuatorOption kActuatorOptions[] = {
    {"--torque-offset", &Args::torque_offset,
     "torque-sensor offsets of tau1, tau2 [N m] (measured = motor + offset; a four_bar: tau1)"},
    {"--actuator-coulomb", &Args::actuator_coulomb,
     "load-independent Coulomb friction of the motors at O, D0 [N m] (a four_bar: at O)"},
    {"--actuator-viscous", &Args::actuator_viscous,
     "viscous friction of the motors at O, D0 [N m s/rad] (a four_bar: at O)"}};

// the scene's actuator terms (`motors` of them: the five-bar's two, the four-bar's one)
// overridden by the options given
void set_actuators(const Args& a, int motors, FrictionLaw law, ActuatorParams<double>* act) {
  std::array<double, kActuators>* dst[] = {&act->offset, &act->coulomb, &act->viscous};
  const std::string expected = motors == 1 ? "one value (tau1)" : "two values A,B (tau1, tau2)";
  for (int g = 0; g < 3; ++g) {
    const std::vector<double>& v = a.*kActuatorOptions[g].values;
    if (v.empty()) continue;
    if (v.size() != size_t(motors)) {
      throw InputError("command line", kActuatorOptions[g].flag,
                       "expected " + expected + ", got " + std::to_string(v.size()) +
                           (motors == 1 ? " (a four_bar scene has one motor, M1 at O)" : ""));
    }
    for (double x : v) {
      if (!std::isfinite(x)) {
        throw InputError("command line", kActuatorOptions[g].flag, "values must be finite numbers");
      }
      if (g > 0 && !(x >= 0)) {
        throw InputError("command line", kActuatorOptions[g].flag, "must be >= 0");
      }
    }
    for (int m = 0; m < motors; ++m) (*dst[g])[m] = v[m];
  }
  if (actuator_friction_active(*act) && !law_descriptor(law).coulomb_sign) {
    throw InputError("command line", "--actuator-coulomb/--actuator-viscous",
                     "actuator friction needs a friction law with a Coulomb sign");
  }
}

// the excitation of the log's header: scene, multisine (with the fit of its tones when they
// were scaled: excite.md, "The multi-sine baseline") or the motion followed
std::string excitation_text(const Args& a, const identification::SynthResult& res) {
  if (!a.motion.empty()) return "motion " + a.motion;
  std::string text = a.excitation;
  if (a.excitation == "multisine" && (res.multisine_factor != 1 || res.multisine_holding_bias)) {
    text += " (tones x " + format_double(res.multisine_factor) +
            (res.multisine_holding_bias ? ", biases: the start pose's holding torques" : "") +
            (std::isfinite(a.so.torque_limit)
                 ? ", torque limit " + format_double(a.so.torque_limit) + " N m"
                 : "") +
            ")";
  }
  return text;
}

// the options that do not depend on the scene
void check_options(const Args& a) {
  const std::string flag_file = "command line";
  if (!(a.so.rate_hz > 0)) throw InputError(flag_file, "--rate", "must be > 0");
  if (!(a.so.duration > 0)) throw InputError(flag_file, "--duration", "must be > 0");
  const std::string rows = log_rows_problem(a.so.duration, a.so.rate_hz);
  if (a.motion.empty() && !rows.empty()) {  // the same row limit as simulate's output rows
    throw InputError(flag_file, "--duration, --rate",
                     "duration " + format_double(a.so.duration) + " s at --rate " +
                         format_double(a.so.rate_hz) + " Hz " + rows);
  }
  // each noise level within the plausible magnitudes of its quantity (a scene key's, scene.h)
  const struct {
    const char* flag;
    double value;
    const char* key;
  } levels[] = {{"--torque-noise", a.so.torque_noise, "loads.M1"},
                {"--angle-noise", a.so.angle_noise, "loads.F_angle"},
                {"--rate-noise", a.so.rate_noise, "initial.omega1"},
                {"--quantization", a.so.quantization, "loads.F_angle"}};
  for (const auto& l : levels) {
    if (!(l.value >= 0))
      throw InputError(flag_file, l.flag, "must be >= 0, got " + format_double(l.value));
    const std::string implausible = limit_problem(l.key, l.value);
    if (!implausible.empty()) throw InputError(flag_file, l.flag, implausible);
  }
  if (!(a.so.torque_limit > 0)) {
    throw InputError(flag_file, "--torque-limit", "must be > 0 N m, got " + format_double(a.so.torque_limit));
  }
  if (std::isfinite(a.so.torque_limit) && a.excitation != "multisine") {
    throw InputError(flag_file, "--torque-limit", "applies to --excitation multisine only");
  }
  if (a.excitation != "scene" && a.excitation != "multisine") {
    throw InputError(flag_file, "--excitation", "expected scene or multisine, got " + a.excitation);
  }
  if (!a.motion.empty() && a.excitation != "scene") {
    throw InputError(flag_file, "--motion", "cannot be combined with --excitation " + a.excitation);
  }
  if (!a.motion.empty() && a.rate_option && a.rate_option->count()) {
    throw InputError(
        flag_file, "--rate",
        "the motion's own grid sets the sampling rate; resample " + a.motion + " to change it");
  }
}

// the friction law of the log: the scene's, or Stribeck with the coefficients given here
void set_law(const Args& a, FrictionParams<double>* fp) {
  if (a.law.empty()) return;
  FrictionLaw law;
  if (!identification::parse_law(a.law, &law)) {
    throw InputError("command line", "--law",
                     "expected " + identification::identifiable_law_names() + ", got " + a.law);
  }
  fp->law = law;
  if (law != FrictionLaw::kStribeck) return;
  const double kinetic = *std::max_element(fp->coulomb.begin(), fp->coulomb.end());
  if (a.static_coulomb < kinetic) {
    throw InputError("command line", "--static-coulomb",
                     format_double(a.static_coulomb) + " is below the scene's Coulomb "
                     "(kinetic) coefficient " + format_double(kinetic) +
                     ": static friction is at least the kinetic (identify fits it so)");
  }
  fp->static_coulomb.fill(a.static_coulomb);
  fp->stribeck_velocity.fill(a.stribeck_velocity);
  fp->stribeck_exponent.fill(a.stribeck_exponent);
}

// the four-bar's log: its scene's loads or a motion; the multisine, which only a five-bar has,
// refused
identification::SynthResult four_bar_log(const Args& a, const Scene& scene,
                                         const identification::SynthOptions& so) {
  if (a.excitation == "multisine") {
    throw InputError("command line", "--excitation",
                     "multisine drives the five-bar's two cranks; a four_bar scene's log follows "
                     "its loads.M1 (--excitation scene) or --motion");
  }
  const LoadExpressions expressions(scene);
  if (a.motion.empty()) {
    expressions.require_finite(so.duration, 1 / so.rate_hz);
    return identification::synthesize_log(scene.four_bar, expressions.four_bar_function(),
                                          scene.initial, so);
  }
  return four_bar_motion_log(scene, expressions, a.motion, a.motion_duration(), so);
}

int run(const Args& a) {
  // a refused or failed run leaves no previous log under that name
  const std::filesystem::path target(a.out);
  OutputDir::remove_previous(target.parent_path().string(), {target.filename().string()});
  check_options(a);
  Scene scene = load_scene(a.scene, a.sets, /*four_bar_ok=*/true);
  const bool four_bar = scene.type == MechanismType::kFourBar;
  set_law(a, four_bar ? &scene.four_bar.friction : &scene.params.friction);
  identification::SynthOptions so = a.so;
  so.multisine = a.excitation == "multisine";
  so.sim = scene.options;
  identification::SynthResult res;
  if (four_bar) {
    set_actuators(a, 1, scene.four_bar.friction.law, &scene.four_bar.actuators);
    res = four_bar_log(a, scene, so);
  } else {
    set_actuators(a, kActuators, scene.params.friction.law, &scene.params.actuators);
    const LoadExpressions expressions(scene);
    if (a.motion.empty()) {
      expressions.require_finite(so.duration, 1 / so.rate_hz);
      res = identification::synthesize_log(scene.params, expressions.function(), scene.initial, so);
    } else {
      res = motion_log(scene, expressions, a.motion, a.motion_duration(), so);
    }
  }
  if (!res.status.ok()) throw NumericalError(scene.path, "simulation", res.status.message);

  identification::TorqueLog& log = res.log;
  log.comments = truth_header(a, scene);
  const int joints = four_bar ? kFourBarJoints : kJoints;
  const std::string names = four_bar ? "O,B,C,D0" : "O,B,C,D,D0";
  std::ostringstream rev;
  for (int k = 0; k < joints; ++k) rev << (k ? "," : "") << res.reversals[k];
  log.comments.push_back(" noise: torque " + format_double(a.so.torque_noise) + " N m, angle " +
                         format_double(a.so.angle_noise) + " rad, rate " +
                         format_double(a.so.rate_noise) + " rad/s, quantization " +
                         format_double(a.so.quantization) + " rad, seed " + std::to_string(a.so.seed));
  log.comments.push_back(" excitation: " + excitation_text(a, res) + "; joint reversals (" +
                         names + "): " + rev.str());
  write_log(a.out, log);
  std::cout << "fivebar synth-log: " << log.size() << " samples over " << log.duration() << " s -> "
            << a.out << "\n  joint reversals (" << names << "): " << rev.str() << "; simulation "
            << res.stats.wall_time_s << " s, " << res.stats.friction_events << " friction events"
            << std::endl;
  return 0;
}

// the command that regenerates the log, every option applied explicit
std::string command_line(const Args& a) {
  std::string cmd = "fivebar synth-log " + shell_word(a.scene) + " --out " + shell_word(a.out);
  for (const std::string& s : a.sets) cmd += " --set " + shell_word(s);
  if (a.motion.empty()) {
    cmd +=
        " --rate " + format_double(a.so.rate_hz) + " --duration " + format_double(a.so.duration);
  } else if (std::isfinite(a.motion_duration())) {
    cmd += " --duration " + format_double(a.so.duration);
  }
  cmd += " --torque-noise " + format_double(a.so.torque_noise) + " --angle-noise " +
         format_double(a.so.angle_noise) + " --seed " + std::to_string(a.so.seed) +
         " --excitation " + a.excitation;
  if (!a.motion.empty()) cmd += " --motion " + shell_word(a.motion);
  if (a.so.rate_noise > 0) cmd += " --rate-noise " + format_double(a.so.rate_noise);
  if (a.so.quantization > 0) cmd += " --quantization " + format_double(a.so.quantization);
  if (a.so.with_rates) cmd += " --with-rates";
  if (std::isfinite(a.so.torque_limit)) cmd += " --torque-limit " + format_double(a.so.torque_limit);
  for (const ActuatorOption& o : kActuatorOptions) {  // as given (set_actuators checks the count)
    const std::vector<double>& v = a.*o.values;
    for (size_t i = 0; i < v.size(); ++i) {
      cmd += (i ? "," : " " + std::string(o.flag) + " ") + format_double(v[i]);
    }
  }
  if (!a.law.empty()) cmd += " --law " + a.law;
  if (a.law == "stribeck") {
    cmd += " --static-coulomb " + format_double(a.static_coulomb) + " --stribeck-velocity " +
           format_double(a.stribeck_velocity) + " --stribeck-exponent " +
           format_double(a.stribeck_exponent);
  }
  return cmd;
}

RunFunction setup(CLI::App* app) {
  auto args = std::make_shared<Args>();
  app->add_option("scene", args->scene, "scene file (YAML)")->type_name("SCENE")->required();
  app->add_option("--out", args->out, "the log to write (CSV)")->type_name("LOG.csv")->required();
  app->add_option("--set", args->sets, "override one scene value (KEY=VALUE)")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);
  app->option_defaults()->always_capture_default();  // the options below show their defaults
  args->rate_option =
      app->add_option("--rate", args->so.rate_hz, "sampling rate [Hz]")->check(positive_number());
  args->duration_option =
      app->add_option("--duration", args->so.duration, "[s]; with --motion, its first seconds")
          ->check(positive_number());
  app->add_option("--torque-noise", args->so.torque_noise, "Gaussian std on tau1, tau2 [N m]")
      ->check(nonnegative_number());
  app->add_option("--angle-noise", args->so.angle_noise, "Gaussian std on theta1, theta2 [rad]")
      ->check(within_a_turn());
  app->add_option("--rate-noise", args->so.rate_noise, "Gaussian std on omega1, omega2 [rad/s]")
      ->check(nonnegative_number());
  app->add_option("--seed", args->so.seed, "std::mt19937_64 seed")->check(nonnegative_number());
  app->add_option("--quantization", args->so.quantization, "encoder step [rad] (0: none)")
      ->check(within_a_turn());
  app->add_option(
      "--excitation", args->excitation,
      "scene: the scene's M1, M2; multisine: built-in excitation reversing every joint");
  app->add_option("--torque-limit", args->so.torque_limit,
                  "multisine: |M1|, |M2| at most this [N m] (the tones scaled down to it; "
                  "default: no limit)")
      ->default_str("");
  app->add_flag("--with-rates", args->so.with_rates, "write omega1,omega2,alpha1,alpha2 (exact)");
  app->add_option("--motion", args->motion,
                  "follow this motion (t,theta1,theta2,omega1,omega2,alpha1,alpha2; a "
                  "four-bar's t,theta1,omega1,alpha1; e.g. excitation.csv of excite): torques "
                  "by inverse dynamics; its grid sets the rate, --duration cuts it")
      ->type_name("MOTION.csv");
  for (const ActuatorOption& o : kActuatorOptions) {
    app->add_option(o.flag, (*args).*o.values, o.help)
        ->type_name("A,B")
        ->default_str("")  // not given: the scene's
        ->delimiter(',');
  }
  app->add_option("--law", args->law,
                  "friction law of the log, overriding the scene's: " +
                      identification::identifiable_law_names());
  app->add_option("--static-coulomb", args->static_coulomb, "stribeck: mu_s of every joint")
      ->check(nonnegative_number())
      ->check(within_scene_limit("friction.static_coulomb"));
  app->add_option("--stribeck-velocity", args->stribeck_velocity,
                  "stribeck: w_st of every joint [rad/s]")
      ->check(positive_number())
      ->check(within_scene_limit("friction.stribeck_velocity"));
  app->add_option("--stribeck-exponent", args->stribeck_exponent, "stribeck: delta")
      ->check(positive_number())
      ->check(within_scene_limit("friction.stribeck_exponent"));
  return [args] {
    args->command_line = command_line(*args);
    return run(*args);
  };
}

const bool kRegistered = register_command({"synth-log", kSummary, setup});

}  // namespace
}  // namespace fivebar::io::synth_log_command
