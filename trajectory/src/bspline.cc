#include "fivebar/trajectory/bspline.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>

#include <Eigen/Dense>

#include "fivebar/model/scalar.h"

namespace fivebar::trajectory {

ClampedBasis::ClampedBasis(int control_points, double duration)
    : n_(control_points), duration_(duration) {
  if (n_ < kDegree + 1) throw std::invalid_argument("ClampedBasis: fewer than 6 control points");
  if (!(duration > 0.0)) throw std::invalid_argument("ClampedBasis: duration must be > 0");
  // clamped uniform knot vector of n + p + 1 knots
  knots_.assign(n_ + kDegree + 1, 0.0);
  const int spans = n_ - kDegree;
  for (int i = 1; i < spans; ++i) knots_[kDegree + i] = duration * i / spans;
  for (int i = n_; i < n_ + kDegree + 1; ++i) knots_[i] = duration;
}

BasisAt ClampedBasis::at(double t) const {
  constexpr int p = kDegree;
  t = std::clamp(t, 0.0, duration_);
  // knot span s with U[s] <= t < U[s+1], the last span closed at t = duration
  int s = static_cast<int>(std::upper_bound(knots_.begin() + p, knots_.begin() + n_, t) -
                           knots_.begin()) - 1;
  s = std::clamp(s, p, n_ - 1);
  const double* U = knots_.data();

  // basis functions and derivatives (Piegl & Tiller, The NURBS Book, algorithm A2.3)
  double ndu[p + 1][p + 1];
  double left[p + 1], right[p + 1];
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = t - U[s + 1 - j];
    right[j] = U[s + j] - t;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];  // lower triangle: knot differences
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;  // upper triangle: basis functions
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  BasisAt out;
  out.first = s - p;
  for (int j = 0; j <= p; ++j) out.d[0][j] = ndu[j][p];
  constexpr int nd = 2;
  double a[2][p + 1];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0, s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= nd; ++k) {
      double d = 0.0;
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = (r - 1 <= pk) ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        d += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        d += a[s2][k] * ndu[r][pk];
      }
      out.d[k][r] = d;
      std::swap(s1, s2);
    }
  }
  // multiply through by p (p - 1) ...
  double f = p;
  for (int k = 1; k <= nd; ++k) {
    for (int j = 0; j <= p; ++j) out.d[k][j] *= f;
    f *= (p - k);
  }
  return out;
}

template <int n>
RestToRestT<n>::RestToRestT(int control_points, double duration, Angles start, Angles goal,
                            EndAcceleration ends)
    : basis_(control_points, duration), start_(start), goal_(goal), ends_(ends) {
  if (control_points < 2 * fixed() + 1) {
    throw std::invalid_argument("RestToRest: too few control points for the fixed ends");
  }
}

template <int n>
std::vector<double> RestToRestT<n>::control_points(const double* x, int j) const {
  std::vector<double> c(basis_.size());
  for (int i = 0; i < basis_.size(); ++i) c[i] = control_point(x, i, j);
  return c;
}

template <int n>
std::array<std::array<double, n>, 3> RestToRestT<n>::state(const double* x, double t) const {
  const BasisAt b = basis_.at(t);
  std::array<Angles, 3> out{};
  for (int j = 0; j < n; ++j) {
    const std::vector<double> c = control_points(x, j);
    for (int k = 0; k < 3; ++k) {
      double s = 0.0;
      for (int i = 0; i <= kDegree; ++i) s += b.d[k][i] * c[b.first + i];
      out[k][j] = s;
    }
  }
  return out;
}

std::array<double, 3> minimum_jerk_blend(double u) {
  const double u2 = u * u, u3 = u2 * u;
  return {u3 * (10.0 - 15.0 * u + 6.0 * u2), 30.0 * u2 * (1.0 - 2.0 * u + u2),
          60.0 * u * (1.0 - 3.0 * u + 2.0 * u2)};
}

template <int n>
std::vector<double> RestToRestT<n>::fit(const std::function<Angles(double)>& path) const {
  // least squares for the inner control points on 8 n samples of each joint's path
  using RowN = Eigen::Matrix<double, 1, n>;
  const int nc = basis_.size(), nf = free_per_joint(), m = 8 * nc;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, nf);
  Eigen::MatrixXd rhs(m, n);
  const RowN start = Eigen::Map<const RowN>(start_.data());
  const RowN goal = Eigen::Map<const RowN>(goal_.data());
  for (int r = 0; r < m; ++r) {
    const double t = duration() * (r + 0.5) / m;
    const BasisAt b = basis_.at(t);
    const Angles q = path(t);
    for (int j = 0; j < n; ++j) rhs(r, j) = q[j];
    for (int i = 0; i <= kDegree; ++i) {
      const int c = b.first + i, v = variable_of(c, 0);
      if (v >= 0) {
        A(r, v) += b.d[0][i];
      } else if (c < fixed()) {
        rhs.row(r) -= b.d[0][i] * start;
      } else {
        rhs.row(r) -= b.d[0][i] * goal;
      }
    }
  }
  const Eigen::MatrixXd sol = A.colPivHouseholderQr().solve(rhs);
  std::vector<double> x(n * nf);
  for (int j = 0; j < n; ++j)
    for (int v = 0; v < nf; ++v) x[j * nf + v] = sol(v, j);
  return x;
}

template <int n>
std::vector<double> RestToRestT<n>::minimum_jerk() const {
  return fit([this](double t) {
    const double s = minimum_jerk_blend(t / duration())[0];
    Angles q;
    for (int j = 0; j < n; ++j) q[j] = start_[j] + (goal_[j] - start_[j]) * s;
    return q;
  });
}

template class RestToRestT<1>;
template class RestToRestT<2>;

}  // namespace fivebar::trajectory
