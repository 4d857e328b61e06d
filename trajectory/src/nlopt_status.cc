#include "fivebar/trajectory/nlopt_status.h"

#include <new>
#include <stdexcept>

#include <nlopt.hpp>

namespace fivebar::trajectory {

const char* outcome_name(SolverOutcome outcome) {
  switch (outcome) {
    case SolverOutcome::kConverged:
      return "converged";
    case SolverOutcome::kMaxEvaluations:
      return "max_evaluations";
    case SolverOutcome::kMaxTime:
      return "max_time";
    case SolverOutcome::kRoundoffLimited:
      return "roundoff_limited";
    case SolverOutcome::kForcedStop:
      return "forced_stop";
    case SolverOutcome::kInvalidArgument:
      return "invalid_argument";
    case SolverOutcome::kOutOfMemory:
      return "out_of_memory";
    case SolverOutcome::kFailure:
      return "failure";
  }
  return "failure";
}

SolverStatus status_from_result(int code) {
  switch (static_cast<nlopt::result>(code)) {
    case nlopt::SUCCESS:
      return {SolverOutcome::kConverged, "converged"};
    case nlopt::STOPVAL_REACHED:
      return {SolverOutcome::kConverged, "converged: objective reached stopval"};
    case nlopt::FTOL_REACHED:
      return {SolverOutcome::kConverged, "converged: relative objective change below ftol"};
    case nlopt::XTOL_REACHED:
      return {SolverOutcome::kConverged, "converged: relative step below xtol"};
    case nlopt::MAXEVAL_REACHED:
      return {SolverOutcome::kMaxEvaluations,
              "stopped at the evaluation limit before convergence"};
    case nlopt::MAXTIME_REACHED:
      return {SolverOutcome::kMaxTime, "stopped at the time limit before convergence"};
    case nlopt::ROUNDOFF_LIMITED:
      return {SolverOutcome::kRoundoffLimited,
              "roundoff limited: no further progress possible at double precision"};
    case nlopt::FORCED_STOP:
      return {SolverOutcome::kForcedStop, "forced stop"};
    case nlopt::INVALID_ARGS:
      return {SolverOutcome::kInvalidArgument, "invalid arguments given to NLopt"};
    case nlopt::OUT_OF_MEMORY:
      return {SolverOutcome::kOutOfMemory, "NLopt ran out of memory"};
    case nlopt::FAILURE:
      return {SolverOutcome::kFailure, "NLopt failure"};
    default:
      break;
  }
  return {SolverOutcome::kFailure, "unknown NLopt result " + std::to_string(code)};
}

SolverStatus status_from_exception(const std::exception_ptr& error) {
  // order matters: the NLopt exceptions derive from std::runtime_error
  try {
    std::rethrow_exception(error);
  } catch (const nlopt::roundoff_limited& e) {
    return {SolverOutcome::kRoundoffLimited,
            std::string("roundoff limited: no further progress possible (") + e.what() + ")"};
  } catch (const nlopt::forced_stop& e) {
    return {SolverOutcome::kForcedStop, std::string("forced stop (") + e.what() + ")"};
  } catch (const std::invalid_argument& e) {
    return {SolverOutcome::kInvalidArgument, std::string("invalid argument: ") + e.what()};
  } catch (const std::bad_alloc& e) {
    return {SolverOutcome::kOutOfMemory, std::string("out of memory: ") + e.what()};
  } catch (const std::exception& e) {
    return {SolverOutcome::kFailure, std::string("optimizer failure: ") + e.what()};
  } catch (...) {
    return {SolverOutcome::kFailure, "optimizer failure: unknown exception"};
  }
}

}  // namespace fivebar::trajectory
