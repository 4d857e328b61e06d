// The reaction/friction loop (model.md section 4): friction torques Mf_k = phi_k N_k that are
// consistent with the reactions N_k they produce. The reactions are affine in the friction
// torques, so the loop probes that map once and iterates on it; three outcomes: a contracting
// fixed point, a Newton solution where it stops contracting, or an error naming why none exists
// or why it is not unique (where the map does not contract everywhere, friction_unique).
#pragma once

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <type_traits>
#include <utility>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/reactions.h"
#include "fivebar/model/reduced_loop.h"
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

/// The previous solution of a friction loop, kept by a caller that evaluates nearby states one
/// after the other (the simulator's right-hand side): the next loop starts from it where its
/// fixed point is unique (the map contracts), so the start changes the cost, not the solution.
/// The start carries over what friction adds to the reactions, N - |F0| (F0: the frictionless
/// reactions), onto the new frictionless ones: N_k = |F0_k| + (N - |F0|)_k of the last loop. That
/// part changes from one state to the next far less than N itself.
struct FrictionWarmStart {
  bool set = false;
  std::array<double, kJoints> N{};  ///< the last consistent reactions [N]
  std::array<double, kJoints> N0{};  ///< the last frictionless reactions |F0_k| [N]
};

/// Optional help for friction_loop; neither changes its solution.
template <typename T>
struct LoopAids {
  /// the change of the reactions per unit friction torque (for torques before `extra`), known in
  /// closed form in the rank-4 form of forward dynamics with no joint stuck: replaces the unit
  /// probes
  const LowRankResponse<T>* low_rank = nullptr;
  /// the same at given accelerations (inverse dynamics), in its rank-2 form (unused where
  /// low_rank is given)
  const CouplerResponse<T>* coupler = nullptr;
  FrictionWarmStart* warm = nullptr;  ///< double evaluations only (ignored for Jets)
};

namespace detail {

/// The reactions as an affine map of the friction torques, F(Mf) = F0 + sum_j dF_j Mf_j, probed
/// once (one solve per joint with friction); each loop iteration then costs a 10x5 product.
template <typename T>
struct AffineReactions {
  std::array<Vec2<T>, kJoints> F0;
  std::array<std::array<Vec2<T>, kJoints>, kJoints> dF;
  std::array<bool, kJoints> active{};  ///< joints with friction (phi_j not exactly zero)

  void operator()(const std::array<T, kJoints>& torque, std::array<Vec2<T>, kJoints>* out) const {
    *out = F0;
    for (int j = 0; j < kJoints; ++j) {
      if (!active[j]) continue;
      for (int k = 0; k < kJoints; ++k) (*out)[k] += dF[j][k] * torque[j];
    }
  }
};

/// The affine map of the reactions around F0 = solve(0): the change per unit torque from
/// `response` (ReactionResponse, reactions.h) where given, else probed at a unit torque per active
/// joint.
template <typename T, typename Solve>
AffineReactions<T> probe_reactions(const std::array<T, kJoints>& phi, Solve& solve,
                                   const std::array<Vec2<T>, kJoints>& F0,
                                   const ReactionResponse<T>* response = nullptr) {
  AffineReactions<T> map;
  map.F0 = F0;
  for (int j = 0; j < kJoints; ++j) {
    map.active[j] = !is_exact_zero(phi[j]);
    if (!map.active[j]) {
      for (auto& v : map.dF[j]) v.setZero();
      continue;
    }
    if (response) {
      map.dF[j] = (*response)[j];
      continue;
    }
    std::array<T, kJoints> unit_torque{};
    unit_torque[j] = T(1);
    std::array<Vec2<T>, kJoints> Fj;
    solve(unit_torque, &Fj);
    for (int k = 0; k < kJoints; ++k) map.dF[j][k] = Fj[k] - map.F0[k];
  }
  return map;
}

/// Newton on R(N) = N - |F(phi N)| (F is affine in the friction torques: F = F0 + sum_j dF_j
/// Mf_j, from unit probes), from the start N. Converged: true and *N_out set.
template <typename T>
bool friction_newton(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                     const AffineReactions<T>& map, std::array<T, kJoints> N,
                     std::array<T, kJoints>* N_out) {
  const auto& F0 = map.F0;
  const auto& dF = map.dF;
  using std::sqrt;
  for (int it = 0; it < 50; ++it) {
    std::array<Vec2<T>, kJoints> F = F0;
    for (int j = 0; j < kJoints; ++j) {
      for (int k = 0; k < kJoints; ++k) F[k] += dF[j][k] * (phi[j] * N[j]);
    }
    Eigen::Matrix<T, kJoints, 1> R;
    Eigen::Matrix<T, kJoints, kJoints> J = Eigen::Matrix<T, kJoints, kJoints>::Identity();
    for (int k = 0; k < kJoints; ++k) {
      const T n = sqrt(F[k].squaredNorm());
      R[k] = N[k] - n;
      if (value_of(n) > 0.0) {
        for (int j = 0; j < kJoints; ++j) J(k, j) -= F[k].dot(dF[j][k]) * phi[j] / n;
      }
    }
    const Eigen::Matrix<T, kJoints, 1> step = J.partialPivLu().solve(R);
    double change = 0.0, scale = 1e-300;
    for (int k = 0; k < kJoints; ++k) {
      N[k] -= step[k];
      change = std::max(change, std::abs(value_of(step[k])));
      scale = std::max(scale, std::abs(value_of(N[k])));
    }
    if (!std::isfinite(change)) return false;
    if (change <= opt.friction_tol * scale) {
      for (int k = 0; k < kJoints; ++k) {
        if (value_of(N[k]) < -1e-9 * scale) return false;  // not a magnitude: no solution
      }
      *N_out = N;
      return true;
    }
  }
  return false;
}

/// The map with its columns scaled by phi: F_k(phi N) = F0_k + sum_j B[k][j] N_j (the columns of
/// joints without friction zero).
template <typename T>
struct ScaledReactions {
  std::array<std::array<Vec2<T>, kJoints>, kJoints> B;  ///< B[k][j] = dF_j[k] phi_j
  std::array<Vec2<T>, kJoints> F0;
  /// An upper bound of the Lipschitz constant of N -> |F(phi N)| in the max norm:
  /// max_k sum_j |B[k][j]| (|v| <= |v_x| + |v_y|). Below 1 the map contracts everywhere: its
  /// fixed point is unique and the iteration reaches it from any start.
  double contraction_bound = 0.0;

  /// From F0 and dF[j][k], the change of F_k per unit torque at joint j (built in one pass with
  /// the bound).
  ScaledReactions(const std::array<T, kJoints>& phi, const std::array<Vec2<T>, kJoints>& F0_,
                  const ReactionResponse<T>& dF)
      : F0(F0_) {
    std::array<double, kJoints> row{};
    for (int j = 0; j < kJoints; ++j) {
      if (is_exact_zero(phi[j])) {
        for (int k = 0; k < kJoints; ++k) B[k][j].setZero();
        continue;
      }
      for (int k = 0; k < kJoints; ++k) {
        B[k][j] = dF[j][k] * phi[j];
        row[k] += std::abs(value_of(B[k][j].x())) + std::abs(value_of(B[k][j].y()));
      }
    }
    contraction_bound = *std::max_element(row.begin(), row.end());
  }
  ScaledReactions(const std::array<T, kJoints>& phi, const AffineReactions<T>& map)
      : ScaledReactions(phi, map.F0, map.dF) {}
  /// The same from the rank-4 form, B[k][j] = R_k (m_j phi_j) + sigma_k phi_j (c3_j f3 + c4_j f4)
  /// (without the unscaled 5 x 5 response).
  ScaledReactions(const std::array<T, kJoints>& phi, const std::array<Vec2<T>, kJoints>& F0_,
                  const LowRankResponse<T>& r)
      : F0(F0_) {
    const std::array<Vec2<T>, kJoints> dF2 = {Vec2<T>::Zero(), r.f3, Vec2<T>(-r.f3 - r.f4), r.f4,
                                              Vec2<T>::Zero()};
    std::array<double, kJoints> row{};
    for (int j = 0; j < kJoints; ++j) {
      if (is_exact_zero(phi[j])) {
        for (int k = 0; k < kJoints; ++k) B[k][j].setZero();
        continue;
      }
      const Vec2<T> a = r.m[j] * phi[j], d = dF2[j] * phi[j];
      for (int k = 0; k < kJoints; ++k) {
        B[k][j] = r.R[k] * a;
        if (k < kJoints - 1) {
          B[k][j] += d;
        } else {
          B[k][j] -= d;
        }
        row[k] += std::abs(value_of(B[k][j].x())) + std::abs(value_of(B[k][j].y()));
      }
    }
    contraction_bound = *std::max_element(row.begin(), row.end());
  }
  /// F = F(phi N) and its norms n_k = |F_k| (one evaluation of the loop's map N -> |F(phi N)|)
  void evaluate(const std::array<T, kJoints>& N, std::array<Vec2<T>, kJoints>* F,
                std::array<T, kJoints>* n) const {
    using std::sqrt;
    for (int k = 0; k < kJoints; ++k) {
      Vec2<T> f = F0[k];
      for (int j = 0; j < kJoints; ++j) f += B[k][j] * N[j];
      (*F)[k] = f;
      (*n)[k] = sqrt(f.squaredNorm());
    }
  }
};

/// max_k |a_k - b_k| and max_k |a_k| (at least 1e-300), the loop's convergence test quantities.
template <typename T>
void change_and_scale(const std::array<T, kJoints>& a, const std::array<T, kJoints>& b,
                      double* change, double* scale) {
  *change = 0.0;
  *scale = 1e-300;
  for (int k = 0; k < kJoints; ++k) {
    *change = std::max(*change, std::abs(value_of(a[k]) - value_of(b[k])));
    *scale = std::max(*scale, std::abs(value_of(a[k])));
  }
}

/// Fixed-point iteration N <- |F(phi N)| from `start` (nullptr: N = |F0|). True when it converged
/// (N, Mf, F consistent); otherwise *contracting tells whether it was still contracting, *ratio
/// the last ratio of successive changes.
template <typename T>
bool friction_fixed_point(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                          const ScaledReactions<T>& map, const std::array<T, kJoints>* start,
                          std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                          std::array<Vec2<T>, kJoints>* F, int* iterations, bool* contracting,
                          double* ratio) {
  if (start) {
    *N = *start;
  } else {
    reaction_norms(map.F0, N);
  }
  double prev_err = 0.0;
  *contracting = true;
  *ratio = 0.0;
  for (int it = 1; it <= opt.friction_max_iter; ++it) {
    const std::array<T, kJoints> N_old = *N;
    map.evaluate(N_old, F, N);
    double err, scale;
    change_and_scale(*N, N_old, &err, &scale);
    *iterations = it;
    if (!std::isfinite(err)) {
      *contracting = false;
      return false;
    }
    if (err <= opt.friction_tol * scale) {
      // friction torques consistent with the final reactions
      for (int j = 0; j < kJoints; ++j) (*Mf)[j] = phi[j] * (*N)[j];
      return true;
    }
    *ratio = prev_err > 0.0 ? err / prev_err : 0.0;
    // growing changes after the first few iterations: the loop does not contract
    if (it >= 4 && *ratio > 1.0) {
      *contracting = false;
      return false;
    }
    prev_err = err;
  }
  return false;
}

/// J <- its LU factors in place, for a strictly diagonally dominant J (Gaussian elimination, no
/// pivoting needed): U above the diagonal, the reciprocals of U's diagonal on it, the multipliers
/// of L below it. (Loops unrolled: five unknowns, called in the loop. The reciprocals take the
/// divisions off the back substitution, whose steps depend on each other.)
inline void factor_dominant(double J[kJoints][kJoints]) {
#pragma GCC unroll 5
  for (int c = 0; c < kJoints; ++c) {
    const double inv = 1.0 / J[c][c];
    J[c][c] = inv;
#pragma GCC unroll 5
    for (int i = c + 1; i < kJoints; ++i) {
      const double f = J[i][c] * inv;
      J[i][c] = f;
#pragma GCC unroll 5
      for (int j = c + 1; j < kJoints; ++j) J[i][j] -= f * J[c][j];
    }
  }
}

/// r <- J^-1 r from the factors of factor_dominant.
inline void solve_factored(const double LU[kJoints][kJoints], double r[kJoints]) {
#pragma GCC unroll 5
  for (int c = 0; c < kJoints; ++c) {
#pragma GCC unroll 5
    for (int i = c + 1; i < kJoints; ++i) r[i] -= LU[i][c] * r[c];
  }
#pragma GCC unroll 5
  for (int c = kJoints - 1; c >= 0; --c) {
#pragma GCC unroll 5
    for (int j = c + 1; j < kJoints; ++j) r[c] -= LU[c][j] * r[j];
    r[c] *= LU[c][c];
  }
}

/// A chord step (the last factored Newton matrix again) is taken while the last step shrank the
/// change by at least this factor; otherwise the matrix is formed anew at the current point.
inline constexpr double kChordShrink = 1e-2;

/// The fixed point of a contracting map (ScaledReactions::contraction_bound < 1, so that it is
/// unique and I - dG/dN is strictly diagonally dominant) in fewer evaluations: the fixed-point
/// evaluation N' = G(N) = |F(phi N)| alternates with a Newton step from N, and the loop stops on
/// the fixed point's own test (max |N' - N| <= tol max N') with N = N'. From a warm `start`, once
/// a step has shrunk the change by kChordShrink or more, the following steps reuse its factored
/// matrix (chord steps: each shrinks the change about as much, for a back substitution instead of
/// a new matrix); from N = |F0| (`start` null: the cold loops of forward and inverse dynamics)
/// every step is a Newton step. False if it did not converge within friction_max_iter
/// evaluations.
inline bool friction_contracting_newton(const std::array<double, kJoints>& phi,
                                        const EvalOptions& opt,
                                        const ScaledReactions<double>& map,
                                        const std::array<double, kJoints>* start,
                                        std::array<double, kJoints>* N_out,
                                        std::array<double, kJoints>* Mf,
                                        std::array<Vec2<double>, kJoints>* F, int* iterations) {
  std::array<double, kJoints> N, Nn;
  if (start) {
    N = *start;
  } else {
    reaction_norms(map.F0, &N);
  }
  double LU[kJoints][kJoints];
  double last_err = 0.0;
  bool chord = false;  // LU holds a matrix worth reusing
  for (int it = 1; it <= opt.friction_max_iter; ++it) {
    map.evaluate(N, F, &Nn);
    double err, scale;
    change_and_scale(Nn, N, &err, &scale);
    *iterations = it;
    if (!std::isfinite(err)) return false;
    if (err <= opt.friction_tol * scale) {
      *N_out = Nn;
      for (int k = 0; k < kJoints; ++k) (*Mf)[k] = phi[k] * Nn[k];
      return true;
    }
    chord = chord && err <= kChordShrink * last_err;
    if (!chord) {
      // Newton on R(N) = N - G(N), dG_k/dN_j = F_k . B_kj / |F_k|: N <- N - (I - dG/dN)^-1 R
      for (int k = 0; k < kJoints; ++k) {
        const Vec2<double> u =
            Nn[k] > 0.0 ? Vec2<double>((*F)[k] / Nn[k]) : Vec2<double>::Zero();
        for (int j = 0; j < kJoints; ++j) LU[k][j] = -u.dot(map.B[k][j]);
        LU[k][k] += 1.0;
      }
      factor_dominant(LU);
    }
    double step[kJoints];
    for (int k = 0; k < kJoints; ++k) step[k] = N[k] - Nn[k];
    solve_factored(LU, step);
    for (int k = 0; k < kJoints; ++k) N[k] -= step[k];
    chord = start != nullptr;
    last_err = err;
  }
  return false;
}

/// A start far above the consistent reactions, N = 100 |F0| + 1: where there are several
/// consistent N, Newton from there finds a large one.
template <typename T>
std::array<T, kJoints> large_start(const AffineReactions<T>& map) {
  std::array<T, kJoints> N;
  reaction_norms(map.F0, &N);
  for (auto& n : N) n = n * T(100) + T(1);
  return N;
}

/// Newton on the affine map from |F0|, else from a large start (large_start): a consistent N, or
/// an error saying that there is none. (Whether it is the only one: friction_unique.)
template <typename T>
Status friction_newton_fallback(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                                const AffineReactions<T>& map, bool contracting, double ratio,
                                std::array<T, kJoints>* N) {
  std::array<T, kJoints> N0;
  reaction_norms(map.F0, &N0);
  if (friction_newton(phi, opt, map, N0, N) ||
      friction_newton(phi, opt, map, large_start(map), N)) {
    return Status::Ok();
  }
  std::ostringstream msg;
  msg << "friction loop: fixed point " << (contracting ? "did not converge" : "does not contract")
      << " (ratio " << ratio << "); Newton finds no consistent reaction forces: r_k * mu too "
      << "large for the loads (friction would lock the joints)";
  return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
}

/// The largest relative change of N in one step of friction_continuation. (Where other solutions
/// are near, as on random four-bars at high rates, longer steps jump to them: half the largest N
/// did there, a tenth did not.)
inline constexpr double kContinuationStep = 0.1;

/// The solution of the loop connected to the frictionless reactions: Newton along the friction
/// scale s (friction arms s phi) from N = |F0| at s = 0 to s = 1, each step started from the last
/// solution. A step is kept where Newton converges and no N_k moves by more than a tenth of the
/// largest N (kContinuationStep; else it is halved, down to 1/1024 of s: there the branch folds
/// back before s = 1 and the answer is false), and the next may be twice as long, up to 1/4.
template <typename T>
bool friction_continuation(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                           const AffineReactions<T>& map, std::array<T, kJoints>* N) {
  reaction_norms(map.F0, N);
  double s = 0.0, h = 0.25;
  while (s < 1.0) {
    const double next = std::min(1.0, s + h);
    std::array<T, kJoints> phi_s, N_next;
    for (int j = 0; j < kJoints; ++j) phi_s[j] = phi[j] * T(next);
    double change = 0.0, scale = 0.0;
    const bool converged = friction_newton(phi_s, opt, map, *N, &N_next);
    if (converged) change_and_scale(N_next, *N, &change, &scale);
    if (converged && change <= kContinuationStep * scale) {
      *N = N_next;
      s = next;
      h = std::min(2.0 * h, 0.25);
    } else if ((h *= 0.5) < 1.0 / 1024) {
      return false;
    }
  }
  return true;
}

/// Relative difference under which two solutions of the loop are taken for the same one
/// (their own tolerance is friction_tol).
inline constexpr double kSameSolution = 1e-6;

/// Where the map does not contract everywhere (ScaledReactions::contraction_bound >= 1) the loop
/// can have several consistent N, each the reactions of a possible motion: in forward dynamics
/// different accelerations for the same torques, in inverse dynamics different drive torques for
/// the same motion (on random four-bars at joint rates to 60 rad/s, forward dynamics at either
/// drive torque gives the same accelerations, each as its unique solution). None of them is more
/// physical than the other, so the loop does not choose: the solution N found is compared with two
/// others, the one connected to the frictionless reactions (friction_continuation) and Newton's
/// from a large start, and any difference is an error that gives both. (Two Newton starts alone
/// miss the solution connected to the frictionless one where both reach the large one; the
/// continuation alone misses the large one.) Where the bound is below 1 the solution is unique
/// and nothing is checked.
template <typename T>
Status friction_unique(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                       const AffineReactions<T>& map, double bound,
                       const std::array<T, kJoints>& N) {
  std::array<T, kJoints> other[2];
  const bool found[2] = {friction_continuation(phi, opt, map, &other[0]),
                         friction_newton(phi, opt, map, large_start(map), &other[1])};
  for (int i = 0; i < 2; ++i) {
    double diff, scale, other_scale;
    change_and_scale(N, other[i], &diff, &scale);
    change_and_scale(other[i], N, &diff, &other_scale);
    if (!found[i] || diff <= kSameSolution * std::max(scale, other_scale)) continue;
    std::ostringstream msg;
    msg << "friction loop: several consistent reaction forces (max |N| " << scale << " N and "
        << other_scale << " N, differing by up to " << diff << " N; the loop's gain bound is "
        << bound << " >= 1): the motion, or in inverse dynamics the drive torque, is not unique "
        << "(r_k * mu too large for the reactions at this pose and speed)";
    return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
  }
  return Status::Ok();
}

/// The value parts of x in *out (the double shadow of a Jet evaluation); null stays null.
template <typename T>
const std::array<double, kJoints>* array_values(const std::array<T, kJoints>* x,
                                                std::array<double, kJoints>* out) {
  if (!x) return nullptr;
  for (int j = 0; j < kJoints; ++j) (*out)[j] = value_of((*x)[j]);
  return out;
}

/// The converged friction loop of a double evaluation, kept for the Jet evaluation of the same
/// point (implicit derivative, friction_loop_implicit): the consistent N, the affine map of the
/// reactions and the loop's iteration count (friction_max_iter + 1: a Newton solve).
struct LoopSolution {
  bool set = false;
  std::array<double, kJoints> N{};
  AffineReactions<double> map;
  int iterations = 0;
};

/// J^-1 r for a double matrix J and a right-hand side r of Jets: Gaussian elimination with
/// partial pivoting, its row operations applied to r (no Jet-valued matrix, no general LU).
template <typename T>
std::array<T, kJoints> solve_with_double_matrix(Eigen::Matrix<double, kJoints, kJoints> J,
                                                std::array<T, kJoints> r) {
  for (int c = 0; c < kJoints; ++c) {
    int pivot = c;
    for (int i = c + 1; i < kJoints; ++i) {
      if (std::abs(J(i, c)) > std::abs(J(pivot, c))) pivot = i;
    }
    if (pivot != c) {
      J.row(c).swap(J.row(pivot));
      std::swap(r[c], r[pivot]);
    }
    for (int i = c + 1; i < kJoints; ++i) {
      const double f = J(i, c) / J(c, c);
      if (f == 0.0) continue;
      J.row(i) -= f * J.row(c);
      r[i] -= f * r[c];
    }
  }
  for (int c = kJoints - 1; c >= 0; --c) {
    for (int j = c + 1; j < kJoints; ++j) {
      if (J(c, j) != 0.0) r[c] -= J(c, j) * r[j];
    }
    r[c] = r[c] / J(c, c);
  }
  return r;
}

/// The Jet derivatives of the loop's solution by the implicit function theorem. The loop solves
/// N = G(N, p) = |F(phi N)|; with N* the double solution, one Newton step in Jets from N*,
/// N = N* + (I - G_N)^-1 (G(N*, p) - N*), gives the value (refined) and dN/dp =
/// (I - G_N)^-1 G_p: one Jet solve of the reactions at phi N* instead of the Jet probes and
/// iterations. G_N (double) comes from the double map at the reactions F(phi N*).
template <typename T, typename Solve>
void friction_loop_implicit(const std::array<T, kJoints>& phi, const LoopSolution& sol,
                            Solve& solve, std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                            std::array<Vec2<T>, kJoints>* F, int* iterations) {
  std::array<T, kJoints> M;
  for (int j = 0; j < kJoints; ++j) M[j] = phi[j] * sol.N[j];
  std::array<Vec2<T>, kJoints> Fs;
  solve(M, &Fs);
  // I - G_N at F(phi N*), in double; r = G(N*, p) - N* in Jets
  Eigen::Matrix<double, kJoints, kJoints> J = Eigen::Matrix<double, kJoints, kJoints>::Identity();
  std::array<T, kJoints> r;
  for (int k = 0; k < kJoints; ++k) {
    using std::sqrt;
    const T n = sqrt(Fs[k].squaredNorm());
    r[k] = n - sol.N[k];
    if (!(value_of(n) > 0.0)) continue;
    const Vec2<double> Fk(value_of(Fs[k].x()), value_of(Fs[k].y()));
    for (int j = 0; j < kJoints; ++j) {
      if (sol.map.active[j]) J(k, j) -= Fk.dot(sol.map.dF[j][k]) * value_of(phi[j]) / value_of(n);
    }
  }
  const std::array<T, kJoints> dN = solve_with_double_matrix(J, r);  // N - N*
  for (int k = 0; k < kJoints; ++k) {
    (*N)[k] = dN[k] + sol.N[k];
    (*Mf)[k] = phi[k] * (*N)[k];
  }
  // F is affine in the friction torques: F(phi N) = F(phi N*) + sum_j dF_j phi_j (N_j - N*_j)
  *F = Fs;
  for (int j = 0; j < kJoints; ++j) {
    if (!sol.map.active[j]) continue;
    const T dM = phi[j] * dN[j];
    for (int k = 0; k < kJoints; ++k) {
      add_scaled(&(*F)[k].x(), sol.map.dF[j][k].x(), dM);
      add_scaled(&(*F)[k].y(), sol.map.dF[j][k].y(), dM);
    }
  }
  *iterations = sol.iterations;
}

/// The end of scaled_friction_loop where the fixed point did not converge (Newton on the unscaled
/// map `affine`, friction_newton_fallback) or the map does not contract everywhere (`bound` >= 1:
/// the solution N is checked to be the only one found, friction_unique). `converged`: the fixed
/// point's N, Mf, F are consistent; otherwise Newton's N is completed into Mf and F here.
template <typename T, typename Solve>
Status friction_loop_beyond_contraction(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                                        Solve& solve, double bound,
                                        const AffineReactions<T>& affine, bool converged,
                                        bool contracting, double ratio, std::array<T, kJoints>* N,
                                        std::array<T, kJoints>* Mf,
                                        std::array<Vec2<T>, kJoints>* F, int* iterations) {
  if (!converged) {
    const Status st = friction_newton_fallback(phi, opt, affine, contracting, ratio, N);
    if (!st.ok()) return st;
  }
  if (bound >= 1.0) {  // not a contraction: the solution found need not be the only one
    const Status st = friction_unique(phi, opt, affine, bound, *N);
    if (!st.ok()) return st;
  }
  if (converged) return Status::Ok();
  for (int j = 0; j < kJoints; ++j) (*Mf)[j] = phi[j] * (*N)[j];
  solve(*Mf, F);
  reaction_norms(*F, N);
  *iterations = opt.friction_max_iter + 1;  // marks a Newton solve
  return Status::Ok();
}

/// The loop on the scaled map: Newton steps where it contracts, else the fixed point, else Newton
/// on `affine()`, the unscaled map (friction_newton_fallback); where it does not contract
/// everywhere, the solution is checked to be the only one found (friction_unique). `warm`: as in
/// joint_friction_loop.
template <typename T, typename Solve, typename Affine>
Status scaled_friction_loop(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                            Solve& solve, const ScaledReactions<T>& scaled, const Affine& affine,
                            const FrictionWarmStart* warm, std::array<T, kJoints>* N,
                            std::array<T, kJoints>* Mf, std::array<Vec2<T>, kJoints>* F,
                            int* iterations) {
  // a warm start only where the fixed point is unique (a contraction): the same solution, sooner
  const std::array<T, kJoints>* start = nullptr;
  std::array<T, kJoints> N_warm;
  const bool contracts = scaled.contraction_bound < 1.0;
  if (warm && warm->set && contracts) {
    reaction_norms(scaled.F0, &N_warm);
    for (int j = 0; j < kJoints; ++j) N_warm[j] += T(warm->N[j] - warm->N0[j]);
    start = &N_warm;
  }
  bool contracting = true;
  double ratio = 0.0;
  if constexpr (std::is_same_v<T, double>) {
    // a contraction: unique fixed point, reached sooner by Newton steps
    if (contracts &&
        friction_contracting_newton(phi, opt, scaled, start, N, Mf, F, iterations)) {
      return Status::Ok();
    }
  }
  bool converged =
      friction_fixed_point(phi, opt, scaled, start, N, Mf, F, iterations, &contracting, &ratio);
  if (!converged && start) {  // (a contraction converges from anywhere: not expected)
    converged = friction_fixed_point<T>(phi, opt, scaled, nullptr, N, Mf, F, iterations,
                                        &contracting, &ratio);
  }
  if (converged && contracts) return Status::Ok();  // the only solution
  return friction_loop_beyond_contraction(phi, opt, solve, scaled.contraction_bound, affine(),
                                          converged, contracting, ratio, N, Mf, F, iterations);
}

/// The contracting loop on a reduced map (ReducedMap: forward dynamics with no joint stuck, or
/// given accelerations; friction_reduced_newton), started from |F0| (`N0`) or, with `warm` set,
/// from friction's share of the last reactions carried onto it (FrictionWarmStart). True with N,
/// Mf, F set; false where the map's gain bound is 1 or more (the exact bound and the uniqueness
/// check of scaled_friction_loop decide there) or Newton did not converge (scaled_friction_loop
/// takes the loop from the start, with the same outcome as without this path).
template <int n>
bool reduced_friction_loop(const ReducedMap<n>& map, const EvalOptions& opt,
                           const std::array<double, kJoints>& N0, const FrictionWarmStart* warm,
                           std::array<double, kJoints>* N, std::array<double, kJoints>* Mf,
                           std::array<Vec2<double>, kJoints>* F, int* iterations) {
  if (!(map.gain_bound < 1.0)) return false;
  std::array<double, kJoints> start = N0;
  if (warm && warm->set) {
    for (int j = 0; j < kJoints; ++j) start[j] += warm->N[j] - warm->N0[j];
  }
  return friction_reduced_newton(map, opt, start, N, Mf, F, iterations);
}

/// The loop of friction_loop below for the load-dependent torques phi_k N_k alone. `loop`
/// (may be null): a double evaluation records its solution there; a Jet evaluation given a
/// recorded solution differentiates it (friction_loop_implicit) instead of iterating in Jets.
template <typename T, typename Solve>
Status joint_friction_loop(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                           Solve&& solve, std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                           std::array<Vec2<T>, kJoints>* F, int* iterations,
                           LoopSolution* loop = nullptr, const LoopAids<T>& aids = {}) {
  if constexpr (!std::is_same_v<T, double>) {
    if (loop && loop->set) {
      friction_loop_implicit(phi, *loop, solve, N, Mf, F, iterations);
      return Status::Ok();
    }
  }
  Mf->fill(T(0));
  std::array<Vec2<T>, kJoints> F0;
  solve(std::array<T, kJoints>{}, &F0);
  // the response per torque expanded from the low-rank form where a path needs it
  ReactionResponse<T> expanded;
  const auto full_response = [&]() -> const ReactionResponse<T>* {
    if (aids.low_rank) {
      expanded = aids.low_rank->expand();
    } else if (aids.coupler) {
      expanded = aids.coupler->expand();
    } else {
      return nullptr;
    }
    return &expanded;
  };
  // the unscaled map only where it is needed (the Newton fallback, the solution recorded for the
  // Jet pass)
  AffineReactions<T> map;
  bool have_map = false;
  const auto affine = [&]() -> const AffineReactions<T>& {
    if (!have_map) map = probe_reactions(phi, solve, F0, full_response());
    have_map = true;
    return map;
  };
  FrictionWarmStart* warm = std::is_same_v<T, double> ? aids.warm : nullptr;
  std::array<T, kJoints> N0;  // |F0|
  reaction_norms(F0, &N0);
  bool reduced = false;  // solved on a reduced map (ReducedMap)
  if constexpr (std::is_same_v<T, double>) {
    if (aids.low_rank) {
      reduced = reduced_friction_loop(ReducedReactions(phi, F0, *aids.low_rank), opt, N0, warm, N,
                                      Mf, F, iterations);
    } else if (aids.coupler) {
      reduced = reduced_friction_loop(CouplerReactions(phi, F0, *aids.coupler), opt, N0, warm, N,
                                      Mf, F, iterations);
    }
  }
  if (!reduced) {
    const ScaledReactions<T> scaled = aids.low_rank
                                          ? ScaledReactions<T>(phi, F0, *aids.low_rank)
                                          : ScaledReactions<T>(phi, affine());
    const Status st =
        scaled_friction_loop(phi, opt, solve, scaled, affine, warm, N, Mf, F, iterations);
    if (!st.ok()) {
      if (warm) warm->set = false;
      return st;
    }
  }
  if (warm) {
    warm->set = true;
    for (int j = 0; j < kJoints; ++j) {
      warm->N[j] = value_of((*N)[j]);
      warm->N0[j] = value_of(N0[j]);
    }
  }
  if constexpr (std::is_same_v<T, double>) {
    if (loop) *loop = LoopSolution{true, *N, affine(), *iterations};
  }
  return Status::Ok();
}

}  // namespace detail

/// Resolution of the reaction/friction loop (section 4, steps 1-4, at every call): a fixed point
/// on N, which contracts when r_k |f_k| is small against the geometry; where it stops
/// contracting, Newton; where the map does not contract everywhere, an error when another
/// consistent N is found (friction_unique: the loop never chooses between solutions).
/// `solve(Mf, F)` evaluates the reactions for friction torques Mf; phi_k = r_k f_k(w_k) is fixed.
/// `extra` (may be null) adds load-independent torques (the actuators' friction, actuator.h):
/// Mf_k = phi_k N_k + extra_k. The caller solves once more with the returned Mf. `loop`: see
/// joint_friction_loop (the implicit derivative).
/// `aids`: the reactions' response to the torques, known in closed form (no probes), and a warm
/// start; neither changes the solution.
template <typename T, typename Solve>
Status friction_loop(const std::array<T, kJoints>& phi, const EvalOptions& opt, Solve&& solve,
                     std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                     std::array<Vec2<T>, kJoints>* F, int* iterations,
                     const std::array<T, kJoints>* extra = nullptr,
                     detail::LoopSolution* loop = nullptr, const LoopAids<T>& aids = {}) {
  if (!extra) {
    return detail::joint_friction_loop(phi, opt, solve, N, Mf, F, iterations, loop, aids);
  }
  auto shifted = [&](const std::array<T, kJoints>& M, std::array<Vec2<T>, kJoints>* out) {
    std::array<T, kJoints> all = M;
    for (int j = 0; j < kJoints; ++j) all[j] += (*extra)[j];
    solve(all, out);
  };
  const Status st =
      detail::joint_friction_loop(phi, opt, shifted, N, Mf, F, iterations, loop, aids);
  for (int j = 0; j < kJoints; ++j) (*Mf)[j] += (*extra)[j];
  return st;
}

}  // namespace fivebar
