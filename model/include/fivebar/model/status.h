// Outcome of a numerical evaluation: numerical failure is a status with a message, never a NaN.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>

namespace fivebar {

enum class StatusCode : int {
  kOk = 0,
  kCannotAssemble,        ///< |BD| outside [|l3 - l4|, l3 + l4]: no closure exists
  kNearSingular,          ///< |sin(th4 - th3)| below the singularity margin
  /// the reaction/friction loop has no consistent solution, or several (the message says which:
  /// "no consistent reaction forces" or "several consistent reaction forces")
  kFrictionNotConverged,
  kInvalidInput,          ///< a value out of its domain (NaN, non-positive length, ...)
  kSolverFailed,          ///< the integrator or optimizer gave up
  /// no consistent joint modes, or several with different motions (Painleve-type): the motion
  /// of the model is not determined at that instant
  kIndeterminateModes,
};

struct Status {
  StatusCode code = StatusCode::kOk;
  std::string message;

  bool ok() const { return code == StatusCode::kOk; }
  static Status Ok() { return {}; }
  static Status Error(StatusCode c, std::string m) { return {c, std::move(m)}; }
};

/// An error about one value of one input: what() is `<file>: <key>: <reason>`, the one line a
/// user sees (`fivebar: error: ...`). The apps' InputError (exit 2) and NumericalError (exit 3)
/// and the libraries' input errors derive from it.
class FieldError : public std::runtime_error {
 public:
  FieldError(std::string file, std::string key, std::string reason)
      : std::runtime_error(file + ": " + key + ": " + reason),
        file_(std::move(file)),
        key_(std::move(key)),
        reason_(std::move(reason)) {}

  const std::string& file() const { return file_; }
  const std::string& key() const { return key_; }
  const std::string& reason() const { return reason_; }

 private:
  std::string file_, key_, reason_;
};

}  // namespace fivebar
