// Numbers as text for the libraries' messages and files (libraries never print; the apps have
// their own writers in apps/src/format.cc and use these two as well).
#pragma once

#include <charconv>
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

/// Shortest text that reads back as exactly x (std::to_chars: "0.3", "1e-05", "100000");
/// "nan", "inf", "-inf" for non-finite values. The files' number format.
inline std::string format_shortest(double x) {
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

}  // namespace fivebar
