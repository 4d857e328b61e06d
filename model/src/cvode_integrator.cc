// CVODE (Adams with fixed-point iteration, BDF with Newton and a dense Jacobian) behind the
// Integrator interface. The only file that includes CVODE. Every call's flag is checked; the
// flag names come from CVodeGetReturnFlagName.
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <string>

#include "sundials_common.h"

namespace fivebar::sim::detail {
namespace {

class Cvode final : public Integrator {
 public:
  Cvode(const OdeProblem& prob, const Options& opt, double t_end)
      : prob_(prob), t_end_(t_end), sc_(prob, opt) {
    ok_ = sc_.ready && setup(opt, opt.method == Method::kCvodeAdams);
  }
  ~Cvode() override {
    if (mem_) CVodeFree(&mem_);
    if (nls_) SUNNonlinSolFree(nls_);
  }

  bool start(double t0, const double* y0) override {
    long n = 0;
    if (!ok_ || !current_steps(&n)) return false;
    sc_.steps_before += n;
    sc_.load(y0, prob_.n);
    // the stop time is cleared once reached and is not kept across a re-initialization
    return check(CVodeReInit(mem_, t0, sc_.y), "CVodeReInit") &&
           check(CVodeSetStopTime(mem_, t_end_), "CVodeSetStopTime");
  }
  bool set_max_step(double h) override {
    return check(CVodeSetMaxStep(mem_, h), "CVodeSetMaxStep");
  }
  bool step(double* y, double* t) override {
    const int flag = CVode(mem_, t_end_, sc_.y, t, CV_ONE_STEP);
    sc_.store(y, prob_.n);
    return check(flag, "CVode");
  }
  bool dense(double t, double* y) override {
    NV_DATA_S(sc_.out) = y;  // a view of the caller's array: no allocation per call
    const int flag = CVodeGetDky(mem_, t, 0, sc_.out);
    return check(flag, "CVodeGetDky");
  }
  bool sample(double t, double* y) override { return dense(t, y); }
  bool steps(long* n) override {
    if (!current_steps(n)) return false;
    *n += sc_.steps_before;
    return true;
  }
  std::string error() const override { return sc_.error; }

 private:
  bool setup(const Options& opt, bool adams) {
    mem_ = CVodeCreate(adams ? CV_ADAMS : CV_BDF, sc_.ctx);
    if (!check_created(mem_, "CVodeCreate", &sc_.error) ||
        !check(CVodeSetErrHandlerFn(mem_, &SundialsCommon::on_error, &sc_),
               "CVodeSetErrHandlerFn") ||
        !check(CVodeInit(mem_, &Cvode::rhs, 0.0, sc_.y), "CVodeInit") ||
        !check(CVodeSVtolerances(mem_, opt.rtol, sc_.atol), "CVodeSVtolerances") ||
        !check(CVodeSetUserData(mem_, this), "CVodeSetUserData") ||
        !check(CVodeSetMaxNumSteps(mem_, opt.max_steps), "CVodeSetMaxNumSteps")) {
      return false;
    }
    if (adams) {
      nls_ = SUNNonlinSol_FixedPoint(sc_.y, 0, sc_.ctx);
      return check_created(nls_, "SUNNonlinSol_FixedPoint", &sc_.error) &&
             check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
    }
    return sc_.make_dense_solver(prob_.n) &&
           check(CVodeSetLinearSolver(mem_, sc_.ls, sc_.A), "CVodeSetLinearSolver");
  }
  bool check(int flag, const char* call) {
    return check_flag(flag, call, &CVodeGetReturnFlagName, &sc_.solver_message, &sc_.error);
  }
  /// Steps since the last (re)start; 0 before the solver exists.
  bool current_steps(long* n) {
    *n = 0;
    return !mem_ || check(CVodeGetNumSteps(mem_, n), "CVodeGetNumSteps");
  }
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Cvode*>(self);
    // the serial vector's data (the library's accessors: two unoptimized calls each)
    return me->prob_.rhs(t, NV_DATA_S(y), NV_DATA_S(ydot), me->prob_.user);
  }
  OdeProblem prob_;
  double t_end_;
  SundialsCommon sc_;
  bool ok_ = false;
  void* mem_ = nullptr;
  SUNNonlinearSolver nls_ = nullptr;
};

}  // namespace

std::unique_ptr<Integrator> make_cvode(const OdeProblem& prob, const Options& opt, double t_end) {
  return std::make_unique<Cvode>(prob, opt, t_end);
}

}  // namespace fivebar::sim::detail
