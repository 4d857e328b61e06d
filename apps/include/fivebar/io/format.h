// Text helpers shared by the writers and readers of the apps layer: every number the apps print
// goes through format_double or format_grid_value.
#pragma once

#include <string>
#include <string_view>

#include "fivebar/model/format.h"  // format_significant, format_number

namespace fivebar::io {

/// Shortest text that reads back as exactly `x` ("0.29", "1e-10", "1.5707963267948966");
/// "nan", "inf", "-inf" for non-finite values.
std::string format_double(double x);

/// For values that stand for a short decimal but carry the rounding of the arithmetic that made
/// them, such as output times i * h (476 * 0.001 = 0.47600000000000003) or sweep values: the
/// shortest decimal of at most 15 significant digits that reads back within one unit in the
/// last place of `x` ("0.476"); format_double(x) when there is none. Reading the text back may
/// therefore give x's neighbouring double: use format_double where exactness matters.
std::string format_grid_value(double x);

/// `x` through one printf conversion of a double, such as "%.3e" or "%.4f" (table columns and
/// reports with a fixed layout); format_significant(x, digits) for "%.<digits>g".
std::string format_printf(double x, const char* format);

/// `s` without leading and trailing blanks (space, tab, CR, LF).
std::string trim(const std::string& s);
/// The same as a view into `s` (no copy).
std::string_view trimmed(std::string_view s);

/// The whole of `text` (blanks trimmed) as a finite number: true and *v set, else false.
bool parse_finite(const std::string& text, double* v);

}  // namespace fivebar::io
