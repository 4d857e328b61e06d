// The implicit derivative of the friction loop (friction_loop.h, EvalOptions::
// implicit_loop_derivative): Jets through inverse and forward dynamics, differentiated by one
// Newton step at the double solution, against the whole loop iterated in Jets and against
// central differences, where joints slip, where they are stuck (rest rule, forward modes,
// locked) and near lock (the fixed point stops contracting and Newton solves the loop).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "fivebar/model/dynamics.h"
#include "paper.h"

namespace fivebar {
namespace {

using Jet6 = ceres::Jet<double, 6>;
// the two derivatives differ by the loop's tolerance (1e-13) times the conditioning
constexpr double kValueTol = 1e-12;
constexpr double kDerivativeTol = 1e-9;

using State6 = testing::MotionState;

EvalOptions reference_options(EvalOptions o) {
  o.implicit_loop_derivative = false;
  return o;
}

void expect_same(const Jet6& implicit, const Jet6& full, const char* what) {
  const double scale = 1.0 + std::abs(full.a) + full.v.cwiseAbs().maxCoeff();
  EXPECT_NEAR(implicit.a, full.a, kValueTol * scale) << what;
  for (int m = 0; m < 6; ++m) {
    EXPECT_NEAR(implicit.v[m], full.v[m], kDerivativeTol * scale) << what << " d/dx" << m;
  }
}

void expect_same(const Evaluation<Jet6>& a, const Evaluation<Jet6>& b) {
  // both by the fixed point, or both by the Newton fallback (the double loop reaches a
  // contracting fixed point in fewer iterations than the loop iterated in Jets)
  const int fixed_point_limit = EvalOptions{}.friction_max_iter;
  EXPECT_EQ(a.iterations > fixed_point_limit, b.iterations > fixed_point_limit);
  EXPECT_EQ(a.slip, b.slip);
  expect_same(a.M1, b.M1, "M1");
  expect_same(a.M2, b.M2, "M2");
  expect_same(a.thdd[0], b.thdd[0], "alpha1");
  expect_same(a.thdd[1], b.thdd[1], "alpha2");
  expect_same(a.P_diss, b.P_diss, "P_diss");
  for (int k = 0; k < kJoints; ++k) {
    expect_same(a.N[k], b.N[k], "N");
    expect_same(a.Mf[k], b.Mf[k], "Mf");
    expect_same(a.F[k].x(), b.F[k].x(), "Fx");
    expect_same(a.hold_margin[k], b.hold_margin[k], "hold_margin");
  }
}

// inverse dynamics with the state seeded (derivative m: d / d state[m])
Status inverse6(const Params<Jet6>& p, const Loads<double>& L, const State6& s,
                const JointModes* slip, const EvalOptions& o, Evaluation<Jet6>* ev) {
  return inverse_dynamics(p, L.cast<Jet6>(), Jet6(s.th1, 0), Jet6(s.th2, 1), Jet6(s.w1, 2),
                          Jet6(s.w2, 3), Jet6(s.a1, 4), Jet6(s.a2, 5), slip, o, ev);
}

// the paper scene with parameters seeded: l3 mass, r_2, mu_c,3, gravity, M3 and F
Status forward6(const Params<double>& pd, const Loads<double>& Ld, const State6& s,
                const JointModes* slip, const EvalOptions& o, Evaluation<Jet6>* ev) {
  Params<Jet6> p = pd.cast<Jet6>();
  Loads<Jet6> L = Ld.cast<Jet6>();
  p.links[2].mass.v[0] = 1.0;
  p.friction.pin_radius[1].v[1] = 1.0;
  p.friction.coulomb[2].v[2] = 1.0;
  p.gravity.v[3] = 1.0;
  L.M3.v[4] = 1.0;
  L.F.v[5] = 1.0;
  return forward_dynamics(p, L, Jet6(s.th1), Jet6(s.th2), Jet6(s.w1), Jet6(s.w2), slip, o, ev);
}

Params<double> with_actuators(Params<double> p) {
  p.actuators.coulomb = {0.05, 0.03};
  p.actuators.viscous = {0.002, 0.001};
  return p;
}

TEST(ImplicitLoop, SlippingJointsMatchTheJetIteration) {
  for (const Params<double>& pd : {paper_params(), with_actuators(paper_params())}) {
    const Params<Jet6> p = pd.cast<Jet6>();
    for (const auto& r : testing::random_states(pd, 40, 12)) {
      const State6 s{r.th1, r.th2, r.w1, r.w2, 50.0 * r.loads.M1, -30.0 * r.loads.M2};
      Evaluation<Jet6> a, b;
      ASSERT_TRUE(inverse6(p, r.loads, s, nullptr, EvalOptions{}, &a).ok());
      ASSERT_TRUE(inverse6(p, r.loads, s, nullptr, reference_options({}), &b).ok());
      expect_same(a, b);
      ASSERT_TRUE(forward6(pd, r.loads, s, nullptr, EvalOptions{}, &a).ok());
      ASSERT_TRUE(forward6(pd, r.loads, s, nullptr, reference_options({}), &b).ok());
      expect_same(a, b);
    }
  }
}

TEST(ImplicitLoop, StuckJointsMatchTheJetIteration) {
  const Params<double> pd = paper_params();
  const Params<Jet6> p = pd.cast<Jet6>();
  const Loads<double> L = testing::paper_loads(0.2);
  // inverse: crank 1 at rest and not accelerating is stuck under the rest rule
  EvalOptions rest;
  rest.rest_rate = 1e-3;
  rest.rest_acceleration = 1e-2;
  Evaluation<Jet6> a, b;
  const State6 still{2.0, 1.1, 0.0, 4.0, 0.0, -3.0};
  ASSERT_TRUE(inverse6(p, L, still, nullptr, rest, &a).ok());
  ASSERT_TRUE(inverse6(p, L, still, nullptr, reference_options(rest), &b).ok());
  EXPECT_EQ(a.slip[0], kStuck);
  expect_same(a, b);
  // forward: joint O stuck (one constraint), then O and D0 (locked)
  const State6 s{2.0, 1.1, 0.0, 0.0, 0.0, 0.0};
  JointModes one{kStuck, JointMode::kRest, JointMode::kRest, JointMode::kRest,
                 JointMode::kRest};
  JointModes two = one;
  two[4] = kStuck;
  for (const JointModes* modes : {&one, &two}) {
    ASSERT_TRUE(forward6(pd, L, s, modes, EvalOptions{}, &a).ok());
    ASSERT_TRUE(forward6(pd, L, s, modes, reference_options({}), &b).ok());
    expect_same(a, b);
  }
  // forward with one joint stuck and the others slipping
  const State6 moving{2.0, 1.1, 0.0, 6.0, 0.0, 0.0};
  ASSERT_TRUE(forward6(pd, L, moving, &one, EvalOptions{}, &a).ok());
  ASSERT_TRUE(forward6(pd, L, moving, &one, reference_options({}), &b).ok());
  expect_same(a, b);
}

// d/dw1 of the accelerations by central differences of the double model
Vec2<double> central_difference(const std::function<Vec2<double>(double)>& f) {
  constexpr double h = 1e-6;
  return (f(h) - f(-h)) / (2 * h);
}

TEST(ImplicitLoop, NearLockNewtonSolutionMatchesJetsAndDifferences) {
  Params<double> pd = paper_params();
  pd.friction.pin_radius.fill(0.15);  // the fixed point stalls: Newton solves the loop
  const Loads<double> L = testing::paper_loads(0.3);
  const State6 s{2.0, 1.0, 30.0, -20.0, 0.0, 0.0};
  Evaluation<Jet6> a, b;
  ASSERT_TRUE(forward6(pd, L, s, nullptr, EvalOptions{}, &a).ok());
  ASSERT_TRUE(forward6(pd, L, s, nullptr, reference_options({}), &b).ok());
  EXPECT_GT(a.iterations, EvalOptions{}.friction_max_iter);  // the Newton path
  expect_same(a, b);
  // the same point seeded in w1: implicit derivative against central differences
  const Params<Jet6> p = pd.cast<Jet6>();
  Evaluation<Jet6> j;
  ASSERT_TRUE(forward_dynamics(p, L.cast<Jet6>(), Jet6(s.th1), Jet6(s.th2), Jet6(s.w1, 0),
                               Jet6(s.w2), nullptr, EvalOptions{}, &j)
                  .ok());
  const Vec2<double> fd = central_difference([&](double h) {
    Evaluation<double> e;
    EXPECT_TRUE(forward_dynamics(pd, L, s.th1, s.th2, s.w1 + h, s.w2, nullptr, EvalOptions{}, &e)
                    .ok());
    return e.thdd;
  });
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(j.thdd[i].v[0], fd[i], 1e-6 * (1 + std::abs(fd[i])));
  // and the inverse dynamics of those accelerations, near lock as well
  const State6 si{2.0, 1.0, 30.0, -20.0, value_of(a.thdd[0]), value_of(a.thdd[1])};
  ASSERT_TRUE(inverse6(p, L, si, nullptr, EvalOptions{}, &a).ok());
  ASSERT_TRUE(inverse6(p, L, si, nullptr, reference_options({}), &b).ok());
  expect_same(a, b);
}

// the implicit path reports the loop's failure as the Jet iteration does
TEST(ImplicitLoop, NoConsistentReactionsFailsTheSameWay) {
  Params<double> pd = paper_params();
  pd.friction.pin_radius.fill(0.5);
  const State6 s{2.0, 1.0, 30.0, -20.0, 0.0, 0.0};
  Evaluation<Jet6> a, b;
  const Status sa = forward6(pd, testing::paper_loads(0.3), s, nullptr, EvalOptions{}, &a);
  const Status sb =
      forward6(pd, testing::paper_loads(0.3), s, nullptr, reference_options({}), &b);
  EXPECT_EQ(sa.code, StatusCode::kFrictionNotConverged);
  EXPECT_EQ(sa.code, sb.code);
}

}  // namespace
}  // namespace fivebar
