// The power_viscous law, the test of the friction-law descriptors: with
// n = 1 it is the paper's law exactly; with n = 0.5 friction never supplies power on a run with
// reversals and sticks; its Jet derivative in mu_v matches a difference.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/friction.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

Params<double> power_law(double n) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kPowerViscous;
  p.friction.viscous_exponent.fill(n);
  p.friction.viscous.fill(0.05);
  return p;
}

TEST(PowerViscous, ExponentOneIsTheCoulombViscousLaw) {
  Params<double> cv = power_law(1.0);
  cv.friction.law = FrictionLaw::kCoulombViscous;
  sim::Options o;
  o.duration = 0.5;
  const sim::Result a = sim::simulate(power_law(1.0), testing::paper_loads, testing::paper_initial(), o);
  const sim::Result b = sim::simulate(cv, testing::paper_loads, testing::paper_initial(), o);
  ASSERT_TRUE(a.status.ok()) << a.status.message;
  ASSERT_TRUE(b.status.ok()) << b.status.message;
  EXPECT_EQ(sim::max_angle_difference(a.rows, b.rows), 0.0);
}

// A library caller who only switches the law of paper_params() (leaving n at FrictionParams'
// default) gets the law a scene that omits viscous_exponent gets: n = 1, the linear law, not
// mu_v sign(w) (which an exponent defaulted to 0 would give).
TEST(PowerViscous, DefaultExponentIsTheDescriptorsAndLinear) {
  Params<double> pv = paper_params();
  pv.friction.law = FrictionLaw::kPowerViscous;
  for (double n : pv.friction.viscous_exponent) {
    EXPECT_EQ(n, coefficient_info(Coefficient::kViscousExponent).default_value);
  }
  for (int k = 0; k < kJoints; ++k) {
    for (double w : {-2.5, -0.3, 0.7, 4.0}) {
      EXPECT_EQ(friction_law(pv.friction, k, w, sign_of(w)),
                friction_law(paper_params().friction, k, w, sign_of(w)))
          << "joint " << k << ", w = " << w;
    }
  }
}

// Every coefficient that a scene may omit starts, in a default FrictionParams, at the value the
// descriptors give for an omitted key (those that default to another coefficient aside).
TEST(FrictionDescriptors, FrictionParamsDefaultsAreTheDescriptors) {
  const FrictionParams<double> fp;
  for (const CoefficientInfo& c : kCoefficientInfo) {
    if (c.same_as != c.id) continue;
    for (double v : coefficient(fp, c.id)) EXPECT_EQ(v, c.default_value) << c.key;
  }
}

// The simulator's exact-sign test and state layout come from the descriptor: laws with a sign
// jump have no internal state, LuGre has one per joint and no sign jump.
TEST(FrictionDescriptors, SignJumpAndInternalStates) {
  for (const LawDescriptor& d : kLaws) {
    FrictionParams<double> fp;
    fp.law = d.law;
    EXPECT_EQ(exact_sign(fp), d.coulomb_sign) << d.name;
    fp.smoothing_velocity = 0.01;
    EXPECT_FALSE(exact_sign(fp)) << d.name;
    EXPECT_LE(d.states_per_joint, kMaxStatesPerJoint) << d.name;
    if (d.coulomb_sign) {
      EXPECT_EQ(d.states_per_joint, 0) << d.name;
    }
  }
  EXPECT_EQ(law_descriptor(FrictionLaw::kLuGre).states_per_joint, 1);
  EXPECT_FALSE(law_descriptor(FrictionLaw::kNone).coulomb_sign);
}

TEST(PowerViscous, FrictionNeverSuppliesPower) {
  const Params<double> p = power_law(0.5);
  sim::Options o;
  o.duration = 1.0;
  o.full_rows = true;
  const sim::Result r = sim::simulate(p, testing::paper_loads, testing::paper_initial(), o);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const sim::RunChecks checks = sim::check_run(p, testing::paper_loads, r);
  EXPECT_TRUE(checks.verdict.ok()) << checks.verdict.message;
  EXPECT_GE(checks.friction_power_min, -1e-9);
  EXPECT_GT(r.stats.friction_events, 0);
  // and it is not the linear law: the motions differ
  const sim::Result lin = sim::simulate(power_law(1.0), testing::paper_loads,
                                        testing::paper_initial(), o);
  EXPECT_GT(sim::max_angle_difference(r.rows, lin.rows), 1e-4);
}

TEST(PowerViscous, JetDerivativeInTheViscousCoefficient) {
  using Jet1 = ceres::Jet<double, 1>;
  const Params<double> p = power_law(0.5);
  Params<Jet1> pj = p.cast<Jet1>();
  for (auto& v : pj.friction.viscous) v.v[0] = 1.0;  // d / d mu_v (shared)
  const double th1 = 1.9, th2 = 1.2, w1 = 3.0, w2 = -2.0, a1 = 10.0, a2 = 5.0;
  Evaluation<Jet1> ej;
  ASSERT_TRUE(inverse_dynamics(pj, testing::paper_loads(0.1).cast<Jet1>(), Jet1(th1), Jet1(th2),
                               Jet1(w1), Jet1(w2), Jet1(a1), Jet1(a2), nullptr, EvalOptions{}, &ej)
                  .ok());
  const double h = 1e-6;
  auto torque = [&](double mu_v) {
    Params<double> q = p;
    q.friction.viscous.fill(mu_v);
    Evaluation<double> ev;
    EXPECT_TRUE(inverse_dynamics(q, testing::paper_loads(0.1), th1, th2, w1, w2, a1, a2, nullptr,
                                 EvalOptions{}, &ev)
                    .ok());
    return ev.M1;
  };
  const double fd = (torque(0.05 + h) - torque(0.05 - h)) / (2 * h);
  EXPECT_NEAR(ej.M1.v[0], fd, 1e-6 * (1 + std::abs(fd)));
}

}  // namespace
}  // namespace fivebar
