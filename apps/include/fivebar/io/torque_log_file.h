// Torque log files (interfaces.md, "Torque log CSV"): reading with every check a user's file
// needs, and writing. The log itself, and the checks that need the model, are
// identification's (fivebar/identification/torque_log.h).
#pragma once

#include <string>

#include "fivebar/identification/torque_log.h"

namespace fivebar::io {

/// Reads a torque log. Throws LogError naming file, line and/or column and reason for: a missing
/// or empty file, a missing, unknown or duplicate column, an unpaired omega/alpha column, a row
/// with the wrong number of fields, a field that is not a finite number (NaN, inf, text), time
/// not strictly increasing, and angles that look like degrees (see identification::looks_like_degrees).
/// `dof` is the mechanism's number of driven cranks (2: the five-bar's columns; 1: the
/// four-bar's t,theta1,tau1 and optional omega1, alpha1); a column of the other mechanism is
/// refused naming it.
identification::TorqueLog read_torque_log(const std::string& path, int dof = 2);

/// Parses a log from text (`path` only names it in messages). Same checks as read_torque_log.
identification::TorqueLog parse_torque_log(const std::string& text, const std::string& path,
                                           int dof = 2);

/// Writes a log of log.dof cranks: `#` + each comment line, the header (rates and accelerations
/// when has_rates / has_accels), then one row per sample in shortest round-trip form. Throws LogError on failure.
void write_torque_log(const std::string& path, const identification::TorqueLog& log);

}  // namespace fivebar::io
