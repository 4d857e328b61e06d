// The general planar chain (planar_chain.h) against the five-bar's Appell model: forward and
// inverse dynamics and the joint reactions at random states, with and without friction; its
// velocity closure against the influence coefficients; its failure statuses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "agreement.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/five_bar_chain.h"
#include "fivebar/model/planar_chain.h"
#include "paper.h"

namespace fivebar {
namespace {

// two formulations (Appell in 2 coordinates; Newton-Euler by a 22x22 QR) of O(100) quantities
constexpr double kAgreementTol = 1e-10;

using testing::random_states;

using testing::reaction_error;
using testing::relative_error;
using testing::sci;
using testing::RandomState;

/// The five-bar's chain at a state: pose, body rates (the chain's velocity closure) and loads.
struct ChainState {
  Kinematics<double> k;
  chain::Chain c;
  chain::Pose q;
  std::vector<double> rate;
  chain::ChainLoads L;
};

ChainState chain_state(const Params<double>& p, const RandomState& s) {
  ChainState out;
  EXPECT_TRUE(solve_kinematics(p, s.th1, s.th2, &out.k).ok());
  out.c = five_bar_chain(p);
  out.q = five_bar_pose(p, out.k);
  EXPECT_TRUE(chain::body_rates(out.c, out.q, {s.w1, s.w2}, &out.rate).ok());
  out.L = five_bar_loads(p, out.k, s.loads);
  return out;
}

/// The paper's five-bar with an off-axis coupler centre of mass and joint-wise friction (or none).
Params<double> test_params(bool friction) {
  Params<double> p = paper_params();
  p.links[2].com_angle = 0.2;
  p.friction.coulomb = {0.12, 0.2, 0.05, 0.3, 0.1};
  if (!friction) p.friction.law = FrictionLaw::kNone;
  return p;
}

TEST(PlanarChain, VelocityClosureMatchesTheInfluenceCoefficients) {
  const Params<double> p = test_params(true);
  for (const RandomState& s : random_states(p, 200, 31)) {
    const ChainState cs = chain_state(p, s);
    EXPECT_LT(chain::closure_residual(cs.c, cs.q), 1e-14);
    const std::vector<double> expect = five_bar_rates(cs.k, s.w1, s.w2);
    EXPECT_LT(relative_error(cs.rate, expect, 4), 1e-12);
  }
}

TEST(PlanarChain, FiveBarForwardDynamicsAndReactionsAgree) {
  for (bool friction : {false, true}) {
    const Params<double> p = test_params(friction);
    double worst_acc = 0.0, worst_F = 0.0, worst_Mf = 0.0;
    for (const RandomState& s : random_states(p, 1000, friction ? 41 : 42)) {
      Evaluation<double> ev;
      ASSERT_TRUE(
          forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &ev).ok());
      const ChainState cs = chain_state(p, s);
      chain::Solution sol;
      ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, {}, &sol).ok());
      const double acc[4] = {ev.thdd[0], ev.thdd[1], ev.alpha3, ev.alpha4};
      worst_acc = std::max(worst_acc, relative_error(sol.alpha, acc, 4));
      worst_F = std::max(worst_F, reaction_error(sol.F, ev.F, kJoints));
      worst_Mf = std::max(worst_Mf, relative_error(sol.Mf, ev.Mf, kJoints));
    }
    EXPECT_LT(worst_acc, kAgreementTol);
    EXPECT_LT(worst_F, kAgreementTol);
    EXPECT_LT(worst_Mf, kAgreementTol);
    const std::string tag = friction ? "friction" : "frictionless";
    RecordProperty("forward_accel_" + tag, sci(worst_acc));
    RecordProperty("forward_reactions_" + tag, sci(worst_F));
  }
}

TEST(PlanarChain, FiveBarInverseDynamicsAndReactionsAgree) {
  for (bool friction : {false, true}) {
    const Params<double> p = test_params(friction);
    double worst_tau = 0.0, worst_F = 0.0;
    for (const RandomState& s : random_states(p, 1000, friction ? 43 : 44)) {
      const double a1 = 10.0 * s.loads.M1, a2 = 10.0 * s.loads.M2;  // up to 100 rad/s^2
      Evaluation<double> ev;
      ASSERT_TRUE(inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, a1, a2, nullptr,
                                   EvalOptions{}, &ev)
                      .ok());
      const ChainState cs = chain_state(p, s);
      chain::Solution sol;
      const std::vector<double> drive_alpha = {a1, a2};
      ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, &drive_alpha, {}, &sol).ok());
      const double tau[2] = {ev.M1, ev.M2};
      worst_tau = std::max(worst_tau, relative_error(sol.drive, tau, 2));
      worst_F = std::max(worst_F, reaction_error(sol.F, ev.F, kJoints));
    }
    EXPECT_LT(worst_tau, kAgreementTol);
    EXPECT_LT(worst_F, kAgreementTol);
    const std::string tag = friction ? "friction" : "frictionless";
    RecordProperty("inverse_torque_" + tag, sci(worst_tau));
    RecordProperty("inverse_reactions_" + tag, sci(worst_F));
  }
}

/// The paper's five-bar with its lengths, masses, inertias, centres of mass and joint friction
/// drawn at random around the paper's values.
Params<double> random_mechanism(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> near(0.9, 1.1), wide(0.5, 2.0), angle(-0.5, 0.5),
      mu(0.02, 0.4), radius(0.004, 0.02);
  Params<double> p = paper_params();
  for (Link<double>& l : p.links) {
    l.length *= near(rng);
    l.mass *= wide(rng);
    l.inertia *= wide(rng);
    l.com_offset *= near(rng);
    l.com_angle = angle(rng);
  }
  for (int j = 0; j < kJoints; ++j) {
    p.friction.coulomb[j] = mu(rng);
    p.friction.viscous[j] = 0.1 * mu(rng);
    p.friction.pin_radius[j] = radius(rng);
  }
  return p;
}

/// Joint modes as an integrator's segment has them: slip directions (mostly sign(w)), some
/// joints at rest (no Coulomb term: a transition), and up to two stuck (as many as the degrees
/// of freedom).
JointModes random_segment_modes(std::mt19937_64& rng, const std::array<double, kJoints>& w) {
  JointModes m;
  int stuck = 0;
  for (int j = 0; j < kJoints; ++j) {
    const unsigned draw = rng() % 8;
    m[j] = draw < 5                    ? slip_mode(sign_of(w[j]))
           : draw < 6                  ? slip_mode(-sign_of(w[j]))
           : draw < 7 || stuck == kDof ? JointMode::kRest
                                       : kStuck;
    stuck += m[j] == kStuck;
  }
  return m;
}

/// The simulator's right-hand-side evaluation options (no reactions or angles asked for).
EvalOptions rhs_options() {
  EvalOptions opt;
  opt.want_reactions = false;
  opt.want_angles = false;
  opt.singular_margin = 1e-3;
  return opt;
}

// The simulator's right-hand side (forward dynamics without the final reaction solve) against
// the general chain: with every joint slipping along sign(w), the chain solves the friction loop
// itself; in any mode (slip against sign(w), rest, stuck), the chain given the evaluation's
// friction and holding torques has the same accelerations, holds the stuck joints (relative
// acceleration 0) and has reactions with Mf_k = r_k f_k N_k at the others. Random mechanisms and
// states, seeded.
TEST(PlanarChain, FiveBarFrictionRightHandSideAgreesInEveryJointMode) {
  std::mt19937_64 rng(57);
  const EvalOptions opt = rhs_options();
  double worst_acc = 0.0, worst_N = 0.0, worst_Mf = 0.0, worst_hold = 0.0;
  int loops = 0, stuck = 0, rest = 0;
  for (int mechanism = 0; mechanism < 40; ++mechanism) {
    const Params<double> p = random_mechanism(rng);
    for (const RandomState& s : random_states(p, 25, 100 + mechanism)) {
      const ChainState cs = chain_state(p, s);
      const std::array<double, kJoints> w = relative_rates(
          s.w1, s.w2, cs.k.G3.dot(Vec2<double>(s.w1, s.w2)), cs.k.G4.dot(Vec2<double>(s.w1, s.w2)));
      const bool own_loop = rng() % 2;  // every joint along sign(w): the chain's own loop
      JointModes modes;
      for (int j = 0; j < kJoints; ++j) modes[j] = slip_mode(sign_of(w[j]));
      if (!own_loop) modes = random_segment_modes(rng, w);
      Evaluation<double> ev;
      const Status st = forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, &modes, opt, &ev);
      if (!st.ok()) continue;  // (dependent stuck joints, or a loop without a unique solution)
      chain::Solution sol;
      chain::Options copt;
      const std::vector<double> torques(ev.Mf.begin(), ev.Mf.end());
      if (!own_loop) copt.friction_torques = &torques;
      ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, copt, &sol).ok());
      const double acc[4] = {ev.thdd[0], ev.thdd[1], ev.alpha3, ev.alpha4};
      worst_acc = std::max(worst_acc, relative_error(sol.alpha, acc, 4));
      worst_N = std::max(worst_N, relative_error(sol.N, ev.N, kJoints));
      // relative accelerations of the chain's motion (the stuck joints' are held at zero)
      const std::array<double, kJoints> wdot =
          relative_rates(sol.alpha[0], sol.alpha[1], sol.alpha[2], sol.alpha[3]);
      double scale = 1.0;
      for (double a : sol.alpha) scale = std::max(scale, std::abs(a));
      for (int j = 0; j < kJoints; ++j) {
        if (modes[j] == kStuck) {
          worst_hold = std::max(worst_hold, std::abs(wdot[j]) / scale);
          ++stuck;
          continue;
        }
        rest += modes[j] == JointMode::kRest;
        const double phi =
            p.friction.pin_radius[j] * friction_law(p.friction, j, ev.w[j], coulomb_sign(modes[j]));
        worst_Mf = std::max(worst_Mf, std::abs(ev.Mf[j] - phi * sol.N[j]) / (1.0 + sol.N[j]));
      }
      loops += own_loop;
    }
  }
  EXPECT_GT(loops, 300);
  EXPECT_GT(stuck, 300);
  EXPECT_GT(rest, 100);
  EXPECT_LT(worst_acc, kAgreementTol);
  EXPECT_LT(worst_N, kAgreementTol);
  EXPECT_LT(worst_Mf, kAgreementTol);
  EXPECT_LT(worst_hold, kAgreementTol);
  RecordProperty("rhs_accel", sci(worst_acc));
  RecordProperty("rhs_reactions", sci(worst_N));
}

// The simulator's right-hand side as it evaluates it, warm-started (FrictionWarmStart carried from
// one evaluation to the next) along short stretches of motion, states 2e-5 s apart, every joint
// slipping along sign(w), against the general chain solving the friction loop itself: random
// mechanisms and states, seeded. The warm start must reach the cold start's solution, not its own.
TEST(PlanarChain, FiveBarWarmStartedRightHandSideAgreesAlongAMotion) {
  std::mt19937_64 rng(61);
  const EvalOptions opt = rhs_options();
  double worst_acc = 0.0, worst_N = 0.0;
  int warm = 0;
  for (int mechanism = 0; mechanism < 20; ++mechanism) {
    const Params<double> p = random_mechanism(rng);
    for (const RandomState& s0 : random_states(p, 5, 300 + mechanism)) {
      FrictionWarmStart start;
      for (int i = 0; i < 12; ++i) {
        RandomState s = s0;
        s.th1 += 2e-5 * i * s0.w1;
        s.th2 += 2e-5 * i * s0.w2;
        Kinematics<double> k;
        if (!solve_kinematics(p, s.th1, s.th2, &k, 0.05).ok()) break;
        const ChainState cs = chain_state(p, s);
        const std::array<double, kJoints> w =
            relative_rates(s.w1, s.w2, cs.k.G3.dot(Vec2<double>(s.w1, s.w2)),
                           cs.k.G4.dot(Vec2<double>(s.w1, s.w2)));
        JointModes modes;
        for (int j = 0; j < kJoints; ++j) modes[j] = slip_mode(sign_of(w[j]));
        const bool warm_start = start.set;
        Evaluation<double> ev;
        const Status st =
            forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, &modes, opt, &ev,
                             static_cast<const std::array<double, kJoints>*>(nullptr), &start);
        if (!st.ok()) break;  // (a loop without a unique solution)
        chain::Solution sol;
        ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, {}, &sol).ok());
        const double acc[4] = {ev.thdd[0], ev.thdd[1], ev.alpha3, ev.alpha4};
        worst_acc = std::max(worst_acc, relative_error(sol.alpha, acc, 4));
        worst_N = std::max(worst_N, relative_error(sol.N, ev.N, kJoints));
        warm += warm_start;
      }
    }
  }
  EXPECT_GT(warm, 800);
  EXPECT_LT(worst_acc, kAgreementTol);
  EXPECT_LT(worst_N, kAgreementTol);
  RecordProperty("warm_rhs_accel", sci(worst_acc));
  RecordProperty("warm_rhs_reactions", sci(worst_N));
}

// the inverse mode returns the drive torques that the forward mode was given
TEST(PlanarChain, InverseModeInvertsForwardMode) {
  const Params<double> p = test_params(true);
  for (const RandomState& s : random_states(p, 100, 45)) {
    const ChainState cs = chain_state(p, s);
    chain::Solution fwd, inv;
    ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, {}, &fwd).ok());
    const std::vector<double> drive_alpha = {fwd.alpha[0], fwd.alpha[1]};
    ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, &drive_alpha, {}, &inv).ok());
    EXPECT_NEAR(inv.drive[0], s.loads.M1, 1e-9);
    EXPECT_NEAR(inv.drive[1], s.loads.M2, 1e-9);
  }
}

TEST(PlanarChain, ReportsDrivesThatDoNotFixTheMotion) {
  const Params<double> p = paper_params();
  const ChainState cs = chain_state(p, random_states(p, 1, 46)[0]);
  chain::Chain c = cs.c;
  c.drives.pop_back();  // one drive for two degrees of freedom
  std::vector<double> rate;
  const Status st = chain::body_rates(c, cs.q, {1.0}, &rate);
  EXPECT_EQ(st.code, StatusCode::kInvalidInput);
  EXPECT_NE(st.message.find("degrees of freedom"), std::string::npos) << st.message;
}

TEST(PlanarChain, ReportsARedundantJointAsSingular) {
  const Params<double> p = paper_params();
  const ChainState cs = chain_state(p, random_states(p, 1, 47)[0]);
  chain::Chain c = cs.c;
  c.joints.push_back(c.joints[1]);  // a second pin at B: dependent constraints
  chain::Solution sol;
  const Status st = chain::solve(c, cs.q, cs.rate, cs.L, nullptr, {}, &sol);
  EXPECT_EQ(st.code, StatusCode::kNearSingular);
}

// where the fixed point contracts slowly (the five-bar's loop takes Newton after 50 iterations),
// the chain's Newton, after a fixed point cut at 20 iterations, finds the same motion and reactions
TEST(PlanarChain, NewtonResolvesTheFiveBarsNonContractingFrictionLoop) {
  Params<double> p = paper_params();
  p.friction.pin_radius.fill(0.15);
  const RandomState s{2.0, 1.0, 30.0, -20.0, testing::paper_loads(0.3)};
  Evaluation<double> ev;
  ASSERT_TRUE(
      forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, nullptr, EvalOptions{}, &ev).ok());
  const ChainState cs = chain_state(p, s);
  chain::Options opt;
  opt.max_iter = 20;
  chain::Solution sol;
  ASSERT_TRUE(chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, opt, &sol).ok());
  EXPECT_GT(sol.iterations, opt.max_iter);  // the Newton path
  EXPECT_NEAR(sol.alpha[0], ev.thdd[0], 1e-9 * (1 + std::abs(ev.thdd[0])));
  EXPECT_NEAR(sol.alpha[1], ev.thdd[1], 1e-9 * (1 + std::abs(ev.thdd[1])));
  for (int k = 0; k < kJoints; ++k) EXPECT_NEAR(sol.N[k], ev.N[k], 1e-9 * (1 + ev.N[k]));
}

// where the five-bar's friction loop finds no consistent reactions, neither does the chain
TEST(PlanarChain, ReportsFrictionWithoutConsistentReactions) {
  Params<double> p = paper_params();
  p.friction.pin_radius.fill(0.5);
  const RandomState s{2.0, 1.0, 30.0, -20.0, testing::paper_loads(0.3)};
  const ChainState cs = chain_state(p, s);
  chain::Solution sol;
  const Status st = chain::solve(cs.c, cs.q, cs.rate, cs.L, nullptr, {}, &sol);
  EXPECT_EQ(st.code, StatusCode::kFrictionNotConverged);
}

}  // namespace
}  // namespace fivebar
