// Every simulation with an estimate of its own global error: a companion run at a ten times
// tighter tolerance, and, when the scene leaves the tolerance open, the tolerance chosen to meet
// simulation.target_error.
#pragma once

#include <string>
#include <vector>

#include "fivebar/sim/simulator.h"

namespace fivebar::sim {

/// One tolerance tried: the run at rtol = atol = `rtol` and its estimated error.
struct Attempt {
  double rtol = 0;
  double estimate = 0;  ///< [rad]
};

struct EstimatedRun {
  Result run;       ///< the output run (rows as Options::full_rows asks)
  Options options;  ///< the settings of the output run (tolerances as chosen)
  /// [rad] max over the output grid and the four link angles of |theta - theta_companion|, the
  /// companion run being the same method at rtol / 10, atol / 10. For a method whose error is
  /// proportional to its tolerance this is 0.9 times the run's own error; NaN when the companion
  /// failed (see note)
  double estimated_max_error_rad = 0;
  /// estimated_max_error_rad <= kTargetMargin * options.target_error, and the estimate is not
  /// rounding-limited
  bool target_met = false;
  /// the companion run is limited by rounding, not by its tolerance (rounding_limited): the
  /// estimate is then a lower bound of the error, not a measure of it, and the target is not met
  bool rounding_limited = false;
  std::vector<Attempt> attempts;  ///< every tolerance tried, in order
  std::string note;               ///< why the target was not met, or why there is no estimate
};

/// Largest tolerance simulate_to_target goes down to (rtol = atol): below it round-off in the
/// right-hand side, not the tolerance, limits the error.
inline constexpr double kTightestRtol = 1e-13;

/// The estimate meets the target only below this fraction of it: on 66 runs (6 scenes x 11
/// integrators and tolerances, docs/outputs.md) the true error reached 1.5 times the estimate
/// wherever the estimate was above the rounding floor.
inline constexpr double kTargetMargin = 1.0 / 3.0;

/// Below this companion tolerance (rtol / 10 of the run) the companion's own rounding error is of
/// the order of the run's: estimates at rtol 1e-12 and 1e-13 were up to 70 to 240 times below
/// the difference to runs of other methods at rtol 1e-13 (docs/outputs.md).
inline constexpr double kRoundingCompanionRtol = 1e-12;

/// True when an estimate `e` of a run (its tolerance, its rows and steps) says nothing beyond the
/// rounding of the solution: a companion tolerance below kRoundingCompanionRtol, or a companion
/// tolerance below the rounding accumulated over the run (100 eps x the steps taken) with `e`
/// below that floor times the largest |theta|. A companion tolerance above that floor measures
/// the error even when `e` is below it, and an `e` of exactly 0 (both runs equal to the last bit:
/// a run held at rest, however many steps it took) is the error.
bool rounding_limited(double e, double rtol, const Result& run);

/// max over common output times and theta1..theta4 of |a - b| [rad] (rows on the same grid).
double max_angle_difference(const std::vector<Row>& a, const std::vector<Row>& b);

/// Simulates with an error estimate. With options.auto_tolerance it starts from
/// rtol = atol = 1e-4 target_error (not below 10 kRoundingCompanionRtol) and tightens in
/// proportion to the estimate until the target is met with its margin (at most four tries, never
/// below kTightestRtol); it stops at a rounding-limited estimate, and where chaos makes the target
/// unreachable as soon as the proportional prediction says so; the note says which.
EstimatedRun simulate_to_target(const Params<double>& params, const LoadFunction& loads,
                                const Initial& initial, const Options& options);
/// The same for the four-bar.
EstimatedRun simulate_to_target(const FourBarParamsT<double>& params,
                                const FourBarLoadFunction& loads, const Initial& initial,
                                const Options& options);

}  // namespace fivebar::sim
