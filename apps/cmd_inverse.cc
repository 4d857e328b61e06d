// fivebar inverse SCENE --motion MOTION.csv [--out DIR] [--set KEY=VALUE]... [--no-plots]
// Inverse dynamics along a given motion of the driven cranks (the five-bar's two, the four-bar's
// one): the torques that produce it under the scene's other loads, with every joint reaction
// and friction torque.
#include <CLI/CLI.hpp>
#include <array>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>

#include "fivebar/identification/condition.h"
#include "fivebar/identification/degrees.h"
#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/differences.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::inverse_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "inverse dynamics along a given motion: driving torques, reactions, friction";

struct Args {
  SceneArgs scene;
  std::string motion;
  bool no_plots = false;
};

const std::vector<std::string> kOutputs = {
    "trajectory.csv", "summary.json",  "fig5_inverse_torques.png", "fig6_friction_torques.png",
    "plots.gnuplot",  "trajectory.bin"};

// minimum number of samples for the 5-point differences
constexpr size_t kMinSamplesForDifferences = 5;

// The motion of the driven cranks read from a CSV, with where each rate came from.
struct Motion {
  int cranks = 2;              // the five-bar's two, the four-bar's one
  std::vector<sim::Row> rows;  // t, theta, omega, alpha of the cranks filled
  std::string omega_source, alpha_source;
  bool has_torques = false;  // the file has the drive torques (e.g. a trajectory.csv of simulate)
  std::vector<double> M1, M2;
  // noise standard deviations of the rates and accelerations used (rest rule, docs/hold.md)
  double rate_noise = 0, acceleration_noise = 0;
  // the largest rest rate threshold the noise may give (rest_rate_cap)
  double rest_rate_cap = INFINITY;
  // the first pose that cannot close away from the singular poses (pose_fault): its line and
  // what is wrong with it, both empty when every pose closes
  std::string pose_key, pose_reason;
};

// largest |n-th forward difference| of a series (0 when it is too short)
double max_difference(std::vector<double> f, int n) {
  for (int k = 0; k < n && !f.empty(); ++k) {
    for (size_t i = 0; i + 1 < f.size(); ++i) f[i] = f[i + 1] - f[i];
    f.pop_back();
  }
  double worst = 0.0;
  for (double d : f) worst = std::max(worst, std::abs(d));
  return worst;
}

// the largest of the cranks' `noise` (series_noise, rounding_noise) or max_difference
template <typename F>
double largest(const std::vector<std::vector<double>>& series, const F& f) {
  double worst = 0.0;
  for (const std::vector<double>& s : series) worst = std::max(worst, f(s));
  return worst;
}
double crank_noise(const std::vector<std::vector<double>>& series) {
  return largest(series, [](const std::vector<double>& s) { return series_noise(s); });
}

// time must increase strictly from row to row
void check_times(const std::string& path, const CsvTable& table, const std::vector<double>& t) {
  if (t.empty()) throw InputError(path, "(file)", "no data rows after the header");
  for (size_t i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      throw InputError(path, "line " + std::to_string(table.lines[i]) + ", column t",
                       "t must increase strictly, got " + format_double(t[i]) + " after " +
                           format_double(t[i - 1]));
    }
  }
}

// why a pose of the scene's mechanism at the crank angles `theta` is refused ("" when it closes
// away from the singular poses)
std::string pose_problem(const Scene& scene, const std::vector<double>& theta) {
  const double sine = scene.type == MechanismType::kFourBar
                          ? four_bar_sine(scene.four_bar, theta[0])
                          : coupler_sine(scene.params, theta[0], theta[1]);
  if (sine >= scene.options.singular_margin) return "";
  return sine < 0 ? "the mechanism cannot assemble" : "too close to a singular configuration";
}

// the first pose that does not close away from the singular poses: its line and the problem
// into *key and *reason (left empty when every pose closes)
void pose_fault(const CsvTable& table, const Scene& scene,
                const std::vector<std::vector<double>>& theta, std::string* key,
                std::string* reason) {
  std::vector<double> pose(theta.size());
  for (size_t i = 0; i < theta[0].size(); ++i) {
    for (size_t j = 0; j < theta.size(); ++j) pose[j] = theta[j][i];
    const std::string problem = pose_problem(scene, pose);
    if (problem.empty()) continue;
    std::string at;
    for (size_t j = 0; j < theta.size(); ++j) {
      at += (j ? ", theta" : " at theta") + std::to_string(j + 1) + " = " + format_double(pose[j]);
    }
    *key = "line " + std::to_string(table.lines[i]);
    *reason = problem + at;
    return;
  }
}

// A four-bar has one crank: a motion file with a second crank's columns (theta2 without the
// four-bar trajectory's theta3, or any of theta4, omega2, alpha2, M2 with theta2 and no theta3)
// is a five-bar's. A trajectory.csv of a four-bar (theta2, theta3: coupler and rocker) is read
// by its crank's columns.
void check_four_bar_columns(const std::string& path, const CsvTable& table) {
  const bool trajectory = table.has("theta3") && !table.has("theta4");
  for (const char* column : {"theta2", "theta4", "omega2", "alpha2", "M2"}) {
    if (!table.has(column) || (trajectory && std::string(column) != "theta4" &&
                               std::string(column) != "M2")) {
      continue;
    }
    throw InputError(path, column,
                     "is a five-bar motion column (the second crank), not one of mechanism.type "
                     "four_bar: its motion files have t, theta1 and optionally omega1, alpha1");
  }
}

// the crank series of a motion file (one entry per crank): angles, and rates and accelerations
// from the file or by differences on the uniform step h (0 when every series comes from the file)
struct CrankSeries {
  std::vector<double> t;
  std::vector<std::vector<double>> theta, omega, alpha;
  bool has_omega = false, has_alpha = false;
  double h = 0;
};

// column `name` of crank j (0-based): theta1, omega2, ...
std::string crank_column(const char* name, size_t j) { return name + std::to_string(j + 1); }

// whether the table has column `name` of every crank
bool has_all(const CsvTable& table, const char* name, size_t cranks) {
  for (size_t j = 0; j < cranks; ++j) {
    if (!table.has(crank_column(name, j))) return false;
  }
  return true;
}

// rates from the file when it has every crank's column, else by differences on a uniform grid
void derive_rates(const std::string& path, const CsvTable& table, CrankSeries* c, Motion* m) {
  const size_t n = c->theta.size();
  c->has_omega = has_all(table, "omega", n);
  c->has_alpha = has_all(table, "alpha", n);
  if (!c->has_omega || !c->has_alpha) {
    if (c->t.size() < kMinSamplesForDifferences) {
      throw InputError(path, "(file)",
                       "at least 5 samples are needed to estimate the missing "
                       "omega/alpha columns by finite differences, got " +
                           std::to_string(c->t.size()));
    }
    c->h = uniform_step(c->t, table.lines, path);
  }
  c->omega.resize(n);
  c->alpha.resize(n);
  m->omega_source = c->has_omega ? "file" : "5-point central differences of theta";
  m->alpha_source = c->has_alpha   ? "file"
                    : c->has_omega ? "5-point central differences of omega"
                                   : "5-point central second differences of theta";
  for (size_t j = 0; j < n; ++j) {
    c->omega[j] = c->has_omega ? table.column(crank_column("omega", j))
                               : first_derivative(c->theta[j], c->h);
    c->alpha[j] = c->has_alpha   ? table.column(crank_column("alpha", j))
                  : c->has_omega ? first_derivative(c->omega[j], c->h)
                                 : second_derivative(c->theta[j], c->h);
  }
}

// noise of what the rest rule compares with its thresholds: measured from the series given,
// or propagated from the angles' (or rates') noise through the difference stencils
void estimate_noise(const CrankSeries& c, Motion* m) {
  const double theta_noise = crank_noise(c.theta);
  // given series: never below the rounding of the angles over one step
  double h = c.h;
  const size_t n = c.t.size();
  if (h == 0) h = n > 1 ? (c.t.back() - c.t.front()) / double(n - 1) : 1.0;
  const double rounding =
      largest(c.theta, [](const std::vector<double>& s) { return rounding_noise(s); });
  // differentiated angles: also never below the stencils' own truncation error where the
  // motion has a kink (h^4/30 |f^(5)| for the rate, h^4/90 |f^(6)| for the acceleration, from
  // the largest 5th and 6th differences): the row before a held pose starts to move would
  // otherwise read as slipping
  const double trunc_rate =
      largest(c.theta, [](const std::vector<double>& s) { return max_difference(s, 5); }) /
      (30 * h);
  const double trunc_accel =
      largest(c.theta, [](const std::vector<double>& s) { return max_difference(s, 6); }) /
      (90 * h * h);
  m->rate_noise = c.has_omega
                      ? std::max(crank_noise(c.omega), rounding / h)
                      : std::max(kFirstDerivativeNoiseGain * theta_noise / h, trunc_rate);
  if (c.has_alpha) {
    m->acceleration_noise = std::max(crank_noise(c.alpha), rounding / (h * h));
  } else if (c.has_omega) {
    m->acceleration_noise = kFirstDerivativeNoiseGain * m->rate_noise / h;
  } else {
    m->acceleration_noise =
        std::max(kSecondDerivativeNoiseGain * theta_noise / (h * h), trunc_accel);
  }
}

/// A rest rate threshold derived from the noise is capped at this share of the motion's largest
/// rate: a rule that holds rows moving faster than a tenth of the peak cannot tell rest from
/// motion. On the crank-rocker sampled at 20-33 Hz (rates 7-35 rad/s) the derived threshold was
/// 0.26-3 times the peak rate and held every row; at 50 Hz from angles, 0.22; from 100 Hz on,
/// and the five-bar at 25 Hz and finer, below 0.07 (not capped).
constexpr double kRestResolution = 0.1;
/// The rate threshold derived from the noise is at least this fraction of the largest rate: a
/// simulated run holds a stuck joint within its tolerance (2.6e-10 rad/s at the default rtol on a
/// Stribeck five-bar), above the rounding-level noise such a smooth file reads (a threshold of
/// 3.2e-11 read 478 held rows as slipping, their torques 0.29 N m off)
constexpr double kHeldRateFloor = 1e-8;

/// A crank's angles move when they span more than this many deviations of their noise: angles at
/// rest span about 9 over 1e5 samples of Gaussian noise (a noisy hold, whose largest rates are
/// its noise, is not capped)
constexpr double kMoveSigmas = 4 * kRestSigmas;

/// The cap on the rest rate threshold (kRestResolution of the largest rate of the cranks; infinite
/// when no crank's angles move beyond their noise). A motion sampled too coarsely for its
/// content (a turning crank at 20 Hz) has differences that do not fall with the order: its own
/// motion reads as noise, and the threshold derived from it grows past the rates it should tell
/// from rest.
double rest_rate_cap(const CrankSeries& c) {
  bool moves = false;
  double peak = 0;
  for (size_t j = 0; j < c.theta.size(); ++j) {
    const auto [lo, hi] = std::minmax_element(c.theta[j].begin(), c.theta[j].end());
    moves = moves || *hi - *lo > kMoveSigmas * series_noise(c.theta[j]);
    for (double w : c.omega[j]) peak = std::max(peak, std::abs(w));
  }
  return moves ? kRestResolution * peak : INFINITY;
}

Motion read_motion(const std::string& path, const Scene& scene) {
  const CsvTable table = read_csv(path, "--motion");
  const bool four_bar = scene.type == MechanismType::kFourBar;
  if (four_bar) check_four_bar_columns(path, table);
  CrankSeries c;
  c.t = table.column("t");
  check_times(path, table, c.t);
  const size_t cranks = four_bar ? 1 : 2;
  for (size_t j = 0; j < cranks; ++j) c.theta.push_back(table.column(crank_column("theta", j)));
  Motion m;
  pose_fault(table, scene, c.theta, &m.pose_key, &m.pose_reason);
  m.cranks = static_cast<int>(cranks);
  derive_rates(path, table, &c, &m);
  estimate_noise(c, &m);
  m.rest_rate_cap = rest_rate_cap(c);
  m.rows.resize(c.t.size());
  for (size_t i = 0; i < c.t.size(); ++i) {
    sim::Row& r = m.rows[i];
    r.t = c.t[i];
    for (size_t j = 0; j < cranks; ++j) {
      r.theta[j] = c.theta[j][i];
      r.omega[j] = c.omega[j][i];
      r.alpha[j] = c.alpha[j][i];
    }
  }
  m.has_torques = table.has("M1") && (four_bar || table.has("M2"));
  if (m.has_torques) {
    m.M1 = table.column("M1");
    m.M2 = four_bar ? std::vector<double>(c.t.size(), 0.0) : table.column("M2");
  }
  return m;
}

// max over the rows of |M - M_file|; where a joint is stuck (any torque within its holding range
// gives the motion) the distance of the file's torque to that range
double torque_error(const std::vector<sim::Row>& rows, const Motion& motion) {
  double worst = 0;
  for (size_t i = 0; motion.has_torques && i < rows.size(); ++i) {
    const sim::Row& r = rows[i];
    const auto& h = r.hold_range;
    worst = std::max({worst, std::max({0.0, h[0] - motion.M1[i], motion.M1[i] - h[1]}),
                      std::max({0.0, h[2] - motion.M2[i], motion.M2[i] - h[3]})});
  }
  return worst;
}

// the thresholds of the rest rule: the scene's, else kRestSigmas deviations of the noise (the
// rate's capped at rest_rate_cap; `capped`: the cap applied, and why)
struct RestRule {
  RestThresholds thresholds;
  std::string source, capped;
};

RestRule rest_rule(const Scene& scene, const Motion& motion) {
  RestRule r;
  RestThresholds derived = rest_thresholds(motion.rate_noise, motion.acceleration_noise);
  const bool rate_set = scene.rest_rate_threshold >= 0;
  const bool accel_set = scene.rest_acceleration_threshold >= 0;
  if (!rate_set && derived.rate > motion.rest_rate_cap) {
    const double peak = motion.rest_rate_cap / kRestResolution;
    const std::vector<sim::Row>& rows = motion.rows;  // the mean sample step, for the message
    const double step = (rows.back().t - rows.front().t) / double(rows.size() - 1);
    r.capped = "the rest threshold its noise gives, |w| <= " + format_significant(derived.rate, 3) +
               " rad/s, is " + format_significant(derived.rate / peak, 3) +
               " times its largest rate, " + format_significant(peak, 3) +
               " rad/s: sampled every " + format_significant(step, 3) +
               " s, its noise (or its own motion, too fast for the sampling, read as noise) "
               "cannot tell rest from motion; capped at " +
               format_significant(kRestResolution) + " of the largest rate, " +
               format_significant(motion.rest_rate_cap, 3) +
               " rad/s (sample finer, or set simulation.rest_rate_threshold)";
    derived.rate = motion.rest_rate_cap;
  }
  // (a file whose angles do not move has no cap, and no floor)
  const double floor = std::isfinite(motion.rest_rate_cap)
                           ? kHeldRateFloor * motion.rest_rate_cap / kRestResolution
                           : 0.0;
  const bool floored = !rate_set && derived.rate < floor;
  if (floored) derived.rate = floor;
  r.thresholds = scene.rest_thresholds(derived);
  const std::string noise = format_double(kRestSigmas) + " x the estimated noise";
  const std::string rate_derived =
      !r.capped.empty() ? "capped at " + format_double(kRestResolution) + " x the largest rate"
      : floored         ? "at least " + format_double(kHeldRateFloor) + " x the largest rate"
                        : noise;
  r.source = std::string("rate: ") + (rate_set ? "scene" : rate_derived) +
             "; acceleration: " + (accel_set ? "scene" : noise);
  return r;
}

// the rows at rest (every crank stuck) and what holds them
struct RestSummary {
  int cranks = 2;
  long rows_at_rest = 0, rows_with_stuck_joint = 0;
  std::vector<long> stuck_rows;  // per joint of the mechanism
  // reported holding torques over the rows at rest, and the intersection of their ranges
  double M1_lo = INFINITY, M1_hi = -INFINITY, M2_lo = INFINITY, M2_hi = -INFINITY;
  double range1_lo = -INFINITY, range1_hi = INFINITY, range2_lo = -INFINITY, range2_hi = INFINITY;
};

RestSummary summarize_rest(const std::vector<sim::Row>& rows, const TrajectoryLayout& layout) {
  RestSummary s;
  s.cranks = layout.drives;
  s.stuck_rows.assign(layout.joints, 0);
  for (const sim::Row& r : rows) {
    bool any = false;
    for (int k = 0; k < layout.joints; ++k) {
      const bool stuck = r.mode[k] == kStuck;
      s.stuck_rows[k] += stuck;
      any = any || stuck;
    }
    s.rows_with_stuck_joint += any;
    if (!r.at_rest(layout.drives)) continue;
    ++s.rows_at_rest;
    s.M1_lo = std::min(s.M1_lo, r.M1);
    s.M1_hi = std::max(s.M1_hi, r.M1);
    s.M2_lo = std::min(s.M2_lo, r.M2);
    s.M2_hi = std::max(s.M2_hi, r.M2);
    s.range1_lo = std::max(s.range1_lo, r.hold_range[0]);
    s.range1_hi = std::min(s.range1_hi, r.hold_range[1]);
    s.range2_lo = std::max(s.range2_lo, r.hold_range[2]);
    s.range2_hi = std::min(s.range2_hi, r.hold_range[3]);
  }
  return s;
}

Json pair(double a, double b) {
  Json j = Json::array();
  j.push(a);
  j.push(b);
  return j;
}

Json rest_json(const RestRule& rule, const Motion& motion, const RestSummary& s) {
  Json j = Json::object();
  j.set("rate_threshold", rule.thresholds.rate);
  j.set("acceleration_threshold", rule.thresholds.acceleration);
  j.set("threshold_source", rule.source);
  j.set("rate_noise", motion.rate_noise);
  j.set("acceleration_noise", motion.acceleration_noise);
  if (!rule.capped.empty()) j.set("rate_threshold_capped", rule.capped);
  j.set("rows_at_rest", s.rows_at_rest);
  j.set("rows_with_stuck_joint", s.rows_with_stuck_joint);
  Json per_joint = Json::array_of(s.stuck_rows);
  j.set("stuck_rows_per_joint", std::move(per_joint));
  if (s.rows_at_rest > 0) {
    j.set("holding_M1", pair(s.M1_lo, s.M1_hi));
    if (s.cranks > 1) j.set("holding_M2", pair(s.M2_lo, s.M2_hi));
    // a constant torque inside these holds every row at rest (empty when lo > hi)
    j.set("holding_range_M1", pair(s.range1_lo, s.range1_hi));
    if (s.cranks > 1) j.set("holding_range_M2", pair(s.range2_lo, s.range2_hi));
  }
  return j;
}

void print_rest(const RestRule& rule, const RestSummary& s) {
  char line[320];
  std::snprintf(line, sizeof line,
                "  at rest: |w| <= %.3g rad/s and |dw/dt| <= %.3g rad/s^2 (%s)\n",
                rule.thresholds.rate, rule.thresholds.acceleration, rule.source.c_str());
  std::cout << line;
  if (s.rows_at_rest == 0) return;
  if (s.cranks == 1) {
    std::snprintf(line, sizeof line, "  %ld rows held still: M1 in [%.10g, %.10g] N m (",
                  s.rows_at_rest, s.M1_lo, s.M1_hi);
    std::cout << line;
    if (s.range1_lo <= s.range1_hi) {
      std::snprintf(line, sizeof line, "a constant M1 in [%.6g, %.6g] holds them all)\n",
                    s.range1_lo, s.range1_hi);
      std::cout << line;
    } else {
      std::cout << "no constant M1 holds them all: their ranges do not overlap)\n";
    }
    return;
  }
  if (s.M1_hi - s.M1_lo > 1e-9 || s.M2_hi - s.M2_lo > 1e-9) {  // held at several poses
    std::snprintf(line, sizeof line,
                  "  %ld rows held still at several poses: M1 in [%.6g, %.6g], M2 in [%.6g, "
                  "%.6g] N m (each row's range in trajectory.csv)\n",
                  s.rows_at_rest, s.M1_lo, s.M1_hi, s.M2_lo, s.M2_hi);
    std::cout << line;
    return;
  }
  std::snprintf(line, sizeof line,
                "  %ld rows held still: M1 = %.10g N m (holds in [%.6g, %.6g]), "
                "M2 = %.10g N m (holds in [%.6g, %.6g])\n",
                s.rows_at_rest, s.M1_lo, s.range1_lo, s.range1_hi, s.M2_lo, s.range2_lo,
                s.range2_hi);
  std::cout << line;
}

/// A step of a crank angle between two rows that differs from its neighbouring steps by more
/// than this is a jump, not motion [rad] (a coarsely sampled smooth motion steps far, but evenly)
constexpr double kJumpAngle = 1.0;

/// What in a motion file makes its inverse dynamics meaningless, found before it is run
struct MotionFault {
  std::string key;     ///< the column(s); empty when nothing was found
  std::string reason;  ///< what was found and what to do
  bool refused = true;  ///< bad input (exit 2); false: a warning (the unit cannot be told)
};

/// Whether `motion`'s angles look like degrees, by the rules identify applies to logs. With
/// rates in the file: angles that agree with them in degrees (rates in rad/s) are degrees
/// (identification::rates_look_like_degrees). Rates that agree with the angles on every crank
/// (rates_say_radians) cannot tell radians from degrees with deg/s rates: a start beyond two
/// turns is then named as either (a radian motion cut late in a run, or degrees), a warning.
/// Without rates, by the start (start_looks_like_degrees: beyond two turns, within 360; a
/// motion in radians may start a turn out).
MotionFault motion_in_degrees(const Motion& motion) {
  const std::vector<sim::Row>& r = motion.rows;
  const std::string columns = motion.cranks > 1 ? "theta1, theta2" : "theta1";
  if (r.empty()) return {};
  const std::vector<double> starts(r[0].theta.begin(), r[0].theta.begin() + motion.cranks);
  const std::string start = start_looks_like_degrees(starts);
  if (motion.omega_source != "file") return {start.empty() ? "" : columns, start};
  bool radians = true;
  std::vector<double> t(r.size()), theta(r.size()), omega(r.size());
  for (int k = 0; k < motion.cranks; ++k) {
    for (size_t i = 0; i < r.size(); ++i) {
      t[i] = r[i].t;
      theta[i] = r[i].theta[k];
      omega[i] = r[i].omega[k];
    }
    const std::string why = identification::rates_look_like_degrees(t, theta, omega);
    if (!why.empty()) {
      return {columns, "angles look like degrees, expected radians (theta" +
                           std::to_string(k + 1) + ": " + why + ")"};
    }
    radians = radians && identification::rates_say_radians(t, theta, omega);
  }
  if (!radians || start.empty()) return {start.empty() ? "" : columns, start};
  std::string at;
  for (double a : starts) at += (at.empty() ? "" : ", ") + format_significant(a, 4);
  return {columns,
          "the angles start at " + at +
              ", beyond two turns, and the rates agree with them: radians a few turns out (rad/s "
              "rates), or degrees (deg/s rates); check the units",
          false};
}

/// The first jump of crank k: a step off its neighbouring steps by more than kJumpAngle (a gap,
/// a wrap, a glitch: the rates from differences explode)
MotionFault motion_jump(const std::vector<sim::Row>& r, int k) {
  const auto step = [&](size_t i) { return r[i].theta[k] - r[i - 1].theta[k]; };
  for (size_t i = 1; i < r.size(); ++i) {
    const double s = step(i);
    const bool off_before = i < 2 || std::abs(s - step(i - 1)) > kJumpAngle;
    const bool off_after = i + 1 >= r.size() || std::abs(s - step(i + 1)) > kJumpAngle;
    if (!(off_before && off_after && (i >= 2 || i + 1 < r.size()))) continue;
    return {"theta" + std::to_string(k + 1),
            "jumps by " + format_significant(s, 3) + " rad between t = " +
                format_double(r[i - 1].t) + " and " + format_double(r[i].t) +
                " s: the motion must be continuous (unwrap it, or fill the gap)"};
  }
  return {};
}

/// A sample of crank k off the cubic through its neighbours (identification::loo_deviation) by
/// more than kGlitchAngle and kGlitchSpread times the motion's own spread of such deviations: one
/// or two rows off the motion (a glitch), which a step check misses (it steps there and back).
/// A coarsely sampled smooth motion deviates everywhere alike, and is not one.
constexpr double kGlitchAngle = 0.1;    // [rad]
constexpr double kGlitchSpread = 50.0;  // robust std of the deviations
MotionFault motion_glitch(const std::vector<double>& t, const std::vector<double>& theta, int k) {
  if (t.size() < 8) return {};
  std::vector<double> expected;
  const std::vector<double> dev = identification::loo_deviation(t, theta, &expected);
  const double spread = identification::robust_std(dev);
  for (size_t i = 0; i < dev.size(); ++i) {
    if (!(std::abs(dev[i]) > std::max(kGlitchAngle, kGlitchSpread * spread))) continue;
    // the glitch moves its neighbours' deviations too: the row is the largest nearby
    for (size_t j = i + 1; j < std::min(dev.size(), i + 4); ++j) {
      if (std::abs(dev[j]) > std::abs(dev[i])) i = j;
    }
    return {"theta" + std::to_string(k + 1),
            "the row at t = " + format_double(t[i]) + " s is " +
                format_significant(theta[i] - expected[i], 3) +
                " rad off the motion through its neighbours (a glitch): the motion must be "
                "smooth; fix or remove the row"};
  }
  return {};
}

/// What in `motion` itself makes its inverse dynamics meaningless: angles that look like degrees
/// (motion_in_degrees; checked first: degrees also step by more than a radian), a jump between
/// two rows (motion_jump), a smaller step off the motion's trend (identify's step check of a
/// logged angle, identification::first_angle_step), or a glitch (motion_glitch). An empty key
/// when none is found.
MotionFault motion_fault(const Motion& motion) {
  const std::vector<sim::Row>& r = motion.rows;
  MotionFault degrees = motion_in_degrees(motion);
  if (!degrees.key.empty()) return degrees;
  for (int k = 0; k < motion.cranks; ++k) {
    MotionFault jump = motion_jump(r, k);
    if (!jump.key.empty()) return jump;
  }
  std::vector<double> t(r.size()), theta(r.size());
  for (size_t i = 0; i < r.size(); ++i) t[i] = r[i].t;
  for (int k = 0; k < motion.cranks; ++k) {
    for (size_t i = 0; i < r.size(); ++i) theta[i] = r[i].theta[k];
    double size = 0;
    const int i = identification::first_angle_step(t, theta, &size);
    if (i < 0) continue;
    return {"theta" + std::to_string(k + 1),
            "steps by " + format_significant(size, 3) + " rad off the motion's trend between t = " +
                format_double(r[i - 1].t) + " and " + format_double(r[i].t) +
                " s (a gap, a glitch or an encoder slip): the motion must be continuous; its rates "
                "and the rest thresholds read from them are meaningless"};
  }
  for (int k = 0; k < motion.cranks; ++k) {
    for (size_t i = 0; i < r.size(); ++i) theta[i] = r[i].theta[k];
    MotionFault glitch = motion_glitch(t, theta, k);
    if (!glitch.key.empty()) return glitch;
  }
  return {};
}

// max |M1|, max |M2| over the rows
std::array<double, 2> peak_torques(const std::vector<sim::Row>& rows) {
  std::array<double, 2> peak{};
  for (const sim::Row& r : rows) {
    peak[0] = std::max(peak[0], std::fabs(r.M1));
    peak[1] = std::max(peak[1], std::fabs(r.M2));
  }
  return peak;
}

// summary.json of a run, without its rest record and wall time
Json inverse_summary(const Args& args, const Scene& scene, const Motion& motion,
                     const std::vector<sim::Row>& rows, double max_error) {
  const bool four_bar = scene.type == MechanismType::kFourBar;
  const auto [max_m1, max_m2] = peak_torques(rows);
  Json summary = Json::object();
  summary.set("command", "inverse");
  summary.set("scene", scene.path);
  summary.set("mechanism", mechanism_type_name(scene.type));
  summary.set("motion", args.motion);
  Json sets = Json::array_of(args.scene.sets);
  summary.set("sets", std::move(sets));
  summary.set("samples", static_cast<long>(rows.size()));
  summary.set("t_start", rows.front().t);
  summary.set("t_end", rows.back().t);
  summary.set("omega_source", motion.omega_source);
  summary.set("alpha_source", motion.alpha_source);
  summary.set("rates_estimated", motion.omega_source != "file" || motion.alpha_source != "file");
  summary.set("friction_model", friction_law_name(friction_of(scene).law));
  summary.set("max_abs_M1", max_m1);
  if (!four_bar) summary.set("max_abs_M2", max_m2);
  summary.set("E_diss", rows.back().E_diss);
  if (motion.has_torques) summary.set("inverse_dynamics_max_abs_error", max_error);
  return summary;
}

/// The motion itself, refused before anything is run or written, whether the model would run on
/// it or not (its torques would be those of the numbers as written): its fault (a jump or degrees
/// first: they also make poses that cannot close, far from the jump), then a pose that cannot
/// close. A fault that is only suspected is warned of and returned.
MotionFault checked_motion(const std::string& path, const Motion& motion) {
  const MotionFault fault = motion_fault(motion);
  if (fault.refused && !fault.key.empty()) throw InputError(path, fault.key, fault.reason);
  if (!motion.pose_key.empty()) {
    throw InputError(
        path, motion.pose_key,
        motion.pose_reason + (fault.key.empty() ? "" : "; " + fault.key + ": " + fault.reason));
  }
  if (!fault.key.empty()) warn(path + ": " + fault.key + ": " + fault.reason);
  return fault;
}

int run(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  OutputDir::remove_previous(args.scene.out, kOutputs);  // a refused run leaves none of them
  const Scene scene = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  const bool four_bar = scene.type == MechanismType::kFourBar;
  const TrajectoryLayout layout = layout_of(scene);
  const Motion motion = read_motion(args.motion, scene);
  const MotionFault fault = checked_motion(args.motion, motion);
  OutputDir out(args.scene.out, kOutputs);

  const RestRule rest = rest_rule(scene, motion);
  if (!rest.capped.empty()) warn(args.motion + ": " + rest.capped);
  std::vector<sim::Row> rows;
  const LoadExpressions expressions(scene);
  const Status status =
      four_bar ? sim::inverse_rows(scene.four_bar, expressions.four_bar_function(), motion.rows,
                                   &rows, rest.thresholds)
               : sim::inverse_rows(scene.params, expressions.function(), motion.rows, &rows,
                                   rest.thresholds);
  if (!status.ok()) {
    // a motion whose units could not be told (the warning above) that the model fails on is
    // bad input: the units, not the friction loop, are the first cause to check
    if (!fault.key.empty()) {
      throw InputError(args.motion, fault.key,
                       fault.reason + "; the model failed on it: " + status.message);
    }
    throw NumericalError(args.motion, "inverse dynamics", status.message);
  }

  // the file's own torques, when it has them, beside the inverse-dynamics ones
  std::vector<Column> extra;
  const std::array<double, 2> peak = peak_torques(rows);
  const double max_m1 = peak[0], max_m2 = peak[1];
  const double max_error = torque_error(rows, motion);
  if (motion.has_torques) extra = {{"M1_input", motion.M1}};
  if (motion.has_torques && !four_bar) extra.push_back({"M2_input", motion.M2});
  for (Column& c : rest_columns(rows, layout)) extra.push_back(std::move(c));
  write_trajectory_csv(out.file("trajectory.csv"), rows, extra, layout);

  const RestSummary at_rest = summarize_rest(rows, layout);
  Json summary = inverse_summary(args, scene, motion, rows, max_error);
  summary.set("rest", rest_json(rest, motion, at_rest));

  if (!args.no_plots && !four_bar) {  // the figures draw the five-bar's columns
    const std::string warning =
        plot_inverse(out.staging(), "trajectory.csv", motion.has_torques,
                     std::filesystem::path(args.motion).filename().string());
    if (!warning.empty()) warn(warning);
  }
  summary.set("wall_time_s",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  write_json_file(out.file("summary.json"), summary);
  return finish_run(&out, [&] {
    char line[256];
    const std::string m2 = four_bar ? "" : ", max |M2| = " + format_printf(max_m2, "%.4g") + " N m";
    std::snprintf(line, sizeof line, "  %zu samples, t = %g .. %g s; max |M1| = %.4g N m%s, E_diss = %.6g J\n",
                  rows.size(), rows.front().t, rows.back().t, max_m1, m2.c_str(), rows.back().E_diss);
    std::cout << "fivebar inverse: " << args.motion << " under " << scene.path
              << (four_bar ? " (four-bar)" : "") << "\n" << line;
    if (motion.omega_source != "file" || motion.alpha_source != "file") {
      std::cout << "  rates estimated: omega from " << motion.omega_source << ", alpha from "
                << motion.alpha_source << "\n";
    }
    if (motion.has_torques) {
      std::snprintf(line, sizeof line,
                    "  max |M - M_file| = %.3e N m (stuck joints: distance to the holding range)\n",
                    max_error);
      std::cout << line;
    }
    print_rest(rest, at_rest);
    if (four_bar && !args.no_plots) std::cout << "  (four-bar: no figures yet)\n";
  });
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "inverse");
  add_plots_flag(app, &args->no_plots, "the figures");
  app->add_option("--motion", args->motion,
                  "CSV with t, theta1, theta2 and optionally omega1, omega2, alpha1, alpha2; "
                  "a four-bar's: t, theta1 and optionally omega1, alpha1 (a trajectory.csv of "
                  "simulate works)")
      ->type_name("MOTION.csv")
      ->required();
}

const bool kRegistered = register_command(command_of("inverse", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::inverse_command
