// Numbers as text for the libraries' messages and files (libraries never print; the apps have
// their own writers in apps/src/format.cc and use these two as well).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace fivebar {

/// `x` with `digits` significant digits, as printf's %g ("0.000123", "1.5e+03", "nan").
inline std::string format_significant(double x, int digits) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
  return buf;
}

/// Shortest %g text that reads back as exactly x; "nan", "inf", "-inf" for non-finite values.
inline std::string format_number(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[32];
  for (int prec = 1; prec <= 17; ++prec) {
    std::snprintf(buf, sizeof buf, "%.*g", prec, x);
    if (std::strtod(buf, nullptr) == x) break;
  }
  return buf;
}

}  // namespace fivebar
