// ceres::Jet through the templated model: d tau / d thdd equals the mass matrix A (Pinocchio's
// check), and other derivatives against central differences.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"
#include "paper.h"

namespace fivebar {
namespace {

using Jet2 = ceres::Jet<double, 2>;
// Jet derivatives are exact to roundoff; differences with h = 1e-6 carry ~1e-9 relative error
constexpr double kExactTol = 1e-10;
constexpr double kDifferenceTol = 1e-6;

using Pose = testing::MotionState;
const Pose kPoses[] = {{M_PI / 2, M_PI / 2, 3.0, -4.0, 20.0, -7.0},
                       {2.1, 0.9, -12.0, 25.0, -40.0, 60.0},
                       {0.7, 1.9, 30.0, 8.0, 5.0, 15.0}};

TEST(Jet, InverseDynamicsDerivativeInAccelerationsIsTheMassMatrix) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kNone;
  const Params<Jet2> pj = p.cast<Jet2>();
  const Loads<Jet2> lj = testing::paper_loads(0.1).cast<Jet2>();
  for (const Pose& s : kPoses) {
    Evaluation<Jet2> inv;
    ASSERT_TRUE(inverse_dynamics(pj, lj, Jet2(s.th1), Jet2(s.th2), Jet2(s.w1), Jet2(s.w2),
                                 Jet2(s.a1, 0), Jet2(s.a2, 1), nullptr, EvalOptions{}, &inv)
                    .ok());
    Evaluation<double> fwd;
    ASSERT_TRUE(forward_dynamics(p, testing::paper_loads(0.1), s.th1, s.th2, s.w1, s.w2, nullptr,
                                 EvalOptions{}, &fwd)
                    .ok());
    for (int m = 0; m < 2; ++m) {
      EXPECT_NEAR(inv.M1.v[m], fwd.A(0, m), kExactTol);
      EXPECT_NEAR(inv.M2.v[m], fwd.A(1, m), kExactTol);
    }
  }
}

TEST(Jet, InverseDynamicsWithFrictionMatchesCentralDifferences) {
  const Params<double> p = paper_params();
  const Loads<double> L = testing::paper_loads(0.3);
  constexpr double h = 1e-6;
  for (const Pose& s : kPoses) {
    Evaluation<Jet2> inv;
    ASSERT_TRUE(inverse_dynamics(p.cast<Jet2>(), L.cast<Jet2>(), Jet2(s.th1), Jet2(s.th2),
                                 Jet2(s.w1), Jet2(s.w2), Jet2(s.a1, 0), Jet2(s.a2, 1), nullptr,
                                 EvalOptions{}, &inv)
                    .ok());
    for (int m = 0; m < 2; ++m) {
      Evaluation<double> plus, minus;
      const double da1 = m == 0 ? h : 0.0, da2 = m == 1 ? h : 0.0;
      inverse_dynamics(p, L, s.th1, s.th2, s.w1, s.w2, s.a1 + da1, s.a2 + da2, nullptr,
                       EvalOptions{}, &plus);
      inverse_dynamics(p, L, s.th1, s.th2, s.w1, s.w2, s.a1 - da1, s.a2 - da2, nullptr,
                       EvalOptions{}, &minus);
      EXPECT_NEAR(inv.M1.v[m], (plus.M1 - minus.M1) / (2 * h), kDifferenceTol);
      EXPECT_NEAR(inv.M2.v[m], (plus.M2 - minus.M2) / (2 * h), kDifferenceTol);
    }
  }
}

// derivatives of the forward accelerations with respect to parameters: the shared Coulomb
// coefficient (through the friction loop) and the length of link 3 (through the kinematics)
TEST(Jet, ForwardDynamicsParameterDerivativesMatchCentralDifferences) {
  const Params<double> p = paper_params();
  const Loads<double> L = testing::paper_loads(0.2);
  constexpr double h = 1e-6;
  auto with = [&](double coulomb, double l3) {
    Params<double> q = p;
    q.friction.coulomb.fill(coulomb);
    q.links[2].length = l3;
    return q;
  };
  for (const Pose& s : kPoses) {
    Params<Jet2> pj = p.cast<Jet2>();
    for (auto& c : pj.friction.coulomb) c = Jet2(c.a, 0);
    pj.links[2].length = Jet2(p.links[2].length, 1);
    Evaluation<Jet2> ev;
    ASSERT_TRUE(forward_dynamics(pj, L.cast<Jet2>(), Jet2(s.th1), Jet2(s.th2), Jet2(s.w1),
                                 Jet2(s.w2), nullptr, EvalOptions{}, &ev)
                    .ok());
    const double c0 = p.friction.coulomb[0], l30 = p.links[2].length;
    for (int m = 0; m < 2; ++m) {
      Evaluation<double> plus, minus;
      const Params<double> pp = m == 0 ? with(c0 + h, l30) : with(c0, l30 + h);
      const Params<double> pm = m == 0 ? with(c0 - h, l30) : with(c0, l30 - h);
      ASSERT_TRUE(forward_dynamics(pp, L, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &plus).ok());
      ASSERT_TRUE(forward_dynamics(pm, L, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &minus).ok());
      for (int a = 0; a < 2; ++a) {
        const double fd = (plus.thdd[a] - minus.thdd[a]) / (2 * h);
        EXPECT_NEAR(ev.thdd[a].v[m], fd, kDifferenceTol * (1 + std::abs(fd)));
      }
    }
  }
}

// add_scaled (the Jet pass's update of the reactions) is x + c y of Jets bit for bit: the same
// products and sums, the value and every derivative
TEST(Jet, AddScaledIsTheJetsSumBitForBit) {
  using Jet6 = ceres::Jet<double, 6>;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  for (int trial = 0; trial < 200; ++trial) {
    Jet6 x(u(rng)), y(u(rng));
    for (int i = 0; i < 6; ++i) x.v[i] = u(rng), y.v[i] = u(rng);
    const double c = u(rng) * std::pow(10.0, u(rng));
    const Jet6 expected = x + c * y;
    add_scaled(&x, c, y);
    EXPECT_EQ(x.a, expected.a);
    for (int i = 0; i < 6; ++i) EXPECT_EQ(x.v[i], expected.v[i]) << "derivative " << i;
  }
}

}  // namespace
}  // namespace fivebar
