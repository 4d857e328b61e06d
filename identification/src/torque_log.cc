// Torque logs: plausibility checks (units, sample count, poses that assemble).
#include "fivebar/identification/torque_log.h"

#include <algorithm>
#include <cmath>

#include "fivebar/identification/degrees.h"
#include "fivebar/model/kinematics.h"

namespace fivebar::identification {

namespace {
/// The least-squares slope of the finite-difference rate of theta against the rate omega (NaN:
/// no motion)
double rate_slope(const std::vector<double>& t, const std::vector<double>& theta,
                  const std::vector<double>& omega) {
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i + 1 < theta.size() && i + 1 < t.size() && i + 1 < omega.size(); ++i) {
    const double d = (theta[i + 1] - theta[i]) / (t[i + 1] - t[i]);
    const double w = 0.5 * (omega[i] + omega[i + 1]);
    sxy += d * w;
    sxx += w * w;
  }
  return sxx > 0 ? sxy / sxx : NAN;
}
}  // namespace

std::vector<std::string> required_log_columns(int dof) {
  std::vector<std::string> out = {"t"};
  for (const char* name : {"theta", "tau"}) {
    for (int j = 1; j <= dof; ++j) out.push_back(name + std::to_string(j));
  }
  return out;
}

std::vector<std::string> optional_log_columns(int dof) {
  std::vector<std::string> out;
  for (const char* name : {"omega", "alpha"}) {
    for (int j = 1; j <= dof; ++j) out.push_back(name + std::to_string(j));
  }
  return out;
}

bool rates_say_radians(const std::vector<double>& t, const std::vector<double>& theta,
                       const std::vector<double>& omega) {
  return std::abs(rate_slope(t, theta, omega) - 1.0) < 0.2;
}

std::string rates_look_like_degrees(const std::vector<double>& t, const std::vector<double>& theta,
                                    const std::vector<double>& omega) {
  const double slope = rate_slope(t, theta, omega);
  if (std::abs(slope / (180.0 / M_PI) - 1.0) < 0.2) {
    return "d theta/dt is " + format_significant(slope, 6) + " times omega, close to 180/pi";
  }
  return "";
}

std::string looks_like_degrees(const TorqueLog& log, const std::vector<double>& theta,
                               const std::vector<double>* omega) {
  if (theta.size() < 2) return "";
  // without rates the magnitude says nothing (multi-turn angles are radians too): identify
  // decides from the motion and the scene (angle_units_from_motion, condition.h)
  return omega ? rates_look_like_degrees(log.t, theta, *omega) : "";
}

double median_of(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

double median_time_step(const TorqueLog& log) {
  if (log.t.size() < 2) return NAN;
  std::vector<double> steps(log.t.size() - 1);
  for (size_t i = 0; i + 1 < log.t.size(); ++i) steps[i] = log.t[i + 1] - log.t[i];
  return median_of(std::move(steps));
}

std::string rates_mismatch(const TorqueLog& log, const std::vector<double>& theta,
                           const std::vector<double>& omega) {
  const int n = static_cast<int>(theta.size());
  double peak = 0;
  for (double w : omega) peak = std::max(peak, std::abs(w));
  // the ratio of the finite-difference rate (one-turn jumps removed) to the logged rate, where
  // the crank moves: its median is 1 for rates in rad/s of the same crank and sign
  std::vector<double> ratio;
  for (int i = 0; i + 1 < n; ++i) {
    const double w = 0.5 * (omega[i] + omega[i + 1]);
    if (!(std::abs(w) > 0.1 * peak)) continue;
    const double d = std::remainder(theta[i + 1] - theta[i], 2 * M_PI) / (log.t[i + 1] - log.t[i]);
    ratio.push_back(d / w);
  }
  if (ratio.size() < 10) return "";
  const double median = median_of(ratio);
  if (std::abs(median - 1.0) <= 0.1) return "";
  return "d theta/dt is a median " + format_significant(median, 3) +
         " times the logged rate where the crank moves (expected 1)";
}

void require_samples(const TorqueLog& log, int needed, const std::string& what) {
  if (log.size() < needed) {
    throw LogError(log.path, "samples",
                   std::to_string(log.size()) + " samples, fewer than the " +
                       std::to_string(needed) + " needed (" + what + ")");
  }
}

void require_usable_samples(const TorqueLog& log, int used, int params, double min_rate) {
  if (used >= params + 1) return;
  const std::string count = "only " + std::to_string(used) +
                            " samples usable (rate threshold, glitches and filter edges), fewer " +
                            "than the " + std::to_string(params + 1) + " needed for " +
                            std::to_string(params) + " parameters";
  if (!(min_rate > 0)) throw LogError(log.path, "samples", count);
  throw LogError("command line", "--min-rate",
                 format_significant(min_rate, 6) + " rad/s leaves too few samples of " + log.path +
                     ": " + count + "; a lower --min-rate keeps more (0 keeps all)");
}

void require_uniform_sampling(const TorqueLog& log) {
  const int n = log.size();
  if (n < 3) return;
  const double median = median_time_step(log);
  int off = 0, first = -1;
  for (int i = 0; i + 1 < n; ++i) {
    if (std::abs(log.t[i + 1] - log.t[i] - median) <= kSamplingTolerance * median) continue;
    if (first < 0) first = i;
    ++off;
  }
  if (off == 0) return;
  const int line = log.lines.empty() ? first + 2 : log.lines[first + 1];
  throw LogError(log.path, "line " + std::to_string(line) + ", column t",
                 "sampling not uniform: " + std::to_string(off) + " of " +
                     std::to_string(n - 1) + " time steps differ from the median step " +
                     format_significant(median, 4) + " s by more than " +
                     format_significant(100 * kSamplingTolerance, 2) + " % (here " +
                     format_significant(log.t[first + 1] - log.t[first], 4) +
                     " s); the rate estimates and the rest rule need a uniform grid: resample "
                     "the log, or cut it at the gap");
}

void check_poses(const TorqueLog& log, const Params<double>& params) {
  Kinematics<double> k;
  for (int i = 0; i < log.size(); ++i) {
    const Status st = solve_kinematics(params, log.theta1[i], log.theta2[i], &k, 0.0);
    if (!st.ok()) {
      throw LogError(log.path, "line " + std::to_string(log.lines.empty() ? i + 1 : log.lines[i]),
                     "pose does not fit the scene: " + st.message);
    }
  }
}

}  // namespace fivebar::identification
