#include "fivebar/trajectory/nlopt_status.h"

#include <new>
#include <stdexcept>

#include <nlopt.hpp>

#include "fivebar/model/names.h"

namespace fivebar::trajectory {

namespace {

constexpr Named<SolverOutcome> kOutcomeNames[] = {
    {SolverOutcome::kConverged, "converged"},
    {SolverOutcome::kMaxEvaluations, "max_evaluations"},
    {SolverOutcome::kMaxTime, "max_time"},
    {SolverOutcome::kRoundoffLimited, "roundoff_limited"},
    {SolverOutcome::kForcedStop, "forced_stop"},
    {SolverOutcome::kInvalidArgument, "invalid_argument"},
    {SolverOutcome::kOutOfMemory, "out_of_memory"},
    {SolverOutcome::kFailure, "failure"}};

/// What each NLopt result means for the caller, and the message it gets.
struct ResultMeaning {
  nlopt::result result;
  SolverOutcome outcome;
  const char* message;
};

constexpr ResultMeaning kResults[] = {
    {nlopt::SUCCESS, SolverOutcome::kConverged, "converged"},
    {nlopt::STOPVAL_REACHED, SolverOutcome::kConverged, "converged: objective reached stopval"},
    {nlopt::FTOL_REACHED, SolverOutcome::kConverged,
     "converged: relative objective change below ftol"},
    {nlopt::XTOL_REACHED, SolverOutcome::kConverged, "converged: relative step below xtol"},
    {nlopt::MAXEVAL_REACHED, SolverOutcome::kMaxEvaluations,
     "stopped at the evaluation limit before convergence"},
    {nlopt::MAXTIME_REACHED, SolverOutcome::kMaxTime, "stopped at the time limit before convergence"},
    {nlopt::ROUNDOFF_LIMITED, SolverOutcome::kRoundoffLimited,
     "roundoff limited: no further progress possible at double precision"},
    {nlopt::FORCED_STOP, SolverOutcome::kForcedStop, "forced stop"},
    {nlopt::INVALID_ARGS, SolverOutcome::kInvalidArgument, "invalid arguments given to NLopt"},
    {nlopt::OUT_OF_MEMORY, SolverOutcome::kOutOfMemory, "NLopt ran out of memory"},
    {nlopt::FAILURE, SolverOutcome::kFailure, "NLopt failure"}};

}  // namespace

const char* outcome_name(SolverOutcome outcome) { return name_in(kOutcomeNames, outcome, "failure"); }

SolverStatus status_from_result(int code) {
  for (const ResultMeaning& r : kResults) {
    if (static_cast<int>(r.result) == code) return {r.outcome, r.message};
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
