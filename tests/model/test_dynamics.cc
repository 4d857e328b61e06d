// The Appell model against an independent Newton-Euler evaluation in maximal coordinates, inverse
// of forward, energy conservation and dissipation, and the friction loop's failure status.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar {
namespace {

// independent formulation solved by a 22x22 QR: agreement to roundoff of O(100) quantities
constexpr double kCrossCheckTol = 1e-9;

using State = testing::RandomState;
using testing::random_states;

/// Newton-Euler in maximal coordinates: unknowns are the 4 link accelerations (a_cx, a_cy, alpha)
/// and the 5 joint forces; equations are the 12 body equations about the centres of mass and the
/// 10 acceleration constraints of the pins. Friction by a fixed point on |F_k|. Only the pose
/// (th3, th4) comes from the model, and its closure is checked in test_kinematics.
struct NewtonEuler {
  Eigen::Vector2d thdd;
  std::array<double, 5> N;
};

NewtonEuler newton_euler(const Params<double>& p, const State& s) {
  Kinematics<double> k;
  EXPECT_TRUE(solve_kinematics(p, s.th1, s.th2, &k).ok());
  const double th[4] = {s.th1, s.th2, k.th3, k.th4};
  auto e = [](double a) { return Eigen::Vector2d(std::cos(a), std::sin(a)); };
  auto pp = [](const Eigen::Vector2d& v) { return Eigen::Vector2d(-v.y(), v.x()); };
  auto cr = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() * b.y() - a.y() * b.x();
  };
  const double l0 = p.ground_length, l1 = p.links[0].length, l2 = p.links[1].length;
  const double l3 = p.links[2].length, l4 = p.links[3].length;
  const Eigen::Vector2d O(0, 0), D0(l0, 0), B = l1 * e(th[0]), D = D0 + l2 * e(th[1]);
  const Eigen::Vector2d C = B + l3 * e(th[2]), P = B + p.point_p * e(th[2]);
  Eigen::Vector2d c[4];
  const Eigen::Vector2d base[4] = {O, D0, B, D};
  for (int i = 0; i < 4; ++i) c[i] = base[i] + p.links[i].com_offset * e(th[i] + p.links[i].com_angle);
  // coupler rates from the velocity closure l3 e3' w3 - l4 e4' w4 = vD - vB
  Eigen::Matrix2d V;
  V.col(0) = l3 * pp(e(th[2]));
  V.col(1) = -l4 * pp(e(th[3]));
  const Eigen::Vector2d w34 = V.partialPivLu().solve(l2 * s.w2 * pp(e(th[1])) - l1 * s.w1 * pp(e(th[0])));
  const double w[4] = {s.w1, s.w2, w34[0], w34[1]};
  // joints: (point, body i, body j) with body -1 = ground, bodies 0..3 = links 1..4
  struct Joint { Eigen::Vector2d at; int i, j; };
  const Joint joints[5] = {{O, -1, 0}, {B, 0, 2}, {C, 2, 3}, {D, 3, 1}, {D0, -1, 1}};
  const double rel[5] = {w[0], w[2] - w[0], w[3] - w[2], w[1] - w[3], w[1]};
  const double g = p.gravity;
  const Eigen::Vector2d Fext = s.loads.F * e(th[2] + s.loads.F_angle);

  std::array<double, 5> Mf{}, N{};
  Eigen::Matrix<double, 22, 1> x;
  for (int iter = 0; iter < 100; ++iter) {
    Eigen::Matrix<double, 22, 22> A = Eigen::Matrix<double, 22, 22>::Zero();
    Eigen::Matrix<double, 22, 1> b = Eigen::Matrix<double, 22, 1>::Zero();
    // body equations: rows 3i..3i+2; unknown a_c at 3i, 3i+1, alpha at 3i+2; F_k at 12 + 2k
    for (int i = 0; i < 4; ++i) {
      A(3 * i, 3 * i) = p.links[i].mass;
      A(3 * i + 1, 3 * i + 1) = p.links[i].mass;
      A(3 * i + 2, 3 * i + 2) = p.links[i].inertia;
      b(3 * i + 1) = -p.links[i].mass * g;
    }
    b(2) += s.loads.M1;
    b(5) += s.loads.M2;
    b(8) += s.loads.M3 + cr(P - c[2], Fext);
    b.segment<2>(6) += Fext;
    for (int kk = 0; kk < 5; ++kk) {
      const Joint& jt = joints[kk];
      for (int side = 0; side < 2; ++side) {
        const int body = side == 0 ? jt.j : jt.i;
        if (body < 0) continue;
        const double sgn = side == 0 ? 1.0 : -1.0;  // +F_k on j, -F_k on i
        A(3 * body, 12 + 2 * kk) -= sgn;
        A(3 * body + 1, 12 + 2 * kk + 1) -= sgn;
        const Eigen::Vector2d r = jt.at - c[body];  // moment r x F = rx Fy - ry Fx
        A(3 * body + 2, 12 + 2 * kk) -= sgn * -r.y();
        A(3 * body + 2, 12 + 2 * kk + 1) -= sgn * r.x();
        b(3 * body + 2) += -sgn * Mf[kk];  // -Mf on j, +Mf on i
      }
    }
    // pin constraints: a_c + alpha perp(r) - w^2 r equal on both sides (ground: zero)
    for (int kk = 0; kk < 5; ++kk) {
      const Joint& jt = joints[kk];
      for (int side = 0; side < 2; ++side) {
        const int body = side == 0 ? jt.j : jt.i;
        if (body < 0) continue;
        const double sgn = side == 0 ? 1.0 : -1.0;
        const Eigen::Vector2d r = jt.at - c[body];
        for (int d = 0; d < 2; ++d) {
          A(12 + 2 * kk + d, 3 * body + d) += sgn;
          A(12 + 2 * kk + d, 3 * body + 2) += sgn * pp(r)[d];
          b(12 + 2 * kk + d) += sgn * w[body] * w[body] * r[d];
        }
      }
    }
    x = A.colPivHouseholderQr().solve(b);
    std::array<double, 5> N_new;
    for (int kk = 0; kk < 5; ++kk) N_new[kk] = x.segment<2>(12 + 2 * kk).norm();
    double change = 0;
    for (int kk = 0; kk < 5; ++kk) change = std::max(change, std::abs(N_new[kk] - N[kk]));
    N = N_new;
    for (int kk = 0; kk < 5; ++kk) {
      Mf[kk] = p.friction.pin_radius[kk] *
               friction_law(p.friction, kk, rel[kk], (rel[kk] > 0) - (rel[kk] < 0)) * N[kk];
    }
    if (!p.friction.active() || change < 1e-13) break;
  }
  return {Eigen::Vector2d(x(2), x(5)), N};
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
