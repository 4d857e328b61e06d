// The general planar closed-chain solver: Newton-Euler in maximal coordinates over a joint table,
// with the joint reactions as unknowns and load-dependent joint friction Mf_k = r_k f_k(w_k) N_k.
// Any planar mechanism of rigid bodies and revolute joints is a Chain; the five-bar and the
// four-bar are instances (five_bar_chain.h, four_bar.h), which it cross-checks.
//
// Conventions (those of the five-bar, model.md): joint k joins body i to body j (kGround = -1 is
// the ground); F_k is the force body i exerts on body j, acting on j as +F_k and on i as -F_k;
// the friction torque Mf_k acts on j as -Mf_k and on i as +Mf_k; the relative rate of the joint
// is w_k = omega_j - omega_i. A drive applies its torque tau to its body j and -tau to its body i.
// Gravity acts along -y. Each body has a frame: an origin and an angle (its x axis along
// e(angle)); its centre of mass and the joints' points are given in that frame.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "fivebar/model/friction.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar::chain {

using Vec = Vec2<double>;

inline constexpr int kGround = -1;

/// A rigid body: mass, inertia about its centre of mass, and the centre of mass in its frame.
struct Body {
  double mass = 0.0;
  double inertia = 0.0;
  Vec com = Vec::Zero();
};

/// A revolute joint between bodies i and j at the point `at_i` of body i's frame (world
/// coordinates when i is the ground), which is `at_j` of body j's frame. `friction` is the index
/// of its coefficients in Chain::friction (its law's arrays), or -1 for a frictionless pin.
struct Joint {
  int i = kGround;
  int j = kGround;
  Vec at_i = Vec::Zero();
  Vec at_j = Vec::Zero();
  double pin_radius = 0.0;
  int friction = -1;
};

/// A driven joint: a torque between bodies i and j (tau on j, -tau on i); in inverse mode its
/// relative angular acceleration alpha_j - alpha_i is given and tau is solved for.
struct Drive {
  int i = kGround;
  int j = kGround;
};

/// A force (world components) at the point `at` of a body's frame.
struct PointForce {
  int body = 0;
  Vec at = Vec::Zero();
  Vec force = Vec::Zero();
};

/// A planar mechanism: bodies, joints, drives, gravity (along -y) and the joints' friction.
struct Chain {
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Drive> drives;
  double gravity = 0.0;
  FrictionParams<double> friction;
};

/// A pose: each body's frame origin and angle (closed: every joint's two points coincide).
struct Pose {
  std::vector<Vec> origin;
  std::vector<double> angle;
};

/// The loads of one instant: a torque per drive (forward mode), a torque per body, point forces.
struct ChainLoads {
  std::vector<double> drive;
  std::vector<double> torque;
  std::vector<PointForce> forces;
};

/// What a solve returns (per body, per joint, per drive).
struct Solution {
  std::vector<Vec> com_acceleration;  ///< [m/s^2]
  std::vector<double> alpha;          ///< angular accelerations [rad/s^2]
  std::vector<Vec> F;                 ///< joint reactions, force of i on j [N]
  std::vector<double> N;              ///< |F_k| [N]
  std::vector<double> Mf;             ///< friction torques [N m]
  std::vector<double> w;              ///< relative rates omega_j - omega_i [rad/s]
  std::vector<double> drive;          ///< drive torques [N m] (given or solved)
  int iterations = 0;                 ///< friction iterations (fixed point and Newton)
};

/// Settings of the friction loop: stop when max |N - N_prev| <= tol (max N + 1e-300).
struct Options {
  double tol = 1e-13;
  int max_iter = 100;  ///< fixed-point iterations before Newton
  /// given friction torques, one per joint (no friction loop): the motion and reactions they
  /// give, to check another solver's friction solution where it is not unique
  const std::vector<double>* friction_torques = nullptr;
};

/// A link's body: the centre of mass at com_offset, com_angle in the frame along the link.
inline Body link_body(const Link<double>& l) {
  return {l.mass, l.inertia,
          Vec(l.com_offset * std::cos(l.com_angle), l.com_offset * std::sin(l.com_angle))};
}

/// The world position of the point `local` of body b's frame (ground: `local` itself).
inline Vec point(const Pose& q, int b, const Vec& local) {
  if (b == kGround) return local;
  return q.origin[b] + rotate(local, std::cos(q.angle[b]), std::sin(q.angle[b]));
}

/// The centre of mass of body b.
inline Vec com(const Chain& c, const Pose& q, int b) { return point(q, b, c.bodies[b].com); }

/// The angular rate of body b (ground: 0).
inline double body_rate(const std::vector<double>& rate, int b) {
  return b == kGround ? 0.0 : rate[b];
}

/// max |p_i - p_j| over the joints: zero at a closed pose [m].
inline double closure_residual(const Chain& c, const Pose& q) {
  double worst = 0.0;
  for (const Joint& jt : c.joints) {
    worst = std::max(worst, (point(q, jt.i, jt.at_i) - point(q, jt.j, jt.at_j)).norm());
  }
  return worst;
}

/// The relative rates w_k = omega_j - omega_i of the joints.
inline std::vector<double> relative_rates(const Chain& c, const std::vector<double>& rate) {
  std::vector<double> w(c.joints.size());
  for (size_t k = 0; k < c.joints.size(); ++k) {
    w[k] = body_rate(rate, c.joints[k].j) - body_rate(rate, c.joints[k].i);
  }
  return w;
}

namespace detail {

/// f(body, sign) for the two bodies of a joint or drive: +1 on j, -1 on i; the ground is skipped.
template <typename F>
void each_side(int j, int i, F f) {
  if (j != kGround) f(j, 1.0);
  if (i != kGround) f(i, -1.0);
}


/// Positions of the unknowns and equations: per body 3 (a_cx, a_cy, alpha; force and moment
/// balances), per joint 2 (F_k; the pin's acceleration constraint), per drive 1 in inverse mode
/// (tau; the drive's relative acceleration).
struct Layout {
  int bodies, joints, drives;
  int body(int b) const { return 3 * b; }
  int joint(int k) const { return 3 * bodies + 2 * k; }
  int drive(int d) const { return 3 * bodies + 2 * joints + d; }
  int size() const { return 3 * bodies + 2 * joints + drives; }
};

/// The linear system's matrix: body balances, pin constraints and (inverse mode) the drives.
inline Eigen::MatrixXd system_matrix(const Chain& c, const Pose& q, const Layout& n) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n.size(), n.size());
  for (int b = 0; b < n.bodies; ++b) {
    A(n.body(b), n.body(b)) = A(n.body(b) + 1, n.body(b) + 1) = c.bodies[b].mass;
    A(n.body(b) + 2, n.body(b) + 2) = c.bodies[b].inertia;
  }
  for (int k = 0; k < n.joints; ++k) {
    const Joint& jt = c.joints[k];
    const Vec at = point(q, jt.i, jt.at_i);
    each_side(jt.j, jt.i, [&](int b, double s) {  // +F_k on j, -F_k on i
      const Vec r = at - com(c, q, b);
      const int row = n.body(b), col = n.joint(k);
      A(row, col) -= s;
      A(row + 1, col + 1) -= s;
      A(row + 2, col) += s * r.y();  // moment r x F = r_x F_y - r_y F_x
      A(row + 2, col + 1) -= s * r.x();
      // the pin: a_c + alpha perp(r) - omega^2 r equal on both sides (rows of the joint)
      A(col, row) += s;
      A(col + 1, row + 1) += s;
      A(col, row + 2) += s * -r.y();
      A(col + 1, row + 2) += s * r.x();
    });
  }
  for (int d = 0; d < n.drives; ++d) {
    each_side(c.drives[d].j, c.drives[d].i, [&](int b, double s) {
      A(n.body(b) + 2, n.drive(d)) -= s;  // tau on j, -tau on i
      A(n.drive(d), n.body(b) + 2) += s;  // alpha_j - alpha_i
    });
  }
  return A;
}

/// The right-hand side without friction: gravity, loads, drive torques (forward mode) or drive
/// accelerations (inverse mode), and the pins' velocity terms.
inline Eigen::VectorXd system_rhs(const Chain& c, const Pose& q, const std::vector<double>& rate,
                                  const ChainLoads& L, const std::vector<double>* drive_alpha,
                                  const Layout& n) {
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n.size());
  for (int i = 0; i < n.bodies; ++i) {
    b(n.body(i) + 1) = -c.bodies[i].mass * c.gravity;
    if (i < static_cast<int>(L.torque.size())) b(n.body(i) + 2) += L.torque[i];
  }
  for (const PointForce& f : L.forces) {
    b.segment<2>(n.body(f.body)) += f.force;
    b(n.body(f.body) + 2) += cross(Vec(point(q, f.body, f.at) - com(c, q, f.body)), f.force);
  }
  for (int d = 0; d < static_cast<int>(c.drives.size()); ++d) {
    if (drive_alpha) {
      b(n.drive(d)) = (*drive_alpha)[d];
      continue;
    }
    each_side(c.drives[d].j, c.drives[d].i,
              [&](int bd, double s) { b(n.body(bd) + 2) += s * L.drive[d]; });
  }
  for (int k = 0; k < n.joints; ++k) {
    const Joint& jt = c.joints[k];
    const Vec at = point(q, jt.i, jt.at_i);
    each_side(jt.j, jt.i, [&](int bd, double s) {
      b.segment<2>(n.joint(k)) += s * rate[bd] * rate[bd] * (at - com(c, q, bd));
    });
  }
  return b;
}

/// The right-hand side per unit friction torque of joint k (-1 on j's moment, +1 on i's).
inline Eigen::VectorXd friction_column(const Chain& c, int k, const Layout& n) {
  Eigen::VectorXd col = Eigen::VectorXd::Zero(n.size());
  each_side(c.joints[k].j, c.joints[k].i, [&](int b, double s) { col(n.body(b) + 2) = -s; });
  return col;
}

/// |F_k| of the reactions in x.
inline Eigen::VectorXd norms(const Eigen::VectorXd& x, const Layout& n) {
  Eigen::VectorXd N(n.joints);
  for (int k = 0; k < n.joints; ++k) N[k] = x.segment<2>(n.joint(k)).norm();
  return N;
}

/// Newton on R(N) = N - |F(phi N)| with x(Mf) = x0 + X Mf affine; false if it does not converge.
inline bool newton(const Eigen::VectorXd& x0, const Eigen::MatrixXd& X, const Eigen::VectorXd& phi,
                   const Options& opt, const Layout& n, Eigen::VectorXd* N, int* iterations) {
  for (int it = 0; it < 50; ++it, ++*iterations) {
    const Eigen::VectorXd x = x0 + X * phi.cwiseProduct(*N);
    const Eigen::VectorXd R = *N - norms(x, n);
    Eigen::MatrixXd J = Eigen::MatrixXd::Identity(n.joints, n.joints);
    for (int k = 0; k < n.joints; ++k) {
      const Vec F = x.segment<2>(n.joint(k));
      if (!(F.norm() > 0.0)) continue;
      const Vec u = F / F.norm();
      for (int j = 0; j < n.joints; ++j) {
        J(k, j) -= u.dot(Vec(X(n.joint(k), j), X(n.joint(k) + 1, j))) * phi[j];
      }
    }
    const Eigen::VectorXd step = J.partialPivLu().solve(R);
    *N -= step;
    if (!step.allFinite()) return false;
    if (step.cwiseAbs().maxCoeff() <= opt.tol * (N->cwiseAbs().maxCoeff() + 1e-300)) {
      return N->minCoeff() >= -1e-9 * N->cwiseAbs().maxCoeff();
    }
  }
  return false;
}

/// The consistent reactions N = |F(phi N)|: the fixed point from |F0|, then Newton where it does
/// not converge. x(Mf) = x0 + X Mf.
inline Status friction_solve(const Eigen::VectorXd& x0, const Eigen::MatrixXd& X,
                             const Eigen::VectorXd& phi, const Options& opt, const Layout& n,
                             Eigen::VectorXd* N, int* iterations) {
  *N = norms(x0, n);
  *iterations = 0;
  if (phi.isZero(0.0)) return Status::Ok();
  for (int it = 0; it < opt.max_iter; ++it) {
    const Eigen::VectorXd next = norms(x0 + X * phi.cwiseProduct(*N), n);
    const double change = (next - *N).cwiseAbs().maxCoeff();
    *N = next;
    ++*iterations;
    if (!std::isfinite(change)) break;
    if (change <= opt.tol * (N->cwiseAbs().maxCoeff() + 1e-300)) return Status::Ok();
  }
  *N = norms(x0, n);
  if (newton(x0, X, phi, opt, n, N, iterations)) return Status::Ok();
  return Status::Error(StatusCode::kFrictionNotConverged,
                       "planar chain: no consistent reaction forces for the joint friction");
}

/// phi_k = r_k f_k(w_k): the Coulomb sign is sign(w_k), or at w_k = 0 that of wdot_k (nullptr:
/// none; forward mode).
inline Eigen::VectorXd friction_arms(const Chain& c, const std::vector<double>& w,
                                     const std::vector<double>* wdot) {
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(c.joints.size());
  if (!c.friction.active()) return phi;
  for (size_t k = 0; k < c.joints.size(); ++k) {
    const Joint& jt = c.joints[k];
    if (jt.friction < 0) continue;
    int slip = sign_of(w[k]);
    if (slip == 0 && wdot) slip = sign_of((*wdot)[k]);
    phi[k] = jt.pin_radius * friction_law(c.friction, jt.friction, w[k], slip);
  }
  return phi;
}

/// Unpacks the unknowns x into the solution (accelerations, reactions, solved drive torques).
inline void unpack(const Eigen::VectorXd& x, const Layout& n, bool inverse, Solution* s) {
  s->com_acceleration.resize(n.bodies);
  s->alpha.resize(n.bodies);
  for (int b = 0; b < n.bodies; ++b) {
    s->com_acceleration[b] = x.segment<2>(n.body(b));
    s->alpha[b] = x(n.body(b) + 2);
  }
  s->F.resize(n.joints);
  s->N.resize(n.joints);
  for (int k = 0; k < n.joints; ++k) {
    s->F[k] = x.segment<2>(n.joint(k));
    s->N[k] = s->F[k].norm();
  }
  if (inverse) {
    for (int d = 0; d < n.drives; ++d) s->drive[d] = x(n.drive(d));
  }
}

}  // namespace detail

/// Velocity closure: the bodies' angular rates from the drives' relative rates, solving the pins'
/// constraints v_c + omega perp(r) equal on both sides (ground: zero) with the centres' velocities
/// as further unknowns (the constraint rows of detail::system_matrix). Fails unless the drives fix
/// the motion (as many drives as degrees of freedom, away from singular poses). `velocity` (may be
/// null) gets the centres' velocities.
inline Status body_rates(const Chain& c, const Pose& q, const std::vector<double>& drive_rate,
                         std::vector<double>* rate, std::vector<Vec>* velocity = nullptr) {
  const int n = static_cast<int>(c.bodies.size()), m = static_cast<int>(c.joints.size());
  const int d = static_cast<int>(c.drives.size());
  if (2 * m + d != 3 * n) {
    return Status::Error(StatusCode::kInvalidInput,
                         "planar chain: the drives do not match the degrees of freedom");
  }
  const detail::Layout layout{n, m, d};
  const Eigen::MatrixXd A = detail::system_matrix(c, q, layout).bottomLeftCorner(3 * n, 3 * n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(3 * n);
  for (int e = 0; e < d; ++e) b(2 * m + e) = drive_rate[e];
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < 3 * n)
    return Status::Error(StatusCode::kNearSingular, "planar chain: singular pose");
  const Eigen::VectorXd x = qr.solve(b);
  rate->resize(n);
  if (velocity) velocity->resize(n);
  for (int i = 0; i < n; ++i) {
    (*rate)[i] = x(3 * i + 2);
    if (velocity) (*velocity)[i] = x.segment<2>(3 * i);
  }
  return Status::Ok();
}


/// Newton-Euler of the chain at a closed pose with body rates `rate`. Forward mode
/// (`drive_alpha` null): the drive torques are L.drive, and the accelerations are solved for.
/// Inverse mode: the drives' relative accelerations are `drive_alpha`, and their torques are
/// solved for. The friction loop solves Mf_k = r_k f_k(w_k) |F_k| (fixed point, then Newton),
/// unless Options::friction_torques gives the torques.
inline Status solve(const Chain& c, const Pose& q, const std::vector<double>& rate,
                    const ChainLoads& L, const std::vector<double>* drive_alpha, const Options& opt,
                    Solution* s) {
  const bool inverse = drive_alpha != nullptr;
  const detail::Layout n{static_cast<int>(c.bodies.size()), static_cast<int>(c.joints.size()),
                         inverse ? static_cast<int>(c.drives.size()) : 0};
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(detail::system_matrix(c, q, n));
  if (qr.rank() < n.size()) {
    return Status::Error(StatusCode::kNearSingular, "planar chain: singular pose");
  }
  const Eigen::VectorXd x0 = qr.solve(detail::system_rhs(c, q, rate, L, drive_alpha, n));
  Eigen::MatrixXd X(n.size(), n.joints);
  for (int k = 0; k < n.joints; ++k) X.col(k) = qr.solve(detail::friction_column(c, k, n));
  s->w = relative_rates(c, rate);
  s->drive = inverse ? std::vector<double>(c.drives.size()) : L.drive;
  std::vector<double> wdot;  // inverse mode: the accelerations do not depend on the friction
  if (inverse) {
    detail::unpack(x0, n, inverse, s);
    wdot = relative_rates(c, s->alpha);
  }
  Eigen::VectorXd Mf;
  if (opt.friction_torques) {
    Mf = Eigen::Map<const Eigen::VectorXd>(opt.friction_torques->data(), n.joints);
    s->iterations = 0;
  } else {
    const Eigen::VectorXd phi = detail::friction_arms(c, s->w, inverse ? &wdot : nullptr);
    Eigen::VectorXd N;
    const Status st = detail::friction_solve(x0, X, phi, opt, n, &N, &s->iterations);
    if (!st.ok()) return st;
    Mf = phi.cwiseProduct(N);
  }
  detail::unpack(x0 + X * Mf, n, inverse, s);
  s->Mf.assign(Mf.data(), Mf.data() + Mf.size());
  return Status::Ok();
}

}  // namespace fivebar::chain
