// fivebar optimize SCENE --tasks TASKS.yaml [--out DIR] [--threads N] [--set KEY=VALUE]...
//   [--method slsqp|mma|ccsaq] [--global] [--starts N]
//   [--objective total_dissipation|supply_energy|dissipated_energy|input_energy]
//   [--regeneration none|shared_bus] [--end-acceleration free|zero]
//   [--control-points N] [--quadrature-points N] [--singular-margin M] [--no-validate] [--no-plots]
// Energy-optimal rest-to-rest trajectories for every task of a tasks file:
// summary.csv (one row per task, the minimum-jerk baseline beside each result), per task
// DIR/<task>/trajectory.csv, baseline.csv, animation.html and figures. Under mpirun the tasks are
// split across ranks and rank 0 writes the same files as a one-process run. A four-bar scene
// (mechanism.type four_bar) is optimized on its crank angle (docs/optimize.md, "The four-bar").
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "fivebar/io/animation.h"
#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/io/summary_csv.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/distributed.h"
#include "fivebar/trajectory/four_bar_tasks.h"
#include "fivebar/trajectory/tasks.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::optimize_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] = "minimum-dissipation trajectories for a tasks file";

namespace fs = std::filesystem;
using trajectory::TaskResult;

struct Args {
  SceneArgs scene;
  std::string tasks;
  int threads = 0;
  OptimizeSettings settings;  // everything that reaches the optimizer itself
  bool no_validate = false, no_plots = false;
};

// the point whose path the figures draw: the five-bar's C, the four-bar's coupler point P
const char* point_name(const Scene& scene) {
  return scene.type == MechanismType::kFourBar ? "P" : "C";
}

// x and y of that point for each row (extra trajectory.csv columns x_C, y_C or x_P, y_P, for the
// path figure), from the model's loop closure; nan where a row's pose cannot close
std::vector<Column> point_columns(const Scene& scene, const std::vector<sim::Row>& rows) {
  const std::string name = point_name(scene);
  Column x{"x_" + name, {}}, y{"y_" + name, {}};
  for (const sim::Row& r : rows) {
    std::array<double, 2> c{NAN, NAN};  // left so when the pose cannot close
    if (scene.type == MechanismType::kFourBar) {
      trajectory::four_bar_point_p(scene.four_bar, r.theta[0], &c);
    } else {
      trajectory::point_c(scene.params, r.theta[0], r.theta[1], &c);
    }
    x.values.push_back(c[0]);
    y.values.push_back(c[1]);
  }
  return {x, y};
}

// the point's columns and then the rest rule's (the ends of a rest-to-rest motion are held:
// docs/hold.md)
std::vector<Column> extra_columns(const Scene& scene, const std::vector<sim::Row>& rows) {
  std::vector<Column> columns = point_columns(scene, rows);
  for (Column& c : rest_columns(rows, layout_of(scene))) columns.push_back(std::move(c));
  return columns;
}

// writes `path` through a temporary name in the same directory, then renames it
template <typename Write>
void write_atomic(const fs::path& path, Write&& write) {
  const fs::path tmp = path.parent_path() / ("." + path.filename().string() + ".partial");
  write(tmp.string());
  fs::rename(tmp, path);
}

// `point`: C or P (point_name); `drives`: the motors whose torques are drawn (M1, M2 or M1)
std::string plot_script(const std::string& task, double limit, const std::string& terminal,
                        bool baseline, const std::string& point, int drives) {
  const std::string xp = "'x_" + point + "'", yp = "'y_" + point + "'";
  // the minimum-jerk curve beside each optimal one, when the baseline closes
  auto with_baseline = [&](const std::string& column, const std::string& title,
                           const std::string& colour) {
    return baseline ? ", 'baseline.csv' using " + column + " with lines dt 2 lc rgb '" + colour +
                          "' title '" + title + "'"
                    : std::string();
  };
  // each figure sets its title, labels, key and ranges after its `set output` (the figures are
  // drawn at once by two gnuplot processes, see run_gnuplot)
  std::string s = "set datafile separator ','\nset terminal " + terminal +
                  " size 900,600 noenhanced\nset key autotitle columnhead\nset grid\n";
  // the path in true proportions, in a square box around it (a short path along one axis would
  // otherwise be squeezed into a strip)
  s += "set output 'path_" + point +
       ".png'\n"
       "stats 'trajectory.csv' using " +
       xp + ":" + yp +
       " nooutput\n"
       "span = 0.6 * (STATS_max_x - STATS_min_x > STATS_max_y - STATS_min_y ? "
       "STATS_max_x - STATS_min_x : STATS_max_y - STATS_min_y) + 1e-3\n"
       "cx = (STATS_max_x + STATS_min_x) / 2\ncy = (STATS_max_y + STATS_min_y) / 2\n"
       "last = STATS_records - 1\n"
       "set xrange [cx - span:cx + span]\nset yrange [cy - span:cy + span]\n";
  s += "set title '" + task + ": path of " + point +
       "'\nset size ratio -1\n"
       "set xlabel 'x [m]'\nset ylabel 'y [m]'\n"
       "set key outside right top\n"
       "plot 'trajectory.csv' using " +
       xp + ":" + yp + " with lines lw 2 lc rgb '#1f5fa8' title 'optimal'" +
       with_baseline(xp + ":" + yp, "minimum jerk", "#777777") +
       // the ends: the first and the last row
       ", 'trajectory.csv' using ($0 == 0 ? column(" + xp + ") : NaN):" + yp +
       " with points pt 7 ps 2.5 lc 'dark-green' title 'start', 'trajectory.csv' using ($0 == "
       "last ? column(" +
       xp + ") : NaN):" + yp +
       " with points pt 5 ps 2.5 lc 'black' title "
       "'goal'"
       "\nset size noratio\nset autoscale xy\n";
  // the key beside the plot: the torques fill the band between the limits; room above and below,
  // so that the torque limit lines are not drawn on the border
  s += "set output 'torques.png'\nset offsets 0, 0, graph 0.08, graph 0.08\n"
       "set title '" +
       task +
       ": motor torques'\n"
       "set xlabel 't [s]'\nset ylabel 'torque [N m]'\nset key outside right top\n"
       "plot 'trajectory.csv' using 't':'M1' with lines lw 2 lc rgb '#1f5fa8' title 'M1'" +
       (drives > 1 ? std::string(", 'trajectory.csv' using 't':'M2' with lines lw 2 lc rgb "
                                 "'#d62728' title 'M2'")
                   : std::string()) +
       with_baseline("'t':'M1'", "M1 minimum jerk", "#1f5fa8") +
       (drives > 1 ? with_baseline("'t':'M2'", "M2 minimum jerk", "#d62728") : std::string());
  if (std::isfinite(limit)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", limit);
    s += std::string(", ") + buf + " dt 3 lc 'black' title 'limit', -" + buf +
         " dt 3 lc 'black' notitle";
  }
  s += "\nset output 'energy.png'\nset offsets 0, 0, 0, 0\nset title '" + task +
       ": dissipated energy'\nset xlabel 't [s]'\nset ylabel 'E_diss [J]'\n"
       "set key outside right top\n"
       "plot 'trajectory.csv' using 't':'E_diss' with lines lw 2 lc rgb '#1f5fa8' title 'optimal'" +
       with_baseline("'t':'E_diss'", "minimum jerk", "#777777") + "\n";
  return s;
}

// trajectory.csv, baseline.csv (when the baseline closes), animation.html and the figures of one
// solved task, in DIR/<task>/
std::string write_task(const fs::path& dir, const Scene& scene, const TaskResult& r,
                       const trajectory::BatchOptions& options, bool plots) {
  std::vector<sim::Row> rows, base;
  const Status status = task_rows(scene, r, options, &rows, &base);
  if (!status.ok()) return r.task + ": trajectory rows: " + status.message;
  const bool baseline = !base.empty();  // empty when the baseline cannot close
  fs::create_directories(dir);
  const TrajectoryLayout layout = layout_of(scene);
  write_atomic(dir / "trajectory.csv", [&](const std::string& p) {
    write_trajectory_csv(p, rows, extra_columns(scene, rows), layout);
  });
  if (baseline) {
    write_atomic(dir / "baseline.csv", [&](const std::string& p) {
      write_trajectory_csv(p, base, extra_columns(scene, base), layout);
    });
  } else {
    fs::remove(dir / "baseline.csv");  // a stale one from an earlier run would mislead
  }
  AnimationInput animation;
  animation.title = r.task + ", " + fs::path(scene.path).filename().string();
  animation.label = "optimal motion";
  animation.motion = animation_track(rows, layout);
  if (baseline) {
    animation.ghost = animation_track(base, layout);
    animation.ghost_label = "minimum jerk (baseline)";
  }
  write_atomic(dir / "animation.html", [&](const std::string& p) {
    write_text_file(p, animation_html(scene, animation));
  });
  if (!plots) return "";
  return run_gnuplot(dir.string(), "plots.gnuplot",
                     plot_script(r.task, r.torque_limit, gnuplot().terminal, baseline,
                                 point_name(scene), layout.drives),
                     Figures::kStandAlone);
}

// one line per task on stdout; under it, the reason when the task did not end ok, and a note
// when it did but its refinement ran out of levels before the energy settled; the number of
// tasks that ended ok
int report(const std::vector<TaskResult>& results, const trajectory::BatchOptions& options,
           int motors) {
  const double refine_tol = options.refine.tol;
  const std::string note = objective_note(options, motors);
  std::printf("objective: %s\n", trajectory::objective_name(options.problem.objective));
  if (!note.empty()) std::printf("note: %s\n", note.c_str());
  int ok = 0;
  for (const TaskResult& r : results) {
    std::printf("%-20s %-22s objective %.7g J  E_diss %.6g J  winding %.6g J  baseline E_diss "
                "%.6g J  peak %.4g N m  miss %.3g m  %.3f s\n",
                r.task.c_str(), r.status.c_str(), r.objective, r.dissipated_energy,
                r.winding_heat, r.baseline_dissipated_energy, r.peak_torque, r.miss_distance,
                r.wall_time_s);
    if (r.status != "ok") {
      std::printf("  %s: %s\n", r.task.c_str(), r.message.c_str());
      continue;
    }
    ++ok;
    if (r.refinement_limited) {
      std::printf("  %s: note: discretization not shown converged, the finest level stopped at "
                  "its evaluation limit (%s); raise --max-evaluations\n",
                  r.task.c_str(), r.refinement.c_str());
    } else if (r.discretization_unsettled(refine_tol)) {
      std::printf("  %s: note: discretization not converged, the energy changed %.2g%% at the "
                  "last refinement (%s); add a finer level with --refine-levels\n",
                  r.task.c_str(), 100.0 * r.refinement_change, r.refinement.c_str());
    }
  }
  return ok;
}

// resolution statuses: the task cannot be done by this design (bad input rather than numerics)
bool input_failure(const TaskResult& r) {
  return r.control_points == 0 || r.status == "unreachable";
}

int run(const Args& args) {
  const Scene scene = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  const bool four_bar = scene.type == MechanismType::kFourBar;
  const std::vector<trajectory::TaskSpec> tasks = read_tasks(args.tasks, four_bar);
  OptimizeSettings settings = args.settings;
  settings.validate = !args.no_validate;
  const trajectory::BatchOptions options =
      batch_options(settings, scene.windings, layout_of(scene).drives);
  const int rank = trajectory::process_rank();
  const bool tty = rank == 0 && isatty(STDERR_FILENO);

  // every task on the pool of threads (and across MPI ranks); a result depends only on its task
  const int n = static_cast<int>(tasks.size());
  const std::vector<TaskResult> solved = trajectory::run_distributed(
      n, args.threads,
      [&](int i) { return run_scene_task(scene, tasks[i], options); },
      [&](int done, int count) {
        if (tty) std::cerr << "\roptimize: " << done << "/" << count << " tasks" << std::flush;
      });
  if (tty) std::cerr << "\n";
  if (rank != 0) return 0;
  std::vector<TaskResult> results = solved;
  const int motors = layout_of(scene).drives;
  add_objective_note(options, &results, motors);

  // per-task files first, summary.csv last (its presence marks a complete run)
  OutputDir out(args.scene.out, {"summary.csv"});
  for (const TaskResult& r : results) {
    if (!r.solved()) continue;
    const std::string warning = write_task(fs::path(args.scene.out) / r.task, scene, r, options,
                                           !args.no_plots && gnuplot().available);
    if (!warning.empty()) warn(warning);
  }
  std::string csv = csv_line(summary_columns());
  for (const TaskResult& r : results) csv += csv_line(summary_fields(r));
  write_text_file(out.file("summary.csv"), csv);
  // one line per task on stdout; exit non-zero when no task ended ok (outputs kept: they say why)
  int ok = 0;
  finish_run(&out, [&] { ok = report(results, options, motors); });
  if (ok == 0 && !results.empty()) {
    const std::string why = "every task failed (" + std::to_string(results.size()) +
                            "; reasons on stdout and in summary.csv)";
    const bool input = std::all_of(results.begin(), results.end(), input_failure);
    if (input) throw InputError(args.tasks, "tasks", why);
    throw NumericalError(args.tasks, "tasks", why);
  }
  return 0;
}

void add_options(CLI::App* app, Args* args) {
  args->settings = optimize_defaults();  // the refinement on (--no-refine)
  add_scene_options(app, &args->scene, "optimize");
  add_plots_flag(app, &args->no_plots, "the figures");
  app->add_option("--tasks", args->tasks, "tasks file (YAML, docs/formats.md)")->required();
  app->add_option("--threads", args->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  const OptimizeSettings& d = args->settings;  // the defaults, in the help texts
  const auto dflt = [](double v) { return "(default " + format_double(v) + ")"; };
  app->add_option("--node-threads", args->settings.node_threads,
                  "threads of each evaluation inside a task (default " +
                      std::to_string(d.node_threads) + "; same results)");
  app->add_option("--method", args->settings.method,
                  "NLopt algorithm: slsqp, mma, ccsaq (default " + d.method + ")");
  add_objective_options(app, &args->settings);
  app->add_flag("--global", args->settings.global,
                "multi-start: the local method from seeded perturbed starts too, best kept");
  app->add_option("--starts", args->settings.starts, "starts of --global " + dflt(d.starts));
  app->add_option("--control-points", args->settings.control_points,
                  "B-spline control points per joint (default " +
                      std::to_string(d.control_points) + ", " +
                      std::to_string(d.control_points - 6) + " free)");
  app->add_option("--quadrature-points", args->settings.quadrature_points,
                  "Gauss-Legendre points per knot span " + dflt(d.quadrature_points));
  app->add_option("--singular-margin", args->settings.singular_margin,
                  "minimum |sin(theta4 - theta3)| (a four-bar's |sin(theta3 - theta2)|) along "
                  "the motion " + dflt(d.singular_margin));
  app->add_option("--path-step", args->settings.path_step,
                  "grid step [rad] of the path search for a feasible start when the "
                  "minimum-jerk motion cannot close " + dflt(d.path_step));
  app->add_flag("--no-refine", [args](int64_t) { args->settings.refine = false; },
                "no refinement of the control points after the first solve");
  app->add_flag("--no-continuation", [args](int64_t) { args->settings.continuation = false; },
                "no continuation on the smoothing velocity towards the exact law");
  app->add_option("--max-evaluations", args->settings.max_evaluations,
                  "objective evaluations per local solve " + dflt(d.max_evaluations));
  const auto levels = [](const std::vector<int>& v) {
    std::string out;
    for (int n : v) out += (out.empty() ? "" : ",") + std::to_string(n);
    return out;
  };
  app->add_option("--refine-levels", args->settings.refine_levels,
                  "control points per joint of the refinement levels, increasing (default " +
                      levels(trajectory::kSmoothRefineLevels) +
                      " for total_dissipation and supply_energy, else " +
                      levels(trajectory::kRefineLevels) + ")")
      ->delimiter(',');
  app->add_option("--refine-tol", args->settings.refine_tol,
                  "relative objective change that ends the refinement (default " +
                      format_significant(trajectory::kSmoothRefineTol) +
                      " for total_dissipation and supply_energy, else " +
                      format_significant(trajectory::RefineOptions().tol) + ")");
  app->add_flag("--no-validate", args->no_validate,
                "skip the forward simulation of the optimal torques (miss_distance)");
}

const bool kRegistered = register_command(command_of("optimize", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::optimize_command
