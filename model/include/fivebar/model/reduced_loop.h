// The friction loop in the few numbers through which the friction torques move the reactions
// (ReducedMap): in forward dynamics with no joint stuck the coupler moment sums and the crank
// accelerations z = (s3, s4, a1, a2); in inverse dynamics (accelerations given) the coupler moment
// sums z = (s3, s4) alone. The reactions are affine in z, F_k(z) = F0_k + G_k z, and
// z = H Mf with Mf_j = phi_j |F_j(z)|: Newton on z solves 4 x 4 (2 x 2) systems and never forms
// the 5 x 5 response of the reactions to the friction torques.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <type_traits>

#include <Eigen/LU>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/params.h"
#include "fivebar/model/reactions.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// The change of the reactions per unit friction torque at given accelerations (inverse
/// dynamics), in the rank-2 form it has: the torques move the reactions only through the two
/// coupler moment sums s3 = Mf_B - Mf_C, s4 = Mf_D - Mf_C (F2 by f3 s3 + f4 s4, F1, F3, F4 with
/// it and F5 against it): dF_j[k] = sigma_k (c3_j f3 + c4_j f4), with sigma_k = -1 for D0 and +1
/// otherwise, c3 = (0, 1, -1, 0, 0), c4 = (0, 0, -1, 1, 0).
template <typename T>
struct CouplerResponse {
  Vec2<T> f3, f4;  ///< F2 per unit s3 and per unit s4

  /// dF[j][k], the change of F_k per unit Mf_j (ReactionResponse)
  ReactionResponse<T> expand() const {
    const std::array<Vec2<T>, kJoints> dF2 = {Vec2<T>::Zero(), f3, Vec2<T>(-f3 - f4), f4,
                                              Vec2<T>::Zero()};
    ReactionResponse<T> out;
    for (int j = 0; j < kJoints; ++j) {
      for (int k = 0; k < kJoints - 1; ++k) out[j][k] = dF2[j];
      out[j][kJoints - 1] = -dF2[j];
    }
    return out;
  }
};

/// The change of the reactions per unit friction torque in forward dynamics with no joint stuck,
/// in the rank-4 form it has: through the coupler moment sums as at given accelerations
/// (CouplerResponse), and through the crank accelerations they bring, a = sum_j m_j Mf_j (F_k by
/// R_k a): dF_j[k] = sigma_k (c3_j f3 + c4_j f4) + R_k m_j.
template <typename T>
struct LowRankResponse : CouplerResponse<T> {
  std::array<Mat2<T>, kJoints> R;  ///< F_k per unit crank acceleration
  std::array<Vec2<T>, kJoints> m;  ///< crank accelerations per unit Mf_j: -A^-1 J_w^T e_j

  /// dF[j][k], the change of F_k per unit Mf_j (ReactionResponse)
  ReactionResponse<T> expand() const {
    ReactionResponse<T> out = CouplerResponse<T>::expand();
    for (int j = 0; j < kJoints; ++j) {
      for (int k = 0; k < kJoints; ++k) out[j][k] += R[k] * m[j];
    }
    return out;
  }
};

namespace detail {

/// A chord step (the last Newton matrix again) follows a step that shrank the residual by at
/// least this factor; otherwise the matrix is formed anew.
inline constexpr double kReducedChordShrink = 1e-2;

/// The loop's map in z (double): the reactions F_k(z) = F0_k + G_k z and the moments of the
/// friction torques z = H (phi N). n = 4, forward dynamics with no joint stuck: z = (s3, s4, a),
/// G_k = [sigma_k f3, sigma_k f4, R_k] (2 x 4), s3 = phi_B N_B - phi_C N_C, s4 = phi_D N_D -
/// phi_C N_C, a = sum_j m_j phi_j N_j (LowRankResponse). n = 2, given accelerations (inverse
/// dynamics): z = (s3, s4), G_k = [sigma_k f3, sigma_k f4] (CouplerResponse).
/// (The reactions and moments in whole 2-vectors F_k, m_j phi_j: fewer instructions than the
/// same sums in components. The Newton matrix in scalars: formed in rows of vectors it took
/// fewer instructions but longer to run.)
template <int n>
struct ReducedMap {
  static_assert(n == 2 || n == 4, "z: the coupler sums, and with n = 4 the crank accelerations");
  using Vec = Eigen::Matrix<double, n, 1>;
  using Mat = Eigen::Matrix<double, n, n>;
  using Forces = std::array<Vec2<double>, kJoints>;
  using Response = std::conditional_t<n == 4, LowRankResponse<double>, CouplerResponse<double>>;
  const Forces& F0;
  const Response& r;
  const std::array<double, kJoints>& phi;
  Forces m_phi{};  ///< m_j phi_j: crank accelerations per unit N_j (n = 4)
  /// An upper bound of ScaledReactions::contraction_bound, max_k sum_j |B[k][j]|_1 with B[k][j] =
  /// G_k H_j phi_j: |G_k H_j phi_j| <= |G_k| |H_j phi_j| element by element, so the bound is
  /// max_k 1^T |G_k| h with h = sum_j |H_j phi_j| (no 5 x 5 B). Below 1 the map contracts.
  double gain_bound = 0.0;

  ReducedMap(const std::array<double, kJoints>& phi_, const Forces& F0_, const Response& response)
      : F0(F0_), r(response), phi(phi_) {
    using std::abs;
    const double h0 = abs(phi[1]) + abs(phi[2]), h1 = abs(phi[2]) + abs(phi[3]);
    const double coupler = (abs(r.f3.x()) + abs(r.f3.y())) * h0 +
                           (abs(r.f4.x()) + abs(r.f4.y())) * h1;
    gain_bound = coupler;
    if constexpr (n == 4) {
      Vec2<double> h(0.0, 0.0);  // h's crank rows
      for (int j = 0; j < kJoints; ++j) {
        m_phi[j] = r.m[j] * phi[j];
        h += m_phi[j].cwiseAbs();
      }
      double crank = 0.0;  // max_k 1^T |R_k| h
      for (int k = 0; k < kJoints; ++k) {
        const Vec2<double> Rh = r.R[k].col(0).cwiseAbs() * h.x() + r.R[k].col(1).cwiseAbs() * h.y();
        crank = std::max(crank, Rh.x() + Rh.y());
      }
      gain_bound = coupler + crank;
    }
  }

  /// z = H (phi N), the moments of the friction torques phi_j N_j
  Vec moments(const double N[kJoints]) const {
    const double mc = phi[2] * N[2];
    Vec z;
    z[0] = phi[1] * N[1] - mc;
    z[1] = phi[3] * N[3] - mc;
    if constexpr (n == 4) {
      const Vec2<double> a =
          m_phi[0] * N[0] + m_phi[1] * N[1] + m_phi[2] * N[2] + m_phi[3] * N[3] + m_phi[4] * N[4];
      z[2] = a.x();
      z[3] = a.y();
    }
    return z;
  }
  /// out_k = G_k z for all k
  void apply(const Vec& z, Forces* out) const {
    const Vec2<double> c = r.f3 * z[0] + r.f4 * z[1];
    for (int k = 0; k < kJoints; ++k) {
      Vec2<double> f;
      if constexpr (n == 4) {
        f = r.R[k].col(0) * z[2] + r.R[k].col(1) * z[3];
        f = k < kJoints - 1 ? Vec2<double>(f + c) : Vec2<double>(f - c);
      } else {
        f = k < kJoints - 1 ? c : Vec2<double>(-c);
      }
      (*out)[k] = f;
    }
  }
  /// The Newton matrix at F, N = |F|: I - H diag(phi) dN/dz, where dN_k/dz = g_k^T = u_k^T G_k
  /// with u_k = F_k / N_k (0 where N_k = 0), returned in u. n = 4: in its 2 x 2 blocks
  /// J = [P Q; U V] (NewtonBlocks: the coupler sums first, the crank accelerations last), each
  /// entry the same sum as in the 4 x 4 form, formed two entries at a time; n = 2: P alone.
  struct Blocks {
    Mat2<double> P, Q, U, V;
  };
  Blocks newton_matrix(const Forces& F, const double N[kJoints], Forces* u) const {
    // g_k in halves: a_k = (dN_k/ds3, dN_k/ds4) = sigma_k (f3 . u_k, f4 . u_k), b_k = R_k^T u_k
    Mat2<double> C;  // rows f3^T, f4^T
    C.row(0) = r.f3.transpose();
    C.row(1) = r.f4.transpose();
    Forces a, b;
    for (int k = 0; k < kJoints; ++k) {
      const double inv = N[k] > 0.0 ? 1.0 / N[k] : 0.0;
      const Vec2<double> uk = F[k] * inv;
      (*u)[k] = uk;
      a[k] = C * uk;
      if (k == kJoints - 1) a[k] = -a[k];
      if constexpr (n == 4) b[k] = r.R[k].transpose() * uk;
    }
    // H diag(phi): columns (c3_j phi_j, c4_j phi_j, m_j phi_j) with c3 = (0, 1, -1, 0, 0),
    // c4 = (0, 0, -1, 1, 0): two nonzeros in each coupler row, five in each crank row
    Blocks J;
    const Vec2<double> pa = a[2] * phi[2];
    J.P.row(0) = (pa - a[1] * phi[1]).transpose();
    J.P.row(1) = (pa - a[3] * phi[3]).transpose();
    J.P.diagonal().array() += 1.0;
    if constexpr (n == 4) {
      const Vec2<double> pb = b[2] * phi[2];
      J.Q.row(0) = (pb - b[1] * phi[1]).transpose();
      J.Q.row(1) = (pb - b[3] * phi[3]).transpose();
      // (the crank rows' sums over k in the order k = 0..4, negated)
      J.U = -(m_phi[0] * a[0].transpose() + m_phi[1] * a[1].transpose() +
              m_phi[2] * a[2].transpose() + m_phi[3] * a[3].transpose() +
              m_phi[4] * a[4].transpose());
      J.V = -(m_phi[0] * b[0].transpose() + m_phi[1] * b[1].transpose() +
              m_phi[2] * b[2].transpose() + m_phi[3] * b[3].transpose() +
              m_phi[4] * b[4].transpose());
      J.V.diagonal().array() += 1.0;
    }
    return J;
  }
};

/// Newton's matrix J of a ReducedMap, factored for the steps that reuse it. n = 2: J^-1. n = 4:
/// by its 2 x 2 blocks J = [P Q; U V] (the coupler sums first, the crank accelerations last):
/// P^-1, W = P^-1 Q and the inverse of the Schur complement V - U W, each in closed form. P is I
/// less the coupler sums' response to themselves, whose eigenvalues are within the coupler term
/// of gain_bound of 0, and J's are within gain_bound of 1: where the map contracts, neither block
/// is near singular, and no pivoting is needed.
template <int n>
struct NewtonFactors {
  using Vec = Eigen::Matrix<double, n, 1>;
  using Mat = Eigen::Matrix<double, n, n>;
  Mat2<double> P_inv, W, U, C_inv;  ///< n = 4: P^-1, W, U, (V - U W)^-1; n = 2: P_inv = J^-1

  /// from J's blocks (ReducedMap::Blocks)
  template <class Blocks>
  void factor(const Blocks& J) {
    if constexpr (n == 2) {
      P_inv = J.P.inverse();
    } else {
      P_inv = inverse2(J.P);
      W = P_inv * J.Q;
      U = J.U;
      C_inv = inverse2(Mat2<double>(J.V - U * W));
    }
  }
  /// J^-1 r
  Vec solve(const Vec& r) const {
    if constexpr (n == 2) {
      return P_inv * r;
    } else {
      const Vec2<double> t = P_inv * r.template head<2>();
      const Vec2<double> da = C_inv * (r.template tail<2>() - U * t);
      Vec d;
      d.template head<2>() = t - W * da;
      d.template tail<2>() = da;
      return d;
    }
  }
};

/// The map of forward dynamics with no joint stuck (z = (s3, s4, a1, a2)).
using ReducedReactions = ReducedMap<4>;
/// The map at given accelerations, inverse dynamics (z = (s3, s4)).
using CouplerReactions = ReducedMap<2>;

/// Newton on r(z) = z - H (phi |F(z)|) from z = H (phi N_start), for a contracting map
/// (ReducedMap::gain_bound < 1: its solution is unique). F is affine in z, so a step d
/// gives the new reactions exactly, F+ = F - dF with dF_k = G_k d, and no evaluation of the map
/// follows the last step. A step solves J d = r(z) with J = I - H diag(phi) D, D's rows u_k^T G_k
/// taken at this z (a Newton step) or at an earlier one (a chord step, the factored matrix
/// again: taken while each step shrinks the residual by kReducedChordShrink or more). Either
/// leaves the residual r+ = -H (phi rho) with rho_k = N+_k - N_k + u_k . dF_k (u_k of the matrix
/// used), the part of the change of |F_k| that the matrix did not predict. One more fixed-point
/// evaluation at z+ would move N by at most max_k |G_k r+|_1 <= gain_bound max_k |rho_k|; the
/// loop stops where that is at most friction_tol max N+ (the fixed point's own test) and
/// returns N+ = |F+|, F+ and Mf = phi N+. On the paper scene's forward dynamics, from |F0|: one
/// Newton step (leaving rho about 2e-8 of N) and one chord step; from the warm start of nearby
/// states, one Newton step. `iterations`: the evaluations of the map, the start and one per
/// step. False if it did not converge within friction_max_iter steps (*N_out and *F_out, the
/// loop's working copies, are then unspecified; N_start is not one of them).
template <int nz>
bool friction_reduced_newton(const ReducedMap<nz>& map, const EvalOptions& opt,
                             const std::array<double, kJoints>& N_start,
                             std::array<double, kJoints>* N_out, std::array<double, kJoints>* Mf,
                             std::array<Vec2<double>, kJoints>* F_out, int* iterations) {
  using Vec = typename ReducedMap<nz>::Vec;
  typename ReducedMap<nz>::Forces& F = *F_out;  // (the outputs as the working copies)
  typename ReducedMap<nz>::Forces u, dF;
  std::array<double, kJoints>& N = *N_out;
  Vec z = map.moments(N_start.data());
  map.apply(z, &F);
  double last = 0.0;  // the last step's max |rho_k|, or at the start max |N_k - N_start_k|
  for (int k = 0; k < kJoints; ++k) {
    F[k] += map.F0[k];
    N[k] = std::sqrt(F[k].squaredNorm());
    last = std::max(last, std::abs(N[k] - N_start[k]));
  }
  const double gain = std::max(map.gain_bound, 1e-300);
  NewtonFactors<nz> J;
  bool chord = false;  // J worth another step
  for (int it = 1; it <= opt.friction_max_iter; ++it) {
    if (!chord) J.factor(map.newton_matrix(F, N.data(), &u));
    const Vec d = J.solve(z - map.moments(N.data()));
    z -= d;
    // the reactions at the new z, F - dF, and the unpredicted change of their norms
    map.apply(d, &dF);
    double scale = 1e-300, rho = 0.0;
    for (int k = 0; k < kJoints; ++k) {
      const double n = N[k];
      F[k] -= dF[k];
      N[k] = std::sqrt(F[k].squaredNorm());
      const double rho_k = std::abs(N[k] - n + u[k].x() * dF[k].x() + u[k].y() * dF[k].y());
      scale = std::max(scale, N[k]);
      rho = std::max(rho, rho_k);
    }
    *iterations = it + 1;
    if (gain * rho <= opt.friction_tol * scale) {
      // (a NaN passes neither std::max nor a failed test: the step that passes is checked)
      double sum = 0.0;
      for (int k = 0; k < kJoints; ++k) sum += N[k];
      if (!std::isfinite(sum)) return false;
      for (int k = 0; k < kJoints; ++k) (*Mf)[k] = map.phi[k] * N[k];
      return true;
    }
    chord = rho <= kReducedChordShrink * last;
    last = rho;
  }
  return false;
}

}  // namespace detail
}  // namespace fivebar
