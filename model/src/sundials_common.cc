#include "sundials_common.h"

#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

namespace fivebar::sim::detail {

SundialsCommon::SundialsCommon(const OdeProblem& prob, const Options& opt) {
  SUNContext_Create(nullptr, &ctx);
  y = N_VNew_Serial(prob.n, ctx);
  N_VEnableFusedOps_Serial(y, SUNTRUE);  // fewer vector calls per step: the state is tiny
  N_VConst(0.0, y);
  out = N_VMake_Serial(prob.n, nullptr, ctx);
  atol = N_VNew_Serial(prob.n, ctx);
  for (int i = 0; i < prob.n; ++i) NV_Ith_S(atol, i) = opt.atol * prob.atol_scale[i];
}

SundialsCommon::~SundialsCommon() {
  if (ls) SUNLinSolFree(ls);
  if (A) SUNMatDestroy(A);
  N_VDestroy(atol);
  N_VDestroy(y);
  N_VDestroy(out);
  SUNContext_Free(&ctx);
}

void SundialsCommon::make_dense_solver(int n) {
  A = SUNDenseMatrix(n, n, ctx);
  ls = SUNLinSol_Dense(y, A, ctx);
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
    static_cast<SundialsCommon*>(self)->error = std::string(module) + "/" + function + ": " + msg;
  }
}

}  // namespace fivebar::sim::detail
