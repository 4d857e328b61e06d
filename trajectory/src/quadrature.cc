#include "fivebar/trajectory/quadrature.h"

#include <cmath>
#include <stdexcept>

namespace fivebar::trajectory {

Rule gauss_legendre(int n, double a, double b) {
  if (n < 1) throw std::invalid_argument("gauss_legendre: n < 1");
  Rule rule;
  rule.nodes.resize(n);
  rule.weights.resize(n);
  const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    // Newton on P_n from the Chebyshev-like first guess of root i (descending in x)
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = x;  // P_0, P_1; recurrence up to P_n
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      if (n == 1) p0 = 1.0;
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    const double w = 2.0 / ((1.0 - x * x) * dp * dp);
    rule.nodes[i] = mid - half * x;
    rule.nodes[n - 1 - i] = mid + half * x;
    rule.weights[i] = rule.weights[n - 1 - i] = half * w;
  }
  return rule;
}

}  // namespace fivebar::trajectory
