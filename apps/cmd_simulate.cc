// fivebar simulate SCENE [--out DIR] [--set KEY=VALUE]... [--no-plots]
// Forward simulation of a scene, with its frictionless twin when the scene has friction, the
// run checks (energy balance, inverse dynamics), trajectory CSVs, summary.json, figures 2-6 and
// animation.html.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "fivebar/io/animation.h"
#include "fivebar/io/command.h"
#include "fivebar/io/decimate.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "simulate a scene (and its frictionless twin); trajectory, checks, figures 2-6";

struct Args {
  SceneArgs scene;
  bool no_plots = false;
  bool twin = false;
};

// every file this command may write (a previous run's copies are removed first, see OutputDir)
const std::vector<std::string> kOutputs = {"trajectory.csv",
                                           "trajectory_frictionless.csv",
                                           "trajectory_plot.csv",
                                           "trajectory_frictionless_plot.csv",
                                           "summary.json",
                                           "fig2_angles.png",
                                           "fig3_rates.png",
                                           "fig4_accelerations.png",
                                           "fig5_inverse_torques.png",
                                           "fig6_friction_torques.png",
                                           "plots.gnuplot",
                                           "animation.html"};

/// Runs longer than this [s] skip the frictionless twin unless --twin asks for it: without
/// friction the paper mechanism keeps gaining energy, and its twin dominates the run time.
constexpr double kTwinMaxDuration = 20.0;
/// Figures draw at most about 100 buckets x (first row and extrema) points per curve: beyond,
/// decimated copies trajectory_plot.csv (and trajectory_frictionless_plot.csv) are written and
/// plotted.
constexpr size_t kPlotBuckets = 100;
/// runs with more rows than this are drawn from the decimated copy (gnuplot stays fast)
constexpr size_t kPlotMaxRows = 10000;

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

// the frictionless twin for figures 2-4; its failure is reported but does not fail the run
std::optional<sim::Result> run_twin(const Scene& scene, const sim::LoadFunction& loads,
                                    const sim::Options& options, bool forced,
                                    std::optional<sim::RunChecks>* checks) {
  if (!scene.params.friction.active()) return std::nullopt;
  if (options.duration > kTwinMaxDuration && !forced) {
    std::cout << "  frictionless twin skipped: runs over "
              << format_printf(kTwinMaxDuration, "%.4g") << " s draw it only with --twin\n";
    return std::nullopt;
  }
  Params<double> frictionless = scene.params;
  frictionless.friction.law = FrictionLaw::kNone;
  sim::Options o = options;
  o.progress = nullptr;
  sim::Result twin = sim::simulate(frictionless, loads, scene.initial, o);
  if (twin.status.ok()) {
    *checks = sim::check_run(frictionless, loads, twin, o.rtol, o.atol);
  } else {
    warn(scene.path + ": frictionless twin: " + twin.status.message +
         " (trajectory_frictionless.csv not written)");
  }
  return twin;
}

// inverse dynamics of the computed motion (figure 5): the torques that reproduce it
std::vector<Column> inverse_columns(const Scene& scene, const sim::LoadFunction& loads,
                                    const std::vector<sim::Row>& rows) {
  std::vector<sim::Row> inverse;
  const Status status = sim::inverse_rows(scene.params, loads, rows, &inverse);
  if (!status.ok() || inverse.size() != rows.size()) {
    warn(scene.path + ": inverse dynamics of the run failed: " + status.message +
         " (no M1_inverse, M2_inverse columns, no figure 5)");
    return {};
  }
  Column m1{"M1_inverse", {}}, m2{"M2_inverse", {}};
  for (const sim::Row& r : inverse) {
    m1.values.push_back(r.M1);
    m2.values.push_back(r.M2);
  }
  return {std::move(m1), std::move(m2)};
}

// trajectory CSV, and its decimated copy for the figures when it is long; returns the name to plot
std::string write_with_plot_copy(const OutputDir& out, const std::string& name,
                                 const std::vector<sim::Row>& rows,
                                 const std::vector<Column>& extra) {
  write_trajectory_csv(out.file(name + ".csv"), rows, extra);
  if (rows.size() <= kPlotMaxRows) return name + ".csv";
  std::vector<sim::Row> few;
  std::vector<Column> few_extra;
  select_rows(rows, extra, decimation_indices(rows, extra, kPlotBuckets), &few, &few_extra);
  write_trajectory_csv(out.file(name + "_plot.csv"), few, few_extra);
  return name + "_plot.csv";
}

void settings_json(const Args& args, const Scene& scene, const sim::Options& o, Json* out) {
  out->set({{"command", "simulate"},
            {"scene", scene.path},
            {"sets", Json::array_of(args.scene.sets)},
            {"friction_model", friction_law_name(scene.params.friction.law)},
            {"integrator", integrator_name(o.method)},
            {"rtol", o.rtol},
            {"atol", o.atol},
            {"locate_switches", o.locate_switches},
            {"stick", o.stick},
            {"duration", o.duration},
            {"output_step", o.output_step}});
}

void print_report(const Scene& scene, const sim::EstimatedRun& er, const sim::RunChecks& checks,
                  const std::optional<sim::Result>& twin,
                  const std::optional<sim::RunChecks>& twin_checks) {
  const sim::Result& run = er.run;
  const sim::Options& o = er.options;
  const sim::Row& last = run.rows.back();
  std::cout << "fivebar simulate: " << scene.path << " (friction "
            << friction_law_name(scene.params.friction.law) << "), " << integrator_name(o.method)
            << " rtol " << format_printf(o.rtol, "%.4g") << " atol "
            << format_printf(o.atol, "%.4g")
            << (o.auto_tolerance
                    ? " (chosen for target_error " + format_printf(o.target_error, "%.4g") + " rad)"
                    : "")
            << "\n"
            << "  t = 0 .. " << format_printf(last.t, "%.4g") << " s, " << run.rows.size()
            << " rows; " << run.stats.steps << " steps, " << run.stats.rhs_evaluations
            << " rhs evaluations, " << run.stats.friction_events << " friction events, "
            << format_printf(run.stats.wall_time_s, "%.3f") << " s\n"
            << "  estimated error: " << format_printf(er.estimated_max_error_rad, "%.2e") << " rad"
            << (er.target_met ? " (target met)" : "") << "\n";
  if (!er.note.empty()) std::cout << "  note: " << er.note << "\n";
  std::cout << "  energy: W_in " << format_printf(last.W_in, "%.6g") << " J, W_ext "
            << format_printf(last.W_ext, "%.6g") << " J, E_diss "
            << format_printf(last.E_diss, "%.6g") << " J; balance residual "
            << format_printf(checks.energy_balance_relative, "%.2e") << " (relative)\n"
            << "  inverse dynamics: max |M - M_input| = "
            << format_printf(checks.inverse_dynamics_max_abs_error, "%.2e")
            << " N m; min friction power " << format_printf(checks.friction_power_min, "%.2e")
            << " W\n";
  if (twin && twin->status.ok()) {
    std::cout << "  frictionless twin: " << twin->stats.steps << " steps, "
              << format_printf(twin->stats.wall_time_s, "%.3f") << " s, balance residual "
              << format_printf(twin_checks->energy_balance_relative, "%.2e") << "\n";
  }
}

int run(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = load_scene(args.scene.scene, args.scene.sets);
  const sim::LoadFunction loads = LoadExpressions(scene).function();
  OutputDir out(args.scene.out, kOutputs);

  // the run and its error estimate: a failure leaves no output behind
  sim::Options options = scene.options;
  Progress progress("simulate", options.duration, "s");
  options.progress = [&progress](double t) { progress.update(t); };
  const sim::EstimatedRun er = sim::simulate_to_target(scene.params, loads, scene.initial, options);
  const sim::Result& run = er.run;
  if (!run.status.ok()) throw NumericalError(scene.path, "simulation", run.status.message);
  if (run.rows.empty()) throw NumericalError(scene.path, "simulation", "no output rows");
  const sim::RunChecks checks = sim::check_run(scene.params, loads, run, er.options.rtol, er.options.atol);
  std::optional<sim::RunChecks> twin_checks;
  const std::optional<sim::Result> twin =
      run_twin(scene, loads, er.options, args.twin, &twin_checks);
  const bool twin_ok = twin && twin->status.ok();

  const std::vector<Column> extra = inverse_columns(scene, loads, run.rows);
  SimulationFigures figures;
  figures.trajectory = write_with_plot_copy(out, "trajectory", run.rows, extra);
  if (twin_ok) {
    figures.frictionless = write_with_plot_copy(out, "trajectory_frictionless", twin->rows, {});
  }
  AnimationInput animation;
  animation.title = std::filesystem::path(scene.path).filename().string();
  animation.motion = animation_track(run.rows);
  write_text_file(out.file("animation.html"), animation_html(scene, animation));

  // summary.json: the run's checks and statistics, its estimate, its settings, then the twin
  Json summary = run_json(run, &checks);
  estimate_json(er, &summary);
  settings_json(args, scene, er.options, &summary);
  if (twin) summary.set("frictionless", run_json(*twin, twin_checks ? &*twin_checks : nullptr));
  if (!args.no_plots) {  // figures: not essential, a failure is a warning
    figures.inverse = !extra.empty();
    figures.title = std::filesystem::path(scene.path).filename().string();
    const std::string warning = plot_simulation(out.staging(), figures);
    if (!warning.empty()) warn(warning);
  }
  summary.set("total_wall_time_s",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  write_json_file(out.file("summary.json"), summary);
  finish_run(&out, [&] { print_report(scene, er, checks, twin, twin_checks); });
  // a run whose own checks fail is not ok: its outputs stay for the user to look at
  if (!checks.verdict.ok()) {
    throw NumericalError(scene.path, "simulation", "run check failed: " + checks.verdict.message);
  }
  return 0;
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "simulate");
  add_plots_flag(app, &args->no_plots, "the figures");
  app->add_flag("--twin", args->twin,
                "also run the frictionless twin on runs longer than 20 s (always on shorter runs)");
}

const bool kRegistered = register_command(command_of("simulate", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io
