// Internal: Dormand-Prince 5(4) stepped as SUNDIALS 6.4's ERKStep steps it (arkode.c's arkEvolve
// in one-step mode with a stop time, arkHin, arkAdapt with ERKStep's PI controller,
// arkCompleteStep; arkode_erkstep.c's stages and solutions), in the library's arithmetic: the same
// products and sums in the same order, the same special cases where those round differently, so
// its steps, states and error estimates are the library's bit for bit (ErkStepper.* checks it
// against ERKStep). The distribution's library is built without optimization; its step loop,
// controller and generic vector calls cost the simulator more than this. Also ERKStep's dense
// output: ARKODE's Hermite interpolant of degree 4 (arkode_interp.c).
#pragma once

#include <string>
#include <vector>

#include "integrator.h"

namespace fivebar::sim::detail {

/// ERKStep's dense output for Dormand-Prince: ARKODE's Hermite interpolant of degree 4 on the
/// last step [t_new - h, t_new], in the library's arithmetic (SUNDIALS 6.4 arkode_interp.c: the
/// same coefficient expressions in the same order, the same linear combinations). The slopes are
/// those ERKStep holds: f_old and f_new of the step's ends, f_a at t_new - h/3 on the cubic
/// interpolant.
struct QuarticHermite {
  double t_new = 0.0, h = 0.0;
  std::vector<double> y_old, y_new, f_old, f_new;

  /// The cubic interpolant's state at tau = -1/3 (tau = (t - t_new) / h) into ya, and its time.
  double cubic_third(double* ya) const;
  /// The quartic interpolant at t, with f_a the slope at cubic_third's point.
  void quartic(double t, const double* fa, double* y) const;
  /// Whether t is within the step as ERKStepGetDky accepts it (its rounding slack).
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
  /// One step (ERKStepEvolve in ARK_ONE_STEP mode): *t and y the step's end (at the stop time, the
  /// dense output there). Returns ARKODE's flag; on failure, message() has its words.
  int step(double* y, double* t);
  /// The interpolant of the last step (valid once a step succeeded since the last start).
  const QuarticHermite& interpolant() const { return hermite_; }
  bool has_interpolant() const { return has_step_; }
  /// The dense output at t within the last step (one right-hand side, at the interior point).
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
  QuarticHermite hermite_;
  std::vector<double> ya_, fa_;  ///< the dense output's interior point and its slope
  double ta_ = 0.0;
  bool has_interior_ = false;    ///< ya_ and ta_ are the last step's
  std::string message_;
};

}  // namespace fivebar::sim::detail
