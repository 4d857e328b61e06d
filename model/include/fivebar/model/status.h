// Outcome of a numerical evaluation: numerical failure is a status with a message, never a NaN.
#pragma once

#include <string>
#include <utility>

namespace fivebar {

enum class StatusCode : int {
  kOk = 0,
  kCannotAssemble,        ///< |BD| outside [|l3 - l4|, l3 + l4]: no closure exists
  kNearSingular,          ///< |sin(th4 - th3)| below the singularity margin
  kFrictionNotConverged,  ///< the reaction/friction loop did not converge
  kInvalidInput,          ///< a value out of its domain (NaN, non-positive length, ...)
  kSolverFailed,          ///< the integrator or optimizer gave up
};

struct Status {
  StatusCode code = StatusCode::kOk;
  std::string message;

  bool ok() const { return code == StatusCode::kOk; }
  static Status Ok() { return {}; }
  static Status Error(StatusCode c, std::string m) { return {c, std::move(m)}; }
};

}  // namespace fivebar
