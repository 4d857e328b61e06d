// Rest and holding: when is a joint at rest in inverse dynamics, what torques hold a
// pose, and over which range of M1, M2 static friction holds it.
//
// The rule. A joint whose |w_k| is at most a rate threshold is at rest, not slipping: sign(w_k)
// of a rate that is noise would pick a full kinetic friction torque in a random direction. A
// joint at rest whose relative acceleration is also within an acceleration threshold is stuck:
// its friction torque is static, anywhere in [-mu_s r_k N_k, mu_s r_k N_k]. Inverse dynamics
// then reports the torques with no friction torque at the stuck joints (the motors carry the
// load: at a pose at rest, the frictionless equilibrium) and, per stuck joint, the margin
// mu_s r_k N_k that friction could add. A joint at rest that accelerates starts to slip in the
// direction of its acceleration (model.md, sign(0)). EvalOptions::rest_rate and
// rest_acceleration switch the rule on; sim::inverse_rows applies it with RestThresholds.
//
// The range. Whole mechanism at rest: the five friction torques are statically indeterminate;
// the pose holds while some friction torques within the static bounds carry the torques'
// excess over the equilibrium (lock.h, the simulator's lock). Holding reports, for each
// actuator with the other at its equilibrium value, the range over which that holds (what
// forward simulation honours: inside it the mechanism stays locked, outside it breaks away);
// holding_polygon the whole region over (M1, M2). A crank stuck alone (the other one moving)
// holds exactly M +- mu_s r N of its joint: the reactions do not depend on its friction torque.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/lock.h"
#include "fivebar/model/rest_rule.h"

namespace fivebar {

/// EvalOptions with the rest rule switched on.
inline EvalOptions with_rest(EvalOptions opt, const RestThresholds& rest) {
  opt.rest_rate = rest.rate;
  opt.rest_acceleration = rest.acceleration;
  return opt;
}

/// The rest rule at one state (th, thd, thdd of the cranks): which joints are stuck, i.e. have
/// |w_k| <= rest.rate and |dw_k/dt| <= rest.acceleration. Fails like the kinematics.
inline Status stuck_joints(const Params<double>& p, double th1, double th2, double w1, double w2,
                           double a1, double a2, const RestThresholds& rest,
                           std::array<bool, kJoints>* stuck) {
  Kinematics<double> k;
  const Status st = solve_kinematics(p, th1, th2, &k);
  if (!st.ok()) return st;
  Bias<double> b;
  compute_bias(p, k, w1, w2, &b);
  const Vec2<double> thdd(a1, a2);
  const auto w = relative_rates(w1, w2, b.w3, b.w4);
  const auto wdot = relative_accelerations(thdd, k.G3.dot(thdd) + b.h3,
                                                   k.G4.dot(thdd) + b.h4);
  for (int j = 0; j < kJoints; ++j) {
    (*stuck)[j] = std::abs(w[j]) <= rest.rate && std::abs(wdot[j]) <= rest.acceleration;
  }
  return Status::Ok();
}

/// Holding torques of a pose at rest (w = dw/dt = 0 at every joint).
template <typename T>
struct Holding {
  /// frictionless equilibrium [N m]: the torques that hold the pose with no friction torque at
  /// any joint; friction can supply the rest of any torque within the range below
  T M1{}, M2{};
  std::array<T, kJoints> N{};      ///< joint reactions at that equilibrium [N] (O, B, C, D, D0)
  /// mu_s,k r_k N_k [N m], plus the actuator's Coulomb c_a at O, D0 (0 without friction)
  std::array<T, kJoints> bound{};
  /// the range of each actuator, the other at its equilibrium value, over which static friction
  /// holds the pose [N m]: friction at all five joints, as the simulator's lock (lock.h) decides
  /// it (double); for other scalars the sub-range M_eq +- bound that the crank joint O (D0) holds
  /// alone
  T M1_min{}, M1_max{}, M2_min{}, M2_max{};
};

namespace detail {

/// How far actuator `i` (0: M1, 1: M2) can move from the equilibrium h in direction `sign`
/// before the locked mechanism breaks away (lock_extent of lock.h), the other at its equilibrium.
inline Status lock_extent(const Params<double>& p, Loads<double> L, double th1, double th2,
                          const EvalOptions& opt, const Holding<double>& h, int i, double sign,
                          double* d) {
  L.M1 = h.M1;
  L.M2 = h.M2;
  const double start =
      std::max(h.bound[i == 0 ? 0 : 4], 1e-12 * (1.0 + std::abs(i == 0 ? h.M1 : h.M2)));
  return fivebar::lock_extent<FiveBar>(
      p, L, Vec2<double>(th1, th2), opt, i == 0 ? h.M1 : h.M2, sign, start,
      [i](Loads<double>* l, double v) { (i == 0 ? l->M1 : l->M2) = v; }, d);
}

}  // namespace detail

/// Frictionless equilibrium and holding range at (th1, th2) under loads L (M1, M2 ignored).
/// Fails like the kinematics: kCannotAssemble, kNearSingular (opt.singular_margin).
template <typename T>
Status holding_torques(const Params<T>& p, const Loads<T>& L, const T& th1, const T& th2,
                       const EvalOptions& opt, Holding<T>* h) {
  const EvalOptions still = with_rest(opt, RestThresholds{0.0, 0.0});
  Evaluation<T> ev;
  const T zero(0);
  Status st = inverse_dynamics(p, L, th1, th2, zero, zero, zero, zero, nullptr, still, &ev);
  if (!st.ok()) return st;
  h->M1 = ev.M1;
  h->M2 = ev.M2;
  h->N = ev.N;
  for (int j = 0; j < kJoints; ++j) {
    h->bound[j] = p.friction.active() ? T(holding_capacity(p, j, ev.N[j])) : zero;
  }
  T ext[4] = {h->bound[0], h->bound[0], h->bound[4], h->bound[4]};  // lower M1, upper M1, ...
  if constexpr (std::is_same_v<T, double>) {
    if (p.friction.active()) {
      for (int e = 0; e < 4; ++e) {
        st = detail::lock_extent(p, L, th1, th2, opt, *h, e / 2, e % 2 ? 1.0 : -1.0, &ext[e]);
        if (!st.ok()) return st;
      }
    }
  }
  h->M1_min = h->M1 - ext[0];
  h->M1_max = h->M1 + ext[1];
  h->M2_min = h->M2 - ext[2];
  h->M2_max = h->M2 + ext[3];
  return Status::Ok();
}

/// The torques (M1, M2) for which some friction torques with |Mf_k| <= mu_s,k r_k N_k at all
/// five joints hold the pose: (M1, M2) = (M1_eq, M2_eq) + J_w^T Mf (virtual work at rest), with
/// N_k the reactions of those friction torques. Vertices: each of the 32 sign patterns
/// Mf_k = +-mu_s,k r_k N_k, its reactions made consistent by the reaction/friction loop; the
/// polygon is their convex hull, counter-clockwise (exact at the vertices; between them the
/// reactions vary with the inner friction torques by O(mu r / l), and the edges are straight to
/// that order). A superset of the crank rectangle of Holding: the inner joints help hold.
struct HoldingPolygon {
  std::vector<std::array<double, 2>> vertices;  ///< (M1, M2) [N m]
  /// slices through the equilibrium: M1 range at M2 = M2_eq, M2 range at M1 = M1_eq [N m]
  double M1_min = 0, M1_max = 0, M2_min = 0, M2_max = 0;
};

namespace detail {

/// Convex hull (Andrew's monotone chain), counter-clockwise, no repeated points.
inline std::vector<std::array<double, 2>> convex_hull(std::vector<std::array<double, 2>> pts) {
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  if (pts.size() < 3) return pts;
  auto turn = [](const std::array<double, 2>& o, const std::array<double, 2>& a,
                 const std::array<double, 2>& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::vector<std::array<double, 2>> hull(2 * pts.size());
  size_t n = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (n >= 2 && turn(hull[n - 2], hull[n - 1], pts[i]) <= 0) --n;
    hull[n++] = pts[i];
  }
  for (size_t i = pts.size() - 1, lower = n + 1; i-- > 0;) {
    while (n >= lower && turn(hull[n - 2], hull[n - 1], pts[i]) <= 0) --n;
    hull[n++] = pts[i];
  }
  hull.resize(n - 1);
  return hull;
}

/// Range of coordinate `axis` over the polygon's intersection with the line where the other
/// coordinate equals `at` (the polygon contains a point of that line). Vertices count too.
inline void polygon_slice(const std::vector<std::array<double, 2>>& poly, int axis, double at,
                          double* lo, double* hi) {
  const int other = 1 - axis;
  *lo = INFINITY;
  *hi = -INFINITY;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    if (a[other] == at) {
      *lo = std::min(*lo, a[axis]);
      *hi = std::max(*hi, a[axis]);
    }
    if ((a[other] - at) * (b[other] - at) < 0) {
      const double s = (at - a[other]) / (b[other] - a[other]);
      const double x = a[axis] + s * (b[axis] - a[axis]);
      *lo = std::min(*lo, x);
      *hi = std::max(*hi, x);
    }
  }
}

}  // namespace detail

/// The polygon of HoldingPolygon at (th1, th2) under loads L, from its equilibrium `h`.
/// Compiled in fivebar::sim (model/src/double_instances.cc).
Status holding_polygon(const Params<double>& p, const Loads<double>& L, double th1, double th2,
                       const EvalOptions& opt, const Holding<double>& h, HoldingPolygon* out);

#ifdef FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM
// The command-line layer (apps/, at -O1) takes these double instances from fivebar::sim
// (model/src/double_instances.cc) rather than compiling -O1 copies the linker could keep in
// place of the libraries' optimized ones.
extern template Status holding_torques<double>(const Params<double>&, const Loads<double>&,
                                               const double&, const double&, const EvalOptions&,
                                               Holding<double>*);
#endif

}  // namespace fivebar
