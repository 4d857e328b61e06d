// fivebar simulate SCENE [--out DIR] [--set KEY=VALUE]... [--no-plots]
// Forward simulation of a scene, with its frictionless twin when the scene has friction, the
// run checks (energy balance, inverse dynamics), trajectory CSVs, summary.json, figures 2-6 and
// animation.html.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "fivebar/io/animation.h"
#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/decimate.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/io/simulate_json.h"
#include "fivebar/sim/estimate.h"
#include "fivebar/sim/simulator.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::simulate_command {
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
                                           "trajectory.bin",
                                           "trajectory_frictionless.bin",
                                           "trajectory_plot.bin",
                                           "trajectory_frictionless_plot.bin",
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

// the frictionless twin for figures 2-4; its failure is reported but does not fail the run
template <class Mech>
std::optional<TwinRun> run_twin(const Scene& scene, const typename Mech::Loads& loads,
                                const sim::Options& options, bool forced) {
  if (!friction_of(scene).active()) return std::nullopt;
  if (options.duration > kTwinMaxDuration && !forced) {
    std::cout << "  frictionless twin skipped: runs over "
              << format_printf(kTwinMaxDuration, "%.4g") << " s draw it only with --twin\n";
    return std::nullopt;
  }
  TwinRun twin = frictionless_twin(scene, loads, options);
  if (!twin.run.status.ok()) {
    warn(scene.path + ": frictionless twin: " + twin.run.status.message +
         " (trajectory_frictionless.csv not written)");
  } else if (twin.checks && !twin.checks->verdict.ok()) {
    warn(scene.path + ": frictionless twin: run check failed: " + twin.checks->verdict.message +
         " (summary.json: frictionless.status failed; its rows are written and drawn)");
  }
  return twin;
}

// inverse dynamics of the computed motion (figure 5): the torques that reproduce it
template <class Mech>
std::vector<Column> inverse_columns(const Scene& scene, const typename Mech::Loads& loads,
                                    const std::vector<sim::Row>& rows) {
  std::vector<sim::Row> inverse;
  const Status status = Mech::inverse(scene, loads, rows, &inverse);
  const int drives = Mech::layout().drives;
  if (!status.ok() || inverse.size() != rows.size()) {
    warn(scene.path + ": inverse dynamics of the run failed: " + status.message +
         (drives == 1 ? " (no M1_inverse column, no figure 5)"
                      : " (no M1_inverse, M2_inverse columns, no figure 5)"));
    return {};
  }
  std::vector<Column> out;
  for (int i = 0; i < drives; ++i) {
    out.push_back({"M" + std::to_string(i + 1) + "_inverse", {}});
    for (const sim::Row& r : inverse) out.back().values.push_back(i == 0 ? r.M1 : r.M2);
  }
  return out;
}

// trajectory CSV, and its decimated copy for the figures when it is long; returns the name to plot
std::string write_with_plot_copy(const OutputDir& out, const std::string& name,
                                 const std::vector<sim::Row>& rows,
                                 const std::vector<Column>& extra,
                                 const TrajectoryLayout& layout) {
  write_trajectory_csv(out.file(name + ".csv"), rows, extra, layout);
  if (rows.size() <= kPlotMaxRows) return name + ".csv";
  std::vector<sim::Row> few;
  std::vector<Column> few_extra;
  select_rows(rows, extra, decimation_indices(rows, extra, kPlotBuckets), &few, &few_extra);
  write_trajectory_csv(out.file(name + "_plot.csv"), few, few_extra, layout);
  return name + "_plot.csv";
}

void print_report(const Scene& scene, const sim::EstimatedRun& er, const sim::RunChecks& checks,
                  const std::optional<TwinRun>& twin) {
  const sim::Result& run = er.run;
  const sim::Options& o = er.options;
  const sim::Row& last = run.rows.back();
  const FrictionLaw law = friction_of(scene).law;
  std::cout << "fivebar simulate: " << scene.path << " ("
            << (scene.type == MechanismType::kFourBar ? "four-bar, " : "") << "friction "
            << friction_law_name(law) << "), " << integrator_name(sim::method_of(o, law))
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
            << (er.target_met           ? " (target met)"
                : er.rounding_limited ? " (limited by rounding: a lower bound)"
                                      : "") << "\n";
  if (!er.note.empty()) std::cout << "  note: " << er.note << "\n";
  std::cout << "  energy: W_in " << format_printf(last.W_in, "%.6g") << " J, W_ext "
            << format_printf(last.W_ext, "%.6g") << " J, E_diss "
            << format_printf(last.E_diss, "%.6g") << " J; balance residual "
            << format_printf(checks.energy_balance_relative, "%.2e") << " (relative)\n"
            << "  inverse dynamics: "
            << (std::isnan(checks.inverse_failed_at)
                    ? std::string()
                    : "FAILED at t = " + format_printf(checks.inverse_failed_at, "%.6g") +
                          " s (the error below says why); over the other rows ")
            << "max |M - M_input| = " << format_printf(checks.inverse_dynamics_max_abs_error, "%.2e")
            << " N m; min friction power "
            << (law_descriptor(law).states_per_joint > 0
                    ? std::string("not checked (the bristles store and return energy)")
                    : format_printf(checks.friction_power_min, "%.2e") + " W")
            << "\n";
  if (twin && twin->run.status.ok()) {
    std::cout << "  frictionless twin: " << twin->run.stats.steps << " steps, "
              << format_printf(twin->run.stats.wall_time_s, "%.3f") << " s, balance residual "
              << format_printf(twin->checks->energy_balance_relative, "%.2e") << "\n";
  }
}

// The run of a scene of mechanism Mech: the run and its error estimate (a failure leaves no
// output behind), its checks, the frictionless twin, trajectory CSVs, figures, animation.html
// and summary.json.
template <class Mech>
int run_mechanism(const Args& args, const Scene& scene,
                  std::chrono::steady_clock::time_point start) {
  const typename Mech::Loads loads = Mech::loads(LoadExpressions(scene));
  OutputDir out(args.scene.out, kOutputs);
  sim::Options options = scene.options;
  Progress progress("simulate", options.duration, "s");
  options.progress = [&progress](double t) { progress.update(t); };
  const sim::EstimatedRun er =
      sim::simulate_to_target(Mech::params(scene), loads, scene.initial, options);
  const sim::Result& run = er.run;
  if (!run.status.ok()) throw NumericalError(scene.path, "simulation", run.status.message);
  if (run.rows.empty()) throw NumericalError(scene.path, "simulation", "no output rows");
  const sim::RunChecks checks =
      sim::check_run(Mech::params(scene), loads, run, er.options.rtol, er.options.atol);
  const std::optional<TwinRun> twin = run_twin<Mech>(scene, loads, er.options, args.twin);
  const bool twin_ok = twin && twin->run.status.ok();

  const std::vector<Column> extra = inverse_columns<Mech>(scene, loads, run.rows);
  SimulationFigures figures;
  figures.layout = Mech::layout();
  figures.trajectory = write_with_plot_copy(out, "trajectory", run.rows, extra, figures.layout);
  if (twin_ok) {
    figures.frictionless = write_with_plot_copy(out, "trajectory_frictionless", twin->run.rows,
                                                {}, figures.layout);
  }
  AnimationInput animation;
  animation.title = std::filesystem::path(scene.path).filename().string();
  animation.motion = animation_track(run.rows, figures.layout);
  write_text_file(out.file("animation.html"), animation_html(scene, animation));

  // summary.json: the run's checks and statistics, its estimate, its settings, then the twin
  Json summary =
      simulation_summary_json(scene, args.scene.sets, er, checks, twin ? &*twin : nullptr);
  if (!args.no_plots) {  // figures: not essential, a failure is a warning
    figures.inverse = !extra.empty();
    figures.title = std::filesystem::path(scene.path).filename().string();
    const std::string warning = plot_simulation(out.staging(), figures);
    if (!warning.empty()) warn(warning);
  }
  summary.set("total_wall_time_s",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  write_json_file(out.file("summary.json"), summary);
  finish_run(&out, [&] { print_report(scene, er, checks, twin); });
  // a run whose own checks fail is not ok: its outputs stay for the user to look at
  if (!checks.verdict.ok()) {
    throw NumericalError(scene.path, "simulation", "run check failed: " + checks.verdict.message);
  }
  return 0;
}

int run(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  OutputDir::remove_previous(args.scene.out, kOutputs);  // a refused run leaves none of them
  const Scene scene = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  return with_mechanism(scene, [&](auto mech) {
    return run_mechanism<decltype(mech)>(args, scene, start);
  });
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "simulate");
  add_plots_flag(app, &args->no_plots, "the figures");
  app->add_flag("--twin", args->twin,
                "also run the frictionless twin on runs longer than 20 s (always on shorter runs)");
}

const bool kRegistered = register_command(command_of("simulate", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::simulate_command
