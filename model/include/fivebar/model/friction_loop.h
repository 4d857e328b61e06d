// The reaction/friction loop (model.md section 4): friction torques Mf_k = phi_k N_k that are
// consistent with the reactions N_k they produce. The reactions are affine in the friction
// torques, so the loop probes that map once and iterates on it; three outcomes: a contracting
// fixed point, a Newton solution where it stops contracting, or an error naming why none exists.
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
#include "fivebar/model/scalar.h"
#include "fivebar/model/status.h"

namespace fivebar {

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

/// Probes `solve(Mf, F)` at Mf = 0 and at a unit torque per active joint.
template <typename T, typename Solve>
AffineReactions<T> probe_reactions(const std::array<T, kJoints>& phi, Solve& solve) {
  AffineReactions<T> map;
  const std::array<T, kJoints> zero{};
  solve(zero, &map.F0);
  for (int j = 0; j < kJoints; ++j) {
    map.active[j] = !is_exact_zero(phi[j]);
    if (!map.active[j]) {
      for (auto& v : map.dF[j]) v.setZero();
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

/// Fixed-point iteration N <- |F(phi N)| from N = |F0|. True when it converged (N, Mf, F
/// consistent); otherwise *contracting tells whether it was still contracting, *ratio the last
/// ratio of successive changes.
template <typename T>
bool friction_fixed_point(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                          const AffineReactions<T>& map, std::array<T, kJoints>* N,
                          std::array<T, kJoints>* Mf, std::array<Vec2<T>, kJoints>* F,
                          int* iterations, bool* contracting, double* ratio) {
  reaction_norms(map.F0, N);
  double prev_err = 0.0;
  *contracting = true;
  *ratio = 0.0;
  for (int it = 1; it <= opt.friction_max_iter; ++it) {
    for (int j = 0; j < kJoints; ++j) (*Mf)[j] = phi[j] * (*N)[j];
    const std::array<T, kJoints> N_old = *N;
    map(*Mf, F);
    reaction_norms(*F, N);
    double err = 0.0, scale = 1e-300;
    for (int j = 0; j < kJoints; ++j) {
      err = std::max(err, std::abs(value_of((*N)[j]) - value_of(N_old[j])));
      scale = std::max(scale, std::abs(value_of((*N)[j])));
    }
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

/// Newton on the same affine map from two starts (|F0| and a large one): the unique consistent
/// N, or an error saying that there is none or more than one.
template <typename T>
Status friction_newton_fallback(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                                const AffineReactions<T>& map, bool contracting, double ratio,
                                std::array<T, kJoints>* N) {
  std::array<T, kJoints> N0, Na, Nb;
  reaction_norms(map.F0, &N0);
  const bool a = friction_newton(phi, opt, map, N0, &Na);
  std::array<T, kJoints> N_big = N0;
  for (auto& n : N_big) n = n * T(100) + T(1);
  const bool b = friction_newton(phi, opt, map, N_big, &Nb);
  std::ostringstream msg;
  msg << "friction loop: fixed point " << (contracting ? "did not converge" : "does not contract")
      << " (ratio " << ratio << "); ";
  if (!a && !b) {
    msg << "Newton finds no consistent reaction forces: r_k * mu too large for the loads "
           "(friction would lock the joints)";
    return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
  }
  if (a && b) {
    double diff = 0.0, scale = 1e-300;
    for (int j = 0; j < kJoints; ++j) {
      diff = std::max(diff, std::abs(value_of(Na[j]) - value_of(Nb[j])));
      scale = std::max(scale, std::abs(value_of(Na[j])));
    }
    if (diff > 1e-6 * scale) {
      msg << "several consistent reaction forces (max |N| " << scale << " N and differing by "
          << diff << " N): the motion is not unique (r_k * mu too large)";
      return Status::Error(StatusCode::kFrictionNotConverged, msg.str());
    }
  }
  *N = a ? Na : Nb;
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

/// Runs a dynamics pass with the friction loop's implicit derivative: for Jets with friction on
/// (and EvalOptions::implicit_loop_derivative), a double shadow pass first decides the joint
/// modes and solves the loop, then the Jet pass differentiates that solution; otherwise one pass.
/// `pass(params, loads, value, slip, ev, bristle, loop)` runs the pass on the state mapped by
/// `value` (value_of for the shadow, the identity for the pass itself).
template <typename T, typename Pass>
Status with_loop_shadow(const Params<T>& p, const Loads<T>& L, const JointModes* slip,
                        const EvalOptions& opt, Evaluation<T>* ev,
                        const std::array<T, kJoints>* bristle, const Pass& pass) {
  const auto same = [](const T& x) -> const T& { return x; };
  if constexpr (!std::is_same_v<T, double>) {
    if (p.friction.active() && opt.implicit_loop_derivative) {
      LoopSolution loop;
      Evaluation<double> vd;
      std::array<double, kJoints> zd;
      const auto values = [](const T& x) { return value_of(x); };
      const Status st = pass(p.template cast<double>(), L.template cast<double>(), values, slip,
                             &vd, array_values(bristle, &zd), &loop);
      if (!st.ok()) return st;
      return pass(p, L, same, &vd.slip, ev, bristle, &loop);
    }
  }
  return pass(p, L, same, slip, ev, bristle, static_cast<LoopSolution*>(nullptr));
}

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
    for (int k = 0; k < kJoints; ++k) (*F)[k] += sol.map.dF[j][k] * dM;
  }
  *iterations = sol.iterations;
}

/// The loop of friction_loop below for the load-dependent torques phi_k N_k alone. `loop`
/// (may be null): a double evaluation records its solution there; a Jet evaluation given a
/// recorded solution differentiates it (friction_loop_implicit) instead of iterating in Jets.
template <typename T, typename Solve>
Status joint_friction_loop(const std::array<T, kJoints>& phi, const EvalOptions& opt,
                           Solve&& solve, std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                           std::array<Vec2<T>, kJoints>* F, int* iterations,
                           LoopSolution* loop = nullptr) {
  if constexpr (!std::is_same_v<T, double>) {
    if (loop && loop->set) {
      friction_loop_implicit(phi, *loop, solve, N, Mf, F, iterations);
      return Status::Ok();
    }
  }
  Mf->fill(T(0));
  const AffineReactions<T> map = probe_reactions(phi, solve);
  bool contracting = true;
  double ratio = 0.0;
  if (!friction_fixed_point(phi, opt, map, N, Mf, F, iterations, &contracting, &ratio)) {
    const Status st = friction_newton_fallback(phi, opt, map, contracting, ratio, N);
    if (!st.ok()) return st;
    for (int j = 0; j < kJoints; ++j) (*Mf)[j] = phi[j] * (*N)[j];
    solve(*Mf, F);
    reaction_norms(*F, N);
    *iterations = opt.friction_max_iter + 1;  // marks a Newton solve
  }
  if constexpr (std::is_same_v<T, double>) {
    if (loop) *loop = LoopSolution{true, *N, map, *iterations};
  }
  return Status::Ok();
}

}  // namespace detail

/// Resolution of the reaction/friction loop (section 4, steps 1-4, at every call): a fixed point
/// on N, which contracts when r_k |f_k| is small against the geometry; where it stops
/// contracting, Newton from two starts. `solve(Mf, F)` evaluates the reactions for friction
/// torques Mf; phi_k = r_k f_k(w_k) is fixed. `extra` (may be null) adds load-independent
/// torques (the actuators' friction, actuator.h): Mf_k = phi_k N_k + extra_k. The caller solves
/// once more with the returned Mf. `loop`: see joint_friction_loop (the implicit derivative).
template <typename T, typename Solve>
Status friction_loop(const std::array<T, kJoints>& phi, const EvalOptions& opt, Solve&& solve,
                     std::array<T, kJoints>* N, std::array<T, kJoints>* Mf,
                     std::array<Vec2<T>, kJoints>* F, int* iterations,
                     const std::array<T, kJoints>* extra = nullptr,
                     detail::LoopSolution* loop = nullptr) {
  if (!extra) return detail::joint_friction_loop(phi, opt, solve, N, Mf, F, iterations, loop);
  auto shifted = [&](const std::array<T, kJoints>& M, std::array<Vec2<T>, kJoints>* out) {
    std::array<T, kJoints> all = M;
    for (int j = 0; j < kJoints; ++j) all[j] += (*extra)[j];
    solve(all, out);
  };
  const Status st = detail::joint_friction_loop(phi, opt, shifted, N, Mf, F, iterations, loop);
  for (int j = 0; j < kJoints; ++j) (*Mf)[j] += (*extra)[j];
  return st;
}

}  // namespace fivebar
