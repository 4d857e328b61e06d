// Internal: what the CVODE and ARKODE integrators share: the SUNDIALS context, the state and
// tolerance vectors, the dense linear solver's matrix, and the error handler that keeps the
// solver's last message. Each integrator owns one and adds its solver memory. Every creation is
// checked: a failure leaves `ready` false and `error` saying which call failed.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include <string>

#include "integrator.h"

namespace fivebar::sim::detail {

struct SundialsCommon {
  SUNContext ctx = nullptr;
  N_Vector y = nullptr;     ///< the state the solver advances
  N_Vector out = nullptr;   ///< wraps the caller's array for dense output
  N_Vector atol = nullptr;  ///< Options::atol times the problem's per-state scale
  SUNMatrix A = nullptr;    ///< dense Jacobian (implicit methods only)
  SUNLinearSolver ls = nullptr;
  std::string error;           ///< the first failure, as the checks of integrator.h word it
  std::string solver_message;  ///< the error handler's text, until a check takes it
  bool ready = false;          ///< every object above (but A and ls) was created
  long steps_before = 0;       ///< steps taken before the last restart

  SundialsCommon(const OdeProblem& prob, const Options& opt);
  ~SundialsCommon();
  SundialsCommon(const SundialsCommon&) = delete;
  SundialsCommon& operator=(const SundialsCommon&) = delete;

  /// Creates the dense matrix and linear solver for Newton iterations; false with error set.
  bool make_dense_solver(int n);
  /// Copies y0 into the state vector.
  void load(const double* y0, int n);
  /// Copies the state vector into y.
  void store(double* y, int n) const;

  /// SUNDIALS error handler (set with the solver's SetErrHandlerFn and `this` as user data):
  /// keeps the message of errors (code < 0) in solver_message, for check_flag.
  static void on_error(int code, const char* module, const char* function, char* msg,
                       void* self);
};

}  // namespace fivebar::sim::detail
