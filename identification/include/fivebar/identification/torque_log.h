// Torque logs (interfaces.md, "Torque log CSV") as data, and their checks. Reading and writing
// the files is the apps' (fivebar/io/torque_log_file.h).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "fivebar/model/format.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"

namespace fivebar::identification {

/// A log that cannot be used: what() is `<file>: <key>: <reason>` (the key is `line N`,
/// `line N, column NAME`, `header` or `column NAME`).
class LogError : public FieldError {
 public:
  using FieldError::FieldError;
};

/// Measured motion and actuator torques of the driven cranks, one entry per sample: the
/// five-bar's two (dof 2), the four-bar's one (dof 1: theta2, tau2, omega2, alpha2 stay empty).
/// Units: t [s], theta [rad], tau [N m], omega [rad/s], alpha [rad/s^2].
struct TorqueLog {
  std::string path;  ///< as given, for messages
  int dof = 2;       ///< driven cranks: the columns theta1..theta<dof>, tau1..tau<dof>
  std::vector<double> t, theta1, theta2, tau1, tau2;
  std::vector<double> omega1, omega2, alpha1, alpha2;  ///< empty unless has_rates / has_accels
  bool has_rates = false;                              ///< omega1, omega2 came from the file
  bool has_accels = false;                             ///< alpha1, alpha2 came from the file
  std::vector<int> lines;                              ///< 1-based line of each sample in the file
  std::vector<std::string> comments;                   ///< `#` lines, without the leading '#'

  int size() const { return static_cast<int>(t.size()); }
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front(); }
  /// crank j's column (0-based) of the angles, torques, rates and accelerations
  const std::vector<double>& theta(int j) const { return j == 0 ? theta1 : theta2; }
  const std::vector<double>& tau(int j) const { return j == 0 ? tau1 : tau2; }
  const std::vector<double>& omega(int j) const { return j == 0 ? omega1 : omega2; }
  const std::vector<double>& alpha(int j) const { return j == 0 ? alpha1 : alpha2; }
  std::vector<double>& theta(int j) { return j == 0 ? theta1 : theta2; }
  std::vector<double>& tau(int j) { return j == 0 ? tau1 : tau2; }
  std::vector<double>& omega(int j) { return j == 0 ? omega1 : omega2; }
  std::vector<double>& alpha(int j) { return j == 0 ? alpha1 : alpha2; }
};

/// The columns a log of `dof` cranks must have: t, theta1..theta<dof>, tau1..tau<dof>.
std::vector<std::string> required_log_columns(int dof);
/// Its optional columns: omega1..omega<dof> (all or none), alpha1..alpha<dof> (all or none).
std::vector<std::string> optional_log_columns(int dof);

/// Empty if the angles of `log` look like radians, else the reason they look like degrees. Only
/// with rates in the log: the finite-difference rate of theta is ~180/pi times omega
/// (least-squares slope within 20 % of 57.3). Without rates the magnitude is no evidence (a crank
/// that turns continuously gives multi-turn angles; a log cut mid-run starts past 4 pi):
/// identify tells degrees from the motion against the scene (angle_units_from_motion, condition.h).
std::string looks_like_degrees(const TorqueLog& log, const std::vector<double>& theta,
                               const std::vector<double>* omega);

/// Empty if the logged rates `omega` agree with the angles `theta`, else why not: the median
/// ratio of the finite-difference rate (one-turn jumps removed) to omega, over the samples where
/// |omega| exceeds a tenth of its peak, is more than 10 % from 1 (rates in other units, of the
/// opposite sign, or of the other crank).
std::string rates_mismatch(const TorqueLog& log, const std::vector<double>& theta,
                           const std::vector<double>& omega);

/// The median of v (the upper one for an even count); v non-empty.
double median_of(std::vector<double> v);

/// The median time step of the log [s] (the upper one for an even count); NaN below 2 samples.
double median_time_step(const TorqueLog& log);

/// Largest relative departure of a time step from the median step that identify accepts.
inline constexpr double kSamplingTolerance = 0.25;

/// Throws LogError(`<file>: line N, column t: sampling not uniform ...`) when a time step of the
/// log differs from the median step by more than kSamplingTolerance of it (a gap, dropped rows,
/// alternating steps, strong jitter): the Savitzky-Golay rates and the rest rule's noise estimate
/// assume a uniform grid.
void require_uniform_sampling(const TorqueLog& log);

/// Throws LogError(`<file>: samples: ...`) when the log has fewer samples than `needed`
/// (e.g. the number of parameters, or of residuals needed to estimate them).
void require_samples(const TorqueLog& log, int needed, const std::string& what);

/// Throws LogError when the samples a fit may use (after the rate threshold, the glitches and
/// the filter's edges) are fewer than `params` + 1: keyed `samples`, or `--min-rate` (file
/// "command line") when `min_rate` > 0 takes part, since a lower one keeps more.
void require_usable_samples(const TorqueLog& log, int used, int params, double min_rate);

/// Throws LogError(`<file>: line N: pose theta1=..., theta2=... cannot assemble ...`) at the first
/// sample whose pose cannot close with the mechanism of `params`.
void check_poses(const TorqueLog& log, const Params<double>& params);

}  // namespace fivebar::identification
