// Torque logs (interfaces.md, "Torque log CSV"): reading, validation, writing.
#pragma once

#include <functional>
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

/// A numeric table parsed from CSV text: `#` comment lines, blank lines, one header row, then
/// rows of finite numbers. The one CSV parser of the toolkit: torque logs here, motion files and
/// reference trajectories in the apps (io::read_csv).
struct CsvTable {
  std::string path;                       ///< as given, for messages
  std::vector<std::string> columns;       ///< header names, blanks trimmed
  std::vector<std::vector<double>> rows;  ///< rows[i][j]: row i, column j
  std::vector<int> lines;                 ///< 1-based line number in the text of each row
  std::vector<std::string> comments;      ///< `#` lines, trimmed, without the leading '#'
  int header_line = 0;                    ///< line of the header; 0 when the text has none

  /// Index of column `name`, or -1.
  int find(const std::string& name) const;
  bool has(const std::string& name) const { return find(name) >= 0; }
};

/// What a format requires of a CSV beyond the parser's own checks, and how it words a bad field.
/// Every hook is optional and may throw its own error.
struct CsvRules {
  /// Checks the header names (on line `line`) before any row is read.
  std::function<void(const std::vector<std::string>& names, int line)> header;
  /// The reason for a field that is not a finite number (`number`: it reads as a number, just
  /// not a finite one); default "'<field>' is not a finite number".
  std::function<std::string(const std::string& field, bool number)> bad_number;
  /// Checks the table each time a row has been added (e.g. time increasing).
  std::function<void(const CsvTable& table)> row;
};

/// Parses CSV text (`path` only names it in messages). Throws LogError(`<path>: line N: expected
/// K fields, got M`) for a row of the wrong length and LogError(`<path>: line N, column NAME:
/// <bad_number>`) for a field that is not a finite number (strtod syntax), besides whatever the
/// rules' hooks throw. Text without a header row gives a table with header_line = 0.
CsvTable parse_csv(const std::string& text, const std::string& path, const CsvRules& rules = {});

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

/// Reads a torque log. Throws LogError naming file, line and/or column and reason for: a missing
/// or empty file, a missing, unknown or duplicate column, an unpaired omega/alpha column, a row
/// with the wrong number of fields, a field that is not a finite number (NaN, inf, text), time
/// not strictly increasing, and angles that look like degrees (see looks_like_degrees).
TorqueLog read_torque_log(const std::string& path);

/// Parses a log from text (`path` only names it in messages). Same checks as read_torque_log.
TorqueLog parse_torque_log(const std::string& text, const std::string& path);

/// Empty if the angles of `log` look like radians, else the reason they look like degrees. Only
/// with rates in the log: the finite-difference rate of theta is ~180/pi times omega
/// (least-squares slope within 20 % of 57.3). Without rates the magnitude is no evidence (a crank
/// that turns continuously gives multi-turn angles; a log cut mid-run starts past 4 pi):
/// identify tells degrees from the motion against the scene (degrees_from_motion, condition.h).
std::string looks_like_degrees(const TorqueLog& log, const std::vector<double>& theta,
                               const std::vector<double>* omega);

/// Throws LogError(`<file>: samples: ...`) when the log has fewer samples than `needed`
/// (e.g. the number of parameters, or of residuals needed to estimate them).
void require_samples(const TorqueLog& log, int needed, const std::string& what);

/// Throws LogError(`<file>: line N: pose theta1=..., theta2=... cannot assemble ...`) at the first
/// sample whose pose cannot close with the mechanism of `params`.
void check_poses(const TorqueLog& log, const Params<double>& params);

/// Writes a log: `#` + each comment line, the header (rates and accelerations when has_rates /
/// has_accels), then one row per sample in shortest round-trip form. Throws LogError on failure.
void write_torque_log(const std::string& path, const TorqueLog& log);

/// Shortest text that reads back as exactly x (fivebar/model/format.h).
using fivebar::format_number;

}  // namespace fivebar::identification
