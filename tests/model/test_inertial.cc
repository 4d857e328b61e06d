// The standard inertial parameters: round trip through Params, and the frictionless inverse
// dynamics is linear in them (what base-parameter identification relies on).
#include <gtest/gtest.h>

#include <random>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/inertial.h"
#include "paper.h"

namespace fivebar {
namespace {

Params<double> odd_params() {
  Params<double> p = paper_params();
  p.links[0].com_angle = 0.3;
  p.links[2].com_angle = -0.2;
  p.links[3].com_offset = 0.0;
  return p;
}

TEST(Inertial, RoundTripThroughParams) {
  const Params<double> p = odd_params();
  const auto pi = standard_inertial(p);
  EXPECT_TRUE(inertial_consistent(pi));
  Params<double> q = paper_params();
  set_standard_inertial(pi.data(), &q);
  for (int i = 0; i < kLinks; ++i) {
    EXPECT_NEAR(q.links[i].mass, p.links[i].mass, 1e-15);
    EXPECT_NEAR(q.links[i].inertia, p.links[i].inertia, 1e-15);
    EXPECT_NEAR(q.links[i].com_offset, p.links[i].com_offset, 1e-15);
    if (p.links[i].com_offset > 0) {
      EXPECT_NEAR(q.links[i].com_angle, p.links[i].com_angle, 1e-15);
    }
  }
  EXPECT_EQ(inertial_name(5), "mx_2");
}

TEST(Inertial, InconsistentParametersAreFlagged) {
  auto pi = standard_inertial(paper_params());
  pi[3] = 0.5 * pi[1] * pi[1] / pi[0];  // J_O below m c^2: negative inertia about the COM
  EXPECT_FALSE(inertial_consistent(pi));
  pi = standard_inertial(paper_params());
  pi[4] = -1.0;
  EXPECT_FALSE(inertial_consistent(pi));
}

TEST(Inertial, FrictionlessInverseDynamicsIsLinearInThem) {
  Params<double> p = odd_params();
  p.friction.law = FrictionLaw::kNone;
  const Loads<double> loads{};  // actuator torques only: tau = Y(q, w, a) pi
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  const auto pa = standard_inertial(p);
  std::array<double, kInertialParams> pb{}, pc{};
  for (int i = 0; i < kInertialParams; ++i) pb[i] = pa[i] * u(rng);
  for (int i = 0; i < kInertialParams; ++i) pc[i] = 0.3 * pa[i] + 0.7 * pb[i];
  auto tau = [&](const std::array<double, kInertialParams>& pi) {
    Params<double> q = p;
    set_standard_inertial(pi.data(), &q);
    Evaluation<double> ev;
    EXPECT_TRUE(inverse_dynamics(q, loads, 1.9, 1.2, 3.0, -2.0, 10.0, 5.0, nullptr, EvalOptions{},
                                 &ev)
                    .ok());
    return ev;
  };
  const auto ea = tau(pa), eb = tau(pb), ec = tau(pc);
  const double lin1 = 0.3 * ea.M1 + 0.7 * eb.M1, lin2 = 0.3 * ea.M2 + 0.7 * eb.M2;
  EXPECT_NEAR(ec.M1, lin1, 1e-12 * (1 + std::abs(lin1)));
  EXPECT_NEAR(ec.M2, lin2, 1e-12 * (1 + std::abs(lin2)));
}

}  // namespace
}  // namespace fivebar
