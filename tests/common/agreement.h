// Measures of agreement between two formulations, and the figure format of RecordProperty.
#pragma once

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

namespace fivebar::testing {

/// x in scientific notation with 3 digits (RecordProperty figures).
inline std::string sci(double x) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(3) << x;
  return out.str();
}

/// max |a - b| / (1 + max |b|) over the first n entries of two ranges.
template <typename A, typename B>
double relative_error(const A& a, const B& b, int n) {
  double err = 0.0, scale = 0.0;
  for (int i = 0; i < n; ++i) {
    err = std::max(err, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return err / (1.0 + scale);
}

/// max component error of the first n reaction vectors F_k, relative to 1 + the largest |F|.
template <typename A, typename B>
double reaction_error(const A& a, const B& b, int n) {
  double err = 0.0, scale = 0.0;
  for (int i = 0; i < n; ++i) {
    err = std::max(err, (a[i] - b[i]).cwiseAbs().maxCoeff());
    scale = std::max(scale, b[i].norm());
  }
  return err / (1.0 + scale);
}

}  // namespace fivebar::testing
