// Internal: one interface over the SUNDIALS integrators (CVODE in cvode_integrator.cc, ARKODE in
// arkode_integrator.cc), so the simulator's event loop is written once. The integrators advance
// one internal step at a time; switch detection (zeros of the joints' relative rates, holding
// margins) is the simulator's, on the integrators' dense output, identical for every method.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fivebar/sim/simulator.h"

namespace fivebar::sim::detail {

/// ODE right-hand side with SUNDIALS' return convention: 0 ok, > 0 recoverable (retry with a
/// smaller step), < 0 fatal.
using RhsFn = int (*)(double t, const double* y, double* ydot, void* user);
/// Freezes (on) or releases (off) the state-switched parts of the right-hand side at the state
/// y: the Coulomb signs taken from the rates when switches are not located. Difference-quotient
/// Jacobians then see the smooth piece, not a jump divided by a tiny increment.
using FreezeFn = void (*)(const double* y, bool on, void* user);

struct OdeProblem {
  int n = 0;
  RhsFn rhs = nullptr;
  void* user = nullptr;
  /// absolute tolerance of each state (size n), scaling Options::atol
  std::vector<double> atol_scale;
  bool stiff_states = false;  ///< the state has stiff components (LuGre bristles)
  /// optional (nullptr: the right-hand side is smooth within a segment); implicit methods then
  /// form their Newton Jacobian with the switched parts frozen
  FreezeFn freeze = nullptr;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// (Re)starts the integration at (t0, y0), forgetting the history (used after every switch).
  /// False with error() set if SUNDIALS refuses.
  virtual bool start(double t0, const double* y0) = 0;
  /// Largest step [s] from now on (0: none). False with error() set if SUNDIALS refuses.
  virtual bool set_max_step(double h) = 0;
  /// One internal step, never past the end time given at construction; y and *t receive the
  /// state at the step's end. False with error() set on failure.
  virtual bool step(double* y, double* t) = 0;
  /// The integrator's own dense output at t within the last step (accurate to its order).
  virtual bool dense(double t, double* y) = 0;
  /// A cheaper interpolant at t within the last step, for scanning switch functions: CVODE's
  /// dense output (free), or a cubic Hermite from the step's end values and slopes for ARKODE
  /// (whose Hermite dense output evaluates the right-hand side at an interior point of the step).
  virtual bool sample(double t, double* y) = 0;
  /// Steps taken since construction, over all starts. False with error() set if SUNDIALS
  /// refuses the count.
  virtual bool steps(long* n) = 0;
  /// The solver's message for the last failure.
  virtual std::string error() const = 0;
};

std::unique_ptr<Integrator> make_cvode(const OdeProblem& prob, const Options& opt, double t_end);
std::unique_ptr<Integrator> make_arkode(const OdeProblem& prob, const Options& opt, double t_end);

/// The integrator of opt.method; unset: default_method(prob.stiff_states), which is the friction
/// law's (the stiff states are its internal states).
inline std::unique_ptr<Integrator> make_integrator(const OdeProblem& prob, const Options& opt,
                                                   double t_end) {
  Options chosen = opt;
  chosen.method = opt.method.value_or(default_method(prob.stiff_states));
  if (chosen.method == Method::kCvodeAdams || chosen.method == Method::kCvodeBdf) {
    return make_cvode(prob, chosen, t_end);
  }
  return make_arkode(prob, chosen, t_end);
}

// The checks below are the only place that words SUNDIALS failures (sundials_status.cc). Each
// keeps the first failure in *error (a later one is a consequence) and returns whether the call
// succeeded.

/// A solver call's flag (< 0: failure). The message names the call and the flag by its SUNDIALS
/// name, then the error handler's text if it gave one, then what the flag means for a user of
/// fivebar: "CVode returned CV_TOO_MUCH_WORK (CVODE/CVode: At t = ..., mxstep steps taken before
/// reaching tout.): the step limit simulation.max_steps was reached: ...". `flag_name` is the
/// module's *GetReturnFlagName, whose string SUNDIALS allocates: it is called for failures only,
/// and the string freed. `solver_message` holds the error handler's text (SundialsCommon::
/// on_error) and is cleared.
bool check_flag(int flag, const char* call, char* (*flag_name)(long int),
                std::string* solver_message, std::string* error);

/// A constructor's result (N_VNew_Serial, SUNDenseMatrix, CVodeCreate, ...): null is a failure.
bool check_created(const void* object, const char* call, std::string* error);

/// A call outside the solvers that returns 0 on success (SUNContext_Create,
/// N_VEnableFusedOps_Serial): SUNDIALS has no names for these codes.
bool check_call(int flag, const char* call, std::string* error);

/// What a failure flag (by name, CV_ or ARK_ prefix) means and what to try; "" if nothing useful.
std::string sundials_hint(const std::string& flag_name);

}  // namespace fivebar::sim::detail
