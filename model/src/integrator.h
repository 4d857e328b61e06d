// Internal: one interface over the SUNDIALS integrators (CVODE in cvode_integrator.cc, ARKODE in
// arkode_integrator.cc), so the simulator's event loop is written once.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fivebar/sim/simulator.h"

namespace fivebar::sim::detail {

/// ODE right-hand side and root functions with SUNDIALS' return convention:
/// 0 ok, > 0 recoverable (retry with a smaller step), < 0 fatal.
using RhsFn = int (*)(double t, const double* y, double* ydot, void* user);
using RootFn = int (*)(double t, const double* y, double* g, void* user);

struct OdeProblem {
  int n = 0;
  int nroots = 0;
  RhsFn rhs = nullptr;
  RootFn root = nullptr;
  void* user = nullptr;
  /// absolute tolerance of each state (size n), scaling Options::atol
  std::vector<double> atol_scale;
  /// largest step [s], 0 for none (a step must not jump over a double zero of a joint's rate)
  double max_step = 0.0;
  bool stiff_states = false;  ///< the state has stiff components (LuGre bristles)
};

class Integrator {
 public:
  enum Outcome { kReached = 0, kRoot = 1, kFailed = -1 };
  virtual ~Integrator() = default;
  /// (Re)starts the integration at (t0, y0), forgetting the history (used after every switch).
  virtual bool start(double t0, const double* y0) = 0;
  /// Sets the direction of each root function to watch: +1 increasing, -1 decreasing, 0 both.
  virtual void set_root_direction(const int* dirs) = 0;
  /// Advances towards tout; y and *t receive the state at tout (dense output) or at a root.
  virtual Outcome advance(double tout, double* y, double* t) = 0;
  /// Which root functions fired at the last kRoot (+1/-1 per function, 0 if not).
  virtual void root_info(int* which) = 0;
  /// Steps taken since construction, over all starts.
  virtual long steps() = 0;
  /// The solver's message for the last failure.
  virtual std::string error() const = 0;
};

std::unique_ptr<Integrator> make_cvode(const OdeProblem& prob, const Options& opt, double t_end);
std::unique_ptr<Integrator> make_arkode(const OdeProblem& prob, const Options& opt, double t_end);

inline std::unique_ptr<Integrator> make_integrator(const OdeProblem& prob, const Options& opt,
                                                   double t_end) {
  if (opt.method == Method::kCvodeAdams || opt.method == Method::kCvodeBdf) {
    return make_cvode(prob, opt, t_end);
  }
  return make_arkode(prob, opt, t_end);
}

}  // namespace fivebar::sim::detail
