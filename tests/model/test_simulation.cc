// The simulator against datasets/reference (independent Newton-Euler + RK8 trajectories), the
// energy balance, and inverse dynamics of the simulated run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

using testing::paper_initial;
using testing::paper_loads;

// the accuracy at default settings: max |d theta| <= 1e-6 rad
constexpr double kDefaultAccuracy = 1e-6;
// energy balance and inverse dynamics close to 1e-8 at defaults
constexpr double kBalanceTol = 1e-8;
constexpr double kInverseTol = 1e-8;

double max_theta_error(const sim::Result& r, const std::string& ref_name) {
  const auto ref = testing::read_csv(testing::reference_path(ref_name));
  const auto& t = ref.at("t");
  double worst = 0.0;
  size_t matched = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    const long j = std::lround(t[i] / 1e-3);
    if (j < 0 || j >= static_cast<long>(r.rows.size())) continue;
    ++matched;
    for (int k = 0; k < 4; ++k) {
      const double d = std::abs(r.rows[j].theta[k] - ref.at("theta" + std::to_string(k + 1))[i]);
      worst = std::max(worst, d);
    }
  }
  EXPECT_EQ(matched, t.size());
  return worst;
}

class PaperScene : public ::testing::TestWithParam<bool> {};

TEST_P(PaperScene, MatchesReferenceAtDefaults) {
  const bool friction = GetParam();
  Params<double> p = paper_params();
  if (!friction) p.friction.law = FrictionLaw::kNone;
  const sim::LoadFunction loads = paper_loads;
  const sim::Result r = sim::simulate(p, loads, paper_initial(), sim::Options{});
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  ASSERT_EQ(r.rows.size(), 2001u);
  const double err =
      max_theta_error(r, friction ? "paper_friction.csv" : "paper_frictionless.csv");
  EXPECT_LE(err, kDefaultAccuracy);
  const sim::RunChecks checks = sim::check_run(p, loads, r);
  EXPECT_LE(checks.energy_balance_relative, kBalanceTol);
  EXPECT_LE(checks.inverse_dynamics_max_abs_error, kInverseTol);
  if (friction) {
    EXPECT_EQ(r.stats.friction_events, 11);  // reference README: 11 switches over 2 s
  } else {
    EXPECT_EQ(r.stats.friction_events, 0);
  }
  std::printf("[ info ] friction=%d err=%.3e balance=%.3e inverse=%.3e rhs=%ld steps=%ld "
              "events=%ld wall=%.4f s\n",
              friction, err, checks.energy_balance_relative,
              checks.inverse_dynamics_max_abs_error, r.stats.rhs_evaluations, r.stats.steps,
              r.stats.friction_events, r.stats.wall_time_s);
}

INSTANTIATE_TEST_SUITE_P(WithAndWithoutFriction, PaperScene, ::testing::Bool());

}  // namespace
}  // namespace fivebar

namespace fivebar {
namespace {

// with the documented tight settings <= 1e-8 rad (README: cvode_adams, rtol = atol = 1e-13)
TEST(PaperSceneTight, MatchesReferenceToTenNanoradians) {
  for (bool friction : {false, true}) {
    Params<double> p = paper_params();
    if (!friction) p.friction.law = FrictionLaw::kNone;
    sim::Options opt;
    opt.rtol = opt.atol = 1e-13;
    const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), opt);
    ASSERT_TRUE(r.status.ok()) << r.status.message;
    EXPECT_LE(max_theta_error(r, friction ? "paper_friction.csv" : "paper_frictionless.csv"),
              1e-8);
  }
}

// Dormand-Prince's last stage is the step's end: the evaluation ARKODE repeats there (for the
// next step's first stage and the interpolant) comes from the last one, so a step costs its six
// new stages and about one for the interpolant (9.6 evaluations per step here when every repeat
// was evaluated again); the run still matches the reference
TEST(PaperSceneErk45, EvaluatesTheStepEndOnce) {
  sim::Options opt;
  opt.method = sim::Method::kArkodeErk45;
  opt.rtol = opt.atol = 1e-10;
  const sim::Result r = sim::simulate(paper_params(), paper_loads, paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  EXPECT_LT(r.stats.rhs_evaluations, 8 * r.stats.steps);
  EXPECT_LE(max_theta_error(r, "paper_friction.csv"), 3e-8);
}

// the paper scene with LuGre friction and stiff bristles (sigma0 = 1e4 / rad)
Params<double> stiff_lugre() {
  return testing::with_law(paper_params(), FrictionLaw::kLuGre,
                           {{Coefficient::kSigma0, 1e4},
                            {Coefficient::kSigma1, 100.0},
                            {Coefficient::kSigma2, 0.02},
                            {Coefficient::kStaticCoulomb, 0.12}});
}

// LuGre with stiff bristles (sigma0 = 1e4 / rad) on the paper scene: BDF integrates it, the
// mechanical energy balance closes (E_diss is then the work absorbed by the friction elements,
// dissipated or stored in the bristles), and the motion stays near the Coulomb-viscous one
TEST(LuGre, StiffBristlesIntegrateWithBdfAndBalanceEnergy) {
  const Params<double> p = stiff_lugre();
  sim::Options opt;
  opt.duration = 0.5;
  opt.method = sim::Method::kCvodeBdf;
  opt.rtol = opt.atol = 1e-9;
  const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const sim::RunChecks checks = sim::check_run(p, testing::paper_loads, r);
  EXPECT_LT(checks.energy_balance_relative, 1e-6);
  sim::Options copt = opt;
  copt.method = sim::Method::kCvodeAdams;
  const sim::Result coulomb =
      sim::simulate(paper_params(), testing::paper_loads, testing::paper_initial(), copt);
  ASSERT_TRUE(coulomb.status.ok());
  const double diff = sim::max_angle_difference(r.rows, coulomb.rows);
  EXPECT_LT(diff, 0.05);
  std::printf("[ info ] lugre: steps=%ld rhs=%ld balance=%.2e |theta - theta_coulomb|=%.2e\n",
              r.stats.steps, r.stats.rhs_evaluations, checks.energy_balance_relative, diff);
}

// a caller that leaves the integrator unset gets the law's: BDF for LuGre (the same run, row for
// row, as BDF asked for), Adams otherwise
TEST(LuGre, DefaultIntegratorIsBdf) {
  EXPECT_EQ(sim::default_method(FrictionLaw::kLuGre), sim::Method::kCvodeBdf);
  for (FrictionLaw law : {FrictionLaw::kNone, FrictionLaw::kCoulombViscous, FrictionLaw::kStribeck})
    EXPECT_EQ(sim::default_method(law), sim::Method::kCvodeAdams) << int(law);
  const Params<double> p = stiff_lugre();
  sim::Options unset;
  unset.duration = 0.05;
  unset.rtol = unset.atol = 1e-8;
  EXPECT_FALSE(unset.method.has_value());
  EXPECT_EQ(sim::method_of(unset, FrictionLaw::kLuGre), sim::Method::kCvodeBdf);
  sim::Options bdf = unset, adams = unset;
  bdf.method = sim::Method::kCvodeBdf;
  adams.method = sim::Method::kCvodeAdams;
  const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), unset);
  const sim::Result rb = sim::simulate(p, testing::paper_loads, testing::paper_initial(), bdf);
  const sim::Result ra = sim::simulate(p, testing::paper_loads, testing::paper_initial(), adams);
  ASSERT_TRUE(r.status.ok() && rb.status.ok()) << r.status.message << rb.status.message;
  EXPECT_EQ(r.stats.steps, rb.stats.steps);
  EXPECT_EQ(r.stats.rhs_evaluations, rb.stats.rhs_evaluations);
  EXPECT_EQ(sim::max_angle_difference(r.rows, rb.rows), 0.0);
  EXPECT_NE(r.stats.rhs_evaluations, ra.stats.rhs_evaluations);  // Adams is another run
}

}  // namespace
}  // namespace fivebar
