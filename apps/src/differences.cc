#include "fivebar/io/differences.h"

#include <cmath>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"

namespace fivebar::io {

std::vector<double> first_derivative(const std::vector<double>& f, double h) {
  const size_t n = f.size();
  std::vector<double> d(n, 0.0);
  if (n < 5) return d;
  const double s = 1.0 / (12 * h);
  // one-sided at the start and (mirrored, sign flipped) at the end
  d[0] = (-25 * f[0] + 48 * f[1] - 36 * f[2] + 16 * f[3] - 3 * f[4]) * s;
  d[1] = (-3 * f[0] - 10 * f[1] + 18 * f[2] - 6 * f[3] + f[4]) * s;
  for (size_t i = 2; i + 2 < n; ++i) d[i] = (f[i - 2] - 8 * f[i - 1] + 8 * f[i + 1] - f[i + 2]) * s;
  d[n - 2] = (3 * f[n - 1] + 10 * f[n - 2] - 18 * f[n - 3] + 6 * f[n - 4] - f[n - 5]) * s;
  d[n - 1] = (25 * f[n - 1] - 48 * f[n - 2] + 36 * f[n - 3] - 16 * f[n - 4] + 3 * f[n - 5]) * s;
  return d;
}

std::vector<double> second_derivative(const std::vector<double>& f, double h) {
  const size_t n = f.size();
  std::vector<double> d(n, 0.0);
  if (n < 5) return d;
  const double s = 1.0 / (12 * h * h);
  // one-sided at the start and (mirrored) at the end
  d[0] = (35 * f[0] - 104 * f[1] + 114 * f[2] - 56 * f[3] + 11 * f[4]) * s;
  d[1] = (11 * f[0] - 20 * f[1] + 6 * f[2] + 4 * f[3] - f[4]) * s;
  for (size_t i = 2; i + 2 < n; ++i) {
    d[i] = (-f[i - 2] + 16 * f[i - 1] - 30 * f[i] + 16 * f[i + 1] - f[i + 2]) * s;
  }
  d[n - 2] = (11 * f[n - 1] - 20 * f[n - 2] + 6 * f[n - 3] + 4 * f[n - 4] - f[n - 5]) * s;
  d[n - 1] = (35 * f[n - 1] - 104 * f[n - 2] + 114 * f[n - 3] - 56 * f[n - 4] + 11 * f[n - 5]) * s;
  return d;
}

double uniform_step(const std::vector<double>& t, const std::vector<int>& lines,
                    const std::string& file) {
  if (t.size() < 2) return 0;
  const double h = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  // relative tolerance on each step: loose enough for times printed with a few digits
  constexpr double kRelTol = 1e-6;
  for (size_t i = 1; i < t.size(); ++i) {
    const double step = t[i] - t[i - 1];
    if (std::fabs(step - h) > kRelTol * h) {
      throw InputError(file, "line " + std::to_string(lines.at(i)) + ", column t",
                       "the time grid is not uniform (step " + format_double(step) +
                           " s here, mean " + format_double(h) +
                           " s); estimating rates by finite differences needs a uniform grid");
    }
  }
  return h;
}

}  // namespace fivebar::io
