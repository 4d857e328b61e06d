// Position, velocity and acceleration analysis of the five-bar by influence coefficients
// (paper section 2.2; model.md "Geometry and coordinates").
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

/// Pose of the mechanism and its first-order influence coefficients G (gradients with respect
/// to (th1, th2)). Points: O = 0, B, C, D, D0 = (l0, 0), P, and the centres of mass c[0..3].
template <typename T>
struct Kinematics {
  T th1{}, th2{}, th3{}, th4{};
  Vec2<T> e1, e2, e3, e4;          ///< unit vectors along links 1..4 (e(th_i))
  Vec2<T> B, C, D, P;              ///< joint and load points [m]
  std::array<Vec2<T>, kLinks> c;   ///< centres of mass of links 1..4 [m]
  std::array<Vec2<T>, kLinks> ec;  ///< e(th_i + alpha_i): direction to each centre of mass
  T sin43{};                       ///< sin(th4 - th3); zero at the singular poses
  Row2<T> G3, G4;                  ///< dth3/dth, dth4/dth [rad/rad]
  std::array<Mat2<T>, kLinks> Gc;  ///< d c_i / dth: row 0 = G_xci, row 1 = G_yci [m/rad]
  Mat2<T> GP;                      ///< d P / dth [m/rad]
};

/// Velocity-dependent accelerations thd^T H thd (the part of xddot not proportional to thdd).
template <typename T>
struct Bias {
  T w3{}, w4{};                    ///< link rates of the couplers [rad/s]
  T h3{}, h4{};                    ///< thd^T H_3 thd, thd^T H_4 thd [rad/s^2]
  std::array<Vec2<T>, kLinks> hc;  ///< thd^T H_ci thd for x and y [m/s^2]
  Vec2<T> hP;                      ///< thd^T H_P thd [m/s^2]
};

/// Second-order influence coefficients (Hessians with respect to (th1, th2)).
template <typename T>
struct Hessians {
  Mat2<T> H3, H4;
  std::array<std::array<Mat2<T>, 2>, kLinks> Hc;  ///< Hc[i][0] = H_xci, Hc[i][1] = H_yci
  std::array<Mat2<T>, 2> HP;                      ///< H_xP, H_yP
};

/// Message of a pose that cannot close: |BD| outside [|l3 - l4|, l3 + l4] (cold path).
inline Status cannot_assemble_status(double th1, double th2, double L2, double l3, double l4) {
  std::ostringstream msg;
  msg << "cannot assemble at theta1=" << th1 << ", theta2=" << th2 << ": |BD|=" << std::sqrt(L2)
      << " outside [" << std::abs(l3 - l4) << ", " << l3 + l4 << "]";
  return Status::Error(StatusCode::kCannotAssemble, msg.str());
}

/// Message of a pose within the singular margin (cold path).
inline Status near_singular_status(double th1, double th2, double sine, double margin) {
  std::ostringstream msg;
  msg.precision(10);  // a value just under the margin prints below it
  msg << "near-singular pose at theta1=" << th1 << ", theta2=" << th2
      << ": |sin(theta4 - theta3)|=" << sine << " < margin " << margin;
  return Status::Error(StatusCode::kNearSingular, msg.str());
}

/// The cranks of a pose, the first step of the loop closure: th1, th2, e1, e2 and the crank ends
/// B = l1 e1, D = D0 + l2 e2 (every pose has them, closed or not).
template <typename T>
void place_cranks(const Params<T>& p, const T& th1, const T& th2, Kinematics<T>* k) {
  k->th1 = th1;
  k->th2 = th2;
  k->e1 = unit(th1);
  k->e2 = unit(th2);
  k->B = p.links[0].length * k->e1;
  k->D = Vec2<T>(p.ground_length, T(0)) + p.links[1].length * k->e2;
}

/// Loop closure (eq. 4): B and D from the crank angles, then C from the triangle B, C, D, the
/// coupler directions e3, e4 (and th3, th4 when `angles`) and sin43. Fails as solve_kinematics.
template <typename T>
Status close_loop(const Params<T>& p, const T& th1, const T& th2, Kinematics<T>* k,
                  double singular_margin, bool angles) {
  using std::atan2;
  using std::sqrt;
  const T& l3 = p.links[2].length;
  const T& l4 = p.links[3].length;
  place_cranks(p, th1, th2, k);

  // triangle B, C, D: foot of C on BD at distance a from B, height h
  const Vec2<T> d = k->D - k->B;
  const T L2 = d.squaredNorm();
  const double L2v = value_of(L2);
  const double l3v = value_of(l3), l4v = value_of(l4);
  if (!(L2v > 0.0) || L2v > (l3v + l4v) * (l3v + l4v) || L2v < (l3v - l4v) * (l3v - l4v)) {
    return cannot_assemble_status(value_of(th1), value_of(th2), L2v, l3v, l4v);
  }
  const T L = sqrt(L2);
  const Vec2<T> u = d / L;
  const T a = (l3 * l3 + L2 - l4 * l4) / (T(2) * L);
  T h2 = l3 * l3 - a * a;
  if (value_of(h2) < 0.0) h2 = T(0);
  const T h = T(double(p.assembly)) * sqrt(h2);  // elbow_up: C left of B->D
  k->C = k->B + a * u + h * perp(u);
  k->e3 = (k->C - k->B) / l3;
  k->e4 = (k->C - k->D) / l4;
  if (angles) {
    k->th3 = atan2(k->e3.y(), k->e3.x());
    k->th4 = atan2(k->e4.y(), k->e4.x());
  }
  k->sin43 = cross(k->e3, k->e4);  // sin(th4 - th3)
  if (std::abs(value_of(k->sin43)) < singular_margin) {
    return near_singular_status(value_of(th1), value_of(th2), std::abs(value_of(k->sin43)),
                         singular_margin);
  }
  return Status::Ok();
}

/// cos(th4 - th3), the cosine of the coupler angle at C, from |BD| by the law of cosines on the
/// triangle B, C, D, and when asked its gradient with respect to (th1, th2) [1/rad]. Defined at
/// every pose (|cos| > 1 where the loop cannot close) and smooth through the singular poses,
/// where G3 and G4 are not: sin^2(th4 - th3) = 1 - cos^2 is the trajectory optimizer's
/// singular-margin constraint.
template <typename T>
T coupler_cosine(const Params<T>& p, const T& th1, const T& th2, Row2<T>* gradient = nullptr) {
  const T& l3 = p.links[2].length;
  const T& l4 = p.links[3].length;
  Kinematics<T> k;
  place_cranks(p, th1, th2, &k);
  const Vec2<T> d = k.D - k.B;
  const T cosine = (l3 * l3 + l4 * l4 - d.squaredNorm()) / (T(2) * l3 * l4);
  if (gradient) {
    // d|BD|^2/dth1 = -2 (D - B) . dB/dth1, d|BD|^2/dth2 = 2 (D - B) . dD/dth2
    const T dL1 = T(-2) * d.dot(p.links[0].length * perp(k.e1));
    const T dL2 = T(2) * d.dot(p.links[1].length * perp(k.e2));
    const T c = T(-1) / (T(2) * l3 * l4);
    *gradient << c * dL1, c * dL2;
  }
  return cosine;
}

/// The side of each leg at a closed pose, +1 or -1: sign((B - O) x (C - B)) for the left leg and
/// sign((D - D0) x (C - D)) for the right one (the working modes crank_angles keeps).
inline std::array<int, 2> leg_modes(const Params<double>& p, const Kinematics<double>& k) {
  const Vec2<double> D0(p.ground_length, 0.0);
  const double s1 = cross(Vec2<double>(k.B), Vec2<double>(k.C - k.B));
  const double s2 = cross(Vec2<double>(k.D - D0), Vec2<double>(k.C - k.D));
  return {s1 >= 0 ? 1 : -1, s2 >= 0 ? 1 : -1};
}

/// The crank angle th of one leg (crank of length l from `base`, coupler of length r) that puts
/// the leg's end at C with the leg on the side `mode` (+1 or -1, as leg_modes); false if the leg
/// cannot reach C. th is atan2 -+ acos, so within [-2 pi, 2 pi].
inline bool leg_angle(const Vec2<double>& base, double l, const Vec2<double>& C, double r,
                      int mode, double* th) {
  const Vec2<double> d = C - base;
  const double L = d.norm();
  if (!(L > 0) || L > l + r || L < std::abs(l - r)) return false;
  const double phi = std::atan2(d.y(), d.x());
  const double beta = std::acos(std::clamp((l * l + L * L - r * r) / (2 * l * L), -1.0, 1.0));
  for (double cand : {phi + beta, phi - beta}) {
    const Vec2<double> K = base + l * unit(cand);
    const int side = cross(Vec2<double>(K - base), Vec2<double>(C - K)) >= 0 ? 1 : -1;
    if (side == mode) {
      *th = cand;
      return true;
    }
  }
  return false;
}

/// Inverse position analysis: the crank angles that put point C at `C` with the legs in the
/// working modes `modes` (leg_modes); false when a leg cannot reach C. Whether the scene's
/// assembly closes back to the same C is the caller's check (close_loop).
inline bool crank_angles(const Params<double>& p, const Vec2<double>& C,
                         const std::array<int, 2>& modes, std::array<double, 2>* th) {
  const Vec2<double> O(0, 0), D0(p.ground_length, 0);
  return leg_angle(O, p.links[0].length, C, p.links[2].length, modes[0], &(*th)[0]) &&
         leg_angle(D0, p.links[1].length, C, p.links[3].length, modes[1], &(*th)[1]);
}

/// The load point P and the centres of mass c[0..3] with their directions ec (closed loop).
template <typename T>
void place_points(const Params<T>& p, Kinematics<T>* k) {
  using std::cos;
  using std::sin;
  k->P = k->B + p.point_p * k->e3;
  // centres of mass: e(th_i + alpha_i) = rotation of e_i by alpha_i
  const std::array<const Vec2<T>*, kLinks> e = {&k->e1, &k->e2, &k->e3, &k->e4};
  for (int i = 0; i < kLinks; ++i) {
    const T& al = p.links[i].com_angle;
    if (is_exact_zero(al)) {
      k->ec[i] = *e[i];  // centre of mass on the link's line: no rotation (hot path)
    } else {
      k->ec[i] = rotate(*e[i], T(cos(al)), T(sin(al)));
    }
  }
  const Vec2<T> D0(p.ground_length, T(0));
  k->c[0] = p.links[0].com_offset * k->ec[0];
  k->c[1] = D0 + p.links[1].com_offset * k->ec[1];
  k->c[2] = k->B + p.links[2].com_offset * k->ec[2];
  k->c[3] = k->D + p.links[3].com_offset * k->ec[3];
}

/// First-order influence coefficients G3, G4, Gc, GP (section 2.2.2) of a closed pose.
template <typename T>
void first_order_coefficients(const Params<T>& p, Kinematics<T>* k) {
  // l3 s w3 = (vD - vB).e4, l4 s w4 = (vD - vB).e3
  const Vec2<T> dB1 = p.links[0].length * perp(k->e1);  // dB/dth1
  const Vec2<T> dD2 = p.links[1].length * perp(k->e2);  // dD/dth2
  const T s3 = p.links[2].length * k->sin43, s4 = p.links[3].length * k->sin43;
  k->G3 << -dB1.dot(k->e4) / s3, dD2.dot(k->e4) / s3;
  k->G4 << -dB1.dot(k->e3) / s4, dD2.dot(k->e3) / s4;

  // point coefficients: X = base + r e(th_j + alpha) gives G_X = G_base + r e'(..) G_j
  k->Gc[0].setZero();
  k->Gc[0].col(0) = p.links[0].com_offset * perp(k->ec[0]);
  k->Gc[1].setZero();
  k->Gc[1].col(1) = p.links[1].com_offset * perp(k->ec[1]);
  k->Gc[2] = p.links[2].com_offset * perp(k->ec[2]) * k->G3;
  k->Gc[2].col(0) += dB1;
  k->Gc[3] = p.links[3].com_offset * perp(k->ec[3]) * k->G4;
  k->Gc[3].col(1) += dD2;
  k->GP = p.point_p * perp(k->e3) * k->G3;
  k->GP.col(0) += dB1;
}

/// The least |sin(th4 - th3)| the motions the toolkit designs keep by default (optimized
/// trajectories and their path search, excitation designs): a constraint along the motion, where
/// a simulation only stops at sim::Options::singular_margin.
inline constexpr double kMotionSingularMargin = 0.1;

/// Closed-form position solve (eq. 4) for the assembly in params, and the G coefficients.
/// Fails with kCannotAssemble when |BD| is outside [|l3 - l4|, l3 + l4], and with kNearSingular
/// when |sin(th4 - th3)| < singular_margin (pass 0 to accept any pose that assembles).
/// `angles` = false skips th3, th4 themselves (two atan2): the dynamics needs only e3, e4.
template <typename T>
Status solve_kinematics(const Params<T>& p, const T& th1, const T& th2, Kinematics<T>* k,
                        double singular_margin = 0.0, bool angles = true) {
  Status st = close_loop(p, th1, th2, k, singular_margin, angles);
  if (!st.ok()) return st;
  place_points(p, k);
  first_order_coefficients(p, k);
  return Status::Ok();
}

/// thd^T H thd for th3, th4, the centres of mass and P at rates (w1, w2), without forming H.
template <typename T>
void compute_bias(const Params<T>& p, const Kinematics<T>& k, const T& w1, const T& w2,
                  Bias<T>* b) {
  const T& l1 = p.links[0].length;
  const T& l2 = p.links[1].length;
  const T& l3 = p.links[2].length;
  const T& l4 = p.links[3].length;
  b->w3 = k.G3(0) * w1 + k.G3(1) * w2;
  b->w4 = k.G4(0) * w1 + k.G4(1) * w2;
  // closure at acceleration level: l3 e3' al3 - l4 e4' al4 = aD - aB + l3 e3 w3^2 - l4 e4 w4^2
  const Vec2<T> aB = -l1 * w1 * w1 * k.e1;
  const Vec2<T> aD = -l2 * w2 * w2 * k.e2;
  const Vec2<T> delta = aD - aB + (l3 * b->w3 * b->w3) * k.e3 - (l4 * b->w4 * b->w4) * k.e4;
  b->h3 = delta.dot(k.e4) / (l3 * k.sin43);
  b->h4 = delta.dot(k.e3) / (l4 * k.sin43);
  // X = base + r e(th_j + alpha): bias_X = bias_base + r e'(..) h_j - r e(..) w_j^2
  const T& r1 = p.links[0].com_offset;
  const T& r2 = p.links[1].com_offset;
  const T& r3 = p.links[2].com_offset;
  const T& r4 = p.links[3].com_offset;
  b->hc[0] = -r1 * w1 * w1 * k.ec[0];
  b->hc[1] = -r2 * w2 * w2 * k.ec[1];
  b->hc[2] = aB + r3 * (b->h3 * perp(k.ec[2]) - b->w3 * b->w3 * k.ec[2]);
  b->hc[3] = aD + r4 * (b->h4 * perp(k.ec[3]) - b->w4 * b->w4 * k.ec[3]);
  b->hP = aB + p.point_p * (b->h3 * perp(k.e3) - b->w3 * b->w3 * k.e3);
}

/// Exact second-order influence coefficients H (Hessians of th3, th4, c_i, P in (th1, th2)).
template <typename T>
Hessians<T> compute_hessians(const Params<T>& p, const Kinematics<T>& k) {
  const T& l1 = p.links[0].length;
  const T& l2 = p.links[1].length;
  const T& l3 = p.links[2].length;
  const T& l4 = p.links[3].length;
  Mat2<T> E11 = Mat2<T>::Zero(), E22 = Mat2<T>::Zero();
  E11(0, 0) = T(1);
  E22(1, 1) = T(1);
  const Mat2<T> GG3 = k.G3.transpose() * k.G3;
  const Mat2<T> GG4 = k.G4.transpose() * k.G4;
  const T c34 = k.e3.dot(k.e4);
  Hessians<T> H;
  // from compute_bias: h3 = delta.e4 / (l3 s), h4 = delta.e3 / (l4 s), delta quadratic in thd
  H.H3 = (l1 * k.e1.dot(k.e4) * E11 - l2 * k.e2.dot(k.e4) * E22 + l3 * c34 * GG3 - l4 * GG4) /
         (l3 * k.sin43);
  H.H4 = (l1 * k.e1.dot(k.e3) * E11 - l2 * k.e2.dot(k.e3) * E22 + l3 * GG3 - l4 * c34 * GG4) /
         (l4 * k.sin43);
  // X = base + r e(th_j + alpha): H_X = H_base + r e'(..) H_j - r e(..) G_j^T G_j (per component)
  auto point = [](const std::array<Mat2<T>, 2>& Hbase, const T& r, const Vec2<T>& ej,
                  const Mat2<T>& Hj, const Mat2<T>& GGj) {
    std::array<Mat2<T>, 2> out;
    const Vec2<T> ejp = perp(ej);
    for (int c = 0; c < 2; ++c) out[c] = Hbase[c] + r * (ejp[c] * Hj - ej[c] * GGj);
    return out;
  };
  const std::array<Mat2<T>, 2> zero = {Mat2<T>::Zero(), Mat2<T>::Zero()};
  const Mat2<T> Z = Mat2<T>::Zero();
  const std::array<Mat2<T>, 2> HB = {Mat2<T>(-l1 * k.e1.x() * E11), Mat2<T>(-l1 * k.e1.y() * E11)};
  const std::array<Mat2<T>, 2> HD = {Mat2<T>(-l2 * k.e2.x() * E22), Mat2<T>(-l2 * k.e2.y() * E22)};
  H.Hc[0] = point(zero, p.links[0].com_offset, k.ec[0], Z, E11);
  H.Hc[1] = point(zero, p.links[1].com_offset, k.ec[1], Z, E22);
  H.Hc[2] = point(HB, p.links[2].com_offset, k.ec[2], H.H3, GG3);
  H.Hc[3] = point(HD, p.links[3].com_offset, k.ec[3], H.H4, GG4);
  H.HP = point(HB, p.point_p, k.e3, H.H3, GG3);
  return H;
}

#ifdef FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM
// The command-line layer (apps/, at -O1) takes these double instances from fivebar::sim
// (model/src/double_instances.cc) rather than compiling -O1 copies the linker could keep in
// place of the libraries' optimized ones.
extern template Status close_loop<double>(const Params<double>&, const double&, const double&,
                                          Kinematics<double>*, double, bool);
extern template void place_points<double>(const Params<double>&, Kinematics<double>*);
extern template void first_order_coefficients<double>(const Params<double>&, Kinematics<double>*);
extern template Status solve_kinematics<double>(const Params<double>&, const double&, const double&,
                                                Kinematics<double>*, double, bool);
extern template void compute_bias<double>(const Params<double>&, const Kinematics<double>&,
                                          const double&, const double&, Bias<double>*);
#endif

}  // namespace fivebar
