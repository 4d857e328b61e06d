// The simulator's Dormand-Prince integrator steps as ERKStep does and evaluates ERKStep's dense
// output itself (dormand_prince.cc): its steps, states and dense output are the library's
// ERKStepEvolve and ERKStepGetDky bit for bit, at every step, across a restart and a step limit,
// through rejected steps (a kinked right-hand side) and at the stop time. A reference ERKStep,
// set up as the simulator's, steps alongside on a seven-state system.
#include <arkode/arkode_erkstep.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

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

/// Steps the simulator's Dormand-Prince and the library's ERKStep side by side; the reference's
/// error-test failures into *rejected.
template <bool kink>
void compare_with_library(long* rejected) {
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
    ASSERT_TRUE(same_bits(y.data(), NV_DATA_S(yv))) << "step " << steps;
    for (double s : {0.0, 0.1, 0.37, 0.5, 0.9, 1.0}) {
      const double ts = tp + s * (t - tp);
      ASSERT_TRUE(ours->dense(ts, dense.data()));
      ASSERT_EQ(ERKStepGetDky(ref, ts, 0, out), ARK_SUCCESS);
      EXPECT_TRUE(same_bits(dense.data(), NV_DATA_S(out))) << "step " << steps << ", s = " << s;
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

TEST(ErkDenseOutput, IsTheLibrarysBitForBit) {
  long rejected = 0;
  compare_with_library<false>(&rejected);
}

TEST(ErkDenseOutput, StepsAsTheLibraryThroughRejectedSteps) {
  long rejected = 0;
  compare_with_library<true>(&rejected);
  EXPECT_GT(rejected, 0);  // the kink's rejected steps were compared too
}

}  // namespace
}  // namespace fivebar::sim::detail
