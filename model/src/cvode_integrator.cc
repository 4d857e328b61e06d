// CVODE (Adams with fixed-point iteration, BDF with Newton and a dense Jacobian) behind the
// Integrator interface. The only file that includes CVODE.
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
  Cvode(const OdeProblem& prob, const Options& opt, double t_end) : prob_(prob) {
    SUNContext_Create(nullptr, &ctx_);
    y_ = N_VNew_Serial(prob.n, ctx_);
    N_VEnableFusedOps_Serial(y_, SUNTRUE);  // fewer vector calls per step: the state is tiny
    N_VConst(0.0, y_);
    const bool adams = opt.method == Method::kCvodeAdams;
    mem_ = CVodeCreate(adams ? CV_ADAMS : CV_BDF, ctx_);
    CVodeSetErrHandlerFn(mem_, &Cvode::on_error, this);
    CVodeInit(mem_, &Cvode::rhs, 0.0, y_);
    atol_ = N_VNew_Serial(prob.n, ctx_);
    for (int i = 0; i < prob.n; ++i) NV_Ith_S(atol_, i) = opt.atol * prob.atol_scale[i];
    CVodeSVtolerances(mem_, opt.rtol, atol_);
    if (prob.max_step > 0.0) CVodeSetMaxStep(mem_, prob.max_step);
    CVodeSetUserData(mem_, this);
    CVodeSetMaxNumSteps(mem_, opt.max_steps);
    CVodeSetStopTime(mem_, t_end);
    if (adams) {
      nls_ = SUNNonlinSol_FixedPoint(y_, 0, ctx_);
      CVodeSetNonlinearSolver(mem_, nls_);
    } else {
      A_ = SUNDenseMatrix(prob.n, prob.n, ctx_);
      ls_ = SUNLinSol_Dense(y_, A_, ctx_);
      CVodeSetLinearSolver(mem_, ls_, A_);
    }
    if (prob.nroots > 0) {
      CVodeRootInit(mem_, prob.nroots, &Cvode::root);
      CVodeSetNoInactiveRootWarn(mem_);
    }
  }
  ~Cvode() override {
    CVodeFree(&mem_);
    if (ls_) SUNLinSolFree(ls_);
    if (A_) SUNMatDestroy(A_);
    if (nls_) SUNNonlinSolFree(nls_);
    N_VDestroy(atol_);
    N_VDestroy(y_);
    SUNContext_Free(&ctx_);
  }

  bool start(double t0, const double* y0) override {
    steps_before_ += current_steps();
    for (int i = 0; i < prob_.n; ++i) NV_Ith_S(y_, i) = y0[i];
    return CVodeReInit(mem_, t0, y_) == CV_SUCCESS;
  }
  void set_root_direction(const int* dirs) override {
    CVodeSetRootDirection(mem_, const_cast<int*>(dirs));
  }
  Outcome advance(double tout, double* y, double* t) override {
    const int flag = CVode(mem_, tout, y_, t, CV_NORMAL);
    for (int i = 0; i < prob_.n; ++i) y[i] = NV_Ith_S(y_, i);
    if (flag == CV_ROOT_RETURN) return kRoot;
    if (flag >= 0) return kReached;  // CV_SUCCESS, CV_TSTOP_RETURN
    if (error_.empty()) error_ = CVodeGetReturnFlagName(flag);
    return kFailed;
  }
  void root_info(int* which) override { CVodeGetRootInfo(mem_, which); }
  long steps() override { return steps_before_ + current_steps(); }
  std::string error() const override { return error_; }

 private:
  long current_steps() {
    long n = 0;
    CVodeGetNumSteps(mem_, &n);
    return n;
  }
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Cvode*>(self);
    return me->prob_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), me->prob_.user);
  }
  static int root(realtype t, N_Vector y, realtype* g, void* self) {
    auto* me = static_cast<Cvode*>(self);
    return me->prob_.root(t, N_VGetArrayPointer(y), g, me->prob_.user);
  }
  static void on_error(int code, const char* module, const char* function, char* msg,
                       void* self) {
    if (code < 0) {
      static_cast<Cvode*>(self)->error_ = std::string(module) + "/" + function + ": " + msg;
    }
  }

  OdeProblem prob_;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
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
