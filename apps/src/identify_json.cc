// identification.json as one record (identify_json.h): the fields the command line writes and
// the Python module returns.
#include "fivebar/io/identify_json.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "fivebar/identification/parameters.h"
#include "fivebar/io/log_truth.h"

namespace fivebar::io {
namespace {

namespace id = fivebar::identification;

/// One value per driven crank: the five-bar's two (a, b), the four-bar's one (a).
Json cranks(int dof, double a, double b) {
  Json j = Json::array();
  j.push(a);
  if (dof == 2) j.push(b);
  return j;
}

/// "parameters": value, std, truth and errors when the log states the truth.
Json parameters_json(const id::IdentifyResult& res, const id::TorqueLog& log, bool* have_truth) {
  const LogTruth truth = read_truth(log.comments);
  Json params = Json::array();
  *have_truth = !truth.empty();
  for (size_t i = 0; i < res.parameters.size(); ++i) {
    const id::ParameterEstimate& p = res.parameters[i];
    Json e = Json::object();
    e.set("name", p.name);
    e.set("unit", res.layout.unit(int(i)));
    e.set("value", p.value);
    e.set("std", p.std);  // NaN (not determined, or at a bound) is written as null
    e.set("initial", p.initial);
    e.set("at_bound", p.at_bound);
    e.set("std_meaningful", std::isfinite(p.std));
    // the 95 % interval: Wald (value +- ci_quantile std) or profile likelihood; null where there
    // is none, or (ci95_unbounded) where the profile found no end on that side
    e.set("ci95_low", p.ci_low);
    e.set("ci95_high", p.ci_high);
    e.set("ci95_method", p.ci_method);
    if (std::isinf(p.ci_low) || std::isinf(p.ci_high)) {
      e.set("ci95_unbounded",
            std::isinf(p.ci_low) ? (std::isinf(p.ci_high) ? "both" : "low") : "high");
    }
    if (i < res.cramer_rao_std.size()) e.set("cramer_rao_std", res.cramer_rao_std[i]);
    double tv = 0;
    if (true_value(truth, res.layout, int(i), p.name, &tv)) {
      e.set("true", tv);
      e.set("error", p.value - tv);
      e.set("relative_error", tv != 0 ? (p.value - tv) / tv : NAN);
      e.set("error_in_std", (p.value - tv) / p.std);
    } else {
      *have_truth = false;
    }
    params.push(std::move(e));
  }
  return params;
}

/// "inertial": what the log determines of the 16 standard inertial parameters.
Json inertial_json(const id::InertialReport& r) {
  Json j = Json::object();
  j.set("prior_relative_std", r.prior_relative);
  j.set("determined_directions", r.rank);
  Json info = Json::array_of(r.information);
  j.set("information_singular_values", std::move(info));
  j.set("base_combinations", Json::array_of(r.base, [](const id::InertialReport::Combination& c) {
          return Json::object({{"combination", c.text}, {"value", c.value}, {"std", c.std}});
        }));
  Json at = Json::array_of(r.at_prior);
  j.set("left_at_prior", std::move(at));
  j.set("physically_consistent", r.consistent);
  return j;
}

/// Log conditioning: unwrapping, noise levels, glitches, notes.
Json conditioning_json(const id::IdentifyResult& res, const id::TorqueLog& log) {
  Json cond = Json::object();
  cond.set("unwrapped_turns", cranks(log.dof, res.unwrapped[0], res.unwrapped[1]));
  cond.set("angle_noise", cranks(log.dof, res.angle_noise[0], res.angle_noise[1]));
  cond.set("torque_noise", cranks(log.dof, res.torque_noise[0], res.torque_noise[1]));
  if (log.has_rates) cond.set("rate_noise", cranks(log.dof, res.rate_noise[0], res.rate_noise[1]));
  cond.set("rejected_glitches", Json::array_of(res.glitches, [](const id::Glitch& g) {
             return Json::object({{"line", g.line},
                                  {"column", g.column},
                                  {"value", g.value},
                                  {"expected", g.expected},
                                  {"noise_std", g.sigmas}});
           }));
  Json notes = Json::array_of(res.notes);
  cond.set("notes", std::move(notes));
  return cond;
}

/// Rates, std method and torque delay.
void rates_json(const id::IdentifyResult& res, const id::TorqueLog& log, Json* j) {
  Json rates = Json::object();
  rates.set("rates", res.rates_estimated ? "savitzky-golay" : "log");
  rates.set("accelerations", res.accels_estimated ? "savitzky-golay" : "log");
  if (res.accels_estimated) {
    rates.set("sg_half_window_samples", res.sg_half_window);
    rates.set("sg_half_window_s",
              res.sg_half_window * log.duration() / std::max(1, log.size() - 1));
    rates.set("sg_order", res.sg_order);
    rates.set("window_choice", res.window_choice);
  }
  j->set("rate_source", std::move(rates));
  j->set("std_method", res.std_method);
  j->set("ci95_quantile", res.ci_quantile);            // the Wald intervals' half-width in std
  if (res.ci_dof > 0) j->set("ci95_dof", res.ci_dof);  // Student's t degrees of freedom
  if (res.profile_refits > 0) j->set("profile_refits", res.profile_refits);
  if (!res.std_detail.empty()) j->set("std_detail", res.std_detail);
  if (std::isfinite(res.delay_s)) {
    Json d = Json::object();
    d.set("value_s", res.delay_s);  // the logged torques at t + d match the angles at t
    d.set("std_s", res.delay_std_s);
    d.set("corrected", res.delay_corrected);
    if (res.delay_unexplained) d.set("unexplained", true);  // significant, but a model error
    j->set("torque_delay", std::move(d));
  }
}

/// Correlation, singular values, solver summary.
void solver_json(const id::IdentifyResult& res, Json* j) {
  Json corr = Json::array();
  for (int r = 0; r < res.correlation.rows(); ++r) {
    Json row = Json::array();
    for (int c = 0; c < res.correlation.cols(); ++c) row.push(res.correlation(r, c));
    corr.push(std::move(row));
  }
  j->set("correlation", std::move(corr));
  Json sv = Json::array_of(res.singular_values);
  j->set("singular_values", std::move(sv));
  j->set("condition_number", res.singular_values.empty()
                                 ? NAN
                                 : res.singular_values.front() / res.singular_values.back());
  Json solver = Json::object();
  solver.set("iterations", res.iterations);
  solver.set("converged", res.converged);
  solver.set("report", res.solver_message);
  Json costs = Json::array_of(res.iteration_costs);
  solver.set("iteration_costs", std::move(costs));
  j->set("solver", std::move(solver));
}

Json validation_json(const id::Validation& val) {
  Json v = Json::object();
  v.set("full_run_note", full_run_note(val));
  v.set("full_run_divergence_time_s", val.divergence_time_s);
  v.set("full_run_status", val.status.ok() ? "ok" : val.status.message);
  v.set("full_run_duration_s", val.full_duration_s);
  v.set("full_run_rms_angle_error", cranks(val.dof, val.full_rms[0], val.full_rms[1]));
  v.set("full_run_max_angle_error", cranks(val.dof, val.full_max[0], val.full_max[1]));
  v.set("window_s", val.window_s);
  v.set("windowed_rms_angle_error", cranks(val.dof, val.window_rms[0], val.window_rms[1]));
  v.set("windows_skipped_over_time_budget", val.windows_skipped);
  v.set("windows_stopped_early", val.windows_stopped);
  if (val.windows_stopped > 0) v.set("first_window_stop", val.window_stop);
  return v;
}

}  // namespace

std::string full_run_note(const id::Validation& val) {
  if (std::isnan(val.divergence_time_s)) return "the full run follows the log throughout";
  // a one-crank run drifts as its errors accumulate; a five-bar's motion can be chaotic
  const char* why = val.dof == 1 ? "any model or noise error accumulates over a long run"
                                 : "on chaotic motion any model or noise error grows";
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "the full run leaves the log after %.3g s (angle error > %.2g rad): %s, so only "
                "the windowed check (restarted from the log every %.3g s) measures the fit",
                val.divergence_time_s, id::Validation::kDivergedAngle, why, val.window_s);
  return buf;
}

Json identification_json(const IdentifyRun& run, const id::TorqueLog& log,
                         const id::IdentifyResult& res, const id::Validation* validation) {
  Json j = Json::object();
  j.set("command", "identify");
  if (log.dof == 1) j.set("mechanism", "four_bar");
  // the fit's own verdict (docs/identification.md, "Status"): not ok exits 3
  j.set("status", res.unusable.empty() ? "ok" : "failed");
  if (!res.unusable.empty()) j.set("status_reason", res.unusable);
  const std::string& flip = run.torque_sign_flipped;
  j.set("torque_sign", flip.empty() ? "as logged" : flip == "both" ? "flipped" : "flipped tau" + flip);
  j.set("scene", run.scene);
  j.set("log", run.log);
  j.set("method", id::method_name(res.method));
  j.set("law", id::law_name(res.layout.law));
  j.set("per_joint", res.layout.per_joint);
  j.set("estimate", run.estimate);
  j.set("loss", id::loss_name(run.loss));
  if (run.loss != id::Loss::kNone) j.set("loss_scale", res.loss_scale);  // as applied
  bool have_truth = false;
  j.set("parameters", parameters_json(res, log, &have_truth));
  if (res.inertial.estimated) j.set("inertial", inertial_json(res.inertial));
  j.set("rms_torque_residual",
        cranks(log.dof, res.rms_torque_residual[0], res.rms_torque_residual[1]));
  j.set("residual_noise_floor",
        cranks(log.dof, res.residual_noise_floor[0], res.residual_noise_floor[1]));
  j.set("residual_to_noise_ratio",
        cranks(log.dof, res.rms_torque_residual[0] / res.residual_noise_floor[0],
               res.rms_torque_residual[1] / res.residual_noise_floor[1]));
  j.set("rms_torque_residual_initial",
        cranks(log.dof, res.rms_torque_residual_initial[0], res.rms_torque_residual_initial[1]));
  if (res.method == id::Method::kOutputError) {
    j.set("rms_angle_residual",
          cranks(log.dof, res.rms_angle_residual[0], res.rms_angle_residual[1]));
    j.set("window_s", res.window_s);
  }
  if (std::isfinite(res.negated_rms_torque_residual[0])) {
    j.set("negated_rms_torque_residual",
          cranks(log.dof, res.negated_rms_torque_residual[0], res.negated_rms_torque_residual[1]));
  }
  j.set("residual_sigma", res.residual_sigma);
  j.set("samples", res.samples);
  j.set("samples_used", res.samples_used);
  j.set("samples_at_rest", res.samples_at_rest);  // left out: some joint stuck (docs/hold.md)
  j.set("slip_reversals", res.slip_reversals);
  j.set("samples_near_reversals", res.samples_near_reversals);  // window spans a reversal
  j.set("rest_rate_threshold", res.rest_rate_threshold);
  j.set("rest_acceleration_threshold", res.rest_acceleration_threshold);
  j.set("residuals", res.residuals);
  j.set("truth_in_log", have_truth);
  rates_json(res, log, &j);
  j.set("log_conditioning", conditioning_json(res, log));
  solver_json(res, &j);
  if (validation) j.set("validation", validation_json(*validation));
  Json warnings = Json::array_of(res.warnings);
  j.set("warnings", std::move(warnings));
  j.set(
      "model_check", Json::array_of(res.model_check, [](const id::IdentifyResult::MisfitCause& c) {
        const auto num = [&](double v) { return c.checked && std::isfinite(v) ? Json(v) : Json(); };
        return Json::object({{"cause", c.name},
                             {"checked", c.checked},
                             {"drop", num(c.drop)},
                             {"z", num(c.z)},
                             {"z_given", num(c.z_given)},
                             {"explained", num(c.explained)},
                             {"evidenced", c.evidenced}});
      }));
  j.set("identification_wall_time_s", res.wall_time_s);
  return j;
}

}  // namespace fivebar::io
