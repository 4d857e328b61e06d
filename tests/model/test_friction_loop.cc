// The friction loop's shortcuts (friction_loop.h, reduced_loop.h): the reactions' response to the
// friction torques in closed form against unit probes of the reactions, the loop on the four
// numbers of the reduced map against the scaled map, the contracting loop's Newton steps against
// the plain fixed point, and the warm start against the cold loop, on seeded random states: each
// shortcut reaches the same solution. And a loop with two consistent solutions, which it reports
// instead of returning one.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "paper.h"

namespace fivebar {
namespace {

// the reactions are affine in the torques: probes and closed form differ by round-off of
// reactions of ~1e3 N
constexpr double kResponseTol = 1e-9;
// two solutions of the loop each within friction_tol (1e-13) of the fixed point, relative
constexpr double kSameSolution = 1e-11;

JointModes random_modes(std::mt19937_64& rng) {
  JointModes m;
  for (auto& x : m) x = rng() % 2 ? JointMode::kSlipPositive : JointMode::kSlipNegative;
  return m;
}

/// Change of the reactions per unit torque at joint j, by probing `solve` at 0 and e_j.
template <typename Solve>
std::array<Vec2<double>, kJoints> probe(Solve&& solve, int j) {
  std::array<double, kJoints> zero{}, unit{};
  unit[j] = 1.0;
  std::array<Vec2<double>, kJoints> F0, F1;
  solve(zero, &F0);
  solve(unit, &F1);
  for (int k = 0; k < kJoints; ++k) F1[k] -= F0[k];
  return F1;
}

TEST(FrictionLoop, ClosedFormResponseMatchesProbes) {
  const Params<double> p = paper_params();
  for (const auto& s : testing::random_states(p, 50, 11)) {
    Kinematics<double> k;
    ASSERT_TRUE(solve_kinematics(p, s.th1, s.th2, &k).ok());
    Bias<double> b;
    compute_bias(p, k, s.w1, s.w2, &b);
    const Vec2<double> Fvec = force_vector(k, s.loads);
    Mat2<double> A;
    Vec2<double> rhs0;
    mass_and_forces(p, k, b, s.loads, Fvec, &A, &rhs0);
    const Mat2<double> Ainv = inverse2(A);
    double al3, al4;
    const Vec2<double> thdd_fixed(3.0, -7.0);
    auto inverse_solve = [&](const std::array<double, kJoints>& Mf,
                             std::array<Vec2<double>, kJoints>* F) {
      reactions(p, k, b, s.loads, Fvec, thdd_fixed, Mf, F, &al3, &al4);
    };
    auto forward_solve = [&](const std::array<double, kJoints>& Mf,
                             std::array<Vec2<double>, kJoints>* F) {
      const Vec2<double> thdd = Ainv * (rhs0 - friction_transpose(k, Mf));
      reactions(p, k, b, s.loads, Fvec, thdd, Mf, F, &al3, &al4);
    };
    const ReactionResponse<double> inv = reaction_torque_response(k);
    const ReactionResponse<double> fwd = mech::detail::forward_torque_response<FiveBar>(p, k, Ainv);
    const ReactionResponse<double> low = FiveBar::forward_response(p, k, Ainv).expand();
    const ReactionResponse<double> cpl = FiveBar::inverse_response(k).expand();
    for (int j = 0; j < kJoints; ++j) {
      const auto pi = probe(inverse_solve, j), pf = probe(forward_solve, j);
      for (int m = 0; m < kJoints; ++m) {
        const double scale = 1.0 + pf[m].norm() + pi[m].norm();
        EXPECT_LT((inv[j][m] - pi[m]).norm(), kResponseTol * scale) << "inverse j=" << j;
        EXPECT_LT((fwd[j][m] - pf[m]).norm(), kResponseTol * scale) << "forward j=" << j;
        EXPECT_LT((low[j][m] - pf[m]).norm(), kResponseTol * scale) << "low rank j=" << j;
        EXPECT_LT((cpl[j][m] - pi[m]).norm(), kResponseTol * scale) << "rank 2 j=" << j;
      }
    }
  }
}

void expect_same_evaluation(const Evaluation<double>& a, const Evaluation<double>& b) {
  double scale = 1.0;
  for (int k = 0; k < kJoints; ++k) scale = std::max(scale, a.N[k]);
  for (int k = 0; k < kJoints; ++k) {
    EXPECT_NEAR(a.N[k], b.N[k], kSameSolution * scale);
    EXPECT_NEAR(a.Mf[k], b.Mf[k], kSameSolution * scale);
  }
  const double accel = 1.0 + a.thdd.norm();
  EXPECT_NEAR(a.thdd[0], b.thdd[0], kSameSolution * accel);
  EXPECT_NEAR(a.thdd[1], b.thdd[1], kSameSolution * accel);
  EXPECT_EQ(a.slip, b.slip);
}

TEST(FrictionLoop, WarmStartReachesTheColdSolution) {
  // friction raised until some states no longer contract (the cold path takes those)
  for (const double mu : {0.1, 0.6}) {
    Params<double> p = paper_params();
    p.friction.coulomb.fill(mu);
    std::mt19937_64 rng(5);
    EvalOptions opt;
    opt.singular_margin = 1e-3;
    FrictionWarmStart warm;  // carried across unrelated states: the hardest start
    int warm_used = 0;
    for (const auto& s : testing::random_states(p, 200, 23)) {
      const JointModes modes = random_modes(rng);
      Evaluation<double> cold, hot;
      const Status a = forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, &modes, opt, &cold);
      const bool had = warm.set;
      const Status b = forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, &modes, opt, &hot,
                                        static_cast<const std::array<double, kJoints>*>(nullptr),
                                        &warm);
      ASSERT_EQ(a.code, b.code) << a.message << " / " << b.message;
      if (!a.ok()) continue;
      warm_used += had;
      expect_same_evaluation(cold, hot);
    }
    EXPECT_GT(warm_used, 100);
  }
}

TEST(FrictionLoop, WarmStartOnNearbyStatesSavesEvaluations) {
  // states 1e-5 s apart along the paper scene's motion, as an integrator's right-hand sides see
  // them: the warm start carries friction's share of N onto the new frictionless reactions and
  // needs fewer evaluations of the loop's map than the cold start, for the same solution
  const Params<double> p = paper_params();
  EvalOptions opt;
  opt.singular_margin = 1e-3;
  const JointModes slip = {JointMode::kSlipPositive, JointMode::kSlipNegative,
                           JointMode::kSlipPositive, JointMode::kSlipPositive,
                           JointMode::kSlipNegative};
  FrictionWarmStart warm;
  int cold_evaluations = 0, warm_evaluations = 0;
  for (int i = 0; i < 50; ++i) {
    const double dt = 1e-5 * i;
    const Loads<double> L = testing::paper_loads(0.31 + dt);
    Evaluation<double> cold, hot;
    ASSERT_TRUE(forward_dynamics(p, L, 1.3 + 23.0 * dt, 2.0 - 31.0 * dt, 23.0, -31.0, &slip, opt,
                                 &cold)
                    .ok());
    ASSERT_TRUE(forward_dynamics(p, L, 1.3 + 23.0 * dt, 2.0 - 31.0 * dt, 23.0, -31.0, &slip, opt,
                                 &hot, static_cast<const std::array<double, kJoints>*>(nullptr),
                                 &warm)
                    .ok());
    expect_same_evaluation(cold, hot);
    if (i == 0) continue;  // (the first starts cold either way)
    cold_evaluations += cold.iterations;
    warm_evaluations += hot.iterations;
  }
  EXPECT_LT(warm_evaluations, cold_evaluations);
  EXPECT_LE(warm_evaluations, 2 * 49);  // one Newton step reaches the tolerance
}

TEST(FrictionLoop, ContractingNewtonMatchesFixedPoint) {
  const Params<double> p = paper_params();
  std::mt19937_64 rng(7);
  EvalOptions opt;
  int compared = 0;
  for (const auto& s : testing::random_states(p, 100, 31)) {
    const JointModes modes = random_modes(rng);
    // the fixed point alone: the loop iterated in Jets (the reference path) on value-only Jets
    using J1 = ceres::Jet<double, 1>;
    Evaluation<J1> ref;
    EvalOptions ref_opt = opt;
    ref_opt.implicit_loop_derivative = false;
    const Status a =
        forward_dynamics(p.cast<J1>(), s.loads.cast<J1>(), J1(s.th1), J1(s.th2), J1(s.w1),
                         J1(s.w2), &modes, ref_opt, &ref);
    Evaluation<double> fast;
    const Status b = forward_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, &modes, opt, &fast);
    ASSERT_EQ(a.code, b.code);
    if (!a.ok()) continue;
    ++compared;
    double scale = 1.0;
    for (int k = 0; k < kJoints; ++k) scale = std::max(scale, fast.N[k]);
    for (int k = 0; k < kJoints; ++k) EXPECT_NEAR(ref.N[k].a, fast.N[k], kSameSolution * scale);
    EXPECT_NEAR(ref.thdd[0].a, fast.thdd[0], kSameSolution * (1.0 + fast.thdd.norm()));
    EXPECT_NEAR(ref.thdd[1].a, fast.thdd[1], kSameSolution * (1.0 + fast.thdd.norm()));
  }
  EXPECT_GT(compared, 50);
}

/// The reduced map's pieces at a random state with friction raised to mu: the low-rank response,
/// the frictionless reactions and the friction arms of random slip directions.
struct ReducedCase {
  LowRankResponse<double> response;
  std::array<Vec2<double>, kJoints> F0;
  std::array<double, kJoints> phi;
};

std::vector<ReducedCase> reduced_cases(double mu, int n, uint64_t seed) {
  Params<double> p = paper_params();
  p.friction.coulomb.fill(mu);
  std::mt19937_64 rng(seed);
  std::vector<ReducedCase> out;
  for (const auto& s : testing::random_states(p, n, seed)) {
    Kinematics<double> k;
    if (!solve_kinematics(p, s.th1, s.th2, &k).ok()) continue;
    Bias<double> b;
    compute_bias(p, k, s.w1, s.w2, &b);
    const Vec2<double> Fvec = force_vector(k, s.loads);
    Mat2<double> A;
    Vec2<double> rhs0;
    mass_and_forces(p, k, b, s.loads, Fvec, &A, &rhs0);
    const Mat2<double> Ainv = inverse2(A);
    ReducedCase c;
    c.response = FiveBar::forward_response(p, k, Ainv);
    double al3, al4;
    reactions(p, k, b, s.loads, Fvec, Vec2<double>(Ainv * rhs0), std::array<double, kJoints>{},
              &c.F0, &al3, &al4);
    const JointModes modes = random_modes(rng);
    for (int j = 0; j < kJoints; ++j) {
      c.phi[j] = p.friction.pin_radius[j] * mu * (modes[j] == JointMode::kSlipPositive ? 1 : -1);
    }
    out.push_back(c);
  }
  return out;
}

/// The reduced map of a case: forward dynamics' (n = 4) or, from the coupler part of the same
/// response, that at given accelerations (n = 2); and the scaled map of the same response.
template <int n>
detail::ReducedMap<n> reduced_map(const ReducedCase& c) {
  return detail::ReducedMap<n>(c.phi, c.F0, c.response);
}
template <int n>
detail::ScaledReactions<double> scaled_map(const ReducedCase& c) {
  if constexpr (n == 4) return detail::ScaledReactions<double>(c.phi, c.F0, c.response);
  const CouplerResponse<double>& coupler = c.response;
  return detail::ScaledReactions<double>(c.phi, c.F0, coupler.expand());
}

// the reduced map is the scaled map B[k][j] = dF_j[k] phi_j in four (two) numbers, and its gain
// bound is never below the exact one (so the loop's decision between the contracting path and
// the uniqueness check is kept: below 1 the exact bound is below 1 too)
template <int n>
void expect_reduced_map_matches_the_scaled_map() {
  int contracting = 0, beyond = 0;
  for (const double mu : {0.1, 1.0, 5.0, 20.0}) {
    for (const ReducedCase& c : reduced_cases(mu, 60, 41)) {
      const detail::ReducedMap<n> reduced = reduced_map<n>(c);
      const detail::ScaledReactions<double> scaled = scaled_map<n>(c);
      EXPECT_GE(reduced.gain_bound, scaled.contraction_bound * (1.0 - 1e-12));
      (reduced.gain_bound < 1.0 ? contracting : beyond) += 1;
      for (int j = 0; j < kJoints; ++j) {
        double unit[kJoints] = {};
        unit[j] = 1.0;
        typename detail::ReducedMap<n>::Forces f;
        reduced.apply(reduced.moments(unit), &f);
        for (int k = 0; k < kJoints; ++k) {
          const double tol = kResponseTol * (1.0 + scaled.B[k][j].norm());
          EXPECT_NEAR(f[k].x(), scaled.B[k][j].x(), tol) << "k=" << k << " j=" << j;
          EXPECT_NEAR(f[k].y(), scaled.B[k][j].y(), tol) << "k=" << k << " j=" << j;
        }
      }
    }
  }
  EXPECT_GT(contracting, 20);
  EXPECT_GT(beyond, 20);
}

TEST(FrictionLoop, ReducedMapMatchesTheScaledMap) {
  expect_reduced_map_matches_the_scaled_map<4>();
}
TEST(FrictionLoop, CouplerMapMatchesTheScaledMap) {
  expect_reduced_map_matches_the_scaled_map<2>();
}

// Newton and chord steps on the reduced map reach the fixed point of the scaled map's loop (and
// its own convergence test holds there), from |F0| and from a start far off
template <int n>
void expect_reduced_newton_reaches_the_fixed_point() {
  EvalOptions opt;
  int compared = 0;
  for (const double mu : {0.1, 0.6, 3.0}) {
    for (const ReducedCase& c : reduced_cases(mu, 60, 43)) {
      const detail::ReducedMap<n> reduced = reduced_map<n>(c);
      if (!(reduced.gain_bound < 1.0)) continue;
      const detail::ScaledReactions<double> scaled = scaled_map<n>(c);
      std::array<double, kJoints> N_ref, Mf_ref, start;
      std::array<Vec2<double>, kJoints> F_ref;
      int it_ref = 0;
      bool contracting = true;
      double ratio = 0.0;
      ASSERT_TRUE(detail::friction_fixed_point<double>(c.phi, opt, scaled, nullptr, &N_ref,
                                                       &Mf_ref, &F_ref, &it_ref, &contracting,
                                                       &ratio));
      reaction_norms(c.F0, &start);
      for (const double factor : {1.0, 3.0}) {
        std::array<double, kJoints> s = start, N, Mf;
        for (double& v : s) v *= factor;
        std::array<Vec2<double>, kJoints> F;
        int it = 0;
        ASSERT_TRUE(detail::friction_reduced_newton(reduced, opt, s, &N, &Mf, &F, &it));
        double scale = 1.0;
        for (int k = 0; k < kJoints; ++k) scale = std::max(scale, N_ref[k]);
        for (int k = 0; k < kJoints; ++k) {
          EXPECT_NEAR(N[k], N_ref[k], kSameSolution * scale);
          EXPECT_NEAR(N[k], F[k].norm(), 1e-14 * scale);  // N = |F|
          EXPECT_DOUBLE_EQ(Mf[k], c.phi[k] * N[k]);
        }
        // one more fixed-point evaluation moves N by at most the loop's tolerance
        std::array<Vec2<double>, kJoints> F_next;
        std::array<double, kJoints> N_next;
        scaled.evaluate(N, &F_next, &N_next);
        for (int k = 0; k < kJoints; ++k) {
          EXPECT_LE(std::abs(N_next[k] - N[k]), 2 * opt.friction_tol * scale);
        }
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 100);
}

TEST(FrictionLoop, ReducedNewtonReachesTheFixedPoint) {
  expect_reduced_newton_reaches_the_fixed_point<4>();
}
TEST(FrictionLoop, CouplerNewtonReachesTheFixedPoint) {
  expect_reduced_newton_reaches_the_fixed_point<2>();
}

// inverse dynamics on the rank-2 map (double) against the loop iterated in Jets on the unscaled
// map (value-only Jets, the reference path), friction raised until some states no longer
// contract: the same outcome, and the same solution
TEST(FrictionLoop, InverseCouplerLoopMatchesTheReferenceLoop) {
  using J1 = ceres::Jet<double, 1>;
  int compared = 0;
  for (const double mu : {0.12, 2.0, 8.0}) {
    Params<double> p = paper_params();
    p.friction.coulomb.fill(mu);
    std::mt19937_64 rng(9);
    EvalOptions opt, ref_opt;
    ref_opt.implicit_loop_derivative = false;
    for (const auto& s : testing::random_states(p, 60, 47)) {
      const double a1 = std::uniform_real_distribution<double>(-50.0, 50.0)(rng);
      const double a2 = std::uniform_real_distribution<double>(-50.0, 50.0)(rng);
      Evaluation<double> fast;
      Evaluation<J1> ref;
      const Status a =
          inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, a1, a2, nullptr, opt, &fast);
      const Status b = inverse_dynamics(p.cast<J1>(), s.loads.cast<J1>(), J1(s.th1), J1(s.th2),
                                        J1(s.w1), J1(s.w2), J1(a1), J1(a2), nullptr, ref_opt, &ref);
      ASSERT_EQ(a.code, b.code) << a.message << " / " << b.message;
      if (!a.ok()) continue;
      ++compared;
      double scale = 1.0;
      for (int k = 0; k < kJoints; ++k) scale = std::max(scale, fast.N[k]);
      for (int k = 0; k < kJoints; ++k) EXPECT_NEAR(ref.N[k].a, fast.N[k], kSameSolution * scale);
      EXPECT_NEAR(ref.M1.a, fast.M1, kSameSolution * scale);
      EXPECT_NEAR(ref.M2.a, fast.M2, kSameSolution * scale);
    }
  }
  EXPECT_GT(compared, 100);
}

/// A loop whose only friction is at joint O, with F_O = F0 + B Mf_O (the other reactions fixed):
/// N = |F0 + B N| is (|B|^2 - 1) N^2 + 2 (F0 . B) N + |F0|^2 = 0 for |B| > 1, two positive roots
/// where F0 . B < 0 and the discriminant is positive; one for |B| < 1.
struct OneJointLoop {
  Vec2<double> F0, B;
  void operator()(const std::array<double, kJoints>& Mf,
                  std::array<Vec2<double>, kJoints>* F) const {
    for (auto& f : *F) f = Vec2<double>(1.0, 2.0);
    (*F)[0] = F0 + B * Mf[0];
  }
  /// the roots, smaller first (nan where none)
  std::array<double, 2> roots() const {
    const double a = B.squaredNorm() - 1.0, b = F0.dot(B), c = F0.squaredNorm();
    const double d = std::sqrt(b * b - a * c);
    if (a < 0.0) return {(-b - d) / a, NAN};  // the positive root of a N^2 + 2 b N + c = 0
    return {(-b - d) / a, (-b + d) / a};
  }
};

// two consistent N (the loop's gain bound 1.3): the loop reports both instead of returning one,
// and the continuation in the friction scale from the frictionless |F0| reaches the smaller
TEST(FrictionLoop, ReportsSeveralConsistentSolutions) {
  const OneJointLoop loop{Vec2<double>(1.0, 0.0), Vec2<double>(-1.2, 0.1)};
  const std::array<double, 2> root = loop.roots();
  ASSERT_GT(root[0], 0.0);
  ASSERT_GT(root[1], 2 * root[0]);
  std::array<double, kJoints> phi{};
  phi[0] = 1.0;
  std::array<Vec2<double>, kJoints> F0;
  loop(std::array<double, kJoints>{}, &F0);
  const detail::AffineReactions<double> map = detail::probe_reactions(phi, loop, F0);
  std::array<double, kJoints> N, Mf;
  EvalOptions opt;
  ASSERT_TRUE(detail::friction_continuation(phi, opt, map, &N));
  EXPECT_NEAR(N[0], root[0], 1e-12);
  std::array<Vec2<double>, kJoints> F;
  int iterations = 0;
  const Status st = friction_loop(phi, opt, loop, &N, &Mf, &F, &iterations);
  EXPECT_EQ(st.code, StatusCode::kFrictionNotConverged);
  EXPECT_NE(st.message.find("several consistent reaction forces"), std::string::npos)
      << st.message;
}

// a gain bound of 1.2 with one consistent N: the loop returns it
TEST(FrictionLoop, ReturnsTheOnlySolutionWhereTheMapDoesNotContractEverywhere) {
  const OneJointLoop loop{Vec2<double>(1.0, 0.0), Vec2<double>(0.9, -0.3)};
  std::array<double, kJoints> phi{}, N, Mf;
  phi[0] = 1.0;
  std::array<Vec2<double>, kJoints> F;
  int iterations = 0;
  const Status st = friction_loop(phi, EvalOptions{}, loop, &N, &Mf, &F, &iterations);
  ASSERT_TRUE(st.ok()) << st.message;
  EXPECT_NEAR(N[0], loop.roots()[0], 1e-12 * N[0]);
  EXPECT_NEAR(Mf[0], N[0], 1e-12 * N[0]);
}

}  // namespace
}  // namespace fivebar
