#include "fivebar/io/format.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "fivebar/model/format.h"

namespace fivebar::io {

std::string format_double(double x) { return format_shortest(x); }

std::string format_grid_value(double x) {
  if (!std::isfinite(x) || x == 0) return format_double(x);
  // one unit in the last place of x: the rounding error of one multiplication such as i * h
  const double ulp = std::nextafter(std::fabs(x), std::numeric_limits<double>::infinity()) -
                     std::fabs(x);
  char buf[40];
  for (int digits = 1; digits <= 15; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    const double back = std::strtod(buf, nullptr);
    if (std::fabs(back - x) <= ulp) return format_double(back);  // e.g. "0.476"
  }
  return format_double(x);
}

std::string format_printf(double x, const char* format) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string_view trimmed(std::string_view s) {
  const char* blanks = " \t\r\n";
  const auto first = s.find_first_not_of(blanks);
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(blanks) - first + 1);
}

std::string trim(const std::string& s) { return std::string(trimmed(s)); }

bool parse_finite(const std::string& text, double* v) {
  const std::string s = trim(text);
  if (s.empty()) return false;
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(x)) return false;
  *v = x;
  return true;
}

}  // namespace fivebar::io
