// CVODE (Adams with fixed-point iteration, BDF with Newton and a dense Jacobian) behind the
// Integrator interface. The only file that includes CVODE. Every call's flag is checked; the
// flag names come from CVodeGetReturnFlagName.
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <string>

#include "integrator.h"

namespace fivebar::sim::detail {
namespace {

class Cvode final : public Integrator {
 public:
  Cvode(const OdeProblem& prob, const Options& opt, double t_end) : prob_(prob), t_end_(t_end) {
    SUNContext_Create(nullptr, &ctx_);
    y_ = N_VNew_Serial(prob.n, ctx_);
    N_VEnableFusedOps_Serial(y_, SUNTRUE);  // fewer vector calls per step: the state is tiny
    N_VConst(0.0, y_);
    out_ = N_VMake_Serial(prob.n, nullptr, ctx_);
    const bool adams = opt.method == Method::kCvodeAdams;
    mem_ = CVodeCreate(adams ? CV_ADAMS : CV_BDF, ctx_);
    ok_ = mem_ != nullptr;
    if (!ok_) {
      error_ = "CVodeCreate failed";
      return;
    }
    CVodeSetErrHandlerFn(mem_, &Cvode::on_error, this);
    ok_ = check(CVodeInit(mem_, &Cvode::rhs, 0.0, y_), "CVodeInit");
    atol_ = N_VNew_Serial(prob.n, ctx_);
    for (int i = 0; i < prob.n; ++i) NV_Ith_S(atol_, i) = opt.atol * prob.atol_scale[i];
    ok_ = ok_ && check(CVodeSVtolerances(mem_, opt.rtol, atol_), "CVodeSVtolerances") &&
          check(CVodeSetUserData(mem_, this), "CVodeSetUserData") &&
          check(CVodeSetMaxNumSteps(mem_, opt.max_steps), "CVodeSetMaxNumSteps");
    if (adams) {
      nls_ = SUNNonlinSol_FixedPoint(y_, 0, ctx_);
      ok_ = ok_ && check(CVodeSetNonlinearSolver(mem_, nls_), "CVodeSetNonlinearSolver");
    } else {
      A_ = SUNDenseMatrix(prob.n, prob.n, ctx_);
      ls_ = SUNLinSol_Dense(y_, A_, ctx_);
      ok_ = ok_ && check(CVodeSetLinearSolver(mem_, ls_, A_), "CVodeSetLinearSolver");
    }
  }
  ~Cvode() override {
    if (mem_) CVodeFree(&mem_);
    if (ls_) SUNLinSolFree(ls_);
    if (A_) SUNMatDestroy(A_);
    if (nls_) SUNNonlinSolFree(nls_);
    if (atol_) N_VDestroy(atol_);
    N_VDestroy(y_);
    N_VDestroy(out_);
    SUNContext_Free(&ctx_);
  }

  bool start(double t0, const double* y0) override {
    if (!ok_) return false;
    steps_before_ += current_steps();
    for (int i = 0; i < prob_.n; ++i) NV_Ith_S(y_, i) = y0[i];
    // the stop time is cleared once reached and is not kept across a re-initialization
    return check(CVodeReInit(mem_, t0, y_), "CVodeReInit") &&
           check(CVodeSetStopTime(mem_, t_end_), "CVodeSetStopTime");
  }
  bool set_max_step(double h) override {
    return check(CVodeSetMaxStep(mem_, h), "CVodeSetMaxStep");
  }
  bool step(double* y, double* t) override {
    const int flag = CVode(mem_, t_end_, y_, t, CV_ONE_STEP);
    for (int i = 0; i < prob_.n; ++i) y[i] = NV_Ith_S(y_, i);
    return check(flag, "CVode");
  }
  bool dense(double t, double* y) override {
    N_VSetArrayPointer(y, out_);  // a view of the caller's array: no allocation per call
    const int flag = CVodeGetDky(mem_, t, 0, out_);
    return check(flag, "CVodeGetDky");
  }
  bool sample(double t, double* y) override { return dense(t, y); }
  long steps() override { return steps_before_ + current_steps(); }
  std::string error() const override { return error_; }

 private:
  bool check(int flag, const char* call) {
    return check_flag(flag, call, CVodeGetReturnFlagName(flag), &error_);
  }
  long current_steps() {
    long n = 0;
    if (mem_) CVodeGetNumSteps(mem_, &n);
    return n;
  }
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Cvode*>(self);
    return me->prob_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), me->prob_.user);
  }
  static void on_error(int code, const char* module, const char* function, char* msg,
                       void* self) {
    if (code < 0) {
      static_cast<Cvode*>(self)->error_ = std::string(module) + "/" + function + ": " + msg;
    }
  }

  OdeProblem prob_;
  double t_end_;
  bool ok_ = false;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector out_ = nullptr;  ///< wraps the caller's array for dense output
  N_Vector atol_ = nullptr;
  void* mem_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  SUNNonlinearSolver nls_ = nullptr;
  long steps_before_ = 0;
  std::string error_;
};

}  // namespace

std::unique_ptr<Integrator> make_cvode(const OdeProblem& prob, const Options& opt, double t_end) {
  return std::make_unique<Cvode>(prob, opt, t_end);
}

}  // namespace fivebar::sim::detail
