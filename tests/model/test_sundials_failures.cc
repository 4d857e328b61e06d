// SUNDIALS failures reach the caller as a status whose message names the failed call and the
// flag by its SUNDIALS name (CV_..., ARK_...), with what it means for a scene (sundials_status.cc),
// for every integrator: never a crash, a print or "flag -N".
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

bool is_cvode(sim::Method m) {
  return m == sim::Method::kCvodeAdams || m == sim::Method::kCvodeBdf;
}

/// The call that sets the tolerances, as the message names it.
std::string tolerance_call(sim::Method m) {
  if (is_cvode(m)) return "CVodeSVtolerances";
  return m == sim::Method::kArkodeDirk ? "ARKStepSVtolerances" : "ERKStepSVtolerances";
}

sim::Result run(sim::Method m, double rtol, double atol) {
  sim::Options o;
  o.method = m;
  o.rtol = rtol;
  o.atol = atol;
  o.duration = 0.05;
  return sim::simulate(paper_params(), testing::paper_loads, testing::paper_initial(), o);
}

class SundialsFailure : public ::testing::TestWithParam<sim::Method> {};

// A negative relative tolerance is refused at set-up (CV_ILL_INPUT / ARK_ILL_INPUT): the run
// stops at t = 0 with that flag's name, the error handler's text and the hint.
TEST_P(SundialsFailure, RefusedToleranceNamesCallAndFlag) {
  const sim::Method m = GetParam();
  const sim::Result r = run(m, -1e-8, 1e-10);
  ASSERT_FALSE(r.status.ok());
  EXPECT_EQ(r.status.code, StatusCode::kSolverFailed);
  const std::string& msg = r.status.message;
  EXPECT_THAT(msg, HasSubstr(tolerance_call(m) + " returned " +
                             (is_cvode(m) ? "CV_ILL_INPUT" : "ARK_ILL_INPUT")));
  EXPECT_THAT(msg, HasSubstr("reltol < 0 illegal"));  // the handler's text
  EXPECT_THAT(msg, HasSubstr("SUNDIALS rejected a setting"));
  EXPECT_THAT(msg, Not(HasSubstr("flag -")));
  EXPECT_EQ(r.rows.size(), 1u);
}

// Tolerances below double precision fail in the first steps (CV_TOO_MUCH_ACC /
// ARK_TOO_MUCH_ACC): a failure of the integration itself, named the same way.
TEST_P(SundialsFailure, UnreachableToleranceNamesFlag) {
  const sim::Method m = GetParam();
  const sim::Result r = run(m, 1e-300, 1e-300);
  ASSERT_FALSE(r.status.ok());
  EXPECT_EQ(r.status.code, StatusCode::kSolverFailed);
  const std::string& msg = r.status.message;
  EXPECT_THAT(msg, HasSubstr(is_cvode(m) ? "CV_TOO_MUCH_ACC" : "ARK_TOO_MUCH_ACC"));
  EXPECT_THAT(msg, HasSubstr("loosen simulation.rtol/atol"));
  EXPECT_THAT(msg, Not(HasSubstr("flag -")));
}

INSTANTIATE_TEST_SUITE_P(AllMethods, SundialsFailure, ::testing::ValuesIn(sim::kAllMethods),
                         [](const ::testing::TestParamInfo<sim::Method>& info) {
                           return std::string(sim::method_name(info.param));
                         });

}  // namespace
}  // namespace fivebar
