// Predictions of identify(): the fitted model's torques, the output-error residual levels, and
// the warning on a coefficient at its bound under a misfit.
#include "identify_stages.h"

namespace fivebar::identification::stages {

void predictions(const Fit& f, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  out->predicted_tau1.assign(n, kNaN);
  out->predicted_tau2.assign(n, kNaN);
  Params<double> p = f.scene;
  f.layout.apply(f.x.data(), &p);
  for (int i = 0; i < n; ++i) {
    Evaluation<double> ev;
    const Status st =
        inverse_dynamics(p, f.loads(log.t[i]), log.theta1[i], log.theta2[i], out->omega1[i],
                         out->omega2[i], out->alpha1[i], out->alpha2[i], nullptr, f.eval, &ev);
    if (st.ok()) {
      out->predicted_tau1[i] = ev.M1 + p.actuators.offset[0];  // as the sensor reads it
      out->predicted_tau2[i] = ev.M2 + p.actuators.offset[1];
    }
  }
}

void output_error_levels(const TorqueLog& log, int first, int last, IdentifyResult* out) {
  const int channels = out->predicted_tau2.empty() ? 1 : 2;
  const std::vector<double>* tau[2] = {&log.tau1, &log.tau2};
  const std::vector<double>* pred[2] = {&out->predicted_tau1, &out->predicted_tau2};
  for (int j = 0; j < channels; ++j) {
    double s = 0;
    int c = 0;
    std::vector<double> d;
    for (int i = first; i <= last; ++i) {
      const double e = (*tau[j])[i] - (*pred[j])[i];
      if (!std::isfinite(e)) continue;
      s += e * e;
      ++c;
      const double e0 = i > first ? (*tau[j])[i - 1] - (*pred[j])[i - 1] : kNaN;
      if (std::isfinite(e0)) d.push_back(e - e0);
    }
    out->rms_torque_residual[j] = std::sqrt(s / std::max(1, c));
    out->residual_noise_floor[j] = robust_std(d) / std::sqrt(2.0);
  }
}

void output_error_misfit(IdentifyResult* out) {
  const double ratio = misfit_ratio(*out);
  if (!(ratio > kOutputErrorMisfitRatio) || !out->unusable.empty()) return;
  out->unusable = "the fitted scene's torque residual is " + format_significant(ratio, 3) +
                  " times its noise floor (more than " +
                  format_significant(kOutputErrorMisfitRatio) +
                  "): the scene, the law or the log's sensors miss what the log shows, and output "
                  "error names no cause (the default method, inverse dynamics, runs the model "
                  "check that does)";
  out->warnings.push_back(out->unusable);
}

double misfit_ratio(const IdentifyResult& r) {
  double ratio = 0;
  for (int c = 0; c < kActuators; ++c) {
    if (r.residual_noise_floor[c] > 0) {
      ratio = std::max(ratio, r.rms_torque_residual[c] / r.residual_noise_floor[c]);
    }
  }
  return ratio;
}

/// A fit whose every friction coefficient is at its bound explains none of the torques by
/// friction: a residual this many times its floor is then unexplained (a light mechanism whose
/// masses did not match the log gave 2.6-2.8 with both coefficients at 0, true 0.08 and 0.01)
constexpr double kAllAtBoundMisfitRatio = 2.0;

/// The last check, where no stage named a cause: every friction coefficient at its bound with
/// the residual above kAllAtBoundMisfitRatio floors (one at its bound above kMisfitRatio is
/// bound_and_misfit_warning's)
void unexplained_misfit(const ParameterLayout& layout, IdentifyResult* out) {
  const int n = layout.friction_size();
  if (!out->unusable.empty() || n == 0) return;
  // a solver that stopped before converging with no friction coefficient determined (a
  // per-joint Stribeck fit of a four-bar's 3 s log: 16 coefficients, 100 iterations, each at its
  // bound or without a std) has found nothing to report
  bool determined = false;
  for (int i = 0; i < n; ++i) determined = determined || std::isfinite(out->parameters[i].std);
  if (!out->converged && !determined) {
    out->unusable = "the solver stopped before converging (" + std::to_string(out->iterations) +
                    " iterations) and no friction coefficient is determined: the log does not "
                    "determine this law (a simpler law, shared coefficients, or a longer log with "
                    "more motion)";
    return;
  }
  for (int i = 0; i < n; ++i) {
    if (!out->parameters[i].at_bound) return;
  }
  const double ratio = misfit_ratio(*out);
  if (!(ratio > kAllAtBoundMisfitRatio)) return;
  out->unusable = "every friction coefficient at its bound while the torque residual is " +
                  format_significant(ratio, 3) + " times its noise floor (more than " +
                  format_significant(kAllAtBoundMisfitRatio) +
                  "): friction explains none of the torques, and something else does not match "
                  "(the scene's masses or geometry, the law, the log's units)";
}

void bound_and_misfit_warning(const Fit& f, const Analysis& an, IdentifyResult* out) {
  std::string at;
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    if (out->parameters[i].at_bound) at += (at.empty() ? "" : ", ") + out->parameters[i].name;
  }
  const double* fl = out->residual_noise_floor;
  const double ratio = misfit_ratio(*out);
  if (at.empty() || !(ratio > kMisfitRatio)) return;
  const size_t m = f.index.size();
  std::vector<std::pair<double, int>> q(m);  // per sample: residual in floors, log index
  for (size_t u = 0; u < m; ++u) {
    q[u] = {std::hypot(an.r[2 * u] / fl[0], an.r[2 * u + 1] / fl[1]) / std::sqrt(2.0), f.index[u]};
  }
  const size_t top = std::min<size_t>(3, m);
  std::partial_sort(q.begin(), q.begin() + top, q.end(), std::greater<>());
  std::string lines;
  for (size_t k = 0; k < top; ++k) {
    lines += (k ? ", " : "") + sample_name(f.cond.log, q[k].second) + " (" +
             format_significant(q[k].first, 2) + " times)";
  }
  // which cause cannot be told from the residual: a glitch that drags a coefficient to its bound
  // leaves the whole residual off the floor, as a wrong scene does
  out->unusable = at + " at its bound while the torque residual is " +
                  format_significant(ratio, 3) + " times its noise floor (more than " +
                  format_significant(kMisfitRatio) + ")";
  out->warnings.push_back(
      at + " at its bound while the torque residual is " + format_significant(ratio) +
      " times the noise floor: the fit is driven by samples the law cannot explain (largest at " +
      lines + "). Likely causes: glitches the rejection missed (check those lines; --loss cauchy "
      "fits past them), or a scene (masses, geometry, loads) or law that does not match the log "
      "(--estimate friction,inertia, another --law). A coefficient at its bound has no "
      "meaningful std; do not use this fit as it is");
}

}  // namespace fivebar::identification::stages
