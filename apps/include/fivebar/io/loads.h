// Load expressions of a scene (interfaces.md `loads:`), compiled once with muParser.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "fivebar/io/scene.h"
#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// The four load expressions M1(t), M2(t), M3(t) [N m], F(t) [N] (muParser syntax: + - * / ^,
/// sin cos tan exp log sqrt abs min max ..., the variable `t` [s] and the constant `pi`), plus
/// the constant force angle F_angle [rad].
///
/// Threads: a LoadExpressions (and the sim::LoadFunction from function()) may be copied freely;
/// each copy compiles its own parsers, bound to its own `t`. Calls are also safe when one object
/// is shared by several threads: a call that finds the object's parsers in use by another thread
/// evaluates with parsers private to the calling thread (slower on the first call only).
class LoadExpressions {
 public:
  /// Index of each expression in expressions() and constant().
  enum Which : int { kM1 = 0, kM2, kM3, kF };
  static constexpr const char* kNames[4] = {"M1", "M2", "M3", "F"};

  /// Compiles `expressions` (M1, M2, M3, F) and checks that each is finite at t = 0 and 1.
  /// Throws InputError(`<file>: loads.M1: <muParser message>`) otherwise.
  LoadExpressions(const std::array<std::string, 4>& expressions, double F_angle,
                  const std::string& file);
  /// The loads of a scene (file named by scene.path).
  explicit LoadExpressions(const Scene& scene);

  LoadExpressions(const LoadExpressions& other);  // recompiles: parsers bind `t` by address
  LoadExpressions& operator=(const LoadExpressions& other);
  LoadExpressions(LoadExpressions&& other) noexcept;
  LoadExpressions& operator=(LoadExpressions&& other) noexcept;
  ~LoadExpressions();

  /// The loads at time t [s]. Never throws: an expression that cannot be evaluated gives NaN,
  /// and non-finite values (e.g. 1/(t-1) at t = 1) are returned as they are.
  Loads<double> operator()(double t) const;

  /// A copy of these loads as the simulator's load function.
  sim::LoadFunction function() const;
  /// The same for a four-bar: M1 on the crank, M3 and F (at F_angle) on the coupler (M2 unused).
  sim::FourBarLoadFunction four_bar_function() const;

  /// Throws NumericalError(`<file>: loads.<name>: ...`, exit 3, the words of the simulator's
  /// own check) at the first of `times` where a load is NaN or infinite (an expression that
  /// leaves its domain, e.g. sqrt(1.5 - t) after 1.5 s), for the commands that evaluate the loads
  /// outside a simulation: before their work, not as a model failure later.
  void require_finite(const std::vector<double>& times) const;
  /// The same on the grid 0, step, 2 step, ... up to `duration` (and at `duration` itself).
  void require_finite(double duration, double step) const;

  const std::array<std::string, 4>& expressions() const;
  /// True if expression `which` uses no variable (it is evaluated once, at compile time).
  bool constant(int which) const;

 private:
  struct Compiled;
  class Evaluator;

  std::shared_ptr<const Compiled> compiled_;  // immutable, shared by copies
  std::unique_ptr<Evaluator> evaluator_;      // this copy's parsers
  mutable std::atomic_flag busy_ = ATOMIC_FLAG_INIT;
};

}  // namespace fivebar::io
