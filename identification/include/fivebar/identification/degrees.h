// Telling crank angles in degrees from radians where a file gives no unit: by the rates when
// there are any, else by the size of the angles (torque logs, motion files, task goals).
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace fivebar::identification {

/// Crank angles beyond this are read as degrees where nothing else tells the unit [rad]: two
/// turns (a motion in radians may start a turn out, at 7.85 rad; degrees of a five-bar's poses
/// are mostly beyond 12.6). For task goals and motions without rates; logs and motions with
/// rates are told by the rates (rates_look_like_degrees).
inline constexpr double kDegreesBeyond = 4 * M_PI;

/// Empty if the angles `theta` at times `t` look like radians against their rates `omega`, else
/// the reason they look like degrees: the finite-difference rate of theta is ~180/pi times
/// omega (least-squares slope within 20 % of 57.3). Used by looks_like_degrees (torque_log.h).
std::string rates_look_like_degrees(const std::vector<double>& t, const std::vector<double>& theta,
                                    const std::vector<double>& omega);

/// Whether the angles `theta` at times `t` agree with their rates `omega` in radians (the same
/// least-squares slope within 20 % of 1): then they are radians, whatever their start (a motion
/// cut late in a run starts many turns out, at 72.5 rad)
bool rates_say_radians(const std::vector<double>& t, const std::vector<double>& theta,
                       const std::vector<double>& omega);

}  // namespace fivebar::identification
