// Stress catalogue: stiff and extreme cases, each run with every
// integrator, each run ending `ok` (error against a tight reference, energy balance), `rejected`
// (the exit code and message a user would get) or `failed` (NaN, hang, crash, silent garbage).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fivebar/sim/simulator.h"
#include "fivebar/studies/types.h"

namespace fivebar::studies {

/// One case of the catalogue: a scene built in code, with what a correct run must satisfy.
struct StressCase {
  std::string name;         ///< short identifier, the `case` column of stress.csv
  std::string description;  ///< one line: what is extreme about it and what must happen
  Params<double> params;
  LoadFunction loads;
  Initial initial;
  Options options;  ///< the runs' settings; `method` is replaced by each integrator in turn
  /// integrator of the reference run (at StressOptions::reference_tolerance)
  Method reference_method = Method::kCvodeAdams;
  /// an `ok` run farther than this from the reference (max |d theta| over the grid) is silent
  /// garbage [rad]; the default, 1e4 times the runs' tolerance, leaves room for error growth
  /// across friction switches
  double max_error = 1e-4;
  /// the error is measured over t <= error_horizon only (chaotic long runs: beyond it even two
  /// tight references disagree); negative: the whole run [s]
  double error_horizon = -1.0;
  /// below breakaway: an `ok` run whose crank angles move by more than this is `failed` [rad];
  /// negative: no such check
  double max_displacement = -1.0;
};

/// The built-in catalogue. `reduced`: shorter durations (tests); the cases are the same.
std::vector<StressCase> stress_catalogue(bool reduced = false);

enum class StressOutcome : int { kOk = 0, kRejected, kFailed };
/// "ok", "rejected", "failed".
const char* stress_outcome_name(StressOutcome outcome);

/// One run of one case with one integrator (a row of stress.csv).
struct StressRow {
  std::string case_name;
  Method method = Method::kCvodeAdams;
  StressOutcome outcome = StressOutcome::kFailed;
  /// exit status `fivebar simulate` would give on this scene: 0 ok, 2 bad input (the start
  /// cannot assemble or is within the singular margin), 3 numerical failure
  int exit_code = 0;
  /// max |d theta_1..4| vs the reference over t <= the case's error_horizon [rad]; < 0: none
  double error = -1;
  double energy_balance = -1;  ///< check_run's energy_balance_relative; < 0: none
  double displacement = -1;    ///< max |theta_i(t) - theta_i(0)|, cases with max_displacement
  double wall_time_s = 0;      ///< the simulation alone (Stats::wall_time_s)
  long steps = 0;
  long rhs_evaluations = 0;
  double final_time = 0;  ///< time of the last output row
  std::string message;    ///< rejected / failed: why; ok: notes (empty if none)
};

/// The reference run of one case.
struct StressReference {
  std::string case_name;
  Method method = Method::kCvodeAdams;
  double tolerance = 0;
  bool ok = false;
  std::string message;  ///< status message when !ok
  double wall_time_s = 0;
  long steps = 0;
};

struct StressOptions {
  std::vector<Method> methods = {std::begin(kAllMethods), std::end(kAllMethods)};
  double reference_tolerance = 1e-12;  ///< rtol = atol of the reference runs
  /// hard wall-time limit of one run [s]: a run still going is killed and `failed` (a hang).
  /// Each case's max_steps is chosen so that its runs end well before.
  double run_budget_s = 20.0;
  /// run each simulation in a child process (fork): a crash or hang is a `failed` row, never
  /// the end of the whole study. false: in-process, no time limit (for debugging).
  bool isolate = true;
  /// an `ok` run whose energy balance residual exceeds this is `failed`
  double max_energy_balance = 1e-3;
  /// called after every row (e.g. for progress output); may be empty
  std::function<void(const StressRow&)> on_row;
};

struct StressReport {
  std::vector<StressReference> references;
  std::vector<StressRow> rows;
  int count(StressOutcome outcome) const;
};

/// Runs every case with every method of `options` and classifies each run.
StressReport run_stress(const std::vector<StressCase>& cases, const StressOptions& options);

}  // namespace fivebar::studies
