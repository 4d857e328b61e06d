// Internal to identification: telling a misfit of the law from smoothing bias in the table of the
// data-driven Savitzky-Golay window (identify.cc, choose_window).
//
// At each candidate half-window h the torque residual's mean square is the level the sensor noise
// explains (the floor, which falls steeply with h: the estimated accelerations' noise) plus an
// excess E(h) = rms^2 - floor^2. Smoothing bias makes E grow with the window (as h^8 for the
// order-5 filter on smooth motion, and at least as h where the acceleration jumps, at slip
// reversals). A misfit of the law (torques negated or scaled, a scene that does not match) adds
// the same E at every window. On a light mechanism the smallest windows' floor can be 30 times
// the torque noise, so there the ratio rms / floor reads 1 and hides the misfit, while the larger
// windows show it as an excess that does not change with h.
#pragma once

#include <cstddef>
#include <vector>

namespace fivebar::identification::detail {

/// One evaluated candidate: its half-window [samples] and, per actuator (one or two), the rms
/// torque residual and its noise floor over the probes [N m].
struct WindowLevel {
  int half = 0;
  double rms[2] = {0, 0}, floor[2] = {0, 0};
  /// the excess over the floor, rms^2 - floor^2 [N^2 m^2]
  double excess(int j) const { return rms[j] * rms[j] - floor[j] * floor[j]; }
};

/// An excess is resolved at a window when it is at least this fraction of the floor's square
/// (ratio rms / floor above 1.22): measured on clean logs, the ratio scatters by +-0.04 around 1
/// over the windows (rms^2 / floor^2 by +-0.08), so a resolved excess is known within ~20 %.
inline constexpr double kResolvedExcess = 0.5;
/// The excess is flat (a misfit) when, over a doubling of the half-window from the smallest window
/// where it is resolved, it has not grown beyond 1 / kFlatExcess times its value there: bias
/// grows at least 2 times over a doubling (E ~ h at the reversals' jumps), and 2^8 on smooth
/// motion. Nor has it fallen below kFallingExcess times that value: a misfit adds the same
/// excess at every window, within the ~20 % it is known to (negated logs of the light mechanism:
/// sqrt(E) 0.11-0.14 N m over the windows, E down to 0.62 of its value at the first), while an
/// excess that halves is neither a misfit nor bias (the floor's model fails at that window).
inline constexpr double kFlatExcess = 0.75;
inline constexpr double kFallingExcess = 0.5;

/// What the table says about a misfit, from `levels` (in increasing half-window, from the
/// smallest candidate; evaluated so far).
struct WindowMisfit {
  enum State {
    kNone,      ///< no excess resolved, or one that grows: smoothing bias (or nothing)
    kNeedMore,  ///< an excess is resolved at some window, but the table ends before its double
    kMisfit,    ///< the excess is flat over a doubling: a misfit of the law
  };
  State state = kNone;
  int actuator =
      -1;  ///< kMisfit: the actuator that shows it (both: the one flat over fewer windows)
  std::size_t from = 0;  ///< kMisfit: the smallest window where it is resolved (index in levels)
  std::size_t to = 0;    ///< kMisfit: the last window (index) up to which the excess stays flat
};

/// The misfit test on the table (WindowMisfit) over both actuators (the five-bar's
/// choose_window). `more`: whether larger candidates remain to be evaluated (else kNeedMore is
/// kNone).
WindowMisfit window_misfit(const std::vector<WindowLevel>& levels, bool more);

}  // namespace fivebar::identification::detail
