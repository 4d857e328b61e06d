// Numbers as text, the one place for the whole toolkit (model, identification, trajectory, apps
// and python): format_shortest for numbers that are read back (files), format_significant for
// numbers a person reads (messages, notes, figure scripts). Libraries never print; apps/src/
// format.cc adds the apps' table and grid forms on top of these two.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>

namespace fivebar {

/// `x` with `digits` significant digits, as printf's %g ("0.000123", "1.5e+03", "inf"): the
/// numbers of messages and notes (3 digits unless the message needs more). Every NaN is "nan"
/// (printf writes "-nan" for the NaN that x86 arithmetic such as inf - inf makes).
inline std::string format_significant(double x, int digits = 3) {
  if (std::isnan(x)) return "nan";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
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
