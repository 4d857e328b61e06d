// Log conditioning: unwrapping, noise levels, the glitch passes in order (glitch_repair.cc,
// glitch_checks.cc), degrees from the motion.
#include "fivebar/identification/condition.h"
#include "glitches.h"
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include "fivebar/identification/rates.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"

namespace fivebar::identification {

using namespace glitches;

namespace {

/// Readings of logged angles other than radians that the motion can reveal, with their factor
/// to radians: degrees, turns, gradians, the counts of common encoder resolutions, and radians
/// with the two angle columns swapped.
struct AngleUnit {
  const char* name;
  double to_rad;
  bool swapped = false;
};

constexpr AngleUnit kAngleUnits[] = {
    {kSwappedAngles, 1.0, true},
    {"degrees", M_PI / 180},
    {"turns", 2 * M_PI},
    {"gradians", M_PI / 200},
    {"encoder counts (1000 per turn)", 2 * M_PI / 1000},
    {"encoder counts (1024 per turn)", 2 * M_PI / 1024},
    {"encoder counts (2000 per turn)", 2 * M_PI / 2000},
    {"encoder counts (2048 per turn)", 2 * M_PI / 2048},
    {"encoder counts (4000 per turn)", 2 * M_PI / 4000},
    {"encoder counts (4096 per turn)", 2 * M_PI / 4096},
    {"encoder counts (8192 per turn)", 2 * M_PI / 8192},
    {"encoder counts (10000 per turn)", 2 * M_PI / 10000},
    {"encoder counts (16384 per turn)", 2 * M_PI / 16384},
    {"encoder counts (65536 per turn)", 2 * M_PI / 65536},
};
}  // namespace

double robust_std(std::vector<double> v) { return 1.4826 * median_abs(std::move(v)); }

int unwrap_angles(std::vector<double>* theta) {
  std::vector<double>& th = *theta;
  const int n = static_cast<int>(th.size());
  int count = 0;
  double offset = 0, prev_raw = n ? th[0] : 0, prev_step = 0;
  for (int i = 1; i < n; ++i) {
    const double raw = th[i];
    const double step = raw - prev_raw;
    prev_raw = raw;
    // a wrap: this step is the previous one plus or minus one turn (within a quarter turn)
    double turns = 0;
    for (double k : {-1.0, 1.0}) {
      if (std::abs(step - prev_step - 2 * M_PI * k) < M_PI / 2) turns = k;
    }
    if (turns != 0) {
      offset -= 2 * M_PI * turns;
      ++count;
    }
    const double unwrapped_step = step - 2 * M_PI * turns;
    // the predictor follows the motion, not absurd steps (those are glitches, handled later)
    prev_step = std::abs(unwrapped_step) < M_PI / 2 ? unwrapped_step : prev_step;
    th[i] = raw + offset;
  }
  return count;
}

std::vector<double> loo_deviation(const std::vector<double>& t, const std::vector<double>& x,
                                  std::vector<double>* expected) {
  const int n = static_cast<int>(x.size());
  std::vector<double> z(n, 0.0);
  if (expected) *expected = x;
  if (n < 5) return z;
  for (int i = 0; i < n; ++i) {
    const std::array<int, 4> nb = neighbours(i, n);
    // Lagrange weights of the cubic through the four neighbours, evaluated at t_i
    double w[4], gain2 = 1, pred = 0;
    for (int a = 0; a < 4; ++a) {
      w[a] = 1;
      for (int b = 0; b < 4; ++b) {
        if (b != a) w[a] *= (t[i] - t[nb[b]]) / (t[nb[a]] - t[nb[b]]);
      }
      gain2 += w[a] * w[a];
      pred += w[a] * x[nb[a]];
    }
    const double e = (x[i] - pred) / std::sqrt(gain2);
    z[i] = std::isfinite(e) ? e : kInf;
    if (expected) (*expected)[i] = std::isfinite(pred) ? pred : x[i];
  }
  return z;
}

namespace {

/// One column of the log that is checked for glitches, with where its noise estimate goes.
struct NoisyColumn {
  const char* name;
  std::vector<double>* x;
  double* noise;
};

/// The columns checked for glitches: angles and torques, and the logged rates and
/// accelerations when the log has them.
std::vector<NoisyColumn> noisy_columns(ConditionedLog* out) {
  TorqueLog& L = out->log;
  if (L.dof == 1) {  // the four-bar's one crank
    std::vector<NoisyColumn> cols = {{"theta1", &L.theta1, &out->angle_noise[0]},
                                     {"tau1", &L.tau1, &out->torque_noise[0]}};
    if (L.has_rates) cols.push_back({"omega1", &L.omega1, &out->rate_noise[0]});
    if (L.has_accels) cols.push_back({"alpha1", &L.alpha1, &out->accel_noise[0]});
    return cols;
  }
  std::vector<NoisyColumn> cols = {{"theta1", &L.theta1, &out->angle_noise[0]},
                                   {"theta2", &L.theta2, &out->angle_noise[1]},
                                   {"tau1", &L.tau1, &out->torque_noise[0]},
                                   {"tau2", &L.tau2, &out->torque_noise[1]}};
  if (L.has_rates) {
    cols.push_back({"omega1", &L.omega1, &out->rate_noise[0]});
    cols.push_back({"omega2", &L.omega2, &out->rate_noise[1]});
  }
  if (L.has_accels) {  // one alpha spike left in could put Coulomb at its bound 0
    cols.push_back({"alpha1", &L.alpha1, &out->accel_noise[0]});
    cols.push_back({"alpha2", &L.alpha2, &out->accel_noise[1]});
  }
  return cols;
}

/// The glitches of one column (absurd values, frozen angles, spikes), repaired in place; a step
/// in an angle is refused. Sets the column's noise estimate.
std::vector<Glitch> column_glitches(const TorqueLog& L, const NoisyColumn& c,
                                    const ConditionOptions& opt) {
  std::vector<Glitch> g = reject_absurd(L, c.name, c.x);
  if (c.name[0] == 't' && c.name[1] == 'h') {
    std::vector<Glitch> frozen = reject_frozen(L, c.name, c.x);
    g.insert(g.end(), frozen.begin(), frozen.end());
    // before the spikes: a step's two sides would read as a bad pair there
    std::vector<Glitch> runs = runs_or_steps(L, c.name, c.x, opt.glitch_sigmas);
    g.insert(g.end(), runs.begin(), runs.end());
  }
  // logged accelerations are often exact or nearly (computed, not measured): their real fast
  // changes (a Stribeck peak crossed in a few samples) would read as glitches, so a glitch must
  // also leave the cubic by a quarter of the column's interquartile range
  double floor = 0;
  if (c.name[0] == 'a') {
    std::vector<double> v = *c.x;
    std::sort(v.begin(), v.end());
    floor = v.empty() ? 0.0 : 0.25 * (v[(3 * v.size()) / 4] - v[v.size() / 4]);
  }
  std::vector<Glitch> spikes = reject_column(L, c.name, opt.glitch_sigmas, c.x, c.noise, floor);
  g.insert(g.end(), spikes.begin(), spikes.end());
  return g;
}

bool by_line(const Glitch& a, const Glitch& b) { return a.line < b.line; }

/// The note that lists the rejected glitches (the first five).
std::string glitch_note(const std::vector<Glitch>& glitches) {
  std::string what;
  for (size_t i = 0; i < glitches.size() && i < 5; ++i) {
    const Glitch& g = glitches[i];
    what += std::string(i ? "; " : "") + "line " + std::to_string(g.line) + " " + g.column +
            " = " + format_significant(g.value, 6) + " where its neighbours give " +
            format_significant(g.expected, 6) + " (" + format_significant(g.sigmas, 2) +
            " noise std)";
  }
  if (glitches.size() > 5) what += "; ...";
  return "rejected " + std::to_string(glitches.size()) +
         " isolated glitch(es), left out of the fit and interpolated for the rates: " + what;
}
}  // namespace

ConditionedLog condition_log(const TorqueLog& log, const ConditionOptions& opt) {
  ConditionedLog out;
  out.log = log;
  TorqueLog& L = out.log;
  const int n = L.size();
  out.rejected.assign(n, 0);
  for (int i : opt.rejected_before) {
    if (i >= 0 && i < n) out.rejected[i] = 1;
  }
  if (opt.unwrap) {
    out.unwrapped[0] = unwrap_angles(&L.theta1);
    if (L.dof == 1 && out.unwrapped[0] > 0) {
      out.notes.push_back("unwrapped " + std::to_string(out.unwrapped[0]) +
                          " one-turn (2 pi) jumps of theta1 (angles wrapped by the encoder or "
                          "logger)");
    }
    if (L.dof == 2) out.unwrapped[1] = unwrap_angles(&L.theta2);
    if (L.dof == 2 && out.unwrapped[0] + out.unwrapped[1] > 0) {
      out.notes.push_back("unwrapped " + std::to_string(out.unwrapped[0]) + " + " +
                          std::to_string(out.unwrapped[1]) +
                          " one-turn (2 pi) jumps of theta1, theta2 (angles wrapped by the "
                          "encoder or logger)");
    }
  }
  const int allowed = std::max(2, static_cast<int>(opt.max_glitch_fraction * n));
  for (const NoisyColumn& c : noisy_columns(&out)) {
    std::vector<Glitch> g;
    if (opt.reject_glitches) {
      g = column_glitches(L, c, opt);
    } else {
      *c.noise = noise_std(loo_deviation(L.t, *c.x));
    }
    if (static_cast<int>(g.size()) > allowed) {
      std::sort(g.begin(), g.end(), by_line);
      throw LogError(L.path, std::string("column ") + c.name,
                     std::to_string(g.size()) + " samples leave their neighbours' trend (lines " +
                         line_list(g) + "): more than the " + std::to_string(allowed) +
                         " isolated glitches that are rejected; the column is not a smooth "
                         "measurement");
    }
    for (Glitch& x : g) {
      out.rejected[x.index] = 1;
      if (c.x == &L.theta1 || c.x == &L.theta2) {
        // quoted as in the file: the turn the unwrapping added is taken off both values
        const double in_file = (c.x == &L.theta1 ? log.theta1 : log.theta2)[x.index];
        x.expected += in_file - x.value;
        x.value = in_file;
      }
    }
    out.glitches.insert(out.glitches.end(), g.begin(), g.end());
  }
  for (int j = 0; j < L.dof; ++j) {
    if (opt.torque_noise[j] > 0) out.torque_noise[j] = opt.torque_noise[j];
  }
  out.torque_variance_factor = opt.torque_variance_factor;
  if (!out.glitches.empty()) {
    std::sort(out.glitches.begin(), out.glitches.end(), by_line);
    out.notes.push_back(glitch_note(out.glitches));
  }
  return out;
}

namespace {

/// Whether two readings scale the angles nearly alike (within 25 %: degrees and gradians, the
/// counts of neighbouring resolutions), so that one motion can hardly tell them apart.
bool same_scale(const AngleUnit& a, const AngleUnit& b) {
  const double ratio = a.to_rad / b.to_rad;
  return a.swapped == b.swapped && ratio > 0.8 && ratio < 1.25;
}

}  // namespace

std::string angle_units_from_motion(const Params<double>& scene, const sim::LoadFunction& loads,
                                    const TorqueLog& log, std::string* unit) {
  return angle_units_from_motion(
      log,
      [&](const std::vector<double>& a1, const std::vector<double>& a2, double* rate) {
        return torque_mismatch(scene, loads, log, a1, a2, rate);
      },
      unit);
}

std::string angle_units_from_motion(const TorqueLog& log, const TorqueMismatch& mismatch,
                                    std::string* unit) {
  // too little motion says nothing about the units (25-30 samples of a radian log, 1.5
  // Savitzky-Golay windows, can read as "encoder counts"): at least four windows and 40 samples
  const int n = log.size();
  const int window = 2 * sg_half_window(SgOptions{}, log.duration() / std::max(1, n - 1)) + 1;
  if (n < std::max(40, 4 * window)) return "";
  std::vector<double> r1 = log.theta1, r2 = log.theta2;
  unwrap_angles(&r1);
  unwrap_angles(&r2);
  double rate_rad = 0;
  const double as_rad = mismatch(r1, r2, &rate_rad);
  // every reading's mismatch, the best first
  struct Reading {
    const AngleUnit* unit;
    double mismatch, rate;
  };
  std::vector<Reading> readings;
  for (const AngleUnit& u : kAngleUnits) {
    if (u.swapped && log.dof == 1) continue;
    std::vector<double> a1 = u.swapped ? log.theta2 : log.theta1;
    std::vector<double> a2 = u.swapped ? log.theta1 : log.theta2;
    for (std::vector<double>* v : {&a1, &a2}) {
      for (double& x : *v) x *= u.to_rad;
    }
    unwrap_angles(&a1);
    unwrap_angles(&a2);
    Reading r{&u, kInf, 0.0};
    const double m = mismatch(a1, a2, &r.rate);
    if (m < kInf) r.mismatch = m;  // NaN (a pose that does not assemble) sorts last
    readings.push_back(r);
  }
  std::stable_sort(readings.begin(), readings.end(),
                   [](const Reading& a, const Reading& b) { return a.mismatch < b.mismatch; });
  const Reading& best = readings.front();
  // another unit only when that reading explains the torques several times better than
  // radians, and well in absolute terms (within half the logged torques' median size): a log
  // that no reading explains (wrong scene, absurd values) is not called another unit
  std::vector<double> tau;
  for (int i = 0; i < n; ++i) {
    tau.push_back(std::max(std::abs(log.tau1[i]), log.dof == 2 ? std::abs(log.tau2[i]) : 0.0));
  }
  if (!(best.mismatch < 0.5 * median_abs(tau))) return "";
  double rival = as_rad;
  if (!std::isfinite(as_rad)) {
    // motion the scene cannot assemble as radians (a four-bar's swing, counts far out): the
    // rival is the best reading of a clearly different scale, since a wrong scene (a coupler too
    // short) can leave every small swing (degrees, counts) assembled and near-static alike
    rival = kInf;
    for (const Reading& r : readings) {
      if (!same_scale(*r.unit, *best.unit)) rival = std::min(rival, r.mismatch);
    }
  }
  if (!(best.mismatch < 0.25 * rival)) return "";
  // readings of a nearly equal scale that explain the torques about as well are named too (the
  // motion can hardly tell 4000 from 4096 counts per turn)
  std::string best_unit = best.unit->name;
  for (size_t k = 1; k < readings.size(); ++k) {
    if (same_scale(*readings[k].unit, *best.unit) && readings[k].mismatch <= 1.25 * best.mismatch) {
      best_unit += std::string(" or ") + readings[k].unit->name;
    }
  }
  *unit = best_unit;
  const std::string as_radians =
      std::isfinite(as_rad)
          ? "read as radians, the motion (median crank rate " + format_significant(rate_rad, 3) +
                " rad/s) needs torques a median " + format_significant(as_rad, 3) +
                " N m away from the logged ones"
          : std::string("read as radians, the scene cannot assemble the motion");
  return as_radians + "; read as " + best_unit + " (median rate " +
         format_significant(best.rate, 3) + " rad/s), " + format_significant(best.mismatch, 3) +
         " N m";
}

}  // namespace fivebar::identification
