// Loop closure on both assemblies, and the influence coefficients G, H against central
// differences of the position solve.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fivebar/model/kinematics.h"

namespace fivebar {
namespace {

// closure residual is a sum of a few O(0.3 m) terms: a few ulps
constexpr double kClosureTol = 1e-14;
// central differences with step 1e-5 on O(1) functions: truncation ~1e-10, roundoff ~1e-11
constexpr double kStep = 1e-5;
constexpr double kFirstOrderTol = 1e-8;
constexpr double kSecondOrderTol = 1e-6;

/// Seeded random poses that assemble away from the singular poses.
std::vector<std::pair<double, double>> random_poses(const Params<double>& p, int n) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::vector<std::pair<double, double>> poses;
  while (static_cast<int>(poses.size()) < n) {
    const double th1 = angle(rng), th2 = angle(rng);
    Kinematics<double> k;
    if (solve_kinematics(p, th1, th2, &k, 0.1).ok()) poses.emplace_back(th1, th2);
  }
  return poses;
}

TEST(Kinematics, PaperInitialPose) {
  Params<double> p = paper_params();
  Kinematics<double> k;
  ASSERT_TRUE(solve_kinematics(p, M_PI / 2, M_PI / 2, &k).ok());
  // first row of datasets/reference/paper_friction.csv
  EXPECT_NEAR(k.th3, 0.845181298522063, 1e-13);
  EXPECT_NEAR(k.th4, 2.09024813802233, 1e-13);
}

/// f(p, th1, th2, k) at 200 seeded random closed poses of each assembly of the paper mechanism.
template <typename F>
void for_closed_poses(F&& f) {
  for (int assembly : {kElbowUp, kElbowDown}) {
    Params<double> p = paper_params();
    p.assembly = assembly;
    for (auto [th1, th2] : random_poses(p, 200)) {
      Kinematics<double> k;
      ASSERT_TRUE(solve_kinematics(p, th1, th2, &k).ok());
      f(p, th1, th2, k);
    }
  }
}

TEST(Kinematics, LoopClosesOnBothAssemblies) {
  for_closed_poses([](const Params<double>& p, double th1, double th2,
                      const Kinematics<double>& k) {
    const Vec2<double> B = p.links[0].length * unit(th1);
    const Vec2<double> D = Vec2<double>(p.ground_length, 0) + p.links[1].length * unit(th2);
    const Vec2<double> C3 = B + p.links[2].length * unit(k.th3);
    const Vec2<double> C4 = D + p.links[3].length * unit(k.th4);
    EXPECT_LT((C3 - C4).norm(), kClosureTol);
    // elbow_up: C on the left of B->D
    EXPECT_EQ(cross(Vec2<double>(D - B), Vec2<double>(C3 - B)) > 0, p.assembly == kElbowUp);
  });
}

TEST(Kinematics, ReportsPosesThatCannotAssemble) {
  Params<double> p = paper_params();
  p.links[2].length = 0.05;
  p.links[3].length = 0.05;  // couplers too short to span |BD| ~ 0.29
  Kinematics<double> k;
  const Status st = solve_kinematics(p, M_PI / 2, M_PI / 2, &k);
  EXPECT_EQ(st.code, StatusCode::kCannotAssemble);
  EXPECT_NE(st.message.find("cannot assemble"), std::string::npos);
}

TEST(Kinematics, ReportsNearSingularPoses) {
  Params<double> p = paper_params();
  // cranks placed so that |BD| = l3 + l4 - tiny: couplers almost aligned
  p.ground_length = 0.4 - 1e-9;  // th1 = pi, th2 = 0: |BD| = l0 + l1 + l2
  p.links[0].length = 0.05;
  p.links[1].length = 0.05;
  Kinematics<double> k;
  const Status st = solve_kinematics(p, M_PI, 0.0, &k, 1e-3);
  EXPECT_EQ(st.code, StatusCode::kNearSingular) << st.message;
}

// position of every tracked quantity as one vector: th3, th4, c1..c4, P
Eigen::Matrix<double, 12, 1> positions(const Params<double>& p, double th1, double th2) {
  Kinematics<double> k;
  EXPECT_TRUE(solve_kinematics(p, th1, th2, &k).ok());
  Eigen::Matrix<double, 12, 1> x;
  x << k.th3, k.th4, k.c[0], k.c[1], k.c[2], k.c[3], k.P;
  return x;
}

Eigen::Matrix<double, 12, 2> gradients(const Kinematics<double>& k) {
  Eigen::Matrix<double, 12, 2> G;
  G.row(0) = k.G3;
  G.row(1) = k.G4;
  for (int i = 0; i < 4; ++i) G.block<2, 2>(2 + 2 * i, 0) = k.Gc[i];
  G.block<2, 2>(10, 0) = k.GP;
  return G;
}

TEST(Kinematics, FirstOrderCoefficientsMatchCentralDifferences) {
  for (int assembly : {kElbowUp, kElbowDown}) {
    Params<double> p = paper_params();
    p.assembly = assembly;
    p.links[2].com_angle = 0.3;  // exercise the COM angle terms
    p.links[3].com_angle = -0.2;
    p.links[0].com_angle = 0.1;
    for (auto [th1, th2] : random_poses(p, 50)) {
      Kinematics<double> k;
      ASSERT_TRUE(solve_kinematics(p, th1, th2, &k).ok());
      const auto G = gradients(k);
      const Eigen::Matrix<double, 12, 1> d1 = (positions(p, th1 + kStep, th2) - positions(p, th1 - kStep, th2)) / (2 * kStep);
      const Eigen::Matrix<double, 12, 1> d2 = (positions(p, th1, th2 + kStep) - positions(p, th1, th2 - kStep)) / (2 * kStep);
      EXPECT_LT((G.col(0) - d1).cwiseAbs().maxCoeff(), kFirstOrderTol);
      EXPECT_LT((G.col(1) - d2).cwiseAbs().maxCoeff(), kFirstOrderTol);
    }
  }
}

TEST(Kinematics, SecondOrderCoefficientsMatchCentralDifferences) {
  Params<double> p = paper_params();
  p.links[2].com_angle = 0.3;
  p.links[3].com_angle = -0.2;
  for (auto [th1, th2] : random_poses(p, 50)) {
    Kinematics<double> k, kp, km;
    ASSERT_TRUE(solve_kinematics(p, th1, th2, &k).ok());
    const Hessians<double> H = compute_hessians(p, k);
    for (int m = 0; m < 2; ++m) {
      const double a1 = m == 0 ? kStep : 0.0, a2 = m == 1 ? kStep : 0.0;
      ASSERT_TRUE(solve_kinematics(p, th1 + a1, th2 + a2, &kp).ok());
      ASSERT_TRUE(solve_kinematics(p, th1 - a1, th2 - a2, &km).ok());
      const auto dG = ((gradients(kp) - gradients(km)) / (2 * kStep)).eval();
      // column m of each Hessian is d G / d th_m
      EXPECT_LT((H.H3.col(m).transpose() - dG.row(0)).cwiseAbs().maxCoeff(), kSecondOrderTol);
      EXPECT_LT((H.H4.col(m).transpose() - dG.row(1)).cwiseAbs().maxCoeff(), kSecondOrderTol);
      for (int i = 0; i < 4; ++i) {
        for (int c = 0; c < 2; ++c) {
          EXPECT_LT((H.Hc[i][c].col(m).transpose() - dG.row(2 + 2 * i + c)).cwiseAbs().maxCoeff(),
                    kSecondOrderTol);
        }
      }
      for (int c = 0; c < 2; ++c) {
        EXPECT_LT((H.HP[c].col(m).transpose() - dG.row(10 + c)).cwiseAbs().maxCoeff(),
                  kSecondOrderTol);
      }
    }
  }
}

TEST(Kinematics, BiasEqualsQuadraticFormOfHessians) {
  Params<double> p = paper_params();
  p.links[3].com_angle = 0.4;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> rate(0.0, 20.0);
  for (auto [th1, th2] : random_poses(p, 50)) {
    Kinematics<double> k;
    ASSERT_TRUE(solve_kinematics(p, th1, th2, &k).ok());
    const Hessians<double> H = compute_hessians(p, k);
    const Vec2<double> w(rate(rng), rate(rng));
    Bias<double> b;
    compute_bias(p, k, w[0], w[1], &b);
    const double scale = 1.0 + w.squaredNorm();
    EXPECT_NEAR(b.h3, w.dot(H.H3 * w), 1e-12 * scale);
    EXPECT_NEAR(b.h4, w.dot(H.H4 * w), 1e-12 * scale);
    for (int i = 0; i < 4; ++i) {
      for (int c = 0; c < 2; ++c) EXPECT_NEAR(b.hc[i][c], w.dot(H.Hc[i][c] * w), 1e-12 * scale);
    }
  }
}

// the optimizer's coupler cosine: cos(th4 - th3) of the closed loop, its gradient against
// central differences, and a value beyond 1 where the loop cannot close
TEST(Kinematics, CouplerCosineMatchesTheClosedLoop) {
  for_closed_poses([](const Params<double>& p, double th1, double th2,
                      const Kinematics<double>& k) {
    Row2<double> g;
    const double c = coupler_cosine(p, th1, th2, &g);
    EXPECT_NEAR(c, std::cos(k.th4 - k.th3), kClosureTol);
    EXPECT_NEAR(c * c + k.sin43 * k.sin43, 1.0, kClosureTol);
    auto cosine = [&](double a, double b) { return coupler_cosine(p, a, b); };
    const double d1 = (cosine(th1 + kStep, th2) - cosine(th1 - kStep, th2)) / (2 * kStep);
    const double d2 = (cosine(th1, th2 + kStep) - cosine(th1, th2 - kStep)) / (2 * kStep);
    EXPECT_NEAR(g[0], d1, kFirstOrderTol);
    EXPECT_NEAR(g[1], d2, kFirstOrderTol);
  });
  Params<double> p = paper_params();
  p.links[2].length = p.links[3].length = 0.05;  // cannot span |BD| ~ 0.29
  EXPECT_GT(std::abs(coupler_cosine(p, M_PI / 2, M_PI / 2)), 1.0);
}

// inverse position: the crank angles of a closed pose's point C, in its legs' working modes,
// close back to the same angles (modulo 2 pi); a point out of reach is refused
TEST(Kinematics, CrankAnglesInvertTheLoopClosure) {
  for_closed_poses([](const Params<double>& p, double th1, double th2,
                      const Kinematics<double>& k) {
    std::array<double, 2> th{};
    ASSERT_TRUE(crank_angles(p, k.C, leg_modes(p, k), &th));
    EXPECT_NEAR(std::remainder(th[0] - th1, 2 * M_PI), 0.0, 1e-12);
    EXPECT_NEAR(std::remainder(th[1] - th2, 2 * M_PI), 0.0, 1e-12);
  });
  std::array<double, 2> th{};
  EXPECT_FALSE(crank_angles(paper_params(), Vec2<double>(2.0, 2.0), {1, 1}, &th));
}

}  // namespace
}  // namespace fivebar
