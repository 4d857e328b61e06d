// Internal: Dormand-Prince 5(4) stepped as SUNDIALS 6.4's ERKStep steps it (arkode.c's arkEvolve
// in one-step mode with a stop time, arkHin, arkAdapt with ERKStep's PI controller,
// arkCompleteStep; arkode_erkstep.c's stages and solutions), in the library's arithmetic: the same
// products and sums in the same order, the same special cases where those round differently, so
// its steps, states and error estimates are the library's bit for bit (ErkStepper.* checks it
// against ERKStep). The distribution's library is built without optimization; its step loop,
// controller and generic vector calls cost the simulator more than this. Its dense output is
// Dormand-Prince's own (DopriDense), from the step's stages: ERKStep's Hermite interpolant needs
// one more right-hand side per step.
#pragma once

#include <string>
#include <vector>

#include "integrator.h"

namespace fivebar::sim::detail {

/// Dormand-Prince's own continuous extension on the last step [t_new - h, t_new] (Hairer,
/// Norsett and Wanner, DOPRI5's dense output: order 4 from the step's seven stages, no further
/// right-hand side): y(t_new - h + theta h) = y_old + theta (ydiff + (1 - theta) (bspl + theta
/// (r4 + (1 - theta) r5))).
struct DopriDense {
  double t_new = 0.0, h = 0.0;
  std::vector<double> y_old, ydiff, bspl, r4, r5;

  /// From the step's start y0, end y1 and stage slopes k[0..6] (k[6] = f(t_new, y_new)); y_old
  /// is the caller's to set to y0 (DormandPrince moves its vector in).
  void set(double t_end, double step, const std::vector<double>& y0, const std::vector<double>& y1,
           const std::vector<double> (&k)[7]);
  void at(double t, double* y) const;
  /// Whether t is within the step, with ERKStepGetDky's rounding slack.
  bool covers(double t) const;
};

/// The Dormand-Prince pair of ARKODE's table ARKODE_DORMAND_PRINCE_7_4_5 with ERKStep's default
/// step control (PI controller, safety 0.99, bias 1.2, growth 25, first-step growth 1e4, error
/// failures cut to at most 0.3 from the second on, ARKODE's initial step estimate), a stop time
/// and an optional largest step. Right-hand sides go through `rhs` in ERKStep's order. Flags and
/// failure words are ARKODE's (ARK_SUCCESS, ARK_TSTOP_RETURN, ARK_TOO_MUCH_ACC, ...).
class DormandPrince {
 public:
  static constexpr int kStages = 7;

  /// `atol`: the absolute tolerance of each state; `max_nef`: error-test failures per step.
  DormandPrince(int n, RhsFn rhs, void* user, double rtol, const std::vector<double>& atol,
                int max_nef);

  /// Restarts at (t0, y0) as ERKStepReInit followed by ERKStepSetStopTime(t_stop).
  void start(double t0, const double* y0, double t_stop);
  /// Largest step from now on (<= 0: none), as ERKStepSetMaxStep.
  void set_max_step(double h) { hmax_inv_ = h > 0.0 ? 1.0 / h : 0.0; }
  /// One step (ERKStepEvolve in ARK_ONE_STEP mode): *t and y the step's end. Returns ARKODE's
  /// flag (ARK_TSTOP_RETURN at the stop time); on failure, message() has its words.
  int step(double* y, double* t);
  /// The dense output at t within the last step (ARK_BAD_T elsewhere).
  int dense(double t, double* y);
  /// Steps since the last start.
  long steps() const { return nst_; }
  const std::string& message() const { return message_; }

  /// The table's coefficients (ARKODE's, loaded from the library)
  struct Table {
    double A[kStages][kStages] = {}, b[kStages] = {}, c[kStages] = {}, d[kStages] = {};
  };

 private:
  bool set_weights(const double* y);
  int initial_setup();
  int initial_step(double tout);
  bool ydd_norm(double hg, double* norm);
  int attempt(double* dsm);
  int check_error(double dsm, int* nef);
  void adapt(double dsm);
  void complete_step(double dsm);
  void limit_to_stop();
  double weighted_rms(const double* x) const;
  int fail(int flag, const std::string& words);

  int n_;
  RhsFn rhs_;
  void* user_;
  double rtol_;
  std::vector<double> atol_;
  bool atol_has_zero_ = false;
  int max_nef_;
  Table tab_;
  double hmax_inv_ = 0.0;
  // ARKODE's step state (arkode_impl.h names)
  double tn_ = 0.0, tcur_ = 0.0, tstop_ = 0.0, tretlast_ = 0.0;
  bool tstopset_ = false, initsetup_ = true, has_step_ = false;
  double h_ = 0.0, hprime_ = 0.0, eta_ = 1.0, etamax_ = 1.0;
  double ehist_[2] = {1.0, 1.0};
  long nst_ = 0;
  std::vector<double> yn_, ycur_, ewt_, tmp_, F_[kStages];
  DopriDense dense_;
  std::string message_;
};

}  // namespace fivebar::sim::detail
