// summary.json of `simulate` (simulate_json.h).
#include "fivebar/io/simulate_json.h"

namespace fivebar::io {
namespace {

// the statistics and final energies of one run
Json run_json(const sim::Result& run, const sim::RunChecks* checks) {
  Json j = Json::object();
  const bool ok = run.status.ok() && (checks == nullptr || checks->verdict.ok());
  j.set("status", ok ? "ok" : "failed");
  if (!run.status.ok()) j.set("message", run.status.message);
  if (run.status.ok() && checks && !checks->verdict.ok()) {
    j.set("message", "run check failed: " + checks->verdict.message);
  }
  j.set("final_time", run.rows.empty() ? 0.0 : run.rows.back().t);
  j.set("rows", static_cast<long>(run.rows.size()));
  if (checks != nullptr) {
    j.set("energy_balance_relative", checks->energy_balance_relative);
    j.set("inverse_dynamics_max_abs_error", checks->inverse_dynamics_max_abs_error);
    j.set("friction_power_min", checks->friction_power_min);
    Json tol = Json::object();
    tol.set("energy_balance_relative", checks->energy_tol);
    tol.set("inverse_dynamics_max_abs_error", checks->inverse_tol);
    tol.set("friction_power_min", -checks->power_tol);
    j.set("check_thresholds", std::move(tol));
  }
  j.set("wall_time_s", run.stats.wall_time_s);
  j.set("rhs_evaluations", run.stats.rhs_evaluations);
  j.set("steps", run.stats.steps);
  j.set("friction_events", run.stats.friction_events);
  j.set("stick_events", run.stats.stick_events);
  j.set("breakaway_events", run.stats.breakaway_events);
  j.set("mode_decisions", run.stats.mode_decisions);
  j.set("sign_rule_inconsistent", run.stats.sign_rule_inconsistent);
  j.set("mode_corrections", run.stats.mode_corrections);
  if (!run.rows.empty()) {
    j.set("E_diss", run.rows.back().E_diss);
    j.set("W_in", run.rows.back().W_in);
    j.set("W_ext", run.rows.back().W_ext);
  }
  return j;
}

// the error estimate and how the tolerance was chosen
void estimate_json(const sim::EstimatedRun& er, Json* summary) {
  summary->set("estimated_max_error_rad", er.estimated_max_error_rad);
  summary->set("target_error", er.options.target_error);
  summary->set("target_met", er.target_met);
  summary->set("estimate_rounding_limited", er.rounding_limited);
  summary->set("tolerance_choice", er.options.auto_tolerance ? "auto" : "scene");
  Json tried = Json::array();
  for (const sim::Attempt& a : er.attempts) {
    Json t = Json::object();
    t.set("rtol", a.rtol);
    t.set("estimated_max_error_rad", a.estimate);
    tried.push(std::move(t));
  }
  summary->set("tolerances_tried", std::move(tried));
  if (!er.note.empty()) summary->set("estimate_note", er.note);
}

void settings_json(const std::vector<std::string>& sets, const Scene& scene, const sim::Options& o,
                   Json* out) {
  out->set({{"command", "simulate"},
            {"scene", scene.path},
            {"sets", Json::array_of(sets)},
            {"mechanism", mechanism_type_name(scene.type)},
            {"friction_model", friction_law_name(friction_of(scene).law)},
            {"integrator", integrator_name(sim::method_of(o, friction_of(scene).law))},
            {"rtol", o.rtol},
            {"atol", o.atol},
            {"locate_switches", o.locate_switches},
            {"stick", o.stick},
            {"duration", o.duration},
            {"output_step", o.output_step}});
}

}  // namespace

namespace {

// the run of `params` with friction off, and its checks
template <class P, class L>
TwinRun twin_of(P params, const L& loads, const sim::Initial& initial,
                const sim::Options& options) {
  params.friction.law = FrictionLaw::kNone;
  sim::Options o = options;
  o.progress = nullptr;
  TwinRun twin{sim::simulate(params, loads, initial, o), std::nullopt};
  if (twin.run.status.ok()) twin.checks = sim::check_run(params, loads, twin.run, o.rtol, o.atol);
  return twin;
}

}  // namespace

TwinRun frictionless_twin(const Scene& scene, const sim::LoadFunction& loads,
                          const sim::Options& options) {
  return twin_of(scene.params, loads, scene.initial, options);
}

TwinRun frictionless_twin(const Scene& scene, const sim::FourBarLoadFunction& loads,
                          const sim::Options& options) {
  return twin_of(scene.four_bar, loads, scene.initial, options);
}

Json simulation_summary_json(const Scene& scene, const std::vector<std::string>& sets,
                             const sim::EstimatedRun& run, const sim::RunChecks& checks,
                             const TwinRun* twin) {
  Json summary = run_json(run.run, &checks);
  estimate_json(run, &summary);
  settings_json(sets, scene, run.options, &summary);
  if (twin)
    summary.set("frictionless", run_json(twin->run, twin->checks ? &*twin->checks : nullptr));
  return summary;
}

}  // namespace fivebar::io
