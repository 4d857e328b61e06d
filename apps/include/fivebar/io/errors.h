// Errors of the apps layer. Both carry the three parts of the one-line message that `fivebar`
// prints on stderr before a non-zero exit: `fivebar: error: <file>: <key>: <what and why>`.
#pragma once

#include "fivebar/model/status.h"

namespace fivebar {

/// Bad input: a scene, CSV or flag that cannot be used as given (exit status 2), e.g.
/// `paper.yaml: friction.coulomb: expected 1 or 5 numbers, got 4`.
class InputError : public FieldError {
 public:
  using FieldError::FieldError;
};

/// The numerics failed on valid input: singular configuration reached, friction loop did not
/// converge, solver gave up (exit status 3), e.g.
/// `paper.yaml: simulation: at t=0.8 s (...): near-singular pose ...`.
class NumericalError : public FieldError {
 public:
  using FieldError::FieldError;
};

}  // namespace fivebar
