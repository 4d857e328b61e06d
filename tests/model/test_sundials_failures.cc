// SUNDIALS failures reach the caller as a status whose message names the failed call and the
// flag by its SUNDIALS name (CV_..., ARK_...), with what it means for a scene (sundials_status.cc),
// for every integrator: never a crash, a print or "flag -N".
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
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

// A load that leaves its domain mid-run (sqrt(0.02 - t) after 0.02 s) stops the run there,
// naming the load and the time, for every integrator: not after simulation.max_steps of retried
// steps, nor blamed on the friction loop (rows: the ones before 0.02 s only)
TEST_P(SundialsFailure, ANonFiniteLoadStopsTheRunAndIsNamed) {
  sim::Options o;
  o.method = GetParam();
  o.duration = 0.05;
  const sim::LoadFunction loads = [](double t) {
    Loads<double> L = testing::paper_loads(t);
    L.M3 = std::sqrt(0.02 - t);
    return L;
  };
  const sim::Result r = sim::simulate(paper_params(), loads, testing::paper_initial(), o);
  ASSERT_FALSE(r.status.ok());
  EXPECT_THAT(r.status.message, HasSubstr("load M3 = "));
  EXPECT_THAT(r.status.message, HasSubstr(" at t=0.02"));
  EXPECT_THAT(r.status.message, HasSubstr("is not finite"));
  EXPECT_THAT(r.status.message, Not(HasSubstr("friction loop")));
  EXPECT_LE(r.rows.size(), 21u);
}

INSTANTIATE_TEST_SUITE_P(AllMethods, SundialsFailure, ::testing::ValuesIn(sim::kAllMethods),
                         [](const ::testing::TestParamInfo<sim::Method>& info) {
                           return std::string(sim::method_name(info.param));
                         });

}  // namespace
}  // namespace fivebar
