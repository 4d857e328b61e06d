// The one place that turns NLopt's results and exceptions into the toolkit's solver status
// (style.md, "Errors"). NLopt itself stays out of this header.
#pragma once

#include <exception>
#include <string>

namespace fivebar::trajectory {

/// How an NLopt run ended.
enum class SolverOutcome : int {
  kConverged = 0,     ///< SUCCESS, STOPVAL_REACHED, FTOL_REACHED, XTOL_REACHED
  kMaxEvaluations,    ///< MAXEVAL_REACHED: the last point is returned, not converged
  kMaxTime,           ///< MAXTIME_REACHED: idem
  kRoundoffLimited,   ///< ROUNDOFF_LIMITED / nlopt::roundoff_limited: usable, precision-limited
  kForcedStop,        ///< FORCED_STOP / nlopt::forced_stop: a callback stopped the run
  kInvalidArgument,   ///< INVALID_ARGS / std::invalid_argument: bad bounds, dimensions, options
  kOutOfMemory,       ///< OUT_OF_MEMORY / std::bad_alloc
  kFailure,           ///< FAILURE / std::runtime_error / anything else
};

struct SolverStatus {
  SolverOutcome outcome = SolverOutcome::kFailure;
  std::string message;
  /// The optimizer's last point may be used (converged, or stopped by a limit or by roundoff).
  bool usable() const {
    return outcome == SolverOutcome::kConverged || outcome == SolverOutcome::kMaxEvaluations ||
           outcome == SolverOutcome::kMaxTime || outcome == SolverOutcome::kRoundoffLimited;
  }
  /// The run stopped at its evaluation or time limit, not converged.
  bool limited() const {
    return outcome == SolverOutcome::kMaxEvaluations || outcome == SolverOutcome::kMaxTime;
  }
};

/// Short lowercase name of an outcome (summary.csv `solver_status`): converged,
/// max_evaluations, max_time, roundoff_limited, forced_stop, invalid_argument, out_of_memory,
/// failure.
const char* outcome_name(SolverOutcome outcome);

/// Status of a run that returned the nlopt_result / nlopt::result code `code`.
SolverStatus status_from_result(int code);

/// Status of a run that threw: nlopt::roundoff_limited, nlopt::forced_stop,
/// std::invalid_argument, std::bad_alloc, std::runtime_error or anything else.
SolverStatus status_from_exception(const std::exception_ptr& error);

}  // namespace fivebar::trajectory
