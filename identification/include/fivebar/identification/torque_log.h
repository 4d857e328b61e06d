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

/// Measured motion and actuator torques of the two cranks, one entry per sample.
/// Units: t [s], theta [rad], tau [N m], omega [rad/s], alpha [rad/s^2].
struct TorqueLog {
  std::string path;  ///< as given, for messages
  std::vector<double> t, theta1, theta2, tau1, tau2;
  std::vector<double> omega1, omega2, alpha1, alpha2;  ///< empty unless has_rates / has_accels
  bool has_rates = false;                              ///< omega1, omega2 came from the file
  bool has_accels = false;                             ///< alpha1, alpha2 came from the file
  std::vector<int> lines;                              ///< 1-based line of each sample in the file
  std::vector<std::string> comments;                   ///< `#` lines, without the leading '#'

  int size() const { return static_cast<int>(t.size()); }
  double duration() const { return t.empty() ? 0.0 : t.back() - t.front(); }
};

/// Required columns, then the optional ones (omega1,omega2 and alpha1,alpha2 come in pairs).
inline const char* const kLogRequired[] = {"t", "theta1", "theta2", "tau1", "tau2"};
inline const char* const kLogOptional[] = {"omega1", "omega2", "alpha1", "alpha2"};

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

/// Throws LogError(`<file>: line N: pose theta1=..., theta2=... cannot assemble ...`) at the first
/// sample whose pose cannot close with the mechanism of `params`.
void check_poses(const TorqueLog& log, const Params<double>& params);

}  // namespace fivebar::identification
