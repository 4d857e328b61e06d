// Gauss-Legendre quadrature.
#pragma once

#include <vector>

namespace fivebar::trajectory {

/// Nodes and weights of the n-point Gauss-Legendre rule on [a, b]: exact for polynomials of
/// degree 2 n - 1. Nodes are increasing. Requires n >= 1.
struct Rule {
  std::vector<double> nodes, weights;
};
Rule gauss_legendre(int n, double a, double b);

}  // namespace fivebar::trajectory
