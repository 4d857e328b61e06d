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

/// The step of a uniform grid t (strictly increasing, as checked by the caller). Returns the
/// mean step, or throws InputError(`<file>: line N, column t: ...`) naming the first step that
/// differs from the mean by more than 1e-6 of it. `lines` gives the file line of each sample.
double uniform_step(const std::vector<double>& t, const std::vector<int>& lines,
                    const std::string& file);

}  // namespace fivebar::io
