// Work-precision study: every integrator x friction treatment x tolerance against the
// toolkit's own tight reference, timed as the minimum of several runs.
#include "fivebar/studies/accuracy.h"

#include "fivebar/sim/estimate.h"
#include "fivebar/model/names.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fivebar::studies {

const char* treatment_name(Treatment t) {
  static constexpr Named<Treatment> kNames[] = {{Treatment::kExactLocated, "exact_located"},
                                                {Treatment::kExactUnlocated, "exact_unlocated"},
                                                {Treatment::kRegularized, "regularized"},
                                                {Treatment::kAsScene, "as_scene"}};
  return name_in(kNames, t);
}

double max_theta_difference(const std::vector<Row>& a, const std::vector<Row>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  return sim::max_angle_difference(a, b);
}

namespace {

/// a run's wall-time limit in units of WorkPrecisionOptions::max_run_time_s
constexpr double kRunBudget = 2.0;

/// The scene's parameters and options for one treatment (P: the mechanism's parameters).
template <class P>
void apply(Treatment t, double w_s, P* p, Options* o) {
  switch (t) {
    case Treatment::kExactLocated:
      o->locate_switches = true;
      break;
    case Treatment::kExactUnlocated:
      o->locate_switches = false;
      break;
    case Treatment::kRegularized:
      p->friction.smoothing_velocity = w_s;
      break;
    case Treatment::kAsScene:
      break;
  }
}

template <class P, class LF>
Status reference(const P& p, const LF& loads, const Initial& initial, Options o, double tol,
                 Reference* ref) {
  o.rtol = o.atol = tol;
  o.method = Method::kCvodeAdams;
  const Result a = simulate(p, loads, initial, o);
  if (!a.status.ok()) return a.status;
  o.method = Method::kArkodeErk45;
  const Result b = simulate(p, loads, initial, o);
  if (!b.status.ok()) return b.status;
  ref->rows = a.rows;
  ref->stats = a.stats;
  ref->self_difference = max_theta_difference(a.rows, b.rows);
  return Status::Ok();
}

/// One point of the study: the run of method `m` at tolerance `tol` under treatment `t`, timed
/// as the minimum of options.repeats runs (fewer when a run fails or exceeds max_run_time_s),
/// with its error against the treatment's own reference and against the exact one.
template <class P, class LF>
PrecisionPoint measure_point(const P& params, const LF& loads, const Initial& initial,
                             const Options& base, const WorkPrecisionOptions& options, Treatment t,
                             Method m, double tol, const WorkPrecision& refs) {
  P p = params;
  Options o = base;
  apply(t, options.regularization_velocity, &p, &o);
  o.method = m;
  o.rtol = o.atol = tol;
  o.full_rows = false;  // the study times the integration, not the reaction post-processing
  // a run is stopped (failed, its message says so) past twice the time after which the study
  // skips a method's tighter tolerances: integrating a sticking four-bar with the switches left
  // unlocated took 22 s for one run (14.8 M right-hand sides), the default study hours
  const double budget = kRunBudget * options.max_run_time_s;
  if (!(o.max_wall_time_s > 0) || o.max_wall_time_s > budget) o.max_wall_time_s = budget;
  PrecisionPoint pt;
  pt.method = m;
  pt.treatment = t;
  pt.tolerance = tol;
  pt.wall_time_s = std::numeric_limits<double>::infinity();
  Result r;
  for (int rep = 0; rep < std::max(1, options.repeats); ++rep) {
    r = simulate(p, loads, initial, o);
    pt.wall_time_s = std::min(pt.wall_time_s, r.stats.wall_time_s);
    if (!r.status.ok() || r.stats.wall_time_s > options.max_run_time_s) break;
  }
  pt.ok = r.status.ok();
  pt.message = r.status.message;
  pt.rhs_evaluations = r.stats.rhs_evaluations;
  pt.steps = r.stats.steps;
  pt.friction_events = r.stats.friction_events;
  pt.error = pt.error_vs_exact = std::numeric_limits<double>::quiet_NaN();  // a failed run's
  if (pt.ok) {
    const Reference& own = t == Treatment::kRegularized ? refs.regularized : refs.exact;
    pt.error = max_theta_difference(r.rows, own.rows);
    pt.error_vs_exact = max_theta_difference(r.rows, refs.exact.rows);
  }
  return pt;
}

/// Pareto front over (wall time, error) among the successful points of treatment `own`; points
/// at the reference's own tolerance reproduce it and say nothing about the error.
void mark_pareto(Treatment own, double reference_tolerance, std::vector<PrecisionPoint>* points) {
  auto eligible = [&](const PrecisionPoint& p) {
    return p.ok && p.treatment == own && p.tolerance > reference_tolerance;
  };
  for (PrecisionPoint& a : *points) {
    if (!eligible(a)) continue;
    a.pareto = std::none_of(points->begin(), points->end(), [&](const PrecisionPoint& b) {
      return eligible(b) && b.wall_time_s <= a.wall_time_s && b.error <= a.error &&
             (b.wall_time_s < a.wall_time_s || b.error < a.error);
    });
  }
}

/// The fastest Pareto point within each target error.
std::vector<WorkPrecision::Recommendation> recommend(const std::vector<PrecisionPoint>& points) {
  std::vector<WorkPrecision::Recommendation> out;
  for (double target : {1e-6, 1e-8, 1e-9}) {
    WorkPrecision::Recommendation rec;
    rec.target = target;
    for (const PrecisionPoint& p : points) {
      if (p.pareto && p.error <= target &&
          (!rec.found || p.wall_time_s < rec.point.wall_time_s)) {
        rec.point = p;
        rec.found = true;
      }
    }
    out.push_back(rec);
  }
  return out;
}

/// work_precision over the mechanism's parameters P and load function LF.
template <class P, class LF>
Status study(const P& params, const LF& loads, const Initial& initial, const Options& base,
             const WorkPrecisionOptions& options, WorkPrecision* out) {
  *out = WorkPrecision{};
  // treatments: the three of an exact-sign law, else the scene's own
  const bool exact_sign = fivebar::exact_sign(params.friction);
  std::vector<Treatment> treatments;
  if (exact_sign) {
    treatments = {Treatment::kExactLocated, Treatment::kExactUnlocated, Treatment::kRegularized};
  } else {
    treatments = {Treatment::kAsScene};
  }
  Status st = reference(params, loads, initial, base, options.reference_tolerance, &out->exact);
  if (!st.ok()) return st;
  if (exact_sign) {
    P reg = params;
    reg.friction.smoothing_velocity = options.regularization_velocity;
    st = reference(reg, loads, initial, base, options.reference_tolerance, &out->regularized);
    if (!st.ok()) return st;
  }

  const int total =
      static_cast<int>(treatments.size() * options.methods.size() * options.tolerances.size());
  for (Treatment t : treatments) {
    for (Method m : options.methods) {
      for (double tol : options.tolerances) {
        const PrecisionPoint pt =
            measure_point(params, loads, initial, base, options, t, m, tol, *out);
        out->points.push_back(pt);
        if (options.progress) options.progress(static_cast<int>(out->points.size()), total);
        if (pt.ok && pt.wall_time_s > options.max_run_time_s) break;  // tighter only costs more
      }
    }
  }
  mark_pareto(treatments.front(), options.reference_tolerance, &out->points);
  out->recommendations = recommend(out->points);
  return Status::Ok();
}

}  // namespace

Status work_precision(const Params<double>& params, const LoadFunction& loads,
                      const Initial& initial, const Options& base,
                      const WorkPrecisionOptions& options, WorkPrecision* out) {
  return study(params, loads, initial, base, options, out);
}

Status work_precision(const FourBarParamsT<double>& params, const FourBarLoadFunction& loads,
                      const Initial& initial, const Options& base,
                      const WorkPrecisionOptions& options, WorkPrecision* out) {
  return study(params, loads, initial, base, options, out);
}

}  // namespace fivebar::studies
