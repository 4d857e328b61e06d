// Work-precision study (issue 3): every integrator x friction treatment x tolerance against the
// toolkit's own tight reference, timed as the minimum of several runs.
#include "fivebar/studies/accuracy.h"

#include "fivebar/sim/estimate.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fivebar::studies {

const char* treatment_name(Treatment t) {
  switch (t) {
    case Treatment::kExactLocated: return "exact_located";
    case Treatment::kExactUnlocated: return "exact_unlocated";
    case Treatment::kRegularized: return "regularized";
    case Treatment::kAsScene: return "as_scene";
  }
  return "unknown";
}

double max_theta_difference(const std::vector<Row>& a, const std::vector<Row>& b) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  return sim::max_angle_difference(a, b);
}

namespace {

/// The scene's parameters and options for one treatment.
void apply(Treatment t, double w_s, Params<double>* p, Options* o) {
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

Status reference(const Params<double>& p, const LoadFunction& loads, const Initial& initial,
                 Options o, double tol, Reference* ref) {
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

}  // namespace

Status work_precision(const Params<double>& params, const LoadFunction& loads,
                      const Initial& initial, const Options& base,
                      const WorkPrecisionOptions& options, WorkPrecision* out) {
  *out = WorkPrecision{};
  // treatments: the three of an exact-sign law, else the scene's own
  const bool exact_sign = params.friction.active() && params.friction.law != FrictionLaw::kLuGre &&
                          params.friction.smoothing_velocity == 0.0;
  std::vector<Treatment> treatments;
  if (exact_sign) {
    treatments = {Treatment::kExactLocated, Treatment::kExactUnlocated, Treatment::kRegularized};
  } else {
    treatments = {Treatment::kAsScene};
  }
  Status st = reference(params, loads, initial, base, options.reference_tolerance, &out->exact);
  if (!st.ok()) return st;
  if (exact_sign) {
    Params<double> reg = params;
    reg.friction.smoothing_velocity = options.regularization_velocity;
    st = reference(reg, loads, initial, base, options.reference_tolerance, &out->regularized);
    if (!st.ok()) return st;
  }

  for (Treatment t : treatments) {
    for (Method m : options.methods) {
      for (double tol : options.tolerances) {
        Params<double> p = params;
        Options o = base;
        apply(t, options.regularization_velocity, &p, &o);
        o.method = m;
        o.rtol = o.atol = tol;
        o.full_rows = false;  // the study times the integration, not the reaction post-processing
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
        if (pt.ok) {
          const Reference& own = t == Treatment::kRegularized ? out->regularized : out->exact;
          pt.error = max_theta_difference(r.rows, own.rows);
          pt.error_vs_exact = max_theta_difference(r.rows, out->exact.rows);
        }
        out->points.push_back(pt);
        if (options.progress) {
          options.progress(static_cast<int>(out->points.size()),
                           static_cast<int>(treatments.size() * options.methods.size() *
                                            options.tolerances.size()));
        }
        if (pt.ok && pt.wall_time_s > options.max_run_time_s) break;  // tighter only costs more
      }
    }
  }

  // Pareto front over (wall time, error) among successful points of the scene's treatment
  const Treatment own = treatments.front();
  // (points at the reference's own tolerance reproduce it and say nothing about the error)
  auto eligible = [&](const PrecisionPoint& p) {
    return p.ok && p.treatment == own && p.tolerance > options.reference_tolerance;
  };
  for (PrecisionPoint& a : out->points) {
    if (!eligible(a)) continue;
    a.pareto = std::none_of(out->points.begin(), out->points.end(), [&](const PrecisionPoint& b) {
      return eligible(b) && b.wall_time_s <= a.wall_time_s && b.error <= a.error &&
             (b.wall_time_s < a.wall_time_s || b.error < a.error);
    });
  }
  for (double target : {1e-6, 1e-8, 1e-9}) {
    WorkPrecision::Recommendation rec;
    rec.target = target;
    for (const PrecisionPoint& p : out->points) {
      if (p.pareto && p.error <= target &&
          (!rec.found || p.wall_time_s < rec.point.wall_time_s)) {
        rec.point = p;
        rec.found = true;
      }
    }
    out->recommendations.push_back(rec);
  }
  return Status::Ok();
}

}  // namespace fivebar::studies
