// Error estimates by a companion run, and the choice of tolerance for a target error.
#include "fivebar/sim/estimate.h"

#include "fivebar/model/format.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fivebar::sim {

double max_angle_difference(const std::vector<Row>& a, const std::vector<Row>& b) {
  const size_t n = std::min(a.size(), b.size());
  double worst = 0.0;
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < kLinks; ++k) {
      const double d = std::abs(a[i].theta[k] - b[i].theta[k]);
      worst = std::isfinite(d) ? std::max(worst, d) : INFINITY;
    }
  }
  return worst;
}

bool rounding_limited(double e, double rtol, const Result& run) {
  if (rtol / 10 < 0.99 * kRoundingCompanionRtol) return true;
  // both runs agree to the last bit on every row: nothing the tolerance controls moved (a
  // mechanism held at rest takes one step per output row however long it is held), and 0 is the
  // error, whatever the count of steps
  if (e == 0) return false;
  double largest = 0.0;
  for (const Row& r : run.rows) {
    for (int k = 0; k < kLinks; ++k) largest = std::max(largest, std::abs(r.theta[k]));
  }
  // the rounding accumulated over the run, relative to the angles: 100 eps per step
  const double relative_floor = 100 * std::numeric_limits<double>::epsilon() *
                                static_cast<double>(std::max<long>(run.stats.steps, 1));
  // a check run whose tolerance is well above that floor measures the error even when the
  // difference is below the floor
  if (rtol / 10 >= relative_floor) return false;
  return e < relative_floor * largest;
}

namespace {

/// The companion of a run: same method, ten times tighter, angles only, no progress. When the
/// companion finds the joint modes indeterminate, *indeterminate receives its status.
template <class P, class LoadFn>
double companion_estimate(const P& params, const LoadFn& loads,
                          const Initial& initial, const Options& o, const Result& run,
                          std::string* note, Status* indeterminate) {
  Options c = o;
  c.rtol = o.rtol / 10;
  c.atol = o.atol / 10;
  c.full_rows = false;
  c.progress = nullptr;
  const Result companion = simulate(params, loads, initial, c);
  if (!companion.status.ok()) {
    *note = "no error estimate: the companion run at rtol " + format_significant(c.rtol) +
            " failed: " + companion.status.message;
    if (companion.status.code == StatusCode::kIndeterminateModes) *indeterminate = companion.status;
    return NAN;
  }
  return max_angle_difference(run.rows, companion.rows);
}

/// simulate_to_target's body, for the mechanism of P.
template <class P, class LoadFn>
EstimatedRun to_target(const P& params, const LoadFn& loads, const Initial& initial,
                       const Options& options) {
  EstimatedRun out;
  out.options = options;
  Options& o = out.options;
  const double target = o.target_error;
  // the first try: tight enough for the target, loose enough that its check is not rounding-limited
  if (o.auto_tolerance) {
    o.rtol = o.atol = std::clamp(1e-4 * target, 10 * kRoundingCompanionRtol, 1e-6);
  }
  for (int attempt = 0; attempt < 4; ++attempt) {
    out.run = simulate(params, loads, initial, o);
    if (!out.run.status.ok()) return out;
    out.note.clear();
    Status indeterminate;
    const double e =
        companion_estimate(params, loads, initial, o, out.run, &out.note, &indeterminate);
    if (!indeterminate.ok()) {
      // the same motion at a tighter tolerance meets a pose where the joint modes are not
      // determined: this run's answer is not unique either (it only stepped past that pose)
      out.run.status = Status::Error(
          StatusCode::kIndeterminateModes,
          "the check run at rtol " + format_significant(o.rtol / 10) +
              " found the joint modes indeterminate, so this motion is not determined by the "
              "model: " +
              indeterminate.message);
      return out;
    }
    out.estimated_max_error_rad = e;
    out.attempts.push_back({o.rtol, e});
    out.rounding_limited = std::isfinite(e) && rounding_limited(e, o.rtol, out.run);
    out.target_met = e <= kTargetMargin * target && !out.rounding_limited;
    if (!o.auto_tolerance || out.target_met || out.rounding_limited || !std::isfinite(e)) break;
    // error ~ proportional to the tolerance: the tolerance that would meet the target, with margin
    const double wanted = o.rtol * 0.8 * kTargetMargin * target / e;
    const double at_floor = e * kTightestRtol / o.rtol;  // predicted error at the floor
    if (o.rtol <= kTightestRtol * 1.01 || (wanted < kTightestRtol && at_floor > 10 * target)) {
      break;
    }
    o.rtol = o.atol = std::max(wanted, kTightestRtol);
  }
  if (out.rounding_limited && out.note.empty()) {
    out.note = "target_error " + format_significant(target, 3) +
               " rad not confirmed: at rtol " + format_significant(o.rtol, 3) +
               " the check run is limited by rounding, so the estimate " +
               format_significant(out.estimated_max_error_rad, 3) +
               " rad is a lower bound, not the error (a looser target lets fivebar measure it)";
  }
  if (!out.target_met && out.note.empty()) {
    out.note = "target_error " + format_significant(target, 3) +
               " rad not met (the estimate must be at most a third of it): estimated error " +
               format_significant(out.estimated_max_error_rad, 3) + " rad at rtol " +
               format_significant(o.rtol, 3) +
               (o.auto_tolerance ? " (tighter tolerances cannot reach it: errors grow "
                                   "exponentially in this motion)"
                                 : " (the scene fixes rtol; remove it to let fivebar choose)");
  }
  return out;
}

}  // namespace

EstimatedRun simulate_to_target(const Params<double>& params, const LoadFunction& loads,
                                const Initial& initial, const Options& options) {
  return to_target(params, loads, initial, options);
}

EstimatedRun simulate_to_target(const FourBarParamsT<double>& params,
                                const FourBarLoadFunction& loads, const Initial& initial,
                                const Options& options) {
  return to_target(params, loads, initial, options);
}

}  // namespace fivebar::sim
