#include "fivebar/trajectory/design.h"

#include <algorithm>
#include <limits>

#include <nlopt.hpp>

namespace fivebar::trajectory {
namespace {

struct Scaled {
  const std::function<double(const std::vector<double>&)>* f;
  const std::vector<double>* lo;
  const std::vector<double>* hi;
  BoxResult* best;
};

double scaled_cb(unsigned n, const double* u, double* /*grad*/, void* data) {
  Scaled& s = *static_cast<Scaled*>(data);
  std::vector<double> x(n);
  for (unsigned i = 0; i < n; ++i) {
    x[i] = (*s.lo)[i] + std::clamp(u[i], 0.0, 1.0) * ((*s.hi)[i] - (*s.lo)[i]);
  }
  const double v = (*s.f)(x);
  ++s.best->evaluations;
  if (s.best->x.empty() || v < s.best->value) {
    s.best->x = x;
    s.best->value = v;
  }
  return v;
}

}  // namespace

BoxResult minimize_box(const std::function<double(const std::vector<double>&)>& f,
                       const std::vector<double>& lo, const std::vector<double>& hi,
                       const std::vector<double>& x0, const BoxOptions& options) {
  const unsigned n = static_cast<unsigned>(lo.size());
  BoxResult best;
  Scaled data{&f, &lo, &hi, &best};
  std::vector<double> u(n);
  for (unsigned i = 0; i < n; ++i) u[i] = std::clamp((x0[i] - lo[i]) / (hi[i] - lo[i]), 0.0, 1.0);
  try {
    nlopt::opt opt(nlopt::LN_BOBYQA, n);
    opt.set_lower_bounds(std::vector<double>(n, 0.0));
    opt.set_upper_bounds(std::vector<double>(n, 1.0));
    opt.set_min_objective(scaled_cb, &data);
    opt.set_initial_step(std::vector<double>(n, options.initial_step));
    opt.set_xtol_abs(options.xtol);
    opt.set_ftol_rel(options.ftol_rel);
    opt.set_maxeval(options.max_evaluations);
    double value = 0;
    best.solver = status_from_result(static_cast<int>(opt.optimize(u, value)));
  } catch (...) {
    best.solver = status_from_exception(std::current_exception());
  }
  return best;
}

}  // namespace fivebar::trajectory
