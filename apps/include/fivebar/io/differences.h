// Derivatives of sampled signals on a uniform grid (motion files and torque logs that carry
// angles only).
#pragma once

#include <string>
#include <vector>

namespace fivebar::io {

/// df/dt of samples f on a uniform grid of step h: 5-point central differences inside,
/// 5-point one-sided differences at the two first and two last samples; all fourth order,
/// error O(h^4 f^(5)). Needs f.size() >= 5.
std::vector<double> first_derivative(const std::vector<double>& f, double h);

/// d2f/dt2 likewise: 5-point central differences inside (O(h^4)), 5-point one-sided at the ends
/// (O(h^3)). Needs f.size() >= 5.
std::vector<double> second_derivative(const std::vector<double>& f, double h);

/// Noise gains of the two estimates above: white noise of deviation s on f gives derivatives
/// with deviation at most gain * s / h (first) and gain * s / h^2 (second); the largest gain is
/// that of the one-sided stencil at the ends (first: sqrt(25^2 + 48^2 + 36^2 + 16^2 + 3^2) / 12;
/// second: sqrt(35^2 + 104^2 + 114^2 + 56^2 + 11^2) / 12). The rest rule's thresholds use them.
inline constexpr double kFirstDerivativeNoiseGain = 5.5839;
inline constexpr double kSecondDerivativeNoiseGain = 14.0174;

/// The step of a uniform grid t (strictly increasing, as checked by the caller). Returns the
/// mean step, or throws InputError(`<file>: line N, column t: ...`) naming the first step that
/// differs from the mean by more than 1e-6 of it. `lines` gives the file line of each sample.
double uniform_step(const std::vector<double>& t, const std::vector<int>& lines,
                    const std::string& file);

}  // namespace fivebar::io
