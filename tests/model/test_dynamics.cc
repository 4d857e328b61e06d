// The Appell model against an independent Newton-Euler evaluation in maximal coordinates, inverse
// of forward, energy conservation and dissipation, and the friction loop's failure status.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/five_bar_chain.h"
#include "fivebar/model/planar_chain.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

// independent formulation solved by a 22x22 QR: agreement to roundoff of O(100) quantities
constexpr double kCrossCheckTol = 1e-9;

using State = testing::RandomState;
using testing::random_states;

/// Newton-Euler in maximal coordinates by the general planar chain (planar_chain.h) over the
/// five-bar's joint table: unknowns are the 4 link accelerations (a_cx, a_cy, alpha) and the 5
/// joint forces; equations are the 12 body equations about the centres of mass and the 10
/// acceleration constraints of the pins. Friction by a fixed point on |F_k|. Only the pose
/// (th3, th4) comes from the model, and its closure is checked in test_kinematics; the coupler
/// rates come from the chain's own velocity closure.
struct NewtonEuler {
  Eigen::Vector2d thdd;
  std::array<double, 5> N;
};

NewtonEuler newton_euler(const Params<double>& p, const State& s) {
  Kinematics<double> k;
  EXPECT_TRUE(solve_kinematics(p, s.th1, s.th2, &k).ok());
  const chain::Chain c = five_bar_chain(p);
  const chain::Pose q = five_bar_pose(p, k);
  std::vector<double> rate;
  EXPECT_TRUE(chain::body_rates(c, q, {s.w1, s.w2}, &rate).ok());
  chain::Solution sol;
  EXPECT_TRUE(chain::solve(c, q, rate, five_bar_loads(p, k, s.loads), nullptr, {}, &sol).ok());
  NewtonEuler out{Eigen::Vector2d(sol.alpha[0], sol.alpha[1]), {}};
  for (int kk = 0; kk < 5; ++kk) out.N[kk] = sol.N[kk];
  return out;
}

TEST(Dynamics, AgreesWithNewtonEulerInMaximalCoordinates) {
  for (bool friction : {false, true}) {
    Params<double> p = paper_params();
    if (!friction) p.friction.law = FrictionLaw::kNone;
    p.links[2].com_angle = 0.2;
    p.friction.coulomb = {0.12, 0.2, 0.05, 0.3, 0.1};
    for (const State& s : random_states(p, 100, friction ? 11 : 12)) {
      Evaluation<double> ev;
      ASSERT_TRUE(forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &ev).ok());
      const NewtonEuler ne = newton_euler(p, s);
      const double scale = 1.0 + ne.thdd.cwiseAbs().maxCoeff();
      EXPECT_LT((ev.thdd - ne.thdd).cwiseAbs().maxCoeff(), kCrossCheckTol * scale);
      for (int k = 0; k < 5; ++k) EXPECT_NEAR(ev.N[k], ne.N[k], kCrossCheckTol * (1 + ne.N[k]));
    }
  }
}

TEST(Dynamics, InverseOfForwardReturnsTheTorques) {
  Params<double> p = paper_params();
  for (const State& s : random_states(p, 200, 3)) {
    Evaluation<double> fwd, inv;
    ASSERT_TRUE(forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &fwd).ok());
    ASSERT_TRUE(inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, fwd.thdd[0], fwd.thdd[1],
                                 nullptr, EvalOptions{}, &inv).ok());
    EXPECT_NEAR(inv.M1, s.loads.M1, 1e-10);
    EXPECT_NEAR(inv.M2, s.loads.M2, 1e-10);
    for (int k = 0; k < 5; ++k) EXPECT_NEAR(inv.N[k], fwd.N[k], 1e-9 * (1 + fwd.N[k]));
  }
}

TEST(Dynamics, FrictionPowerIsNeverNegative) {
  Params<double> p = paper_params();
  for (const State& s : random_states(p, 200, 5)) {
    Evaluation<double> ev;
    ASSERT_TRUE(forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &ev).ok());
    for (int k = 0; k < 5; ++k) EXPECT_GE(ev.Mf[k] * ev.w[k], 0.0);
  }
}

TEST(Dynamics, FrictionLoopReportsNonConvergence) {
  Params<double> p = paper_params();
  p.friction.pin_radius.fill(0.5);  // r_k * mu far beyond what the reactions can carry
  Evaluation<double> ev;
  const Status st = forward_dynamics(p, testing::paper_loads(0.3), 2.0, 1.0, 30.0, -20.0, nullptr,
                                     EvalOptions{}, &ev);
  EXPECT_EQ(st.code, StatusCode::kFrictionNotConverged);
  EXPECT_NE(st.message.find("fixed point does not contract"), std::string::npos) << st.message;
  EXPECT_NE(st.message.find("no consistent reaction forces"), std::string::npos) << st.message;
}

// where the fixed point stops contracting but a solution exists, Newton finds it
TEST(Dynamics, NewtonResolvesANonContractingFrictionLoop) {
  Params<double> p = paper_params();
  p.friction.pin_radius.fill(0.15);  // the fixed point stalls at this state
  const Loads<double> L = testing::paper_loads(0.3);
  Evaluation<double> ev;
  const Status st = forward_dynamics(p, L, 2.0, 1.0, 30.0, -20.0, nullptr, EvalOptions{}, &ev);
  ASSERT_TRUE(st.ok()) << st.message;
  EXPECT_GT(ev.iterations, EvalOptions{}.friction_max_iter);  // marks the Newton path
  // the solution is consistent: Mf_k = r_k f_k(w_k) N_k with N_k = |F_k|, and the inverse
  // dynamics of its accelerations returns the torques
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(ev.N[k], ev.F[k].norm(), 1e-9 * ev.N[k]);
    const double f = friction_law(p.friction, k, ev.w[k], sign_of(ev.w[k]));
    EXPECT_NEAR(ev.Mf[k], p.friction.pin_radius[k] * f * ev.N[k], 1e-9 * (1 + std::abs(ev.Mf[k])));
  }
  Evaluation<double> inv;
  ASSERT_TRUE(inverse_dynamics(p, L, 2.0, 1.0, 30.0, -20.0, ev.thdd[0], ev.thdd[1], nullptr,
                               EvalOptions{}, &inv)
                  .ok());
  EXPECT_NEAR(inv.M1, L.M1, 1e-8);
  EXPECT_NEAR(inv.M2, L.M2, 1e-8);
}

// an unforced frictionless mechanism conserves KE + PE; the run's own balance closes
TEST(Dynamics, UnforcedFrictionlessRunConservesEnergy) {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kNone;
  const sim::LoadFunction no_loads = [](double) { return Loads<double>{}; };
  sim::Options opt;
  opt.duration = 1.0;
  const sim::Result r = sim::simulate(p, no_loads, {M_PI / 2, M_PI / 2, 10.0, -5.0}, opt);
  ASSERT_TRUE(r.status.ok()) << r.status.message;
  const double e0 = r.rows.front().kinetic + r.rows.front().potential;
  for (const sim::Row& row : r.rows) {
    EXPECT_NEAR(row.kinetic + row.potential, e0, 1e-8 * std::abs(e0));
    EXPECT_EQ(row.E_diss, 0.0);
  }
}

}  // namespace
}  // namespace fivebar
