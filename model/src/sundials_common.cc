#include "sundials_common.h"

#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "serial_vector_ops.h"

namespace fivebar::sim::detail {

SundialsCommon::SundialsCommon(const OdeProblem& prob, const Options& opt) {
  if (!check_call(SUNContext_Create(nullptr, &ctx), "SUNContext_Create", &error)) {
    ctx = nullptr;
    return;
  }
  y = N_VNew_Serial(prob.n, ctx);
  out = N_VMake_Serial(prob.n, nullptr, ctx);
  atol = N_VNew_Serial(prob.n, ctx);
  if (!check_created(y, "N_VNew_Serial", &error) || !check_created(out, "N_VMake_Serial", &error) ||
      !check_created(atol, "N_VNew_Serial", &error) ||
      // fewer vector calls per step: the state is tiny (the dense output's vector too: without
      // them its linear combinations fall back to one scale and one axpy call per term)
      !check_call(N_VEnableFusedOps_Serial(y, SUNTRUE), "N_VEnableFusedOps_Serial", &error) ||
      !check_call(N_VEnableFusedOps_Serial(out, SUNTRUE), "N_VEnableFusedOps_Serial", &error)) {
    return;
  }
  // after the fused operations are enabled (which sets the library's), before any solver clones y
  for (N_Vector v : {y, out, atol}) use_compiled_serial_ops(v);
  N_VConst(0.0, y);
  for (int i = 0; i < prob.n; ++i) NV_Ith_S(atol, i) = opt.atol * prob.atol_scale[i];
  ready = true;
}

// The frees' flags are not checked: a destructor has no one to tell, and SUNDIALS fails them only
// for a null argument, which the guards exclude.
SundialsCommon::~SundialsCommon() {
  if (ls) SUNLinSolFree(ls);
  if (A) SUNMatDestroy(A);
  if (atol) N_VDestroy(atol);
  if (y) N_VDestroy(y);
  if (out) N_VDestroy(out);
  if (ctx) SUNContext_Free(&ctx);
}

bool SundialsCommon::make_dense_solver(int n) {
  A = SUNDenseMatrix(n, n, ctx);
  if (!check_created(A, "SUNDenseMatrix", &error)) return false;
  ls = SUNLinSol_Dense(y, A, ctx);
  return check_created(ls, "SUNLinSol_Dense", &error);
}

void SundialsCommon::load(const double* y0, int n) {
  for (int i = 0; i < n; ++i) NV_Ith_S(y, i) = y0[i];
}

void SundialsCommon::store(double* yout, int n) const {
  for (int i = 0; i < n; ++i) yout[i] = NV_Ith_S(y, i);
}

void SundialsCommon::on_error(int code, const char* module, const char* function, char* msg,
                              void* self) {
  if (code < 0) {
    static_cast<SundialsCommon*>(self)->solver_message =
        std::string(module) + "/" + function + ": " + msg;
  }
}

}  // namespace fivebar::sim::detail
