// A mechanism at rest held by joint friction (every joint stuck: "locked").
//
// At rest (qd = 0, qdd = 0) the generalized forces of the loads and gravity Q must be carried
// by holding torques lambda_k at the joints: J_w^T lambda = Q, kDof equations in as many unknowns
// as joints. The holding torques are statically indeterminate; friction holds the mechanism when
// some lambda has |lambda_k| <= mu_s,k r_k N_k at every joint, N_k the reactions that lambda
// itself produces. lock_analysis finds the lambda that minimizes the largest ratio
// s = max_k |lambda_k| / (mu_s,k r_k N_k): the mechanism holds while s <= 1.
//
// With N fixed this is a linear program. With two degrees of freedom (the five-bar) its dual is
// two-dimensional: maximize Q . u over sum_k w_k |a_k . u| <= 1 (a_k = J_w^T e_k, w_k = mu_s,k
// r_k N_k). Its optimum lies on a kink of the constraint, where u is orthogonal to one a_k, so
// s = max_k |Q . perp(a_k)| / sum_j w_j |a_j . perp(a_k)|, and the primal lambda follows from
// complementary slackness. With one (the four-bar) s = |Q| / sum_k w_k |a_k|. N is updated from
// lambda until it settles (friction changes the reactions little).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <sstream>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/five_bar_mechanism.h"
#include "fivebar/model/mechanism.h"

namespace fivebar {

/// Result of lock_analysis at one pose and load.
struct LockAnalysis {
  std::array<double, kJoints> hold{};  ///< holding torques lambda_k [N m] (friction torques Mf_k)
  std::array<double, kJoints> N{};     ///< reactions |F_k| with those torques [N]
  std::array<Vec2<double>, kJoints> F;  ///< reactions [N]
  /// max_k |lambda_k| / (mu_s,k r_k N_k) at the optimum (<= 1: friction holds the pose);
  /// infinite when no joint can resist in some direction the loads push
  double ratio = 0.0;
};

namespace detail {

/// min over lambda with sum_k a_k lambda_k = q of max_k |lambda_k| / w_k (the dual vertex rule
/// above); returns the ratio and fills lambda. Two degrees of freedom.
inline double min_max_ratio(const std::array<Vec2<double>, kJoints>& a,
                            const std::array<double, kJoints>& w, const Vec2<double>& q,
                            std::array<double, kJoints>* lambda) {
  double best = -1.0;
  int kbest = -1;
  for (int k = 0; k < kJoints; ++k) {
    if (a[k].squaredNorm() == 0.0) continue;
    const Vec2<double> u = perp(a[k]);
    double denom = 0.0;
    for (int j = 0; j < kJoints; ++j) denom += w[j] * std::abs(a[j].dot(u));
    const double num = std::abs(q.dot(u));
    const double s = num == 0.0 ? 0.0 : denom > 0.0 ? num / denom
                                                    : std::numeric_limits<double>::infinity();
    if (s > best) {
      best = s;
      kbest = k;
    }
  }
  lambda->fill(0.0);
  if (kbest < 0 || !std::isfinite(best)) return kbest < 0 ? 0.0 : best;
  Vec2<double> u = perp(a[kbest]);
  if (q.dot(u) < 0.0) u = -u;
  Vec2<double> rest = q;
  for (int j = 0; j < kJoints; ++j) {
    if (j == kbest) continue;
    const double d = a[j].dot(u);
    (*lambda)[j] = d > 0.0 ? best * w[j] : d < 0.0 ? -best * w[j] : 0.0;
    rest -= a[j] * (*lambda)[j];
  }
  (*lambda)[kbest] = rest.dot(a[kbest]) / a[kbest].squaredNorm();
  // the ratio the torques actually reach (differs from the dual's only where columns are parallel)
  for (int j = 0; j < kJoints; ++j) {
    if ((*lambda)[j] == 0.0) continue;
    best = std::max(best, w[j] > 0.0 ? std::abs((*lambda)[j]) / w[j]
                                     : std::numeric_limits<double>::infinity());
  }
  return best;
}

/// The same with one degree of freedom: sum_k a_k lambda_k = q is one equation, and every joint
/// carries its full share, lambda_k = s w_k sign(a_k q), with s = |q| / sum_k w_k |a_k|.
inline double min_max_ratio(const std::array<Eigen::Matrix<double, 1, 1>, kJoints>& a,
                            const std::array<double, kJoints>& w,
                            const Eigen::Matrix<double, 1, 1>& q,
                            std::array<double, kJoints>* lambda) {
  lambda->fill(0.0);
  double denom = 0.0;
  for (int j = 0; j < kJoints; ++j) denom += w[j] * std::abs(a[j](0, 0));
  const double num = std::abs(q(0, 0));
  if (num == 0.0) return 0.0;
  if (!(denom > 0.0)) return std::numeric_limits<double>::infinity();
  const double s = num / denom;
  for (int j = 0; j < kJoints; ++j) {
    const double d = a[j](0, 0) * q(0, 0);
    (*lambda)[j] = d > 0.0 ? s * w[j] : d < 0.0 ? -s * w[j] : 0.0;
  }
  return s;
}

}  // namespace detail

/// Holding torques of the locked mechanism M at pose q, at rest, under loads L.
template <class M>
Status lock_analysis(const typename M::template Params<double>& p,
                     const typename M::template Loads<double>& L,
                     const mech::Vec<M::kDof, double>& q, const EvalOptions& opt,
                     LockAnalysis* out) {
  using V = mech::Vec<M::kDof, double>;
  typename M::template Kinematics<double> k;
  EvalOptions closure = opt;
  closure.want_angles = false;
  Status st = M::close(p, q, &k, closure);
  if (!st.ok()) return st;
  typename M::template Bias<double> b;
  M::bias(p, k, V::Zero().eval(), &b);
  const Vec2<double> Fvec = M::applied(k, L);
  mech::Mat<M::kDof, double> A;
  V rhs;
  M::mass_and_force(p, k, b, L, Fvec, &A, &rhs);
  std::array<V, kJoints> a;
  for (int j = 0; j < kJoints; ++j) {
    std::array<double, kJoints> unit{};
    unit[j] = 1.0;
    a[j] = M::friction_transpose(k, unit);
  }
  const V zero = V::Zero();
  typename M::template Evaluation<double> ev;
  out->hold.fill(0.0);
  for (int it = 0; it < 30; ++it) {
    M::reactions(p, k, b, L, Fvec, zero, out->hold, &out->F, &ev);
    const std::array<double, kJoints> N_old = out->N;
    reaction_norms(out->F, &out->N);
    std::array<double, kJoints> w;
    for (int j = 0; j < kJoints; ++j) w[j] = M::holding_capacity(p, j, out->N[j]);
    out->ratio = detail::min_max_ratio(a, w, rhs, &out->hold);
    double change = 0.0, scale = 1e-300;
    for (int j = 0; j < kJoints; ++j) {
      change = std::max(change, std::abs(out->N[j] - N_old[j]));
      scale = std::max(scale, out->N[j]);
    }
    if (!std::isfinite(out->ratio) || (it > 0 && change <= 1e-13 * scale)) break;
  }
  M::reactions(p, k, b, L, Fvec, zero, out->hold, &out->F, &ev);
  reaction_norms(out->F, &out->N);
  return Status::Ok();
}

/// lock_extent's bound on the extent, in units of its start plus the torque it starts from
inline constexpr double kSelfLocking = 1e6;

/// lock_extent's failure where the extent grows without bound from the drive torque `at`
inline Status self_locking(double at) {
  std::ostringstream msg;
  msg.precision(3);
  msg << "static friction would hold any drive torque here (the lock's extent grows without "
         "bound from M = "
      << at << " N m: self-locking, as near a toggle pose); the motion from rest is not unique";
  return Status::Error(StatusCode::kIndeterminateModes, msg.str());
}

/// How far a drive torque of mechanism M can move from its value in `L` in direction `sign`
/// (set(&L, value) sets it) before the locked mechanism breaks away: lock_analysis's ratio
/// reaches 1. The ratio is homogeneous of degree one in the torque excess for fixed reactions, so
/// d <- d / ratio(d) converges in a few steps (the reactions change with the holding torques by
/// O(mu r / l)); `start` is the first d (> 0). d = 0 where no friction resists that direction.
/// Fails (kIndeterminateModes) where the extent grows without settling: near a toggle friction
/// can lock the mechanism against any torque (the reactions it brings grow with the torque), and
/// the motion from rest is not unique there (the friction loop finds several solutions).
template <class M, class SetDrive>
Status lock_extent(const typename M::template Params<double>& p,
                   const typename M::template Loads<double>& L, const mech::Vec<M::kDof, double>& q,
                   const EvalOptions& opt, double at, double sign, double start, SetDrive set,
                   double* d) {
  *d = start;
  for (int it = 0; it < 50; ++it) {
    typename M::template Loads<double> moved = L;
    set(&moved, at + sign * *d);
    LockAnalysis lock;
    const Status st = lock_analysis<M>(p, moved, q, opt, &lock);
    if (!st.ok()) return st;
    if (!(lock.ratio > 0.0) || !std::isfinite(lock.ratio)) {
      *d = 0.0;
      return Status::Ok();
    }
    const double next = *d / lock.ratio;
    const bool done = std::abs(next - *d) <= 1e-14 * next;
    *d = next;
    if (done) return Status::Ok();
    if (!(next < kSelfLocking * (start + std::abs(at)))) return self_locking(at);
  }
  return Status::Ok();
}

/// The five-bar at pose (th1, th2).
inline Status lock_analysis(const Params<double>& p, const Loads<double>& L, double th1,
                            double th2, const EvalOptions& opt, LockAnalysis* out) {
  return lock_analysis<FiveBar>(p, L, Vec2<double>(th1, th2), opt, out);
}

}  // namespace fivebar
