// ARKODE behind the Integrator interface: ERKStep for the explicit Runge-Kutta pairs
// (Dormand-Prince 5(4), Verner 6(5), Fehlberg 7(8)) and ARKStep for the implicit DIRK (ARK5(4)8L[2]SA, Newton
// with a dense Jacobian). The only file that includes ARKODE.
#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <string>

#include "integrator.h"

namespace fivebar::sim::detail {
namespace {

class Arkode final : public Integrator {
 public:
  Arkode(const OdeProblem& prob, const Options& opt, double t_end)
      : prob_(prob), explicit_(opt.method != Method::kArkodeDirk) {
    SUNContext_Create(nullptr, &ctx_);
    y_ = N_VNew_Serial(prob.n, ctx_);
    N_VEnableFusedOps_Serial(y_, SUNTRUE);  // fewer vector calls per step: the state is tiny
    N_VConst(0.0, y_);
    atol_ = N_VNew_Serial(prob.n, ctx_);
    for (int i = 0; i < prob.n; ++i) NV_Ith_S(atol_, i) = opt.atol * prob.atol_scale[i];
    if (explicit_) {
      mem_ = ERKStepCreate(&Arkode::rhs, 0.0, y_, ctx_);
      ERKStepSetErrHandlerFn(mem_, &Arkode::on_error, this);
      // ARKODE names tables NAME_stages_embedding_order
      ERKStepSetTableNum(mem_, opt.method == Method::kArkodeErk45   ? ARKODE_DORMAND_PRINCE_7_4_5
                               : opt.method == Method::kArkodeErk65 ? ARKODE_VERNER_8_5_6
                                                                    : ARKODE_FEHLBERG_13_7_8);
      // dense output: ARKODE's default degree-5 Hermite interpolant. It costs two extra RHS
      // evaluations per output time, but cubic Hermite or Lagrange lose one to two digits at the
      // 1 ms grid (measured with `fivebar accuracy`); the order-8 pair's error is bounded by it
      ERKStepSVtolerances(mem_, opt.rtol, atol_);
      if (prob.max_step > 0.0) ERKStepSetMaxStep(mem_, prob.max_step);
      ERKStepSetUserData(mem_, this);
      ERKStepSetMaxNumSteps(mem_, opt.max_steps);
      ERKStepSetStopTime(mem_, t_end);
      if (prob.nroots > 0) {
        ERKStepRootInit(mem_, prob.nroots, &Arkode::root);
        ERKStepSetNoInactiveRootWarn(mem_);
      }
    } else {
      mem_ = ARKStepCreate(nullptr, &Arkode::rhs, 0.0, y_, ctx_);
      ARKStepSetErrHandlerFn(mem_, &Arkode::on_error, this);
      ARKStepSetTableNum(mem_, ARKODE_ARK548L2SA_DIRK_8_4_5, ARKODE_ERK_NONE);
      // Lagrange dense output for stiff states, as ARKODE recommends: the Hermite one overshoots
      // LuGre bristles at output times; elsewhere Hermite is two digits more accurate
      // (both measured with `fivebar stress` and `fivebar accuracy`)
      if (prob.stiff_states) ARKStepSetInterpolantType(mem_, ARK_INTERP_LAGRANGE);
      ARKStepSVtolerances(mem_, opt.rtol, atol_);
      if (prob.max_step > 0.0) ARKStepSetMaxStep(mem_, prob.max_step);
      ARKStepSetUserData(mem_, this);
      ARKStepSetMaxNumSteps(mem_, opt.max_steps);
      ARKStepSetStopTime(mem_, t_end);
      A_ = SUNDenseMatrix(prob.n, prob.n, ctx_);
      ls_ = SUNLinSol_Dense(y_, A_, ctx_);
      ARKStepSetLinearSolver(mem_, ls_, A_);
      if (prob.nroots > 0) {
        ARKStepRootInit(mem_, prob.nroots, &Arkode::root);
        ARKStepSetNoInactiveRootWarn(mem_);
      }
    }
  }
  ~Arkode() override {
    if (explicit_) {
      ERKStepFree(&mem_);
    } else {
      ARKStepFree(&mem_);
    }
    if (ls_) SUNLinSolFree(ls_);
    if (A_) SUNMatDestroy(A_);
    N_VDestroy(atol_);
    N_VDestroy(y_);
    SUNContext_Free(&ctx_);
  }

  bool start(double t0, const double* y0) override {
    steps_before_ += current_steps();
    for (int i = 0; i < prob_.n; ++i) NV_Ith_S(y_, i) = y0[i];
    const int flag = explicit_ ? ERKStepReInit(mem_, &Arkode::rhs, t0, y_)
                               : ARKStepReInit(mem_, nullptr, &Arkode::rhs, t0, y_);
    return flag == ARK_SUCCESS;
  }
  void set_root_direction(const int* dirs) override {
    if (explicit_) {
      ERKStepSetRootDirection(mem_, const_cast<int*>(dirs));
    } else {
      ARKStepSetRootDirection(mem_, const_cast<int*>(dirs));
    }
  }
  Outcome advance(double tout, double* y, double* t) override {
    const int flag = explicit_ ? ERKStepEvolve(mem_, tout, y_, t, ARK_NORMAL)
                               : ARKStepEvolve(mem_, tout, y_, t, ARK_NORMAL);
    for (int i = 0; i < prob_.n; ++i) y[i] = NV_Ith_S(y_, i);
    if (flag == ARK_ROOT_RETURN) return kRoot;
    if (flag >= 0) return kReached;
    if (error_.empty()) error_ = "ARKODE flag " + std::to_string(flag);
    return kFailed;
  }
  void root_info(int* which) override {
    if (explicit_) {
      ERKStepGetRootInfo(mem_, which);
    } else {
      ARKStepGetRootInfo(mem_, which);
    }
  }
  long steps() override { return steps_before_ + current_steps(); }
  std::string error() const override { return error_; }

 private:
  long current_steps() {
    long n = 0;
    if (explicit_) {
      ERKStepGetNumSteps(mem_, &n);
    } else {
      ARKStepGetNumSteps(mem_, &n);
    }
    return n;
  }
  static int rhs(realtype t, N_Vector y, N_Vector ydot, void* self) {
    auto* me = static_cast<Arkode*>(self);
    return me->prob_.rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), me->prob_.user);
  }
  static int root(realtype t, N_Vector y, realtype* g, void* self) {
    auto* me = static_cast<Arkode*>(self);
    return me->prob_.root(t, N_VGetArrayPointer(y), g, me->prob_.user);
  }
  static void on_error(int code, const char* module, const char* function, char* msg,
                       void* self) {
    if (code < 0) {
      static_cast<Arkode*>(self)->error_ = std::string(module) + "/" + function + ": " + msg;
    }
  }

  OdeProblem prob_;
  bool explicit_;
  SUNContext ctx_ = nullptr;
  N_Vector y_ = nullptr;
  N_Vector atol_ = nullptr;
  void* mem_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver ls_ = nullptr;
  long steps_before_ = 0;
  std::string error_;
};

}  // namespace

std::unique_ptr<Integrator> make_arkode(const OdeProblem& prob, const Options& opt,
                                        double t_end) {
  return std::make_unique<Arkode>(prob, opt, t_end);
}

}  // namespace fivebar::sim::detail
