// The planar four-bar (4R) with load-dependent joint friction, in reduced coordinates (one degree
// of freedom, the crank angle th1): position, rate and acceleration closure, the mass and bias
// terms M(q) qdd + bias = tau - friction, Newton-Euler reactions, the mechanism FourBar (forward
// and inverse dynamics from mechanism_dynamics.h: the friction loop, stuck joints, the rest rule,
// LuGre and the crank motor's friction as the five-bar's), and its joint table for the general
// planar chain.
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

#include "fivebar/model/actuator.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/five_bar_chain.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/mechanism_dynamics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/planar_chain.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

/// A closed pose and its first-order coefficients G (derivatives with respect to th1).
template <typename T>
struct FourBarKinematicsT {
  T th1{}, th2{}, th3{};
  Vec2<T> e1, e2, e3, B, C, P;
  std::array<Vec2<T>, kFourBarLinks> c, ec;  ///< centres of mass, directions to them
  T sin32{};  ///< sin(th3 - th2), the coupler-rocker angle's sine: zero at singular poses
  T G2{}, G3{};                           ///< dth2/dth1, dth3/dth1
  std::array<Vec2<T>, kFourBarLinks> Gc;  ///< d c_i / dth1 [m/rad]
  Vec2<T> GP;                             ///< d P / dth1 [m/rad]
};
using FourBarKinematics = FourBarKinematicsT<double>;

/// Rates and the accelerations at alpha1 = 0 (the velocity terms).
template <typename T>
struct FourBarBiasT {
  T w1{}, w2{}, w3{};
  T h2{}, h3{};                           ///< alpha2, alpha3 at alpha1 = 0 [rad/s^2]
  std::array<Vec2<T>, kFourBarLinks> hc;  ///< centre-of-mass accelerations at alpha1 = 0
  Vec2<T> hP;
};
using FourBarBias = FourBarBiasT<double>;

/// Everything one evaluation computes (forward: the crank's acceleration from M1; inverse: M1
/// from it). Joint arrays have the friction arrays' kJoints slots; slot 4 stays zero.
template <typename T>
struct FourBarEvaluationT {
  FourBarKinematicsT<T> kin;
  FourBarBiasT<T> bias;
  Eigen::Matrix<T, 1, 1> A;        ///< M(q) [kg m^2]
  Eigen::Matrix<T, 1, 1> thdd;     ///< alpha1 [rad/s^2]
  T alpha2{}, alpha3{};            ///< coupler and rocker [rad/s^2]
  T M1{};                          ///< crank torque [N m]
  std::array<Vec2<T>, kJoints> F;  ///< reactions, force of i on j [N]
  std::array<T, kJoints> N{}, Mf{}, w{};
  JointModes slip{};                     ///< Coulomb sign used at each joint, or kStuck
  std::array<T, kJoints> hold_margin{};  ///< stuck joints: capacity - |holding torque|
  std::array<T, kJoints> zdot{};         ///< LuGre bristle rates [rad/s]
  T P_diss{};  ///< sum Mf_k w_k [W]
  T P_in{};    ///< M1 w1 [W]
  T P_ext{};   ///< M3 w2 + F . v_P [W]
  int iterations = 0;
};
using FourBarEvaluation = FourBarEvaluationT<double>;

/// The pose: C from the triangle B, C, D0 on the side `assembly`, th2, th3, sin32. Fails with
/// kCannotAssemble when |BD0| is outside [|l2 - l3|, l2 + l3], with kNearSingular when
/// |sin32| < singular_margin.
template <typename T>
Status four_bar_close(const FourBarParamsT<T>& p, const T& th1, FourBarKinematicsT<T>* k,
                      double singular_margin) {
  using std::sqrt;
  const T& l2 = p.links[1].length;
  const T& l3 = p.links[2].length;
  k->th1 = th1;
  k->e1 = unit(th1);
  k->B = p.links[0].length * k->e1;
  const Vec2<T> D0(p.ground_length, T(0)), d = D0 - k->B;
  const T L2 = d.squaredNorm();
  const double L2v = value_of(L2), l2v = value_of(l2), l3v = value_of(l3);
  if (!(L2v > 0) || L2v > (l2v + l3v) * (l2v + l3v) || L2v < (l2v - l3v) * (l2v - l3v)) {
    std::ostringstream msg;
    msg << "four-bar cannot assemble at theta1=" << value_of(th1) << ": |BD0|=" << std::sqrt(L2v)
        << " outside [" << std::abs(l2v - l3v) << ", " << l2v + l3v << "]";
    return Status::Error(StatusCode::kCannotAssemble, msg.str());
  }
  const T L = sqrt(L2), a = (l2 * l2 + L2 - l3 * l3) / (T(2) * L);
  const Vec2<T> u = d / L;
  const T h2 = l2 * l2 - a * a;
  const T h = double(p.assembly) * (value_of(h2) > 0.0 ? T(sqrt(h2)) : T(0));
  k->C = k->B + a * u + h * perp(u);
  k->e2 = (k->C - k->B) / l2;
  k->e3 = (k->C - D0) / l3;
  using std::atan2;
  k->th2 = atan2(k->e2.y(), k->e2.x());
  k->th3 = atan2(k->e3.y(), k->e3.x());
  k->sin32 = cross(k->e2, k->e3);
  if (std::abs(value_of(k->sin32)) < singular_margin) {
    std::ostringstream msg;
    msg.precision(10);  // a value just under the margin prints below it
    msg << "near-singular four-bar pose at theta1=" << value_of(th1)
        << ": |sin(theta3 - theta2)|=" << std::abs(value_of(k->sin32)) << " < margin "
        << singular_margin;
    return Status::Error(StatusCode::kNearSingular, msg.str());
  }
  return Status::Ok();
}

/// cos(th3 - th2), the cosine of the coupler-rocker angle at C, from |BD0| by the law of cosines
/// on the triangle B, C, D0 (|BD0|^2 = l0^2 + l1^2 - 2 l0 l1 cos th1), and when asked its
/// derivative in th1 [1/rad]. Defined at every crank angle (|cos| > 1 where the four-bar cannot
/// close) and smooth through the singular poses, where G2 and G3 are not: 1 - cos^2 =
/// sin^2(th3 - th2), the smooth form of the singular measure (for constraints that must also
/// hold the assembly, as the trajectory optimizer's singular margin).
template <typename T>
T four_bar_coupler_cosine(const FourBarParamsT<T>& p, const T& th1, T* derivative = nullptr) {
  using std::cos;
  using std::sin;
  const T& l0 = p.ground_length;
  const T& l1 = p.links[0].length;
  const T& l2 = p.links[1].length;
  const T& l3 = p.links[2].length;
  const T bd2 = l0 * l0 + l1 * l1 - T(2) * l0 * l1 * cos(th1);
  if (derivative) *derivative = -(l0 * l1 * sin(th1)) / (l2 * l3);
  return (l2 * l2 + l3 * l3 - bd2) / (T(2) * l2 * l3);
}

/// Position closure, the load point, the centres of mass and the G coefficients. From
/// vB + l2 w2 e2' = l3 w3 e3': l2 s w2 = -vB.e3, l3 s w3 = -vB.e2 (s = sin32).
template <typename T>
Status four_bar_kinematics(const FourBarParamsT<T>& p, const T& th1, FourBarKinematicsT<T>* k,
                           double singular_margin = 0.0) {
  const Status st = four_bar_close(p, th1, k, singular_margin);
  if (!st.ok()) return st;
  using std::cos;
  using std::sin;
  const std::array<const Vec2<T>*, kFourBarLinks> e = {&k->e1, &k->e2, &k->e3};
  for (int i = 0; i < kFourBarLinks; ++i) {
    const T& al = p.links[i].com_angle;
    k->ec[i] = rotate(*e[i], T(cos(al)), T(sin(al)));
  }
  const Vec2<T> D0(p.ground_length, T(0));
  k->P = k->B + p.point_p * k->e2;
  k->c[0] = p.links[0].com_offset * k->ec[0];
  k->c[1] = k->B + p.links[1].com_offset * k->ec[1];
  k->c[2] = D0 + p.links[2].com_offset * k->ec[2];
  const Vec2<T> dB = p.links[0].length * perp(k->e1);  // dB/dth1
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
template <typename T>
FourBarBiasT<T> four_bar_bias(const FourBarParamsT<T>& p, const FourBarKinematicsT<T>& k,
                              const T& w1) {
  const T& l1 = p.links[0].length;
  const T& l2 = p.links[1].length;
  const T& l3 = p.links[2].length;
  FourBarBiasT<T> b;
  b.w1 = w1;
  b.w2 = k.G2 * w1;
  b.w3 = k.G3 * w1;
  const Vec2<T> aB = -l1 * w1 * w1 * k.e1;  // at alpha1 = 0
  const Vec2<T> delta = -aB + l2 * b.w2 * b.w2 * k.e2 - l3 * b.w3 * b.w3 * k.e3;
  b.h2 = delta.dot(k.e3) / (l2 * k.sin32);
  b.h3 = delta.dot(k.e2) / (l3 * k.sin32);
  // X = base + r e(th_j + alpha): bias_X = bias_base + r (h_j e'(..) - w_j^2 e(..))
  const auto arm = [](const T& r, const Vec2<T>& ec, const T& h, const T& w) -> Vec2<T> {
    return r * (h * perp(ec) - w * w * ec);
  };
  b.hc[0] = arm(p.links[0].com_offset, k.ec[0], T(0), w1);
  b.hc[1] = aB + arm(p.links[1].com_offset, k.ec[1], b.h2, b.w2);
  b.hc[2] = arm(p.links[2].com_offset, k.ec[2], b.h3, b.w3);
  b.hP = aB + arm(p.point_p, k.e2, b.h2, b.w2);
  return b;
}

/// Row of J_w (w = J_w w1) of each joint: O 1, B G2 - 1, C G3 - G2, D0 G3.
template <typename T>
std::array<T, kFourBarJoints> four_bar_joint_rows(const FourBarKinematicsT<T>& k) {
  return {T(1), k.G2 - T(1), k.G3 - k.G2, k.G3};
}

/// The force vector at P: F e(th2 + F_angle).
template <typename T>
Vec2<T> four_bar_force(const FourBarKinematicsT<T>& k, const FourBarLoadsT<T>& L) {
  using std::cos;
  using std::sin;
  return L.F * rotate(k.e2, T(cos(L.F_angle)), T(sin(L.F_angle)));
}

/// M(q) = J1 + J2 G2^2 + J3 G3^2 + sum m_i |G_ci|^2, and the friction-free generalized force
/// Q0 = M1 + M3 G2 + G_P . F - g sum m_i G_ci,y - bias (bias = sum J_i G_i h_i + m_i G_ci . h_ci).
template <typename T>
void four_bar_mass_and_force(const FourBarParamsT<T>& p, const FourBarKinematicsT<T>& k,
                             const FourBarBiasT<T>& b, const FourBarLoadsT<T>& L, T* M, T* Q0) {
  const std::array<T, kFourBarLinks> G = {T(1), k.G2, k.G3}, h = {T(0), b.h2, b.h3};
  *M = T(0);
  *Q0 = L.M1 + L.M3 * k.G2 + k.GP.dot(four_bar_force(k, L));
  for (int i = 0; i < kFourBarLinks; ++i) {
    const Link<T>& l = p.links[i];
    *M += l.inertia * G[i] * G[i] + l.mass * k.Gc[i].squaredNorm();
    *Q0 -=
        l.inertia * G[i] * h[i] + l.mass * k.Gc[i].dot(b.hc[i]) + p.gravity * l.mass * k.Gc[i].y();
  }
}

/// Newton-Euler reactions at crank acceleration al1 and friction torques Mf: F_C from the moments
/// of the rocker about D0 and of the coupler about B, then F_B, F_O, F_D0 by force balances.
template <typename T>
void four_bar_reactions(const FourBarParamsT<T>& p, const FourBarKinematicsT<T>& k,
                        const FourBarBiasT<T>& b, const T& al1, const FourBarLoadsT<T>& L,
                        const std::array<T, kJoints>& Mf, std::array<Vec2<T>, kJoints>* F) {
  const Vec2<T> g(T(0), -p.gravity), D0(p.ground_length, T(0)), Fv = four_bar_force(k, L);
  std::array<Vec2<T>, kFourBarLinks> ma;  // m_i (a_ci - g)
  for (int i = 0; i < kFourBarLinks; ++i) {
    ma[i] = p.links[i].mass * (Vec2<T>(k.Gc[i] * al1 + b.hc[i]) - g);
  }
  const T al2 = k.G2 * al1 + b.h2, al3 = k.G3 * al1 + b.h3;
  // rocker about D0: (C - D0) x F_C = J3 al3 + (c3 - D0) x m3 (a3 - g) + Mf_C + Mf_D0
  const Vec2<T> u = k.C - D0, v = k.C - k.B;
  const T S3 = p.links[2].inertia * al3 + cross(Vec2<T>(k.c[2] - D0), ma[2]) + Mf[2] + Mf[3];
  // coupler about B: (C - B) x F_C = -J2 al2 - (c2 - B) x m2 (a2 - g) + (P - B) x F + M3 - Mf_B +
  // Mf_C
  const T S2 = -p.links[1].inertia * al2 - cross(Vec2<T>(k.c[1] - k.B), ma[1]) +
               cross(Vec2<T>(k.P - k.B), Fv) + L.M3 - Mf[1] + Mf[2];
  (*F)[2] = (S3 * v - S2 * u) / cross(u, v);
  (*F)[1] = ma[1] + (*F)[2] - Fv;  // coupler: F_B - F_C + F = m2 (a2 - g)
  (*F)[0] = ma[0] + (*F)[1];       // crank: F_O - F_B = m1 (a1 - g)
  (*F)[3] = ma[2] - (*F)[2];       // rocker: F_C + F_D0 = m3 (a3 - g)
  (*F)[4] = Vec2<T>::Zero();
}

/// The four-bar as a mechanism (mechanism.h): q = (th1), the crank's angle; joints O, B, C, D0 in
/// slots 0..3; one drive, M1 at O.
struct FourBar {
  static constexpr int kDof = 1;
  static constexpr int kJoints = kFourBarJoints;
  static constexpr int kLinks = kFourBarLinks;
  static constexpr bool kClosedFormResponse = false;  ///< the loop probes the reactions
  template <typename T>
  using Params = FourBarParamsT<T>;
  template <typename T>
  using Loads = FourBarLoadsT<T>;
  template <typename T>
  using Kinematics = FourBarKinematicsT<T>;
  template <typename T>
  using Bias = FourBarBiasT<T>;
  template <typename T>
  using Evaluation = FourBarEvaluationT<T>;
  template <typename T>
  using Q = Eigen::Matrix<T, 1, 1>;
  template <typename T>
  using Slots = std::array<T, fivebar::kJoints>;
  static constexpr const char* kSingularName = "sin(theta3 - theta2)";

  template <typename T>
  static Status close(const Params<T>& p, const Q<T>& q, Kinematics<T>* k,
                      const EvalOptions& opt) {
    return four_bar_kinematics(p, q[0], k, opt.singular_margin);
  }
  /// Zero at the singular (toggle) poses, where the reactions grow as its inverse.
  template <typename T>
  static T singular_measure(const Kinematics<T>& k) {
    return k.sin32;
  }
  /// cos(th3 - th2) at any q, smooth (four_bar_coupler_cosine); its gradient in q when asked.
  template <typename T>
  static T singular_cosine(const Params<T>& p, const Q<T>& q,
                           Eigen::Matrix<T, 1, 1>* gradient = nullptr) {
    return four_bar_coupler_cosine(p, q[0], gradient ? &(*gradient)(0, 0) : nullptr);
  }
  template <typename T>
  static void bias(const Params<T>& p, const Kinematics<T>& k, const Q<T>& v, Bias<T>* b) {
    *b = four_bar_bias(p, k, v[0]);
  }
  template <typename T>
  static Vec2<T> applied(const Kinematics<T>& k, const Loads<T>& L) {
    return four_bar_force(k, L);
  }
  template <typename T>
  static void mass_and_force(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b,
                             const Loads<T>& L, const Vec2<T>&, Eigen::Matrix<T, 1, 1>* A,
                             Q<T>* rhs0) {
    four_bar_mass_and_force(p, k, b, L, &(*A)(0, 0), &(*rhs0)[0]);
  }
  template <typename T>
  static Slots<T> joint_rates(const Kinematics<T>& k, const Bias<T>&, const Q<T>& v) {
    const std::array<T, kFourBarJoints> row = four_bar_joint_rows(k);
    Slots<T> w{};
    for (int j = 0; j < kFourBarJoints; ++j) w[j] = row[j] * v[0];
    return w;
  }
  template <typename T>
  static Slots<T> joint_rates_at(const Kinematics<T>& k, const Q<T>& v) {
    return joint_rates(k, Bias<T>{}, v);
  }
  template <typename T>
  static Slots<T> joint_accelerations(const Kinematics<T>& k, const Bias<T>& b, const Q<T>& qdd) {
    const T& al1 = qdd[0];
    const T al2 = k.G2 * al1 + b.h2, al3 = k.G3 * al1 + b.h3;
    return {al1, al2 - al1, al3 - al2, al3, T(0)};
  }
  template <typename T>
  static Eigen::Matrix<T, 1, 1> joint_row(const Kinematics<T>& k, int j) {
    Eigen::Matrix<T, 1, 1> r;
    r(0, 0) = j < kFourBarJoints ? four_bar_joint_rows(k)[j] : T(0);
    return r;
  }
  template <typename T>
  static Q<T> friction_transpose(const Kinematics<T>& k, const Slots<T>& Mf) {
    const std::array<T, kFourBarJoints> row = four_bar_joint_rows(k);
    Q<T> q(T(0));
    for (int j = 0; j < kFourBarJoints; ++j) q[0] += row[j] * Mf[j];
    return q;
  }
  template <typename T>
  static void link_accelerations(const Kinematics<T>& k, const Bias<T>& b, const Q<T>& qdd,
                                 Evaluation<T>* ev) {
    ev->alpha2 = k.G2 * qdd[0] + b.h2;
    ev->alpha3 = k.G3 * qdd[0] + b.h3;
  }
  template <typename T>
  static void reactions(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b,
                        const Loads<T>& L, const Vec2<T>&, const Q<T>& qdd, const Slots<T>& Mf,
                        std::array<Vec2<T>, fivebar::kJoints>* F, Evaluation<T>* ev) {
    link_accelerations(k, b, qdd, ev);
    four_bar_reactions(p, k, b, qdd[0], L, Mf, F);
  }
  template <typename T>
  static void set_drives(const Loads<T>& L, Evaluation<T>* ev) {
    ev->M1 = L.M1;
  }
  /// The crank about O: I_O al1 = M1 - Mf_O + Mf_B - B x F_B + c1 x m1 g.
  template <typename T>
  static void drive_torques(const Params<T>& p, const Kinematics<T>& k, const Q<T>& qdd,
                            Evaluation<T>* ev) {
    const Link<T>& l1 = p.links[0];
    const T IO = l1.inertia + l1.mass * l1.com_offset * l1.com_offset;
    const Vec2<T> mg(T(0), -l1.mass * p.gravity);
    ev->M1 = IO * qdd[0] + ev->Mf[0] - ev->Mf[1] + cross(k.B, ev->F[1]) - cross(k.c[0], mg);
  }
  template <typename T>
  static T input_power(const Evaluation<T>& ev, const Q<T>& v) {
    return ev.M1 * v[0];
  }
  template <typename T>
  static T external_power(const Kinematics<T>& k, const Bias<T>& b, const Loads<T>& L,
                          const Vec2<T>& Fv, const Q<T>& v) {
    return L.M3 * b.w2 + Fv.dot(k.GP * v[0]);
  }
  /// The crank motor's friction at O (actuator.h, kFourBarActuators).
  template <typename T>
  static bool actuator_torques(const Params<T>& p, const Slots<T>& w, const JointModes& slip,
                               Slots<T>* out) {
    return fivebar::actuator_torques(p.friction, p.actuators, kFourBarActuators, w, slip, out);
  }
  /// mu_s,k r_k N_k, plus the motor's Coulomb friction c_a at the crank's joint O.
  template <typename T>
  static T holding_capacity(const Params<T>& p, int j, const T& N) {
    return fivebar::holding_capacity(p.friction, p.actuators, kFourBarActuators, j, N);
  }
};

/// Forward dynamics: M qdd = Q0 - J_w^T Mf with Mf_k = r_k f_k(w_k) N_k consistent with the
/// reactions (mechanism_dynamics.h). Coulomb sign: sign(w_k), 0 at w_k = 0, unless `slip` gives
/// the joints' modes (kStuck: held by a constraint torque).
template <typename T>
Status four_bar_forward(const FourBarParamsT<T>& p, const FourBarLoadsT<T>& L, const T& th1,
                        const T& w1, const EvalOptions& opt, FourBarEvaluationT<T>* ev,
                        const JointModes* slip = nullptr) {
  return mech::forward<FourBar, T>(p, L, FourBar::Q<T>(th1), FourBar::Q<T>(w1), slip, opt, ev);
}

/// Inverse dynamics: the crank torque M1 (L.M1 is ignored) and the reactions for the motion
/// (th1, w1, al1). Coulomb sign: sign(w_k), at w_k = 0 that of the relative acceleration; the
/// rest rule of EvalOptions as in the five-bar's inverse_dynamics.
template <typename T>
Status four_bar_inverse(const FourBarParamsT<T>& p, const FourBarLoadsT<T>& L, const T& th1,
                        const T& w1, const T& al1, const EvalOptions& opt,
                        FourBarEvaluationT<T>* ev, const JointModes* slip = nullptr) {
  return mech::inverse<FourBar, T>(p, L, FourBar::Q<T>(th1), FourBar::Q<T>(w1),
                                   FourBar::Q<T>(al1), slip, opt, ev);
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

#ifdef FIVEBAR_COMPILED_DOUBLE_DYNAMICS
// As the five-bar's (inverse.h, forward.h): code that links fivebar::sim takes the four-bar's
// double passes from model/src/simulator.cc.
namespace mech::detail {
extern template Status inverse_pass<FourBar, double>(
    const FourBar::Params<double>&, const FourBar::Loads<double>&, const FourBar::Q<double>&,
    const FourBar::Q<double>&, const FourBar::Q<double>&, const JointModes*, const EvalOptions&,
    FourBar::Evaluation<double>*, const std::array<double, kJoints>*, LoopSolution*);
extern template Status forward_pass<FourBar, double>(
    const FourBar::Params<double>&, const FourBar::Loads<double>&, const FourBar::Q<double>&,
    const FourBar::Q<double>&, const JointModes*, const EvalOptions&,
    FourBar::Evaluation<double>*, const std::array<double, kJoints>*, LoopSolution*,
    FrictionWarmStart*);
}  // namespace mech::detail
#endif

#ifdef FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM
// The command-line layer (apps/, at -O1) takes these double instances from fivebar::sim
// (model/src/double_instances.cc) rather than compiling -O1 copies the linker could keep in
// place of the libraries' optimized ones.
extern template Status four_bar_close<double>(const FourBarParamsT<double>&, const double&,
                                              FourBarKinematicsT<double>*, double);
extern template Status four_bar_kinematics<double>(const FourBarParamsT<double>&, const double&,
                                                   FourBarKinematicsT<double>*, double);
#endif

}  // namespace fivebar
