// fivebar simulate SCENE [--out DIR] [--set KEY=VALUE]... [--no-plots]
// Forward simulation of a scene, with its frictionless twin when the scene has friction, the
// run checks (energy balance, inverse dynamics), trajectory CSVs, summary.json and figures 2-6.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "fivebar/io/command.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {
namespace {

struct Args {
  SceneArgs scene;
  bool no_plots = false;
};

// every file this command may write (a previous run's copies are removed first, see OutputDir)
const std::vector<std::string> kOutputs = {"trajectory.csv",
                                           "trajectory_frictionless.csv",
                                           "summary.json",
                                           "fig2_angles.png",
                                           "fig3_rates.png",
                                           "fig4_accelerations.png",
                                           "fig5_inverse_torques.png",
                                           "fig6_friction_torques.png",
                                           "plots.gnuplot"};

std::string fmt(double x, const char* format = "%.4g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

// the statistics and final energies of one run
Json run_json(const sim::Result& run, const sim::RunChecks* checks) {
  Json j = Json::object();
  j.set("status", run.status.ok() ? "ok" : "failed");
  if (!run.status.ok()) j.set("message", run.status.message);
  j.set("final_time", run.rows.empty() ? 0.0 : run.rows.back().t);
  j.set("rows", static_cast<long>(run.rows.size()));
  if (checks != nullptr) {
    j.set("energy_balance_relative", checks->energy_balance_relative);
    j.set("inverse_dynamics_max_abs_error", checks->inverse_dynamics_max_abs_error);
  }
  j.set("wall_time_s", run.stats.wall_time_s);
  j.set("rhs_evaluations", run.stats.rhs_evaluations);
  j.set("steps", run.stats.steps);
  j.set("friction_events", run.stats.friction_events);
  if (!run.rows.empty()) {
    j.set("E_diss", run.rows.back().E_diss);
    j.set("W_in", run.rows.back().W_in);
    j.set("W_ext", run.rows.back().W_ext);
  }
  return j;
}

int run(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = load_scene(args.scene.scene, args.scene.sets);
  const sim::LoadFunction loads = LoadExpressions(scene).function();
  const bool friction = scene.params.friction.active();
  OutputDir out(args.scene.out, kOutputs);

  // the run itself: a failure leaves no output behind (OutputDir discards the staging directory)
  const sim::Result run = sim::simulate(scene.params, loads, scene.initial, scene.options);
  if (!run.status.ok()) throw NumericalError(scene.path, "simulation", run.status.message);
  if (run.rows.empty()) throw NumericalError(scene.path, "simulation", "no output rows");
  const sim::RunChecks checks = sim::check_run(scene.params, loads, run);

  // the frictionless twin for figures 2-4; its failure is reported but does not fail the run
  std::optional<sim::Result> twin;
  std::optional<sim::RunChecks> twin_checks;
  if (friction) {
    Params<double> frictionless = scene.params;
    frictionless.friction.law = FrictionLaw::kNone;
    twin = sim::simulate(frictionless, loads, scene.initial, scene.options);
    if (twin->status.ok()) {
      twin_checks = sim::check_run(frictionless, loads, *twin);
    } else {
      warn(scene.path + ": frictionless twin: " + twin->status.message +
           " (trajectory_frictionless.csv not written)");
    }
  }
  const bool twin_ok = twin && twin->status.ok();

  // inverse dynamics of the computed motion (figure 5): the torques that reproduce it
  std::vector<sim::Row> inverse;
  const Status inverse_status = sim::inverse_rows(scene.params, loads, run.rows, &inverse);
  const bool have_inverse = inverse_status.ok() && inverse.size() == run.rows.size();
  std::vector<Column> extra;
  if (have_inverse) {
    Column m1{"M1_inverse", {}}, m2{"M2_inverse", {}};
    for (const sim::Row& r : inverse) {
      m1.values.push_back(r.M1);
      m2.values.push_back(r.M2);
    }
    extra = {std::move(m1), std::move(m2)};
  } else {
    warn(scene.path + ": inverse dynamics of the run failed: " + inverse_status.message +
         " (no M1_inverse, M2_inverse columns, no figure 5)");
  }

  write_trajectory_csv(out.file("trajectory.csv"), run.rows, extra);
  if (twin_ok) write_trajectory_csv(out.file("trajectory_frictionless.csv"), twin->rows);

  // summary.json: the run's checks and statistics first, then its settings, then the twin
  Json summary = run_json(run, &checks);
  summary.set("command", "simulate");
  summary.set("scene", scene.path);
  Json sets = Json::array();
  for (const std::string& s : args.scene.sets) sets.push(s);
  summary.set("sets", std::move(sets));
  summary.set("friction_model", friction_law_name(scene.params.friction.law));
  summary.set("integrator", integrator_name(scene.options.method));
  summary.set("rtol", scene.options.rtol);
  summary.set("atol", scene.options.atol);
  summary.set("locate_switches", scene.options.locate_switches);
  summary.set("stick", scene.options.stick);
  summary.set("duration", scene.options.duration);
  summary.set("output_step", scene.options.output_step);
  if (twin) {
    summary.set("frictionless", run_json(*twin, twin_checks ? &*twin_checks : nullptr));
  }

  // figures: not essential, a failure is a warning
  if (!args.no_plots) {
    SimulationFigures figures;
    figures.frictionless = twin_ok ? "trajectory_frictionless.csv" : "";
    figures.inverse = have_inverse;
    figures.title = std::filesystem::path(scene.path).filename().string();
    const std::string warning = plot_simulation(out.staging(), figures);
    if (!warning.empty()) warn(warning);
  }
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  summary.set("total_wall_time_s", total_s);
  write_json_file(out.file("summary.json"), summary);
  const std::vector<std::string> written = out.commit();

  // a few lines for the human at the terminal
  const sim::Row& last = run.rows.back();
  std::cout << "fivebar simulate: " << scene.path << " (friction "
            << friction_law_name(scene.params.friction.law) << "), "
            << integrator_name(scene.options.method) << " rtol " << fmt(scene.options.rtol)
            << " atol " << fmt(scene.options.atol) << "\n"
            << "  t = 0 .. " << fmt(last.t) << " s, " << run.rows.size() << " rows; "
            << run.stats.steps << " steps, " << run.stats.rhs_evaluations << " rhs evaluations, "
            << run.stats.friction_events << " friction events, "
            << fmt(run.stats.wall_time_s, "%.3f") << " s\n"
            << "  energy: W_in " << fmt(last.W_in, "%.6g") << " J, W_ext "
            << fmt(last.W_ext, "%.6g") << " J, E_diss " << fmt(last.E_diss, "%.6g")
            << " J; balance residual " << fmt(checks.energy_balance_relative, "%.2e")
            << " (relative)\n"
            << "  inverse dynamics: max |M - M_input| = "
            << fmt(checks.inverse_dynamics_max_abs_error, "%.2e") << " N m\n";
  if (twin_ok) {
    std::cout << "  frictionless twin: " << twin->stats.steps << " steps, "
              << fmt(twin->stats.wall_time_s, "%.3f") << " s, balance residual "
              << fmt(twin_checks->energy_balance_relative, "%.2e") << "\n";
  }
  std::cout << "  wrote " << out.dir() << "/:";
  for (const std::string& name : written) std::cout << " " << name;
  std::cout << std::endl;
  return 0;
}

RunFunction setup(CLI::App* app) {
  auto args = std::make_shared<Args>();
  add_scene_options(app, &args->scene, "simulate");
  app->add_flag("--no-plots", args->no_plots, "do not draw the figures (gnuplot)");
  return [args] { return run(*args); };
}

const bool kRegistered = register_command(
    {"simulate", "simulate a scene (and its frictionless twin); trajectory, checks, figures 2-6",
     setup});

}  // namespace
}  // namespace fivebar::io
