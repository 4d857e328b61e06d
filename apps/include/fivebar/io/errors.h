// Errors of the apps layer. Both carry the three parts of the one-line message that `fivebar`
// prints on stderr before a non-zero exit: `fivebar: error: <file>: <key>: <what and why>`.
#pragma once

#include <stdexcept>
#include <string>

namespace fivebar {

/// Bad input: a scene, CSV or flag that cannot be used as given (exit status 2).
/// what() is `<file>: <key>: <reason>`, e.g.
/// `paper.yaml: friction.coulomb: expected 1 or 5 numbers, got 4`.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string key, std::string reason)
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

/// The numerics failed on valid input: singular configuration reached, friction loop did not
/// converge, solver gave up (exit status 3). Same message layout as InputError, e.g.
/// `paper.yaml: simulation: |sin(th4 - th3)| fell below 1e-3 at t = 0.8 s`.
class NumericalError : public std::runtime_error {
 public:
  NumericalError(std::string file, std::string key, std::string reason)
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
