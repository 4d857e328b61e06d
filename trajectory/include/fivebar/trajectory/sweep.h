// Design studies: grids over scene keys (`--sweep KEY=LO:HI:N`).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace fivebar::trajectory {

/// One swept scene key: N values evenly spaced from LO to HI (both included; N = 1 gives LO).
struct Sweep {
  std::string key;
  double lo = 0, hi = 0;
  int n = 1;
  double value(int i) const { return n == 1 ? lo : lo + (hi - lo) * i / (n - 1); }
};

/// Parses `KEY=LO:HI:N`. Throws std::invalid_argument with the reason (no key, LO or HI not a
/// finite number, N not an integer >= 1, LO > HI, N > 1 with LO == HI).
Sweep parse_sweep(const std::string& text);

/// The designs of a grid: every combination of the sweeps' values, the first sweep varying
/// slowest. design_values(sweeps, d)[k] is the value of sweeps[k] in design d.
int design_count(const std::vector<Sweep>& sweeps);
std::vector<double> design_values(const std::vector<Sweep>& sweeps, int design);

}  // namespace fivebar::trajectory
