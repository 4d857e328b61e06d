// The four-bar in reduced coordinates (four_bar.h): closure of positions, rates and
// accelerations; forward and inverse dynamics and reactions against the general planar chain;
// and on seeded random four-bars (Grashof and not) energy balance, inverse of forward (the torque,
// or a report where the inverse problem has several solutions), friction power and the holding
// torque against the virtual work of gravity; the crank motor's friction (actuator.h: inverse of
// forward, power, its torque, the stuck crank's capacity); stuck joints, the rest rule and LuGre
// from the dynamics written once over the mechanism; and two scenes against trajectories made by
// an independent program (datasets/reference/four_bar/).
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "agreement.h"
#include "four_bar_scenes.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/mechanism_dynamics.h"
#include "fivebar/model/planar_chain.h"
#include "paper.h"

namespace fivebar {
namespace {

constexpr double kAgreementTol = 1e-10;  // reduced coordinates against a 17x17 QR
constexpr int kMechanisms = 20;

using testing::ReferenceScene;
using testing::reference_scenes;
using testing::sci;

/// True for a Grashof four-bar: shortest + longest <= sum of the other two lengths.
bool grashof(const FourBarParams& p) {
  std::array<double, 4> l = {p.ground_length, p.links[0].length, p.links[1].length,
                             p.links[2].length};
  std::sort(l.begin(), l.end());
  return l[0] + l[3] <= l[1] + l[2];
}

/// The fraction of 100 crank angles at which p assembles with |sin32| >= margin.
double assembling_fraction(const FourBarParams& p, double margin) {
  int ok = 0;
  for (int i = 0; i < 100; ++i) {
    FourBarKinematics k;
    ok += four_bar_kinematics(p, -M_PI + 2 * M_PI * (i + 0.5) / 100, &k, margin).ok();
  }
  return ok / 100.0;
}

/// A random four-bar (Grashof or not) that assembles well on at least a quarter of the crank
/// angles, with Coulomb-viscous friction (or none).
FourBarParams random_four_bar(std::mt19937_64& rng, bool want_grashof, bool friction) {
  std::uniform_real_distribution<double> len(0.05, 0.4), mass(0.2, 2.0), inertia(1e-3, 5e-2),
      unit01(0.0, 1.0), angle(-0.5, 0.5), mu(0.05, 0.3), visc(0.0, 0.03);
  FourBarParams p;
  p.gravity = 9.81;
  do {
    p.ground_length = len(rng);
    for (Link<double>& l : p.links) {
      l.length = len(rng);
      l.mass = mass(rng);
      l.inertia = inertia(rng);
      l.com_offset = unit01(rng) * l.length;
      l.com_angle = angle(rng);
    }
    p.assembly = unit01(rng) < 0.5 ? kElbowUp : kElbowDown;
  } while (grashof(p) != want_grashof || assembling_fraction(p, 0.3) < 0.25);
  p.point_p = unit01(rng) * p.links[1].length;
  p.friction.law = friction ? FrictionLaw::kCoulombViscous : FrictionLaw::kNone;
  for (int j = 0; j < kFourBarJoints; ++j) {
    p.friction.pin_radius[j] = 0.01;
    p.friction.coulomb[j] = mu(rng);
    p.friction.viscous[j] = visc(rng);
  }
  return p;
}

/// kMechanisms seeded four-bars, alternately Grashof and not.
std::vector<FourBarParams> mechanisms(bool friction, uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  std::vector<FourBarParams> out;
  for (int m = 0; m < kMechanisms; ++m) out.push_back(random_four_bar(rng, m % 2 == 0, friction));
  return out;
}

struct State {
  double th1, w1;
  FourBarLoads loads;
};

/// n random states of p that assemble with |sin32| >= margin (rates to 10 rad/s, torques to
/// 5 N m, F to 25 N).
std::vector<State> random_states(const FourBarParams& p, int n, uint64_t seed,
                                 double margin = 0.2) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), rate(-10, 10), torque(-5, 5);
  std::vector<State> out;
  for (int tries = 0; static_cast<int>(out.size()) < n && tries < 1000 * n; ++tries) {
    const State s{angle(rng), rate(rng), {torque(rng), torque(rng), 5 * torque(rng), angle(rng)}};
    FourBarKinematics k;
    if (four_bar_kinematics(p, s.th1, &k, margin).ok()) out.push_back(s);
  }
  EXPECT_EQ(static_cast<int>(out.size()), n) << "the mechanism rarely assembles";
  return out;
}

/// The chain's solution at a four-bar state (forward, or inverse with crank acceleration *al1).
chain::Solution chain_solution(const FourBarParams& p, const State& s, const double* al1,
                               const chain::Options& opt = {}) {
  FourBarKinematics k;
  EXPECT_TRUE(four_bar_kinematics(p, s.th1, &k).ok());
  const chain::Chain c = four_bar_chain(p);
  const chain::Pose q = four_bar_pose(p, k);
  std::vector<double> rate;
  EXPECT_TRUE(chain::body_rates(c, q, {s.w1}, &rate).ok());
  chain::Solution sol;
  const std::vector<double> drive_alpha = {al1 ? *al1 : 0.0};
  EXPECT_TRUE(chain::solve(c, q, rate, four_bar_loads(p, k, s.loads), al1 ? &drive_alpha : nullptr,
                           opt, &sol)
                  .ok());
  return sol;
}

/// the reaction error over the four joints (agreement.h)
double reaction_error(const std::vector<Vec2<double>>& a,
                      const std::array<Vec2<double>, kJoints>& b) {
  return testing::reaction_error(a, b, kFourBarJoints);
}

/// True for the friction loop's report of several consistent solutions (friction_unique): at
/// high joint rates the inverse problem can have two, each the reactions of a drive torque that
/// gives the same motion.
bool several_solutions(const Status& st) {
  return st.code == StatusCode::kFrictionNotConverged &&
         st.message.find("several consistent reaction forces") != std::string::npos;
}

// The smooth form of the singular measure (FourBar::singular_cosine): 1 - cos^2 is
// sin^2(theta3 - theta2) and cos is e2 . e3 where the four-bar closes, |cos| > 1 where it cannot;
// its derivative agrees with central differences and with Jets.
TEST(FourBar, SingularCosineIsTheSmoothFormOfTheSingularMeasure) {
  using J = ceres::Jet<double, 1>;
  int closed = 0, open = 0;
  double worst = 0.0, worst_derivative = 0.0;
  for (const FourBarParams& p : mechanisms(false)) {
    const FourBarParamsT<J> pj = p.cast<J>();
    for (int i = 0; i < 200; ++i) {
      const double th1 = -M_PI + 2 * M_PI * (i + 0.5) / 200, h = 1e-6;
      Eigen::Matrix<double, 1, 1> g;
      const double c = FourBar::singular_cosine(p, FourBar::Q<double>(th1), &g);
      FourBarKinematics k;
      if (four_bar_kinematics(p, th1, &k).ok()) {
        ++closed;
        worst = std::max({worst, std::abs(1 - c * c - k.sin32 * k.sin32),
                          std::abs(c - k.e2.dot(k.e3))});
      } else {
        ++open;
        EXPECT_GT(std::abs(c), 1.0) << "theta1 = " << th1;
      }
      const double central =
          (four_bar_coupler_cosine(p, th1 + h) - four_bar_coupler_cosine(p, th1 - h)) / (2 * h);
      worst_derivative = std::max({worst_derivative, std::abs(g(0, 0) - central),
                                   std::abs(four_bar_coupler_cosine(pj, J(th1, 0)).v[0] - g(0, 0))});
    }
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(worst_derivative, 1e-8);
  EXPECT_GT(closed, 0);
  EXPECT_GT(open, 0) << "some non-Grashof four-bar should fail to close somewhere";
}

TEST(FourBar, RandomMechanismsAreGrashofAndNot) {
  int g = 0;
  for (const FourBarParams& p : mechanisms(false)) g += grashof(p);
  EXPECT_EQ(g, kMechanisms / 2);
}

TEST(FourBar, ClosesPositionsRatesAndAccelerations) {
  double worst_pos = 0.0, worst_rate = 0.0, worst_acc = 0.0;
  for (const FourBarParams& p : mechanisms(false)) {
    const double l1 = p.links[0].length, l2 = p.links[1].length, l3 = p.links[2].length;
    for (const State& s : random_states(p, 50, 11)) {
      FourBarKinematics k;
      ASSERT_TRUE(four_bar_kinematics(p, s.th1, &k).ok());
      const double al1 = 10 * s.loads.M1;
      const FourBarBias b = four_bar_bias(p, k, s.w1);
      const double al2 = k.G2 * al1 + b.h2, al3 = k.G3 * al1 + b.h3;
      // O + l1 e1 + l2 e2 = D0 + l3 e3, and its first and second time derivatives
      const Vec2<double> D0(p.ground_length, 0);
      const Vec2<double> e1 = unit(k.th1), e2 = unit(k.th2), e3 = unit(k.th3);
      const Vec2<double> pos = l1 * e1 + l2 * e2 - D0 - l3 * e3;
      const Vec2<double> vel = l1 * s.w1 * perp(e1) + l2 * b.w2 * perp(e2) - l3 * b.w3 * perp(e3);
      const Vec2<double> acc = l1 * (al1 * perp(e1) - s.w1 * s.w1 * e1) +
                               l2 * (al2 * perp(e2) - b.w2 * b.w2 * e2) -
                               l3 * (al3 * perp(e3) - b.w3 * b.w3 * e3);
      const double vscale = l1 * std::abs(s.w1) + l2 * std::abs(b.w2) + l3 * std::abs(b.w3);
      const double ascale = l1 * (std::abs(al1) + s.w1 * s.w1) +
                            l2 * (std::abs(al2) + b.w2 * b.w2) + l3 * (std::abs(al3) + b.w3 * b.w3);
      worst_pos = std::max(worst_pos, pos.norm() / (l1 + l2 + l3));
      worst_rate = std::max(worst_rate, vel.norm() / (1e-300 + vscale));
      worst_acc = std::max(worst_acc, acc.norm() / (1e-300 + ascale));
      // C to the left of B->D0 for elbow up, and the sine of the coupler-rocker angle
      EXPECT_EQ(cross(Vec2<double>(D0 - k.B), Vec2<double>(k.C - k.B)) > 0, p.assembly == kElbowUp);
      EXPECT_NEAR(k.sin32, std::sin(k.th3 - k.th2), 1e-14);
    }
  }
  EXPECT_LT(worst_pos, 1e-14);
  EXPECT_LT(worst_rate, 1e-12);
  EXPECT_LT(worst_acc, 1e-12);
  RecordProperty("closure_position", sci(worst_pos));
  RecordProperty("closure_rate", sci(worst_rate));
  RecordProperty("closure_acceleration", sci(worst_acc));
}

// G2, G3 against central differences of the position solve (step 1e-6: error ~1e-9)
TEST(FourBar, RateCoefficientsMatchCentralDifferences) {
  for (const FourBarParams& p : mechanisms(false)) {
    for (const State& s : random_states(p, 10, 12, 0.3)) {
      FourBarKinematics k, kp, km;
      const double h = 1e-6;
      ASSERT_TRUE(four_bar_kinematics(p, s.th1, &k).ok());
      ASSERT_TRUE(four_bar_kinematics(p, s.th1 + h, &kp).ok());
      ASSERT_TRUE(four_bar_kinematics(p, s.th1 - h, &km).ok());
      EXPECT_NEAR(k.G2, std::remainder(kp.th2 - km.th2, 2 * M_PI) / (2 * h),
                  1e-6 * (1 + std::abs(k.G2)));
      EXPECT_NEAR(k.G3, std::remainder(kp.th3 - km.th3, 2 * M_PI) / (2 * h),
                  1e-6 * (1 + std::abs(k.G3)));
    }
  }
}

TEST(FourBar, ForwardAndInverseDynamicsAgreeWithThePlanarChain) {
  for (bool friction : {false, true}) {
    double worst_acc = 0.0, worst_tau = 0.0, worst_F = 0.0;
    int m = 0, several = 0;
    for (const FourBarParams& p : mechanisms(friction)) {
      for (const State& s : random_states(p, 1000 / kMechanisms, 100 + m++)) {
        FourBarEvaluation fwd, inv;
        ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &fwd).ok());
        const chain::Solution cf = chain_solution(p, s, nullptr);
        const double acc[3] = {fwd.thdd[0], fwd.alpha2, fwd.alpha3};
        double err = 0.0, scale = 0.0;
        for (int i = 0; i < 3; ++i) {
          err = std::max(err, std::abs(cf.alpha[i] - acc[i]));
          scale = std::max(scale, std::abs(acc[i]));
        }
        worst_acc = std::max(worst_acc, err / (1 + scale));
        worst_F = std::max(worst_F, reaction_error(cf.F, fwd.F));
        const double al1 = 10 * s.loads.M3;  // an acceleration unrelated to the forward one
        const Status st = four_bar_inverse(p, s.loads, s.th1, s.w1, al1, EvalOptions{}, &inv);
        if (several_solutions(st)) {
          ++several;
          continue;
        }
        ASSERT_TRUE(st.ok()) << st.message;
        const chain::Solution ci = chain_solution(p, s, &al1);
        worst_tau = std::max(worst_tau, std::abs(ci.drive[0] - inv.M1) / (1 + std::abs(inv.M1)));
        worst_F = std::max(worst_F, reaction_error(ci.F, inv.F));
      }
    }
    EXPECT_LT(worst_acc, kAgreementTol);
    EXPECT_LT(worst_tau, kAgreementTol);
    EXPECT_LT(worst_F, kAgreementTol);
    EXPECT_LT(several, 10);  // of 1000 inverse problems, none without friction
    const std::string tag = friction ? "friction" : "frictionless";
    RecordProperty("inverse_several_solutions_" + tag, several);
    RecordProperty("accel_" + tag, sci(worst_acc));
    RecordProperty("torque_" + tag, sci(worst_tau));
    RecordProperty("reactions_" + tag, sci(worst_F));
  }
}

TEST(FourBar, InverseOfForwardReturnsTheTorque) {
  double worst = 0.0;
  int m = 0;
  for (const FourBarParams& p : mechanisms(true)) {
    for (const State& s : random_states(p, 50, 200 + m++)) {
      FourBarEvaluation fwd, inv;
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &fwd).ok());
      ASSERT_TRUE(four_bar_inverse(p, s.loads, s.th1, s.w1, fwd.thdd[0], EvalOptions{}, &inv).ok());
      worst = std::max(worst, std::abs(inv.M1 - s.loads.M1));
      for (int k = 0; k < kFourBarJoints; ++k) {
        EXPECT_NEAR(inv.N[k], fwd.N[k], 1e-9 * (1 + fwd.N[k]));
      }
    }
  }
  EXPECT_LT(worst, 1e-9);  // N m
  RecordProperty("inverse_of_forward_Nm", sci(worst));
}

// Where the friction loop does not contract everywhere, the inverse problem at the forward's
// accelerations can have two consistent sets of reactions: two drive torques that give the same
// motion (forward dynamics at either returns it as its only solution), and neither is the
// physical one. On seeded random four-bars at crank rates to 10 rad/s (joint rates to 60 rad/s)
// the inverse of the forward returns the torque or reports "several consistent reaction
// forces", never the other torque silently.
TEST(FourBar, InverseOfForwardReturnsTheTorqueOrReportsSeveralSolutions) {
  std::mt19937_64 rng(17);
  double worst = 0.0;
  int returned = 0, reported = 0;
  for (int m = 0; m < 1000; ++m) {
    const FourBarParams p = random_four_bar(rng, m % 2 == 0, true);
    for (const State& s : random_states(p, 50, 2000 + m)) {
      FourBarEvaluation fwd, inv;
      const FourBar::Q<double> q(s.th1), v(s.w1);
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &fwd).ok());
      const Status st = mech::inverse<FourBar, double>(p, s.loads, q, v, fwd.thdd, &fwd.slip,
                                                       EvalOptions{}, &inv);
      if (!st.ok()) {
        ++reported;
        EXPECT_TRUE(several_solutions(st)) << st.message;
        continue;
      }
      ++returned;
      worst = std::max(worst, std::abs(inv.M1 - s.loads.M1));
    }
  }
  EXPECT_LT(worst, 1e-9);               // N m
  EXPECT_GT(reported, 0);               // the seeds reach states with two solutions
  EXPECT_LT(reported, returned / 100);  // rare
  RecordProperty("inverse_of_forward_Nm", sci(worst));
  RecordProperty("returned", returned);
  RecordProperty("several_solutions", reported);
}

TEST(FourBar, FrictionNeverSuppliesPower) {
  double least = INFINITY;
  int m = 0;
  for (const FourBarParams& p : mechanisms(true)) {
    for (const State& s : random_states(p, 50, 300 + m++)) {
      FourBarEvaluation ev;
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &ev).ok());
      // consistent to the loop's tolerance on max N: Mf_k = r_k f_k(w_k) N_k
      const double scale = 1 + *std::max_element(ev.N.begin(), ev.N.end());
      for (int k = 0; k < kFourBarJoints; ++k) {
        EXPECT_GE(ev.Mf[k] * ev.w[k], 0.0);
        const double f = friction_law(p.friction, k, ev.w[k], sign_of(ev.w[k]));
        EXPECT_NEAR(ev.Mf[k] / (p.friction.pin_radius[k] * f), ev.N[k], 1e-10 * scale);
      }
      EXPECT_GT(ev.P_diss, 0.0);
      least = std::min(least, ev.P_diss);
    }
  }
  RecordProperty("least_dissipated_power", sci(least));
}

// at rest and not accelerating, the crank holds the gravity torque dU/dth1 (virtual work)
TEST(FourBar, HoldingTorqueIsTheGravityTorqueOfVirtualWork) {
  double worst = 0.0;
  int m = 0;
  for (const FourBarParams& p : mechanisms(false)) {
    for (const State& s : random_states(p, 20, 400 + m++)) {
      FourBarEvaluation ev;
      ASSERT_TRUE(four_bar_inverse(p, FourBarLoads{}, s.th1, 0.0, 0.0, EvalOptions{}, &ev).ok());
      // fourth-order central difference of U along the closure, step 1e-4
      const double h = 1e-4;
      double U[4];
      const double at[4] = {-2 * h, -h, h, 2 * h};
      for (int i = 0; i < 4; ++i) {
        FourBarKinematics k;
        ASSERT_TRUE(four_bar_kinematics(p, s.th1 + at[i], &k).ok());
        U[i] = four_bar_potential(p, k);
      }
      const double dU = (U[0] - 8 * U[1] + 8 * U[2] - U[3]) / (12 * h);
      const double scale = 1 + std::abs(dU);
      worst = std::max(worst, std::abs(ev.M1 - dU) / scale);
    }
  }
  EXPECT_LT(worst, 1e-9);  // truncation ~h^4, roundoff ~1e-16 U / h
  RecordProperty("holding_vs_virtual_work", sci(worst));
}

/// One RK4 step of (th1, w1) under constant loads, frictionless.
bool rk4_step(const FourBarParams& p, const FourBarLoads& L, double dt, double* th, double* w) {
  auto f = [&](double t, double v, double* a) {
    FourBarEvaluation ev;
    if (!four_bar_forward(p, L, t, v, EvalOptions{}, &ev).ok()) return false;
    *a = ev.thdd[0];
    return true;
  };
  double a1, a2, a3, a4;
  if (!f(*th, *w, &a1)) return false;
  if (!f(*th + 0.5 * dt * *w, *w + 0.5 * dt * a1, &a2)) return false;
  if (!f(*th + 0.5 * dt * (*w + 0.5 * dt * a1), *w + 0.5 * dt * a2, &a3)) return false;
  if (!f(*th + dt * (*w + 0.5 * dt * a2), *w + dt * a3, &a4)) return false;
  *th += dt / 6 * (*w + 2 * (*w + 0.5 * dt * a1) + 2 * (*w + 0.5 * dt * a2) + (*w + dt * a3));
  *w += dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
  return true;
}

// KE + PE - work of the constant torques M1 (crank) and M3 (coupler) stays constant
TEST(FourBar, FrictionlessRunBalancesEnergy) {
  double worst = 0.0;
  int m = 0;
  for (const FourBarParams& p : mechanisms(false)) {
    const std::vector<State> start = random_states(p, 1, 500 + m++, 0.4);
    ASSERT_EQ(start.size(), 1u);
    const State& s0 = start[0];
    const FourBarLoads L{0.2 * s0.loads.M1, 0.2 * s0.loads.M3, 0.0, 0.0};
    double th = s0.th1, w = 1.0, work = 0.0;
    FourBarKinematics k;
    ASSERT_TRUE(four_bar_kinematics(p, th, &k).ok());
    double th2 = k.th2;
    const double e0 = four_bar_kinetic(p, k, w) + four_bar_potential(p, k);
    double scale = std::abs(four_bar_kinetic(p, k, w)) + std::abs(four_bar_potential(p, k));
    int steps = 0;
    for (; steps < 2000; ++steps) {  // 0.1 s, stopped short of a singular pose
      double th_next = th, w_next = w;
      if (!rk4_step(p, L, 5e-5, &th_next, &w_next)) break;
      FourBarKinematics kn;
      if (!four_bar_kinematics(p, th_next, &kn, 0.05).ok()) break;
      work += L.M1 * (th_next - th) + L.M3 * std::remainder(kn.th2 - th2, 2 * M_PI);
      th = th_next;
      w = w_next;
      th2 = kn.th2;
      const double ke = four_bar_kinetic(p, kn, w), pe = four_bar_potential(p, kn);
      scale = std::max(scale, std::abs(ke) + std::abs(pe) + std::abs(work));
      worst = std::max(worst, std::abs(ke + pe - work - e0) / scale);
    }
    EXPECT_GE(steps, 200) << "mechanism " << m << " reached a singular pose at once";
  }
  EXPECT_LT(worst, 1e-9);
  RecordProperty("energy_balance", sci(worst));
}

constexpr size_t kStencil = 3;  ///< half-width of central_difference's stencil

/// 7-point central difference of column x at row i (step h): error h^6 x^(7) / 140.
double central_difference(const std::vector<double>& x, size_t i, double h) {
  return (x[i + 3] - 9 * x[i + 2] + 45 * x[i + 1] - 45 * x[i - 1] + 9 * x[i - 2] - x[i - 3]) /
         (60 * h);
}

// Against trajectories of an independent program (maximal coordinates, 17x17 Newton-Euler, RK4 with
// located switches; datasets/reference/README.md): the closure and the rates at every row, and
// the crank's acceleration and the dissipated power against differences of the reference's
// omega1 and E_diss, at rows whose stencil crosses no switch.
TEST(FourBar, AgreesWithTheIndependentReferences) {
  for (const ReferenceScene& sc : reference_scenes()) {
    const auto ref = testing::read_csv(testing::reference_path("four_bar/" + sc.file + ".csv"));
    const std::vector<double>& t = ref.at("t");
    ASSERT_EQ(t.size(), 2001u) << sc.file;
    EXPECT_EQ(ref.at("theta1")[0], sc.th0) << sc.file;
    const double h = t[1] - t[0];
    double pose = 0, rates = 0, accel = 0, power = 0, accel_scale = 0, power_scale = 0;
    std::vector<FourBarEvaluation> evs(t.size());
    for (size_t i = 0; i < t.size(); ++i) {
      FourBarEvaluation& ev = evs[i];
      const double th1 = ref.at("theta1")[i], w1 = ref.at("omega1")[i];
      ASSERT_TRUE(four_bar_forward(sc.p, sc.loads(t[i]), th1, w1, EvalOptions{}, &ev).ok());
      pose = std::max({pose, std::abs(std::remainder(ev.kin.th2 - ref.at("theta2")[i], 2 * M_PI)),
                       std::abs(std::remainder(ev.kin.th3 - ref.at("theta3")[i], 2 * M_PI))});
      rates = std::max({rates, std::abs(ev.bias.w2 - ref.at("omega2")[i]),
                        std::abs(ev.bias.w3 - ref.at("omega3")[i])});
      accel_scale = std::max(accel_scale, std::abs(ev.thdd[0]));
      power_scale = std::max(power_scale, std::abs(ev.P_diss));
    }
    int compared = 0;
    for (size_t i = kStencil; i + kStencil < t.size(); ++i) {
      bool switches = false;  // a joint rate changing sign inside the stencil
      for (size_t j = i - kStencil; j < i + kStencil; ++j) {
        for (int k = 0; k < kFourBarJoints; ++k) switches |= evs[j].w[k] * evs[j + 1].w[k] <= 0;
      }
      if (switches) continue;
      ++compared;
      accel = std::max(accel, std::abs(evs[i].thdd[0] - central_difference(ref.at("omega1"), i, h)));
      power = std::max(power, std::abs(evs[i].P_diss - central_difference(ref.at("E_diss"), i, h)));
    }
    EXPECT_LT(pose, 1e-12) << sc.file;
    EXPECT_LT(rates, 1e-11) << sc.file;
    EXPECT_GT(compared, 1800) << sc.file;
    EXPECT_LT(accel, sc.difference_tol * accel_scale) << sc.file;
    EXPECT_LT(power, sc.difference_tol * power_scale) << sc.file;
    RecordProperty(sc.file + "_pose", sci(pose));
    RecordProperty(sc.file + "_rates", sci(rates));
    RecordProperty(sc.file + "_acceleration_relative", sci(accel / accel_scale));
    RecordProperty(sc.file + "_power_relative", sci(power / power_scale));
  }
}

// larger pins: where the loop's fixed point stops contracting and Newton solves it, the chain at
// the same friction torques has the same motion and reactions, and they are consistent with the
// law there: Mf_k = r_k f_k(w_k) |F_k|. (The consistent torques need not be unique at this
// friction: the chain's own loop may find another solution, so it is not compared.)
TEST(FourBar, NewtonSolvesOfTheFrictionLoopAreConsistentInThePlanarChain) {
  int newton = 0, m = 0;
  for (FourBarParams p : mechanisms(true)) {
    p.friction.pin_radius.fill(0.1);
    for (const State& s : random_states(p, 50, 700 + m++)) {
      FourBarEvaluation fwd;
      if (!four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &fwd).ok()) continue;
      if (fwd.iterations <= EvalOptions{}.friction_max_iter) continue;  // not a Newton solve
      ++newton;
      const std::vector<double> Mf(fwd.Mf.begin(), fwd.Mf.end());
      chain::Options opt;
      opt.friction_torques = &Mf;
      const chain::Solution cf = chain_solution(p, s, nullptr, opt);
      EXPECT_NEAR(cf.alpha[0], fwd.thdd[0], 1e-9 * (1 + std::abs(fwd.thdd[0])));
      EXPECT_LT(reaction_error(cf.F, fwd.F), 1e-9);
      for (int k = 0; k < kFourBarJoints; ++k) {
        const double f = friction_law(p.friction, k, fwd.w[k], sign_of(fwd.w[k]));
        EXPECT_NEAR(Mf[k], p.friction.pin_radius[k] * f * cf.N[k], 1e-9 * (1 + std::abs(Mf[k])));
      }
    }
  }
  EXPECT_GT(newton, 0);
  RecordProperty("newton_solves", newton);
}

// pins far too large for the loads: the friction loop finds no consistent reactions and says so
TEST(FourBar, ReportsFrictionWithoutConsistentReactions) {
  FourBarParams p = mechanisms(true)[0];
  p.friction.pin_radius.fill(0.5);
  p.friction.coulomb.fill(0.5);
  int failed = 0;
  for (const State& s : random_states(p, 20, 600)) {
    FourBarEvaluation ev;
    const Status st = four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &ev);
    if (st.ok()) continue;
    ++failed;
    EXPECT_EQ(st.code, StatusCode::kFrictionNotConverged);
    EXPECT_NE(st.message.find("friction loop"), std::string::npos) << st.message;
  }
  EXPECT_GT(failed, 0);
  RecordProperty("failed_of_20", failed);
}

TEST(FourBar, ReportsPosesThatCannotAssembleOrAreSingular) {
  FourBarParams p;
  p.ground_length = 1.0;
  p.links[0].length = 0.2;
  p.links[1].length = 0.3;
  p.links[2].length = 0.3;
  FourBarKinematics k;
  Status st = four_bar_kinematics(p, 0.0, &k);  // |BD0| = 0.8 > 0.6
  EXPECT_EQ(st.code, StatusCode::kCannotAssemble);
  EXPECT_NE(st.message.find("|BD0|"), std::string::npos) << st.message;
  p.ground_length = 0.79;  // |BD0| = 0.59 at th1 = 0: coupler and rocker nearly aligned
  st = four_bar_kinematics(p, 0.0, &k, 0.5);
  EXPECT_EQ(st.code, StatusCode::kNearSingular);
  EXPECT_NE(st.message.find("sin(theta3 - theta2)"), std::string::npos) << st.message;
}

// The dynamics written once over the mechanism concept (mechanism_dynamics.h) give the four-bar
// what the five-bar has: stuck joints held by constraint torques, the rest rule, LuGre.

// at rest with one joint stuck the mechanism is locked: no acceleration, and the holding torque
// lambda at joint j balances the generalized force, J_wj lambda = Q0 (every other joint at rest
// carries no friction torque)
TEST(FourBar, AStuckJointHoldsTheGeneralizedForce) {
  double worst = 0.0;
  int m = 0;
  for (const FourBarParams& p : mechanisms(true)) {
    for (const State& s : random_states(p, 5, 600 + m++)) {
      for (int j = 0; j < kFourBarJoints; ++j) {
        JointModes slip{};
        slip[j] = kStuck;
        FourBarEvaluation ev;
        ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, 0.0, EvalOptions{}, &ev, &slip).ok());
        double M, Q0;
        four_bar_mass_and_force(p, ev.kin, ev.bias, s.loads, &M, &Q0);
        const double row = four_bar_joint_rows(ev.kin)[j];
        EXPECT_EQ(ev.thdd[0], 0.0);
        worst = std::max(worst, std::abs(row * ev.Mf[j] - Q0) / (1 + std::abs(Q0)));
        EXPECT_NEAR(ev.hold_margin[j],
                    holding_bound(p.friction, j) * ev.N[j] - std::abs(ev.Mf[j]),
                    1e-12 * (1 + ev.N[j]));
        for (int k = 0; k < kJoints; ++k) {
          if (k != j) {
            EXPECT_EQ(ev.Mf[k], 0.0);
          }
        }
        // the reactions are those of the holding torque
        std::array<Vec2<double>, kJoints> F;
        four_bar_reactions(p, ev.kin, ev.bias, 0.0, s.loads, ev.Mf, &F);
        for (int k = 0; k < kJoints; ++k) {
          EXPECT_NEAR((F[k] - ev.F[k]).norm(), 0.0, 1e-12 * (1 + ev.N[k]));
        }
      }
    }
  }
  EXPECT_LT(worst, 1e-12);
  RecordProperty("holding_torque_balance", sci(worst));
}

// the rest rule: a crank at rest that does not accelerate stands still, every joint is stuck and
// carries no friction torque (the drive holds the frictionless equilibrium), and each joint's
// hold margin is its static capacity mu_s r N
TEST(FourBar, TheRestRuleHoldsThePoseWithTheDrive) {
  EvalOptions rest;
  rest.rest_rate = 1e-6;
  rest.rest_acceleration = 1e-6;
  int m = 0;
  for (const FourBarParams& p : mechanisms(true)) {
    FourBarParams frictionless = p;
    frictionless.friction.law = FrictionLaw::kNone;
    for (const State& s : random_states(p, 5, 700 + m++)) {
      FourBarEvaluation held, free;
      ASSERT_TRUE(four_bar_inverse(p, s.loads, s.th1, 1e-7, 0.0, rest, &held).ok());
      ASSERT_TRUE(four_bar_inverse(frictionless, s.loads, s.th1, 0.0, 0.0, EvalOptions{}, &free)
                      .ok());
      EXPECT_NEAR(held.M1, free.M1, 1e-12 * (1 + std::abs(free.M1)));
      EXPECT_EQ(held.thdd[0], 0.0);
      for (int k = 0; k < kFourBarJoints; ++k) {
        EXPECT_EQ(held.slip[k], kStuck) << "joint " << k;
        EXPECT_EQ(held.Mf[k], 0.0);
        EXPECT_NEAR(held.hold_margin[k], holding_bound(p.friction, k) * held.N[k],
                    1e-12 * (1 + held.N[k]));
      }
      EXPECT_EQ(held.slip[kFourBarJoints], JointMode::kRest);  // the unused slot
    }
  }
}

/// The mechanisms of mechanisms(true) with the crank motor's friction (actuator.h): c_a and v_a
/// drawn from `seed`, and a sensor offset (no effect on the dynamics).
std::vector<FourBarParams> motor_mechanisms(uint64_t seed = 23) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> c(0.02, 0.3), v(0.002, 0.02);
  std::vector<FourBarParams> out = mechanisms(true);
  for (FourBarParams& p : out) {
    p.actuators.coulomb[0] = c(rng);
    p.actuators.viscous[0] = v(rng);
    p.actuators.offset[0] = 0.03;
  }
  return out;
}

// The crank motor's friction c_a sign(w1) + v_a w1 at O on seeded random four-bars: the inverse of
// the forward dynamics (in the forward's modes) returns the crank torque, or reports that the
// inverse problem has several consistent reactions (rare, as without the motor).
TEST(FourBar, MotorFrictionInverseOfForwardReturnsTheTorque) {
  double worst = 0.0;
  int m = 0, returned = 0, reported = 0;
  for (const FourBarParams& p : motor_mechanisms()) {
    for (const State& s : random_states(p, 50, 1000 + m++)) {
      FourBarEvaluation fwd, inv;
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &fwd).ok());
      const Status st = mech::inverse<FourBar, double>(p, s.loads, FourBar::Q<double>(s.th1),
                                                       FourBar::Q<double>(s.w1), fwd.thdd,
                                                       &fwd.slip, EvalOptions{}, &inv);
      if (!st.ok()) {
        ++reported;
        EXPECT_TRUE(several_solutions(st)) << st.message;
        continue;
      }
      ++returned;
      worst = std::max(worst, std::abs(inv.M1 - s.loads.M1));
    }
  }
  EXPECT_LT(worst, 1e-9);  // N m
  EXPECT_LE(reported, returned / 100);
  RecordProperty("inverse_of_forward_Nm", sci(worst));
  RecordProperty("several_solutions", reported);
}

// Joint and motor friction never supply power: every joint's Mf_k w_k >= 0, O carrying at least
// the motor's share c_a + v_a |w1| (the joint friction there has the same sign), and the
// dissipated power counts the motor's.
TEST(FourBar, MotorFrictionNeverSuppliesPower) {
  int m = 0;
  for (const FourBarParams& p : motor_mechanisms()) {
    const double c = p.actuators.coulomb[0], v = p.actuators.viscous[0];
    for (const State& s : random_states(p, 50, 1100 + m++)) {
      FourBarEvaluation ev;
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, s.w1, EvalOptions{}, &ev).ok());
      double power = 0.0;
      for (int k = 0; k < kFourBarJoints; ++k) {
        EXPECT_GE(ev.Mf[k] * ev.w[k], 0.0) << "joint " << k;
        power += ev.Mf[k] * ev.w[k];
      }
      EXPECT_GE(std::abs(ev.Mf[0]), c + v * std::abs(s.w1) - 1e-12);
      EXPECT_NEAR(ev.P_diss, power, 1e-12 * (1 + power));
      EXPECT_GE(ev.P_diss, (c + v * std::abs(s.w1)) * std::abs(s.w1) * (1 - 1e-12));
    }
  }
}

// With no joint friction arm (pin radii 0, the law on) the crank torque of a motion grows by
// exactly the motor's c_a sign(w1) + v_a w1, its dissipated power by that times w1; the sensor
// offset changes nothing.
TEST(FourBar, MotorFrictionAddsItsTorqueAtTheCrank) {
  int m = 0;
  for (FourBarParams bare : mechanisms(true)) {
    bare.friction.pin_radius.fill(0.0);
    FourBarParams motor = bare;
    motor.actuators.coulomb[0] = 0.05;
    motor.actuators.viscous[0] = 0.004;
    motor.actuators.offset[0] = 0.3;
    for (const State& s : random_states(bare, 20, 1200 + m++)) {
      FourBarEvaluation a, b;
      ASSERT_TRUE(four_bar_inverse(bare, s.loads, s.th1, s.w1, 3.0, EvalOptions{}, &a).ok());
      ASSERT_TRUE(four_bar_inverse(motor, s.loads, s.th1, s.w1, 3.0, EvalOptions{}, &b).ok());
      const double friction = 0.05 * (s.w1 > 0 ? 1.0 : -1.0) + 0.004 * s.w1;
      EXPECT_NEAR(b.M1 - a.M1, friction, 1e-12);
      EXPECT_NEAR(b.P_diss - a.P_diss, friction * s.w1, 1e-10);
    }
  }
}

// A stuck crank (joint O held) holds up to its capacity mu_s r N_O plus the motor's c_a; the
// other joints' capacities have no motor share.
TEST(FourBar, AStuckCrankHoldsWithinItsCapacityWithTheMotor) {
  int m = 0;
  for (const FourBarParams& p : motor_mechanisms()) {
    for (const State& s : random_states(p, 5, 1300 + m++)) {
      JointModes slip{};
      slip[0] = kStuck;
      FourBarEvaluation ev;
      ASSERT_TRUE(four_bar_forward(p, s.loads, s.th1, 0.0, EvalOptions{}, &ev, &slip).ok());
      EXPECT_EQ(ev.thdd[0], 0.0);
      const double capacity = holding_bound(p.friction, 0) * ev.N[0] + p.actuators.coulomb[0];
      EXPECT_NEAR(FourBar::holding_capacity(p, 0, ev.N[0]), capacity, 1e-15 * (1 + capacity));
      EXPECT_NEAR(ev.hold_margin[0], capacity - std::abs(ev.Mf[0]), 1e-12 * (1 + ev.N[0]));
      for (int k = 1; k < kFourBarJoints; ++k) {
        EXPECT_EQ(FourBar::holding_capacity(p, k, ev.N[k]), holding_bound(p.friction, k) * ev.N[k]);
      }
    }
  }
}

// LuGre with bristle states: the inverse of the forward dynamics at the same bristle states and
// modes returns the crank torque, and both give the same bristle rates and reactions, or it
// reports that the inverse problem has several consistent reactions (as the Coulomb-viscous
// states of InverseOfForwardReturnsTheTorqueOrReportsSeveralSolutions).
TEST(FourBar, LuGreInverseOfForwardReturnsTheTorque) {
  double worst = 0.0;
  int m = 0, returned = 0, reported = 0;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> load(0.0, 1.0);
  for (FourBarParams p : mechanisms(true)) {
    p.friction.law = FrictionLaw::kLuGre;
    for (int j = 0; j < kFourBarJoints; ++j) {
      p.friction.static_coulomb[j] = 1.3 * p.friction.coulomb[j];
      p.friction.stribeck_velocity[j] = 0.1;
      p.friction.sigma0[j] = 1e4;
      p.friction.sigma1[j] = 0.01;
      p.friction.sigma2[j] = p.friction.viscous[j];
    }
    for (const State& s : random_states(p, 10, 800 + m++)) {
      // bristles loaded part of the way to their steady state g(w) sign(w) / sigma0
      FourBarKinematics k;
      ASSERT_TRUE(four_bar_kinematics(p, s.th1, &k).ok());
      std::array<double, kJoints> z{};
      for (int j = 0; j < kFourBarJoints; ++j) {
        const double w = four_bar_joint_rows(k)[j] * s.w1;
        z[j] = load(rng) * sign_of(w) * stribeck_level(p.friction, j, w) / p.friction.sigma0[j];
      }
      const FourBar::Q<double> q(s.th1), v(s.w1);
      FourBarEvaluation fwd, inv;
      const Status forward =
          mech::forward<FourBar, double>(p, s.loads, q, v, nullptr, EvalOptions{}, &fwd, &z);
      ASSERT_TRUE(forward.ok()) << forward.message;
      const Status inverse = mech::inverse<FourBar, double>(p, s.loads, q, v, fwd.thdd, &fwd.slip,
                                                            EvalOptions{}, &inv, &z);
      if (!inverse.ok()) {
        ++reported;
        EXPECT_TRUE(several_solutions(inverse)) << inverse.message;
        continue;
      }
      ++returned;
      worst = std::max(worst, std::abs(inv.M1 - s.loads.M1) / (1 + std::abs(s.loads.M1)));
      for (int j = 0; j < kFourBarJoints; ++j) {
        EXPECT_NEAR(inv.zdot[j], fwd.zdot[j], 1e-12 * (1 + std::abs(fwd.zdot[j])));
        EXPECT_NEAR(inv.N[j], fwd.N[j], 1e-9 * (1 + fwd.N[j]));
      }
    }
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(reported, returned / 20);
  RecordProperty("lugre_inverse_of_forward", sci(worst));
  RecordProperty("lugre_inverse_returned", returned);
  RecordProperty("lugre_inverse_several_solutions", reported);
}

// the four-bar in Jets: derivatives of its inverse dynamics with friction in six parameters (the
// four joints' Coulomb coefficients, the coupler's mass, gravity) from the friction loop's
// implicit derivative, written once over the mechanism, against the loop iterated in Jets and
// against central differences
TEST(FourBar, JetDerivativesOfInverseDynamicsMatchCentralDifferences) {
  using J = ceres::Jet<double, 6>;
  const auto parameter = [](auto& p, int i) -> auto& {
    return i < kFourBarJoints ? p.friction.coulomb[i] : i == 4 ? p.links[1].mass : p.gravity;
  };
  double worst_fd = 0.0, worst_loop = 0.0;
  int m = 0;
  for (const FourBarParams& p : mechanisms(true)) {
    if (m >= 6) break;
    for (const State& s : random_states(p, 5, 900 + m++)) {
      FourBarParamsT<J> pj = p.cast<J>();
      for (int i = 0; i < 6; ++i) parameter(pj, i).v[i] = 1.0;
      const FourBarLoadsT<J> Lj = s.loads.cast<J>();
      const J th(s.th1), w(s.w1), al(3.0 * s.loads.M1);
      FourBarEvaluationT<J> implicit, iterated;
      EvalOptions loop;
      loop.implicit_loop_derivative = false;
      ASSERT_TRUE(four_bar_inverse(pj, Lj, th, w, al, EvalOptions{}, &implicit).ok());
      ASSERT_TRUE(four_bar_inverse(pj, Lj, th, w, al, loop, &iterated).ok());
      for (int i = 0; i < 6; ++i) {
        // fourth-order central difference, h = 1e-3 (M1 is a difference of terms near N |B|,
        // which rounds to ~1e-10 N m at the larger reactions: smaller steps amplify that)
        const double x = parameter(p, i), h = 1e-3 * std::max(1.0, std::abs(x));
        double M1[4];
        const double at[4] = {-2 * h, -h, h, 2 * h};
        for (int e = 0; e < 4; ++e) {
          FourBarParams q = p;
          parameter(q, i) = x + at[e];
          FourBarEvaluation ev;
          ASSERT_TRUE(four_bar_inverse(q, s.loads, s.th1, s.w1, al.a, EvalOptions{}, &ev).ok());
          M1[e] = ev.M1;
        }
        const double fd = (M1[0] - 8 * M1[1] + 8 * M1[2] - M1[3]) / (12 * h), d = implicit.M1.v[i];
        worst_fd = std::max(worst_fd, std::abs(d - fd) / (1 + std::abs(fd)));
        worst_loop = std::max(worst_loop, std::abs(d - iterated.M1.v[i]) / (1 + std::abs(d)));
      }
    }
  }
  EXPECT_LT(worst_fd, 1e-6);     // the stencil: truncation ~h^4, roundoff ~1e-10 / h
  EXPECT_LT(worst_loop, 1e-10);  // the same derivative, two ways
  RecordProperty("jet_vs_central_difference", sci(worst_fd));
  RecordProperty("implicit_vs_iterated", sci(worst_loop));
}

}  // namespace
}  // namespace fivebar
