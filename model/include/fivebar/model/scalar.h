// Scalar helpers shared by the templated model: value parts of Jets, small vector types.
#pragma once

#include <cmath>
#include <type_traits>

#include <Eigen/Core>

namespace fivebar {

/// Degrees of freedom of the five-bar: the two crank angles (th1, th2).
inline constexpr int kDof = 2;

template <typename T>
using Vec2 = Eigen::Matrix<T, 2, 1>;
template <typename T>
using Row2 = Eigen::Matrix<T, 1, 2>;
template <typename T>
using Mat2 = Eigen::Matrix<T, 2, 2>;

/// Value part of a scalar: the number itself for double, the real part of a ceres::Jet (also
/// nested). Stopping tests and branch choices look at this only, never at derivatives.
inline double value_of(double x) { return x; }
template <typename J>
auto value_of(const J& x) -> decltype(value_of(x.a)) {
  return value_of(x.a);
}

/// Determinant and inverse of a 2x2 matrix in closed form (no Eigen/LU needed, Jet-friendly).
template <typename T>
T det2(const Mat2<T>& m) {
  return m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
}
template <typename T>
Mat2<T> inverse2(const Mat2<T>& m) {
  const T inv_det = T(1) / det2(m);
  Mat2<T> out;
  out << m(1, 1) * inv_det, -m(0, 1) * inv_det, -m(1, 0) * inv_det, m(0, 0) * inv_det;
  return out;
}

/// *x += c y for a double c. For a Jet: its value and each derivative in turn, the same products
/// and sums as *x += c * y, in scalars (the compiler may leave Eigen's sum of two derivative
/// vectors a call, which in a hot loop costs more than the sum).
inline void add_scaled(double* x, double c, double y) { *x += c * y; }
template <typename J>
auto add_scaled(J* x, double c, const J& y) -> decltype(x->v[0], void()) {
  add_scaled(&x->a, c, y.a);
  for (int i = 0; i < x->v.size(); ++i) add_scaled(&x->v[i], c, y.v[i]);
}

/// Exact zero including derivative parts: a term is skipped only if it cannot contribute.
inline bool is_exact_zero(double x) { return x == 0.0; }
template <typename J>
auto is_exact_zero(const J& x) -> decltype(x.v.isZero(), bool()) {
  return is_exact_zero(x.a) && x.v.isZero();
}

/// Planar unit vector e(a) = (cos a, sin a) and its derivative e'(a) = (-sin a, cos a).
template <typename T>
Vec2<T> unit(const T& a) {
  using std::cos;
  using std::sin;
  return Vec2<T>(cos(a), sin(a));
}
template <typename T>
Vec2<T> perp(const Vec2<T>& v) {
  return Vec2<T>(-v.y(), v.x());
}

/// Planar cross product a x b = ax*by - ay*bx.
template <typename T>
T cross(const Vec2<T>& a, const Vec2<T>& b) {
  return a.x() * b.y() - a.y() * b.x();
}

/// Rotates v by the angle whose cosine and sine are c, s.
template <typename T>
Vec2<T> rotate(const Vec2<T>& v, const T& c, const T& s) {
  return Vec2<T>(c * v.x() - s * v.y(), s * v.x() + c * v.y());
}

}  // namespace fivebar
