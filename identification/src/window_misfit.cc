// Telling a misfit of the law from smoothing bias in the window table (window_misfit.h).
#include "window_misfit.h"

namespace fivebar::identification::detail {
namespace {

/// One actuator's verdict (WindowMisfit with actuator j).
WindowMisfit channel_misfit(const std::vector<WindowLevel>& levels, bool more, int j) {
  WindowMisfit m;
  const std::size_t n = levels.size();
  std::size_t a = 0;
  while (a < n &&
         !(levels[a].excess(j) >= kResolvedExcess * levels[a].floor[j] * levels[a].floor[j])) {
    ++a;
  }
  if (a == n) return m;
  // the excess must stay within [kFallingExcess, 1 / kFlatExcess] of its value at a up to twice
  // a's half-window
  const double cap = levels[a].excess(j) / kFlatExcess;
  const double low = levels[a].excess(j) * kFallingExcess;
  std::size_t to = a;
  while (to + 1 < n && levels[to + 1].excess(j) <= cap && levels[to + 1].excess(j) >= low) ++to;
  if (levels[to].half < 2 * levels[a].half) {
    // grew beyond the cap (bias) or fell below the low bound before the doubling, or the table
    // ends before it
    if (to + 1 == n && more) m.state = WindowMisfit::kNeedMore;
    return m;
  }
  // flat over a doubling; the table is evaluated until the excess grows or the candidates end
  m.state = to + 1 == n && more ? WindowMisfit::kNeedMore : WindowMisfit::kMisfit;
  m.actuator = j;
  m.from = a;
  m.to = to;
  return m;
}

}  // namespace

WindowMisfit window_misfit(const std::vector<WindowLevel>& levels, bool more) {
  WindowMisfit out;
  for (int j = 0; j < 2; ++j) {
    const WindowMisfit m = channel_misfit(levels, more, j);
    if (m.state == WindowMisfit::kNeedMore) return m;
    // both show it: the one whose excess stays flat over the fewer windows (the first bias)
    if (m.state == WindowMisfit::kMisfit && (out.state != WindowMisfit::kMisfit || m.to < out.to)) {
      out = m;
    }
  }
  return out;
}

}  // namespace fivebar::identification::detail
