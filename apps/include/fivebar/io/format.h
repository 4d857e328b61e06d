// Text helpers shared by the writers and readers of the apps layer.
#pragma once

#include <string>

namespace fivebar::io {

/// Shortest text that reads back as exactly `x` ("0.29", "1e-10", "1.5707963267948966");
/// "nan", "inf", "-inf" for non-finite values.
std::string format_double(double x);

/// `s` without leading and trailing blanks (space, tab, CR, LF).
std::string trim(const std::string& s);

}  // namespace fivebar::io
