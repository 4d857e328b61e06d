// The planar four-bar (4R) with load-dependent joint friction, in reduced coordinates (one degree
// of freedom, the crank angle th1): position, rate and acceleration closure, the mass and bias
// terms M(q) qdd + bias = tau - friction, Newton-Euler reactions, forward and inverse dynamics
// with the reaction/friction loop, and its joint table for the general planar chain.
//
// Geometry: O at the origin, D0 = (l0, 0). Link 1 (crank) O->B at th1, link 2 (coupler) B->C at
// th2, link 3 (rocker) D0->C at th3, all from +x. Joints in order O (ground-crank), B
// (crank-coupler), C (coupler-rocker), D0 (ground-rocker), with the five-bar's conventions
// (appell.h): F_k is the force of body i on body j, Mf_k acts -Mf_k on j and +Mf_k on i,
// w_k = omega_j - omega_i. Loads: M1 on the crank (the drive at O), M3 on the coupler and a force
// F at P (on the coupler, point_p from B) at the angle F_angle from the coupler's direction.
// Friction coefficients use slots 0..3 of FrictionParams (joints O, B, C, D0); slot 4 is unused.
#pragma once

#include <array>
#include <cmath>
#include <sstream>
#include <vector>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/five_bar_chain.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/params.h"
#include "fivebar/model/planar_chain.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

inline constexpr int kFourBarJoints = 4;  ///< O, B, C, D0
inline constexpr int kFourBarLinks = 3;   ///< crank, coupler, rocker

/// Every constant of a four-bar (links at index 0..2: crank O->B, coupler B->C, rocker D0->C).
struct FourBarParams {
  double ground_length = 0.0;  ///< l0 [m]: O at (0,0), D0 at (l0,0)
  std::array<Link<double>, kFourBarLinks> links;
  double point_p = 0.0;             ///< P on the coupler, from B [m]
  int assembly = kElbowUp;          ///< kElbowUp: C left of the directed line B->D0
  double gravity = 0.0;             ///< along -y [m/s^2]
  FrictionParams<double> friction;  ///< slots 0..3: joints O, B, C, D0
};

/// Loads of one instant: M1 on the crank, M3 on the coupler, F at P at F_angle from the coupler.
struct FourBarLoads {
  double M1 = 0.0, M3 = 0.0, F = 0.0, F_angle = 0.0;
};

/// A closed pose and its first-order coefficients G (derivatives with respect to th1).
struct FourBarKinematics {
  double th1 = 0, th2 = 0, th3 = 0;
  Vec2<double> e1, e2, e3, B, C, P;
  std::array<Vec2<double>, kFourBarLinks> c, ec;  ///< centres of mass, directions to them
  double sin32 = 0;  ///< sin(th3 - th2), the coupler-rocker angle's sine: zero at singular poses
  double G2 = 0, G3 = 0;                       ///< dth2/dth1, dth3/dth1
  std::array<Vec2<double>, kFourBarLinks> Gc;  ///< d c_i / dth1 [m/rad]
  Vec2<double> GP;                             ///< d P / dth1 [m/rad]
};

/// Rates and the accelerations at alpha1 = 0 (the velocity terms).
struct FourBarBias {
  double w1 = 0, w2 = 0, w3 = 0;
  double h2 = 0, h3 = 0;                       ///< alpha2, alpha3 at alpha1 = 0 [rad/s^2]
  std::array<Vec2<double>, kFourBarLinks> hc;  ///< centre-of-mass accelerations at alpha1 = 0
  Vec2<double> hP;
};

/// Everything one evaluation computes (forward: qdd from M1; inverse: M1 from qdd).
struct FourBarEvaluation {
  FourBarKinematics kin;
  FourBarBias bias;
  double mass = 0;  ///< M(q) [kg m^2]
  double qdd = 0;   ///< alpha1 [rad/s^2]
  double alpha2 = 0, alpha3 = 0;
  double M1 = 0;                               ///< crank torque [N m]
  std::array<Vec2<double>, kFourBarJoints> F;  ///< reactions, force of i on j [N]
  std::array<double, kFourBarJoints> N{}, Mf{}, w{};
  double P_diss = 0;  ///< sum Mf_k w_k [W]
  int iterations = 0;
};

/// The pose: C from the triangle B, C, D0 on the side `assembly`, th2, th3, sin32. Fails with
/// kCannotAssemble when |BD0| is outside [|l2 - l3|, l2 + l3], with kNearSingular when
/// |sin32| < singular_margin.
inline Status four_bar_close(const FourBarParams& p, double th1, FourBarKinematics* k,
                             double singular_margin) {
  const double l2 = p.links[1].length, l3 = p.links[2].length;
  k->th1 = th1;
  k->e1 = unit(th1);
  k->B = p.links[0].length * k->e1;
  const Vec2<double> D0(p.ground_length, 0), d = D0 - k->B;
  const double L2 = d.squaredNorm();
  if (!(L2 > 0) || L2 > (l2 + l3) * (l2 + l3) || L2 < (l2 - l3) * (l2 - l3)) {
    std::ostringstream msg;
    msg << "four-bar cannot assemble at theta1=" << th1 << ": |BD0|=" << std::sqrt(L2)
        << " outside [" << std::abs(l2 - l3) << ", " << l2 + l3 << "]";
    return Status::Error(StatusCode::kCannotAssemble, msg.str());
  }
  const double L = std::sqrt(L2), a = (l2 * l2 + L2 - l3 * l3) / (2 * L);
  const Vec2<double> u = d / L;
  const double h = double(p.assembly) * std::sqrt(std::max(l2 * l2 - a * a, 0.0));
  k->C = k->B + a * u + h * perp(u);
  k->e2 = (k->C - k->B) / l2;
  k->e3 = (k->C - D0) / l3;
  k->th2 = std::atan2(k->e2.y(), k->e2.x());
  k->th3 = std::atan2(k->e3.y(), k->e3.x());
  k->sin32 = cross(k->e2, k->e3);
  if (std::abs(k->sin32) < singular_margin) {
    std::ostringstream msg;
    msg << "near-singular four-bar pose at theta1=" << th1
        << ": |sin(theta3 - theta2)|=" << std::abs(k->sin32) << " < margin " << singular_margin;
    return Status::Error(StatusCode::kNearSingular, msg.str());
  }
  return Status::Ok();
}

/// Position closure, the load point, the centres of mass and the G coefficients. From
/// vB + l2 w2 e2' = l3 w3 e3': l2 s w2 = -vB.e3, l3 s w3 = -vB.e2 (s = sin32).
inline Status four_bar_kinematics(const FourBarParams& p, double th1, FourBarKinematics* k,
                                  double singular_margin = 0.0) {
  const Status st = four_bar_close(p, th1, k, singular_margin);
  if (!st.ok()) return st;
  const std::array<const Vec2<double>*, kFourBarLinks> e = {&k->e1, &k->e2, &k->e3};
  for (int i = 0; i < kFourBarLinks; ++i) {
    const double al = p.links[i].com_angle;
    k->ec[i] = rotate(*e[i], std::cos(al), std::sin(al));
  }
  const Vec2<double> D0(p.ground_length, 0);
  k->P = k->B + p.point_p * k->e2;
  k->c[0] = p.links[0].com_offset * k->ec[0];
  k->c[1] = k->B + p.links[1].com_offset * k->ec[1];
  k->c[2] = D0 + p.links[2].com_offset * k->ec[2];
  const Vec2<double> dB = p.links[0].length * perp(k->e1);  // dB/dth1
  k->G2 = -dB.dot(k->e3) / (p.links[1].length * k->sin32);
  k->G3 = -dB.dot(k->e2) / (p.links[2].length * k->sin32);
  k->Gc[0] = p.links[0].com_offset * perp(k->ec[0]);
  k->Gc[1] = dB + p.links[1].com_offset * k->G2 * perp(k->ec[1]);
  k->Gc[2] = p.links[2].com_offset * k->G3 * perp(k->ec[2]);
  k->GP = dB + p.point_p * k->G2 * perp(k->e2);
  return Status::Ok();
}

/// Rates and velocity terms at crank rate w1. Acceleration closure: l2 al2 e2' - l3 al3 e3' =
/// -aB + l2 w2^2 e2 - l3 w3^2 e3 = delta, so l2 s al2 = delta.e3, l3 s al3 = delta.e2.
inline FourBarBias four_bar_bias(const FourBarParams& p, const FourBarKinematics& k, double w1) {
  const double l1 = p.links[0].length, l2 = p.links[1].length, l3 = p.links[2].length;
  FourBarBias b;
  b.w1 = w1;
  b.w2 = k.G2 * w1;
  b.w3 = k.G3 * w1;
  const Vec2<double> aB = -l1 * w1 * w1 * k.e1;  // at alpha1 = 0
  const Vec2<double> delta = -aB + l2 * b.w2 * b.w2 * k.e2 - l3 * b.w3 * b.w3 * k.e3;
  b.h2 = delta.dot(k.e3) / (l2 * k.sin32);
  b.h3 = delta.dot(k.e2) / (l3 * k.sin32);
  // X = base + r e(th_j + alpha): bias_X = bias_base + r (h_j e'(..) - w_j^2 e(..))
  const auto arm = [](double r, const Vec2<double>& ec, double h, double w) -> Vec2<double> {
    return r * (h * perp(ec) - w * w * ec);
  };
  b.hc[0] = arm(p.links[0].com_offset, k.ec[0], 0.0, w1);
  b.hc[1] = aB + arm(p.links[1].com_offset, k.ec[1], b.h2, b.w2);
  b.hc[2] = arm(p.links[2].com_offset, k.ec[2], b.h3, b.w3);
  b.hP = aB + arm(p.point_p, k.e2, b.h2, b.w2);
  return b;
}

/// Row of J_w (w = J_w w1) of each joint: O 1, B G2 - 1, C G3 - G2, D0 G3.
inline std::array<double, kFourBarJoints> four_bar_joint_rows(const FourBarKinematics& k) {
  return {1.0, k.G2 - 1.0, k.G3 - k.G2, k.G3};
}

/// The force vector at P: F e(th2 + F_angle).
inline Vec2<double> four_bar_force(const FourBarKinematics& k, const FourBarLoads& L) {
  return L.F * rotate(k.e2, std::cos(L.F_angle), std::sin(L.F_angle));
}

/// M(q) = J1 + J2 G2^2 + J3 G3^2 + sum m_i |G_ci|^2, and the friction-free generalized force
/// Q0 = M1 + M3 G2 + G_P . F - g sum m_i G_ci,y - bias (bias = sum J_i G_i h_i + m_i G_ci . h_ci).
inline void four_bar_mass_and_force(const FourBarParams& p, const FourBarKinematics& k,
                                    const FourBarBias& b, const FourBarLoads& L, double* M,
                                    double* Q0) {
  const std::array<double, kFourBarLinks> G = {1.0, k.G2, k.G3}, h = {0.0, b.h2, b.h3};
  *M = 0;
  *Q0 = L.M1 + L.M3 * k.G2 + k.GP.dot(four_bar_force(k, L));
  for (int i = 0; i < kFourBarLinks; ++i) {
    const Link<double>& l = p.links[i];
    *M += l.inertia * G[i] * G[i] + l.mass * k.Gc[i].squaredNorm();
    *Q0 -=
        l.inertia * G[i] * h[i] + l.mass * k.Gc[i].dot(b.hc[i]) + p.gravity * l.mass * k.Gc[i].y();
  }
}

/// Newton-Euler reactions at crank acceleration al1 and friction torques Mf: F_C from the moments
/// of the rocker about D0 and of the coupler about B, then F_B, F_O, F_D0 by force balances.
inline void four_bar_reactions(const FourBarParams& p, const FourBarEvaluation& ev, double al1,
                               const FourBarLoads& L, const std::array<double, kFourBarJoints>& Mf,
                               std::array<Vec2<double>, kFourBarJoints>* F) {
  const FourBarKinematics& k = ev.kin;
  const Vec2<double> g(0, -p.gravity), D0(p.ground_length, 0), Fv = four_bar_force(k, L);
  std::array<Vec2<double>, kFourBarLinks> ma;  // m_i (a_ci - g)
  for (int i = 0; i < kFourBarLinks; ++i) {
    ma[i] = p.links[i].mass * (Vec2<double>(k.Gc[i] * al1 + ev.bias.hc[i]) - g);
  }
  const double al2 = k.G2 * al1 + ev.bias.h2, al3 = k.G3 * al1 + ev.bias.h3;
  // rocker about D0: (C - D0) x F_C = J3 al3 + (c3 - D0) x m3 (a3 - g) + Mf_C + Mf_D0
  const Vec2<double> u = k.C - D0, v = k.C - k.B;
  const double S3 =
      p.links[2].inertia * al3 + cross(Vec2<double>(k.c[2] - D0), ma[2]) + Mf[2] + Mf[3];
  // coupler about B: (C - B) x F_C = -J2 al2 - (c2 - B) x m2 (a2 - g) + (P - B) x F + M3 - Mf_B +
  // Mf_C
  const double S2 = -p.links[1].inertia * al2 - cross(Vec2<double>(k.c[1] - k.B), ma[1]) +
                    cross(Vec2<double>(k.P - k.B), Fv) + L.M3 - Mf[1] + Mf[2];
  (*F)[2] = (S3 * v - S2 * u) / cross(u, v);
  (*F)[1] = ma[1] + (*F)[2] - Fv;  // coupler: F_B - F_C + F = m2 (a2 - g)
  (*F)[0] = ma[0] + (*F)[1];       // crank: F_O - F_B = m1 (a1 - g)
  (*F)[3] = ma[2] - (*F)[2];       // rocker: F_C + F_D0 = m3 (a3 - g)
}

namespace detail {

/// The four-bar's friction arms in the friction loop's five slots (slot 4 inactive: phi = 0).
/// The Coulomb sign is sign(w), or at w = 0 that of wdot (null: none).
inline std::array<double, kJoints> four_bar_arms(const FourBarParams& p,
                                                 const std::array<double, kFourBarJoints>& w,
                                                 const std::array<double, kFourBarJoints>* wdot) {
  std::array<double, kJoints> phi{};
  if (!p.friction.active()) return phi;
  for (int j = 0; j < kFourBarJoints; ++j) {
    int slip = sign_of(w[j]);
    if (slip == 0 && wdot) slip = sign_of((*wdot)[j]);
    phi[j] = p.friction.pin_radius[j] * friction_law(p.friction, j, w[j], slip);
  }
  return phi;
}

/// Runs friction_loop (friction_loop.h) on the four joints through its five slots, with
/// `solve(Mf, F)` the four-bar's reactions; fills ev->N, Mf, F.
template <typename Solve>
Status four_bar_friction_loop(const std::array<double, kJoints>& phi, const EvalOptions& opt,
                              Solve&& solve, FourBarEvaluation* ev) {
  auto padded = [&](const std::array<double, kJoints>& Mf, std::array<Vec2<double>, kJoints>* F) {
    std::array<double, kFourBarJoints> m;
    std::array<Vec2<double>, kFourBarJoints> f;
    for (int j = 0; j < kFourBarJoints; ++j) m[j] = Mf[j];
    solve(m, &f);
    for (int j = 0; j < kFourBarJoints; ++j) (*F)[j] = f[j];
    (*F)[kFourBarJoints] = Vec2<double>::Zero();
  };
  std::array<double, kJoints> N, Mf;
  std::array<Vec2<double>, kJoints> F;
  const Status st = friction_loop(phi, opt, padded, &N, &Mf, &F, &ev->iterations);
  if (!st.ok()) return st;
  for (int j = 0; j < kFourBarJoints; ++j) ev->Mf[j] = Mf[j];
  return Status::Ok();
}

/// The evaluation's kinematics and velocity terms at (th1, w1).
inline Status four_bar_state(const FourBarParams& p, double th1, double w1, const EvalOptions& opt,
                             FourBarEvaluation* ev) {
  const Status st = four_bar_kinematics(p, th1, &ev->kin, opt.singular_margin);
  if (!st.ok()) return st;
  ev->bias = four_bar_bias(p, ev->kin, w1);
  const std::array<double, kFourBarJoints> row = four_bar_joint_rows(ev->kin);
  for (int j = 0; j < kFourBarJoints; ++j) ev->w[j] = row[j] * w1;
  ev->Mf.fill(0.0);
  ev->iterations = 0;
  return Status::Ok();
}

/// The reactions' norms, the couplers' accelerations and the dissipated power of a solved ev.
inline void four_bar_finish(const FourBarParams& p, const FourBarLoads& L, FourBarEvaluation* ev) {
  four_bar_reactions(p, *ev, ev->qdd, L, ev->Mf, &ev->F);
  ev->P_diss = 0;
  for (int j = 0; j < kFourBarJoints; ++j) {
    ev->N[j] = ev->F[j].norm();
    ev->P_diss += ev->Mf[j] * ev->w[j];
  }
  ev->alpha2 = ev->kin.G2 * ev->qdd + ev->bias.h2;
  ev->alpha3 = ev->kin.G3 * ev->qdd + ev->bias.h3;
}

}  // namespace detail

/// Forward dynamics: M qdd = Q0 - J_w^T Mf with Mf_k = r_k f_k(w_k) N_k consistent with the
/// reactions (friction_loop: fixed point, Newton where it stops contracting). Coulomb sign:
/// sign(w_k), 0 at w_k = 0.
inline Status four_bar_forward(const FourBarParams& p, const FourBarLoads& L, double th1, double w1,
                               const EvalOptions& opt, FourBarEvaluation* ev) {
  Status st = detail::four_bar_state(p, th1, w1, opt, ev);
  if (!st.ok()) return st;
  double Q0;
  four_bar_mass_and_force(p, ev->kin, ev->bias, L, &ev->mass, &Q0);
  const std::array<double, kFourBarJoints> row = four_bar_joint_rows(ev->kin);
  const auto accel = [&](const std::array<double, kFourBarJoints>& Mf) {
    double q = Q0;
    for (int j = 0; j < kFourBarJoints; ++j) q -= row[j] * Mf[j];
    return q / ev->mass;
  };
  const std::array<double, kJoints> phi = detail::four_bar_arms(p, ev->w, nullptr);
  if (p.friction.active()) {
    st = detail::four_bar_friction_loop(
        phi, opt,
        [&](const std::array<double, kFourBarJoints>& Mf,
            std::array<Vec2<double>, kFourBarJoints>* F) {
          four_bar_reactions(p, *ev, accel(Mf), L, Mf, F);
        },
        ev);
    if (!st.ok()) return st;
  }
  ev->qdd = accel(ev->Mf);
  ev->M1 = L.M1;
  detail::four_bar_finish(p, L, ev);
  return Status::Ok();
}

/// Inverse dynamics: the crank torque M1 (L.M1 is ignored) and the reactions for the motion
/// (th1, w1, al1). Coulomb sign: sign(w_k), at w_k = 0 that of the relative acceleration.
inline Status four_bar_inverse(const FourBarParams& p, const FourBarLoads& L, double th1, double w1,
                               double al1, const EvalOptions& opt, FourBarEvaluation* ev) {
  Status st = detail::four_bar_state(p, th1, w1, opt, ev);
  if (!st.ok()) return st;
  double Q0;
  four_bar_mass_and_force(p, ev->kin, ev->bias, L, &ev->mass, &Q0);
  ev->qdd = al1;
  const double al2 = ev->kin.G2 * al1 + ev->bias.h2, al3 = ev->kin.G3 * al1 + ev->bias.h3;
  const std::array<double, kFourBarJoints> wdot = {al1, al2 - al1, al3 - al2, al3};
  const std::array<double, kJoints> phi = detail::four_bar_arms(p, ev->w, &wdot);
  if (p.friction.active()) {
    st = detail::four_bar_friction_loop(
        phi, opt,
        [&](const std::array<double, kFourBarJoints>& Mf,
            std::array<Vec2<double>, kFourBarJoints>* F) {
          four_bar_reactions(p, *ev, al1, L, Mf, F);
        },
        ev);
    if (!st.ok()) return st;
  }
  detail::four_bar_finish(p, L, ev);
  // the crank about O: I_O al1 = M1 - Mf_O + Mf_B - B x F_B + c1 x m1 g
  const Link<double>& l1 = p.links[0];
  const double IO = l1.inertia + l1.mass * l1.com_offset * l1.com_offset;
  const Vec2<double> mg(0, -l1.mass * p.gravity);
  ev->M1 = IO * al1 + ev->Mf[0] - ev->Mf[1] + cross(ev->kin.B, ev->F[1]) - cross(ev->kin.c[0], mg);
  return Status::Ok();
}

/// Kinetic energy M(q) w1^2 / 2 [J] and potential energy g sum m_i y_ci [J].
inline double four_bar_kinetic(const FourBarParams& p, const FourBarKinematics& k, double w1) {
  double M, Q0;
  four_bar_mass_and_force(p, k, four_bar_bias(p, k, 0.0), FourBarLoads{}, &M, &Q0);
  return 0.5 * M * w1 * w1;
}
inline double four_bar_potential(const FourBarParams& p, const FourBarKinematics& k) {
  double u = 0;
  for (int i = 0; i < kFourBarLinks; ++i) u += p.links[i].mass * k.c[i].y();
  return p.gravity * u;
}

/// The four-bar's joint table: bodies 0..2 = crank, coupler, rocker with frames at O, B, D0;
/// joints O, B, C, D0 with friction slots 0..3; one drive (M1) at O.
inline chain::Chain four_bar_chain(const FourBarParams& p) {
  using chain::kGround;
  using chain::Vec;
  chain::Chain c;
  for (const Link<double>& l : p.links) c.bodies.push_back(chain::link_body(l));
  const std::array<double, kJoints>& r = p.friction.pin_radius;
  c.joints = {{kGround, 0, Vec(0, 0), Vec(0, 0), r[0], 0},
              {0, 1, Vec(p.links[0].length, 0), Vec(0, 0), r[1], 1},
              {1, 2, Vec(p.links[1].length, 0), Vec(p.links[2].length, 0), r[2], 2},
              {kGround, 2, Vec(p.ground_length, 0), Vec(0, 0), r[3], 3}};
  c.drives = {{kGround, 0}};
  c.gravity = p.gravity;
  c.friction = p.friction;
  return c;
}

/// The chain's pose, body rates and loads of a four-bar state.
inline chain::Pose four_bar_pose(const FourBarParams& p, const FourBarKinematics& k) {
  return {{Vec2<double>(0, 0), k.B, Vec2<double>(p.ground_length, 0)}, {k.th1, k.th2, k.th3}};
}
inline std::vector<double> four_bar_rates(const FourBarKinematics& k, double w1) {
  return {w1, k.G2 * w1, k.G3 * w1};
}
inline chain::ChainLoads four_bar_loads(const FourBarParams& p, const FourBarKinematics& k,
                                        const FourBarLoads& L) {
  return {{L.M1}, {0.0, L.M3, 0.0}, {{1, chain::Vec(p.point_p, 0), four_bar_force(k, L)}}};
}

}  // namespace fivebar
