// The simulator's Dormand-Prince integrator steps as ERKStep does (dormand_prince.cc): its steps
// and states are the library's ERKStepEvolve bit for bit, at every step, across a restart and a
// step limit, through rejected steps (a kinked right-hand side); its dense output, Dormand-Prince's
// own continuous extension, agrees with ERKStepGetDky's Hermite interpolant to well within the
// tolerance, as does the state at the stop time (ERKStep interpolates it). A reference ERKStep,
// set up as the simulator's, steps alongside on a seven-state system.
#include <arkode/arkode_erkstep.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "integrator.h"

namespace fivebar::sim::detail {
namespace {

constexpr int kStates = 7;
constexpr double kEnd = 3.0;
constexpr double kTol = 1e-10;

/// a smooth, nonlinear, deterministic right-hand side; `kink`: with a jump in the slope of f[3]
/// where y[1] crosses 0.2 (the error test fails there, as at a friction switch not located)
template <bool kink>
void slope(double t, const double* y, double* f) {
  f[0] = y[3];
  f[1] = y[4];
  f[2] = y[5];
  f[3] = -std::sin(y[0]) + 0.1 * y[4] * y[2] + 0.5 * std::cos(3.0 * t);
  if (kink) f[3] += 2.0 * std::abs(y[1] - 0.2);
  f[4] = -2.0 * y[1] + 0.5 * std::cos(y[2]);
  f[5] = -0.3 * y[5] + y[6] * y[0];
  f[6] = -y[6] + 0.2 * y[3] * y[3];
}
template <bool kink>
int problem_rhs(double t, const double* y, double* f, void*) {
  slope<kink>(t, y, f);
  return 0;
}
template <bool kink>
int library_rhs(realtype t, N_Vector y, N_Vector f, void*) {
  slope<kink>(t, NV_DATA_S(y), NV_DATA_S(f));
  return 0;
}

bool same_bits(const double* a, const double* b) {
  return std::memcmp(a, b, kStates * sizeof(double)) == 0;
}

double max_difference(const double* a, const double* b) {
  double d = 0.0;
  for (int i = 0; i < kStates; ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return d;
}

/// Steps the simulator's Dormand-Prince and the library's ERKStep side by side; the reference's
/// error-test failures into *rejected, the largest difference of the dense outputs into
/// *dense_diff.
template <bool kink>
void compare_with_library(long* rejected, double* dense_diff) {
  Options opt;
  opt.method = Method::kArkodeErk45;
  opt.rtol = opt.atol = kTol;
  OdeProblem prob{kStates, &problem_rhs<kink>, nullptr, std::vector<double>(kStates, 1.0), false};
  auto ours = make_arkode(prob, opt, kEnd);

  // the reference: the library's ERKStep as the simulator sets it up
  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
  std::vector<double> y(kStates, 0.0), y_ref(kStates), dense(kStates);
  y[0] = 1.0;
  y[4] = 0.5;
  N_Vector yv = N_VNew_Serial(kStates, ctx), atol = N_VNew_Serial(kStates, ctx);
  N_Vector out = N_VNew_Serial(kStates, ctx);
  N_VConst(0.0, yv);
  N_VConst(kTol, atol);
  void* ref = ERKStepCreate(&library_rhs<kink>, 0.0, yv, ctx);
  ASSERT_NE(ref, nullptr);
  ASSERT_EQ(ERKStepSetTableNum(ref, ARKODE_DORMAND_PRINCE_7_4_5), ARK_SUCCESS);
  ASSERT_EQ(ERKStepSVtolerances(ref, kTol, atol), ARK_SUCCESS);
  ASSERT_EQ(ERKStepSetMaxNumSteps(ref, opt.max_steps), ARK_SUCCESS);
  ASSERT_EQ(ERKStepSetMaxErrTestFails(ref, 20), ARK_SUCCESS);
  const auto start = [&](double t0, double h_max) {
    std::copy(y.begin(), y.end(), NV_DATA_S(yv));
    ASSERT_TRUE(ours->start(t0, y.data()));
    ASSERT_TRUE(ours->set_max_step(h_max));
    ASSERT_EQ(ERKStepReInit(ref, &library_rhs<kink>, t0, yv), ARK_SUCCESS);
    ASSERT_EQ(ERKStepSetStopTime(ref, kEnd), ARK_SUCCESS);
    ASSERT_EQ(ERKStepSetMaxStep(ref, h_max), ARK_SUCCESS);
  };
  start(0.0, 0.0);
  double t = 0.0, t_ref = 0.0;
  int steps = 0, compared = 0;
  while (t < kEnd) {
    const double tp = t;
    ASSERT_TRUE(ours->step(y.data(), &t));
    ASSERT_GE(ERKStepEvolve(ref, kEnd, yv, &t_ref, ARK_ONE_STEP), 0);
    ASSERT_EQ(t, t_ref);
    if (t < kEnd) {
      ASSERT_TRUE(same_bits(y.data(), NV_DATA_S(yv))) << "step " << steps;
    } else {
      EXPECT_LT(max_difference(y.data(), NV_DATA_S(yv)), 10 * kTol);
    }
    for (double s : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0}) {
      const double ts = tp + s * (t - tp);
      ASSERT_TRUE(ours->dense(ts, dense.data()));
      ASSERT_EQ(ERKStepGetDky(ref, ts, 0, out), ARK_SUCCESS);
      *dense_diff = std::max(*dense_diff, max_difference(dense.data(), NV_DATA_S(out)));
      ++compared;
    }
    if (++steps == 40) start(t, 0.01);  // a restart, as at a switch, with a step limit
  }
  EXPECT_GT(steps, 100);
  EXPECT_GT(compared, 600);
  EXPECT_EQ(t, kEnd);
  ASSERT_EQ(ERKStepGetNumErrTestFails(ref, rejected), ARK_SUCCESS);
  ERKStepFree(&ref);
  for (N_Vector v : {yv, atol, out}) N_VDestroy(v);
  SUNContext_Free(&ctx);
}

TEST(ErkStepper, StepsAsTheLibrary) {
  long rejected = 0;
  double dense_diff = 0.0;
  compare_with_library<false>(&rejected, &dense_diff);
  EXPECT_LT(dense_diff, 10 * kTol);  // 3.2e-10
  EXPECT_GT(dense_diff, 0.0);        // two interpolants
}

TEST(ErkStepper, StepsAsTheLibraryThroughRejectedSteps) {
  long rejected = 0;
  double dense_diff = 0.0;
  compare_with_library<true>(&rejected, &dense_diff);
  EXPECT_GT(rejected, 0);             // the kink's rejected steps were compared too
  EXPECT_LT(dense_diff, 100 * kTol);  // 6.5e-9: a kink inside a step
}

// The dense output against a run at rtol = atol = 1e-14 (its own dense output), at seven points
// of every step: at most the error of the library's Hermite interpolant (3.9e-10, against 1.3e-10
// for Dormand-Prince's own and 1.0e-10 at the steps' ends).
TEST(ErkStepper, DenseOutputAtLeastAsAccurateAsTheLibrarys) {
  Options opt;
  opt.method = Method::kArkodeErk45;
  opt.rtol = opt.atol = kTol;
  Options fine_opt = opt;
  fine_opt.rtol = fine_opt.atol = 1e-14;
  OdeProblem prob{kStates, &problem_rhs<false>, nullptr, std::vector<double>(kStates, 1.0), false};
  auto ours = make_arkode(prob, opt, kEnd);
  auto fine = make_arkode(prob, fine_opt, kEnd);
  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(nullptr, &ctx), 0);
  std::vector<double> y(kStates, 0.0), yf, d(kStates), df(kStates);
  y[0] = 1.0;
  y[4] = 0.5;
  yf = y;
  N_Vector yv = N_VNew_Serial(kStates, ctx), atol = N_VNew_Serial(kStates, ctx);
  N_Vector out = N_VNew_Serial(kStates, ctx);
  std::copy(y.begin(), y.end(), NV_DATA_S(yv));
  N_VConst(kTol, atol);
  void* ref = ERKStepCreate(&library_rhs<false>, 0.0, yv, ctx);
  ASSERT_NE(ref, nullptr);
  ASSERT_EQ(ERKStepSetTableNum(ref, ARKODE_DORMAND_PRINCE_7_4_5), ARK_SUCCESS);
  ASSERT_EQ(ERKStepSVtolerances(ref, kTol, atol), ARK_SUCCESS);
  ASSERT_EQ(ERKStepSetStopTime(ref, kEnd), ARK_SUCCESS);
  ASSERT_TRUE(ours->start(0.0, y.data()));
  ASSERT_TRUE(fine->start(0.0, yf.data()));
  double t = 0.0, t_fine = 0.0, t_ref = 0.0, error_ours = 0.0, error_library = 0.0;
  while (t < kEnd) {
    const double tp = t;
    ASSERT_TRUE(ours->step(y.data(), &t));
    ASSERT_GE(ERKStepEvolve(ref, kEnd, yv, &t_ref, ARK_ONE_STEP), 0);
    for (double s : {0.1, 0.25, 0.37, 0.5, 0.63, 0.75, 0.9}) {
      const double ts = tp + s * (t - tp);
      while (t_fine < ts) ASSERT_TRUE(fine->step(yf.data(), &t_fine));
      ASSERT_TRUE(fine->dense(ts, df.data()));
      ASSERT_TRUE(ours->dense(ts, d.data()));
      ASSERT_EQ(ERKStepGetDky(ref, ts, 0, out), ARK_SUCCESS);
      error_ours = std::max(error_ours, max_difference(d.data(), df.data()));
      error_library = std::max(error_library, max_difference(NV_DATA_S(out), df.data()));
    }
  }
  EXPECT_LE(error_ours, error_library);
  EXPECT_LT(error_ours, 2 * kTol);
  ERKStepFree(&ref);
  for (N_Vector v : {yv, atol, out}) N_VDestroy(v);
  SUNContext_Free(&ctx);
}

}  // namespace
}  // namespace fivebar::sim::detail
