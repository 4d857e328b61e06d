#include "fivebar/trajectory/sweep.h"

#include <cmath>
#include <cstdlib>

namespace fivebar::trajectory {
namespace {

bool to_double(const std::string& s, double* v) {
  if (s.empty()) return false;
  char* end = nullptr;
  *v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(*v);
}

}  // namespace

Sweep parse_sweep(const std::string& text) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw std::invalid_argument("expected KEY=LO:HI:N, got '" + text + "'");
  }
  Sweep s;
  s.key = text.substr(0, eq);
  const std::string range = text.substr(eq + 1);
  const size_t c1 = range.find(':');
  const size_t c2 = c1 == std::string::npos ? c1 : range.find(':', c1 + 1);
  if (c2 == std::string::npos || range.find(':', c2 + 1) != std::string::npos) {
    throw std::invalid_argument("expected LO:HI:N after '" + s.key + "=', got '" + range + "'");
  }
  if (!to_double(range.substr(0, c1), &s.lo)) {
    throw std::invalid_argument("LO '" + range.substr(0, c1) + "' is not a finite number");
  }
  if (!to_double(range.substr(c1 + 1, c2 - c1 - 1), &s.hi)) {
    throw std::invalid_argument("HI '" + range.substr(c1 + 1, c2 - c1 - 1) +
                                "' is not a finite number");
  }
  const std::string ns = range.substr(c2 + 1);
  char* end = nullptr;
  const long n = std::strtol(ns.c_str(), &end, 10);
  if (ns.empty() || end != ns.c_str() + ns.size() || n < 1 || n > 100000) {
    throw std::invalid_argument("N '" + ns + "' is not an integer in [1, 100000]");
  }
  s.n = static_cast<int>(n);
  if (s.lo > s.hi) throw std::invalid_argument("LO > HI");
  if (s.n > 1 && s.lo == s.hi) throw std::invalid_argument("N > 1 with LO == HI");
  return s;
}

int design_count(const std::vector<Sweep>& sweeps) {
  long long n = 1;
  for (const Sweep& s : sweeps) n *= s.n;
  if (n > 1000000) throw std::invalid_argument("more than 1e6 designs");
  return static_cast<int>(n);
}

std::vector<double> design_values(const std::vector<Sweep>& sweeps, int design) {
  std::vector<double> v(sweeps.size());
  for (int k = static_cast<int>(sweeps.size()) - 1; k >= 0; --k) {
    v[k] = sweeps[k].value(design % sweeps[k].n);
    design /= sweeps[k].n;
  }
  return v;
}

}  // namespace fivebar::trajectory
