// fivebar study SCENE --tasks TASKS.yaml --sweep KEY=LO:HI:N [--sweep ...] [--out DIR]
//   [--threads N] [--set KEY=VALUE]... [--method ...] [--global] [--validate] [--no-plots]
// Design study (issue 5): every combination of the swept scene keys is a design; every task is
// optimized for every design and the energies summed. Designs that cannot do a task are marked
// in study.csv, not dropped. Writes study.csv (one row per design), study_tasks.csv (one row per
// design and task), heatmap.png for two sweeps, and prints the best design. Under mpirun the
// (design, task) pairs are split across ranks; rank 0 writes the files.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <unistd.h>

#include "fivebar/io/command.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/distributed.h"
#include "fivebar/trajectory/sweep.h"
#include "fivebar/trajectory/tasks.h"

namespace fivebar::io {
namespace {

using trajectory::TaskResult;

struct Args {
  SceneArgs scene;
  std::string tasks;
  std::vector<std::string> sweeps;
  int threads = 0;
  std::string method = "slsqp";
  bool global = false;
  bool validate = false;
  bool no_plots = false;
};

std::string num(double v) { return format_double(v); }  // shortest round-trip, "nan"

// one design: its scene, or why the scene with its values is unusable
struct Design {
  std::vector<double> values;
  std::optional<Scene> scene;
  std::string error;
};

int run(const Args& args) {
  std::vector<trajectory::Sweep> sweeps;
  for (const std::string& s : args.sweeps) {
    try {
      sweeps.push_back(trajectory::parse_sweep(s));
    } catch (const std::invalid_argument& e) {
      throw InputError("command line", "--sweep " + s, e.what());
    }
  }
  const Scene base = load_scene(args.scene.scene, args.scene.sets);
  std::vector<trajectory::TaskSpec> tasks;
  try {
    tasks = trajectory::load_tasks(args.tasks);
  } catch (const trajectory::TaskFileError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
  trajectory::BatchOptions options;
  if (!trajectory::parse_method(args.method, &options.optimizer.method)) {
    throw InputError("command line", "--method", "'" + args.method + "' is not slsqp, mma or ccsaq");
  }
  options.optimizer.global = args.global;
  options.validate = args.validate;

  // the designs: a scene that cannot close at its initial pose is marked, a bad key is an error
  int count = 0;
  try {
    count = trajectory::design_count(sweeps);
  } catch (const std::invalid_argument& e) {
    throw InputError("command line", "--sweep", e.what());
  }
  std::vector<Design> designs(count);
  for (int d = 0; d < count; ++d) {
    designs[d].values = trajectory::design_values(sweeps, d);
    std::vector<std::string> sets = args.scene.sets;
    for (size_t k = 0; k < sweeps.size(); ++k) {
      sets.push_back(sweeps[k].key + "=" + format_double(designs[d].values[k]));
    }
    try {
      designs[d].scene = load_scene(args.scene.scene, sets);
    } catch (const InputError& e) {
      const bool geometry = e.key().rfind("initial", 0) == 0 ||
                            e.reason().find("assembl") != std::string::npos ||
                            e.reason().find("singular") != std::string::npos;
      if (!geometry) throw InputError(e.file(), "--sweep " + e.key(), e.reason());
      designs[d].error = e.reason();
    }
  }

  // every (design, task) pair, on the threads and across MPI ranks
  const int nt = static_cast<int>(tasks.size());
  const int rank = trajectory::process_rank();
  const bool tty = rank == 0 && isatty(STDERR_FILENO);
  const std::vector<TaskResult> results = trajectory::run_distributed(
      count * nt, args.threads,
      [&](int i) {
        const Design& design = designs[i / nt];
        const trajectory::TaskSpec& task = tasks[i % nt];
        if (!design.scene) {
          TaskResult r;
          r.task = task.name;
          r.status = "design_cannot_assemble";
          r.message = design.error;
          return r;
        }
        const sim::LoadFunction loads = LoadExpressions(*design.scene).function();
        return trajectory::run_task(design.scene->params, loads, task, design.scene->initial,
                                    options);
      },
      [&](int done, int total) {
        if (tty) std::cerr << "\rstudy: " << done << "/" << total << " optimizations" << std::flush;
      });
  if (tty) std::cerr << "\n";
  if (rank != 0) return 0;

  // study.csv: one row per design; study_tasks.csv: one row per design and task
  std::string header = "design";
  for (const auto& s : sweeps) header += "," + s.key;
  std::string study = header + ",status,tasks_ok,total_dissipated_energy,"
                               "total_baseline_dissipated_energy,saving_percent";
  for (const auto& t : tasks) study += ",E_" + t.name;
  for (const auto& t : tasks) study += ",status_" + t.name;
  study += "\n";
  std::string per_task = header + "," + trajectory::csv_line(trajectory::summary_columns());
  int best = -1;
  std::vector<double> totals(count, NAN);
  for (int d = 0; d < count; ++d) {
    std::string values;
    for (double v : designs[d].values) values += "," + format_double(v);
    int ok = 0;
    double total = 0, base_total = 0;
    std::string energies, statuses;
    for (int t = 0; t < nt; ++t) {
      const TaskResult& r = results[d * nt + t];
      if (r.status == "ok") ++ok;
      total += r.dissipated_energy;
      base_total += r.baseline_dissipated_energy;
      energies += "," + num(r.dissipated_energy);
      statuses += "," + r.status;
      per_task += std::to_string(d) + values + "," +
                  trajectory::csv_line(trajectory::summary_fields(r));
    }
    const bool complete = ok == nt;
    if (!complete) total = base_total = NAN;
    totals[d] = total;
    study += std::to_string(d) + values + "," +
             (complete ? std::string("ok")
                       : (designs[d].scene ? "incomplete" : "design_cannot_assemble")) +
             "," + std::to_string(ok) + "," + num(total) + "," + num(base_total) + "," +
             num(100.0 * (1.0 - total / base_total)) + energies + statuses + "\n";
    if (complete && (best < 0 || total < totals[best])) best = d;
  }
  OutputDir out(args.scene.out, {"study.csv", "study_tasks.csv", "heatmap.png", "heatmap.dat",
                                 "heatmap.gnuplot"});
  write_text_file(out.file("study_tasks.csv"), per_task);
  if (sweeps.size() == 2 && !args.no_plots && gnuplot().available) {
    // heatmap of the total energy of the complete designs (blank where a design failed a task)
    std::string dat;
    for (int i = 0; i < sweeps[0].n; ++i) {
      for (int j = 0; j < sweeps[1].n; ++j) {
        const int d = i * sweeps[1].n + j;
        dat += num(sweeps[0].value(i)) + " " + num(sweeps[1].value(j)) + " " + num(totals[d]) +
               "\n";
      }
      dat += "\n";
    }
    write_text_file(out.file("heatmap.dat"), dat);
    const std::string script =
        "set terminal " + gnuplot().terminal + " size 800,650 noenhanced\nset output 'heatmap.png'\n"
        "set title 'total dissipated energy [J] over " + std::to_string(nt) + " tasks'\n"
        "set xlabel '" + sweeps[0].key + "'\nset ylabel '" + sweeps[1].key + "'\n"
        "set datafile missing 'nan'\nset view map\nunset key\n"
        "plot 'heatmap.dat' using 1:2:3 with image\n";
    const std::string warning = run_gnuplot(out.staging(), "heatmap.gnuplot", script);
    if (!warning.empty()) warn(warning);
  }
  write_text_file(out.file("study.csv"), study);
  out.commit();

  // the best design on stdout
  if (best < 0) {
    std::printf("no design completed every task (see study.csv)\n");
  } else {
    std::printf("best design %d:", best);
    for (size_t k = 0; k < sweeps.size(); ++k) {
      std::printf(" %s=%s", sweeps[k].key.c_str(), format_double(designs[best].values[k]).c_str());
    }
    std::printf("  total dissipated energy %.6g J over %d tasks\n", totals[best], nt);
  }
  return 0;
}

RunFunction setup(CLI::App* app) {
  auto args = std::make_shared<Args>();
  add_scene_options(app, &args->scene, "study");
  app->add_option("--tasks", args->tasks, "tasks file (YAML, docs/formats.md)")->required();
  app->add_option("--sweep", args->sweeps, "KEY=LO:HI:N, a scene key swept over N values")
      ->required();
  app->add_option("--threads", args->threads, "worker threads (default: all cores)");
  app->add_option("--method", args->method, "NLopt algorithm: slsqp (default), mma, ccsaq");
  app->add_flag("--global", args->global, "multi-start optimization of every task");
  app->add_flag("--validate", args->validate,
                "simulate the optimal torques forward (miss_distance in study_tasks.csv)");
  app->add_flag("--no-plots", args->no_plots, "do not draw the heatmap");
  return [args] { return run(*args); };
}

const bool kRegistered =
    register_command({"study", "design study: optimize every task for a grid of designs", setup});

}  // namespace
}  // namespace fivebar::io
