// The five-bar as a mechanism (mechanism.h): q = (th1, th2), the two cranks' angles; joints O, B,
// C, D, D0; drives M1 at O and M2 at D0. Each member forwards to the five-bar's own headers
// (kinematics.h, appell.h, reactions.h, actuator.h).
#pragma once

#include <array>

#include "fivebar/model/actuator.h"
#include "fivebar/model/appell.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/mechanism.h"
#include "fivebar/model/params.h"
#include "fivebar/model/reactions.h"

namespace fivebar {

struct FiveBar {
  static constexpr int kDof = 2;
  static constexpr int kJoints = fivebar::kJoints;
  static constexpr int kLinks = fivebar::kLinks;
  static constexpr bool kClosedFormResponse = true;
  template <typename T>
  using Params = fivebar::Params<T>;
  template <typename T>
  using Loads = fivebar::Loads<T>;
  template <typename T>
  using Kinematics = fivebar::Kinematics<T>;
  template <typename T>
  using Bias = fivebar::Bias<T>;
  template <typename T>
  using Evaluation = fivebar::Evaluation<T>;
  template <typename T>
  using Joints = std::array<T, kJoints>;
  /// the singular measure's name in messages (singular_measure)
  static constexpr const char* kSingularName = "sin(theta4 - theta3)";

  template <typename T>
  static Status close(const Params<T>& p, const Vec2<T>& q, Kinematics<T>* k,
                      const EvalOptions& opt) {
    return solve_kinematics(p, q[0], q[1], k, opt.singular_margin, opt.want_angles);
  }
  /// Zero at the singular poses, where the reactions grow as its inverse.
  template <typename T>
  static T singular_measure(const Kinematics<T>& k) {
    return k.sin43;
  }
  /// cos(th4 - th3) at any q, smooth (coupler_cosine): 1 - cos^2 = singular_measure^2 where the
  /// five-bar closes, |cos| > 1 where it cannot; its gradient in q when asked.
  template <typename T>
  static T singular_cosine(const Params<T>& p, const Vec2<T>& q, Row2<T>* gradient = nullptr) {
    return coupler_cosine(p, q[0], q[1], gradient);
  }
  template <typename T>
  static void bias(const Params<T>& p, const Kinematics<T>& k, const Vec2<T>& v, Bias<T>* b) {
    compute_bias(p, k, v[0], v[1], b);
  }
  /// The force at P (the only applied force).
  template <typename T>
  static Vec2<T> applied(const Kinematics<T>& k, const Loads<T>& L) {
    return force_vector(k, L);
  }
  template <typename T>
  static void mass_and_force(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b,
                             const Loads<T>& L, const Vec2<T>& Fvec, Mat2<T>* A, Vec2<T>* rhs0) {
    mass_and_forces(p, k, b, L, Fvec, A, rhs0);
  }
  template <typename T>
  static Joints<T> joint_rates(const Kinematics<T>&, const Bias<T>& b, const Vec2<T>& v) {
    return relative_rates(v[0], v[1], b.w3, b.w4);
  }
  /// w = J_w v from the first-order kinematics alone (no velocity terms).
  template <typename T>
  static Joints<T> joint_rates_at(const Kinematics<T>& k, const Vec2<T>& v) {
    return relative_rates(v[0], v[1], T(k.G3.dot(v)), T(k.G4.dot(v)));
  }
  template <typename T>
  static Joints<T> joint_accelerations(const Kinematics<T>& k, const Bias<T>& b,
                                       const Vec2<T>& qdd) {
    return relative_accelerations(qdd, T(k.G3.dot(qdd) + b.h3), T(k.G4.dot(qdd) + b.h4));
  }
  template <typename T>
  static Row2<T> joint_row(const Kinematics<T>& k, int j) {
    return fivebar::joint_row(k, j);
  }
  template <typename T>
  static Vec2<T> friction_transpose(const Kinematics<T>& k, const Joints<T>& Mf) {
    return fivebar::friction_transpose(k, Mf);
  }
  template <typename T>
  static void link_accelerations(const Kinematics<T>& k, const Bias<T>& b, const Vec2<T>& qdd,
                                 Evaluation<T>* ev) {
    ev->alpha3 = k.G3.dot(qdd) + b.h3;
    ev->alpha4 = k.G4.dot(qdd) + b.h4;
  }
  template <typename T>
  static void reactions(const Params<T>& p, const Kinematics<T>& k, const Bias<T>& b,
                        const Loads<T>& L, const Vec2<T>& Fvec, const Vec2<T>& qdd,
                        const Joints<T>& Mf, std::array<Vec2<T>, kJoints>* F, Evaluation<T>* ev) {
    fivebar::reactions(p, k, b, L, Fvec, qdd, Mf, F, &ev->alpha3, &ev->alpha4);
  }
  template <typename T>
  static ReactionResponse<T> reaction_torque_response(const Kinematics<T>& k) {
    return fivebar::reaction_torque_response(k);
  }
  template <typename T>
  static std::array<Mat2<T>, kJoints> reaction_acceleration_response(const Params<T>& p,
                                                                     const Kinematics<T>& k) {
    return fivebar::reaction_acceleration_response(p, k);
  }
  /// The change of the reactions per unit friction torque at given accelerations (inverse
  /// dynamics), in rank-2 form (CouplerResponse; reaction_torque_response expanded).
  template <typename T>
  static CouplerResponse<T> inverse_response(const Kinematics<T>& k) {
    const Vec2<T> u3 = k.B - k.C, u4 = k.D - k.C;
    const T inv = T(1) / cross(u3, u4);
    CouplerResponse<T> r;
    r.f3 = u4 * inv;
    r.f4 = -u3 * inv;
    return r;
  }
  /// The change of the reactions per unit friction torque in forward dynamics with no joint
  /// stuck, in rank-4 form (LowRankResponse): through the coupler moments (as
  /// reaction_torque_response) and through the accelerations they bring, dthdd = -A^-1 J_w^T e_j.
  template <typename T>
  static LowRankResponse<T> forward_response(const Params<T>& p, const Kinematics<T>& k,
                                             const Mat2<T>& Ainv) {
    LowRankResponse<T> r;
    static_cast<CouplerResponse<T>&>(r) = inverse_response(k);
    fivebar::reaction_acceleration_response(p, k, r.f3, r.f4, &r.R);
    // -A^-1 J_w^T e_j from the rows of J_w (joint_row): e1, G3 - e1, G4 - G3, e2 - G4, e2
    const Vec2<T> g3 = Ainv * k.G3.transpose(), g4 = Ainv * k.G4.transpose();
    r.m[0] = -Ainv.col(0);
    r.m[1] = Ainv.col(0) - g3;
    r.m[2] = g3 - g4;
    r.m[3] = g4 - Ainv.col(1);
    r.m[4] = -Ainv.col(1);
    return r;
  }
  template <typename T>
  static void set_drives(const Loads<T>& L, Evaluation<T>* ev) {
    ev->M1 = L.M1;
    ev->M2 = L.M2;
  }
  /// The motor torques from the moments about the fixed pivots O and D0 of the two cranks.
  template <typename T>
  static void drive_torques(const Params<T>& p, const Kinematics<T>& k, const Vec2<T>& qdd,
                            Evaluation<T>* ev) {
    const Vec2<T> gvec(T(0), -p.gravity);
    const Link<T>& L1 = p.links[0];
    const Link<T>& L2 = p.links[1];
    const Vec2<T> D0(p.ground_length, T(0));
    const T I1 = L1.inertia + L1.mass * L1.com_offset * L1.com_offset;
    const T I2 = L2.inertia + L2.mass * L2.com_offset * L2.com_offset;
    ev->M1 = I1 * qdd[0] + ev->Mf[0] - ev->Mf[1] + cross(k.B, ev->F[1]) -
             cross(k.c[0], Vec2<T>(L1.mass * gvec));
    ev->M2 = I2 * qdd[1] + ev->Mf[4] + ev->Mf[3] - cross(Vec2<T>(k.D - D0), ev->F[3]) -
             cross(Vec2<T>(k.c[1] - D0), Vec2<T>(L2.mass * gvec));
  }
  template <typename T>
  static T input_power(const Evaluation<T>& ev, const Vec2<T>& v) {
    return ev.M1 * v[0] + ev.M2 * v[1];
  }
  template <typename T>
  static T external_power(const Kinematics<T>& k, const Bias<T>& b, const Loads<T>& L,
                          const Vec2<T>& Fvec, const Vec2<T>& v) {
    return L.M3 * b.w3 + Fvec.dot(k.GP * v);
  }
  template <typename T>
  static bool actuator_torques(const Params<T>& p, const Joints<T>& w, const JointModes& slip,
                               Joints<T>* out) {
    return fivebar::actuator_torques(p, w, slip, out);
  }
  template <typename T>
  static T holding_capacity(const Params<T>& p, int j, const T& N) {
    return fivebar::holding_capacity(p, j, N);
  }
};

}  // namespace fivebar
