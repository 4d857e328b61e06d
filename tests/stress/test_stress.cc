// The stress catalogue on short durations with a few integrators: no run may fail, every
// rejection carries the exit code and a message naming its reason, and the cases test what
// their names say (Newton where the fixed point stops contracting, zero creep below breakaway).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>

#include "fivebar/model/dynamics.h"
#include "fivebar/studies/stress.h"

namespace fivebar::studies {
namespace {

using ::testing::AnyOf;
using ::testing::HasSubstr;

// zero displacement while stuck, below 1e-12 rad
constexpr double kStuckDisplacement = 1e-12;

const StressCase& find_case(const std::vector<StressCase>& cases, const std::string& name) {
  const auto it = std::find_if(cases.begin(), cases.end(),
                               [&](const StressCase& c) { return c.name == name; });
  EXPECT_NE(it, cases.end()) << name;
  return *it;
}

/// The reduced catalogue, run once for all tests (about 10 s): an implicit and an explicit
/// method per case, plus the default integrator.
const StressReport& report() {
  static const StressReport r = [] {
    StressOptions opt;
    opt.methods = {Method::kCvodeAdams, Method::kCvodeBdf, Method::kArkodeErk45};
    return run_stress(stress_catalogue(/*reduced=*/true), opt);
  }();
  return r;
}

std::map<std::string, std::vector<StressRow>> rows_by_case() {
  std::map<std::string, std::vector<StressRow>> out;
  for (const StressRow& r : report().rows) out[r.case_name].push_back(r);
  return out;
}

TEST(Stress, CatalogueHasTheIssueCases) {
  const auto cases = stress_catalogue(true);
  for (const char* name :
       {"near_singular_start", "near_singular_start_margin_1e-5", "driven_through_singularity",
        "friction_newton", "friction_no_solution", "friction_several_solutions", "tiny_inertia", "lugre_stiff", "drive_200hz",
        "long_run_60s", "unassemblable_start", "stick_below_breakaway"}) {
    const StressCase& c = find_case(cases, name);
    EXPECT_FALSE(c.description.empty()) << name;
  }
}

TEST(Stress, NoRunFails) {
  for (const StressRow& r : report().rows) {
    EXPECT_NE(r.outcome, StressOutcome::kFailed)
        << r.case_name << " / " << method_name(r.method) << ": " << r.message;
  }
}

TEST(Stress, EveryRejectionNamesItsReason) {
  for (const StressRow& r : report().rows) {
    if (r.outcome != StressOutcome::kRejected) continue;
    SCOPED_TRACE(r.case_name + " / " + method_name(r.method));
    EXPECT_THAT(r.exit_code, AnyOf(2, 3));
    EXPECT_THAT(r.message, AnyOf(HasSubstr("near-singular"), HasSubstr("cannot assemble"),
                                 HasSubstr("friction loop"), HasSubstr("max_steps"),
                                 HasSubstr("run check failed"), HasSubstr("joint modes")));
  }
}

TEST(Stress, OkRowsCarryTheirChecks) {
  for (const StressRow& r : report().rows) {
    if (r.outcome != StressOutcome::kOk) continue;
    SCOPED_TRACE(r.case_name + " / " + method_name(r.method));
    EXPECT_GE(r.error, 0.0);
    EXPECT_GE(r.energy_balance, 0.0);
    EXPECT_LE(r.energy_balance, 1e-3);
    EXPECT_EQ(r.exit_code, 0);
  }
}

TEST(Stress, ExpectedOutcomes) {
  const auto by_case = rows_by_case();
  auto all = [&](const std::string& name, StressOutcome outcome, int exit_code,
                 const std::string& reason) {
    ASSERT_TRUE(by_case.count(name)) << name;
    for (const StressRow& r : by_case.at(name)) {
      SCOPED_TRACE(name + " / " + method_name(r.method));
      EXPECT_EQ(r.outcome, outcome) << r.message;
      EXPECT_EQ(r.exit_code, exit_code);
      EXPECT_THAT(r.message, HasSubstr(reason));
    }
  };
  all("near_singular_start", StressOutcome::kRejected, 2, "near-singular");
  all("unassemblable_start", StressOutcome::kRejected, 2, "cannot assemble");
  // stops with the time and the pose
  all("driven_through_singularity", StressOutcome::kRejected, 3, "near-singular pose at theta1=");
  all("driven_through_singularity", StressOutcome::kRejected, 3, "at t=");
  all("friction_no_solution", StressOutcome::kRejected, 3, "no consistent reaction forces");
  all("friction_several_solutions", StressOutcome::kRejected, 3,
      "several consistent reaction forces");
  all("friction_newton", StressOutcome::kOk, 0, "");
  all("drive_200hz", StressOutcome::kOk, 0, "");
  all("long_run_60s", StressOutcome::kOk, 0, "");
  all("hard_drive_40", StressOutcome::kOk, 0, "");
  // the stiff LuGre case: BDF must run it
  for (const StressRow& r : by_case.at("lugre_stiff")) {
    if (r.method == Method::kCvodeBdf) EXPECT_EQ(r.outcome, StressOutcome::kOk) << r.message;
  }
}

TEST(Stress, StuckBelowBreakawayDoesNotMove) {
  const auto by_case = rows_by_case();  // (a temporary's .at() would dangle in the loop)
  for (const StressRow& r : by_case.at("stick_below_breakaway")) {
    ASSERT_EQ(r.outcome, StressOutcome::kOk) << r.message;
    EXPECT_LE(r.displacement, kStuckDisplacement) << method_name(r.method);
  }
}

// the friction_newton case is what its name says: along its motion the fixed point stops
// contracting and Newton solves the loop (iterations = max_iter + 1) at some output rows, while
// the paper's pin radius converges by the fixed point alone at the same states
TEST(Stress, FrictionNewtonCaseNeedsNewton) {
  const auto cases = stress_catalogue(true);
  const StressCase& c = find_case(cases, "friction_newton");
  const Result run = simulate(c.params, c.loads, c.initial, c.options);
  ASSERT_TRUE(run.status.ok()) << run.status.message;
  const EvalOptions eval;
  int newton = 0, paper_newton = 0;
  for (const Row& row : run.rows) {
    if (std::count(row.mode.begin(), row.mode.end(), kStuck) > 0) continue;
    Evaluation<double> ev;
    ASSERT_TRUE(forward_dynamics(c.params, c.loads(row.t), row.theta[0], row.theta[1],
                                 row.omega[0], row.omega[1], &row.mode, eval, &ev)
                    .ok());
    newton += ev.iterations > eval.friction_max_iter;
    ASSERT_TRUE(forward_dynamics(paper_params(), c.loads(row.t), row.theta[0], row.theta[1],
                                 row.omega[0], row.omega[1], &row.mode, eval, &ev)
                    .ok());
    paper_newton += ev.iterations > eval.friction_max_iter;
  }
  EXPECT_GT(newton, 0);
  EXPECT_EQ(paper_newton, 0);
}

}  // namespace
}  // namespace fivebar::studies
