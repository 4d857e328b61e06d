// identify's rules on a four-bar's log (identify_four_bar.cc) that the excitation design's
// prediction of its std repeats (excitation_four_bar.cc): one definition for both.
#pragma once

namespace fivebar::identification::four_bar_rules {

/// a joint whose relative rate is within this many of its noise std of zero is left out (its
/// Coulomb sign is not known)
constexpr double kRestSigmas = 4.0;

/// the Savitzky-Golay order when the window is not given: the crank-rocker's crank turns at
/// ~23 rad/s, and order 5 smooths its accelerations (noise-free log, 5 ms: coulomb -4 %; seeded
/// logs at 10 ms: -2 std); order 7 at 10 ms left |error| <= 1.3 std on the seeds tried. A
/// smaller window does not help: the acceleration noise then biases the friction (the reactions'
/// norms grow with it) by up to -5 std at 4 ms.
constexpr int kWindowOrder = 7;

}  // namespace fivebar::identification::four_bar_rules
