// Clamped B-splines of degree 5 on a uniform knot vector over [0, T], and the rest-to-rest
// parameterization of a joint motion by them (ends fixed with zero rate and acceleration).
#pragma once

#include <array>
#include <functional>
#include <vector>

namespace fivebar::trajectory {

/// Degree of every trajectory spline (quintic: continuous acceleration and jerk).
inline constexpr int kDegree = 5;

/// Values and first two time derivatives of the kDegree + 1 basis functions that are non-zero
/// at one instant; basis function `first + j` has value d[0][j], rate d[1][j], acceleration
/// d[2][j].
struct BasisAt {
  int first = 0;
  std::array<std::array<double, kDegree + 1>, 3> d{};
};

/// Clamped uniform B-spline basis of degree 5 with `n` control points over [0, duration]:
/// knots 0 (6 times), duration * i / (n - 5) for i = 1..n-6, duration (6 times); n - 5 knot
/// spans. Requires n >= 6 and duration > 0.
class ClampedBasis {
 public:
  ClampedBasis(int control_points, double duration);

  int size() const { return n_; }
  double duration() const { return duration_; }
  int spans() const { return n_ - kDegree; }
  /// Start and end time of knot span s (0-based, s < spans()).
  double span_begin(int s) const { return knots_[kDegree + s]; }
  double span_end(int s) const { return knots_[kDegree + s + 1]; }

  /// Non-zero basis functions and their derivatives [1/s, 1/s^2] at t in [0, duration].
  BasisAt at(double t) const;

 private:
  int n_;
  double duration_;
  std::vector<double> knots_;
};

/// What a rest-to-rest spline does at its ends besides resting (zero rate): kFree leaves the
/// acceleration free (two fixed control points per end), kZero makes it zero too (three).
enum class EndAcceleration : int { kFree = 0, kZero = 1 };

/// A rest-to-rest motion of n joints (the five-bar's th1, th2; the four-bar's th1) from `start`
/// to `goal` [rad] in `duration` [s]: each angle is a clamped quintic B-spline whose first
/// `fixed()` control points equal the start and last `fixed()` equal the goal: two make the rate
/// zero at both ends, three (kZero) the acceleration too. The free variables are the
/// n - 2 fixed() inner control points of joint 0, followed by those of joint 1, ...
/// Instantiated for n = 1 and 2 (bspline.cc).
template <int n>
class RestToRestT {
 public:
  using Angles = std::array<double, n>;
  RestToRestT(int control_points, double duration, Angles start, Angles goal,
              EndAcceleration ends = EndAcceleration::kZero);

  const ClampedBasis& basis() const { return basis_; }
  EndAcceleration ends() const { return ends_; }
  /// control points fixed at each end (2 or 3)
  int fixed() const { return ends_ == EndAcceleration::kZero ? 3 : 2; }
  int free_per_joint() const { return basis_.size() - 2 * fixed(); }
  int num_variables() const { return n * free_per_joint(); }
  const Angles& start() const { return start_; }
  const Angles& goal() const { return goal_; }
  double duration() const { return basis_.duration(); }

  /// All control points of joint j (0-based) for the free variables x.
  std::vector<double> control_points(const double* x, int j) const;
  /// Index of the control point that variable `v` of a joint moves (fixed() .. n - 1 - fixed()).
  int control_index(int v) const { return v + fixed(); }
  /// The free variable of control point c of joint j, or -1 for a fixed end point.
  int variable_of(int c, int j) const {
    const int f = fixed();
    return c < f || c > basis_.size() - 1 - f ? -1 : j * free_per_joint() + c - f;
  }
  /// Control point c of joint j for the free variables x (start or goal at the ends).
  double control_point(const double* x, int c, int j) const {
    const int v = variable_of(c, j);
    return v >= 0 ? x[v] : (c < fixed() ? start_[j] : goal_[j]);
  }

  /// (th, thd, thdd) of every joint at time t: out[0] angles, out[1] rates, out[2]
  /// accelerations.
  std::array<Angles, 3> state(const double* x, double t) const;

  /// The free variables that reproduce the minimum-jerk quintic
  /// th(t) = start + (goal - start) (10 s^3 - 15 s^4 + 6 s^5), s = t / duration. The spline space
  /// contains every quintic polynomial, so the fit (least squares on 8 n samples) is exact up to
  /// rounding.
  std::vector<double> minimum_jerk() const;

  /// The free variables whose spline is the least-squares fit (8 n samples in time) of the
  /// joint path `path(t)`, t in [0, duration]. The ends stay at rest at start and goal whatever
  /// the path does there.
  std::vector<double> fit(const std::function<Angles(double)>& path) const;

 private:
  ClampedBasis basis_;
  Angles start_, goal_;
  EndAcceleration ends_;
};

extern template class RestToRestT<1>;
extern template class RestToRestT<2>;
/// The five-bar's motion of (th1, th2).
using RestToRest = RestToRestT<2>;

/// Minimum-jerk quintic blend s(u) = 10 u^3 - 15 u^4 + 6 u^5 and its first two derivatives in u.
std::array<double, 3> minimum_jerk_blend(double u);

}  // namespace fivebar::trajectory
