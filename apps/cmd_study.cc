// fivebar study SCENE --tasks TASKS.yaml --sweep KEY=LO:HI:N [--sweep ...] [--out DIR]
//   [--threads N] [--set KEY=VALUE]... [--method ...] [--global] [--validate] [--no-plots]
// Design study: every combination of the swept scene keys is a design; every task is
// optimized for every design and the energies summed. Designs that cannot do a task are marked
// in study.csv, not dropped. Writes study.csv (one row per design), study_tasks.csv (one row per
// design and task), heatmap.png for two sweeps, and prints the best design. Under mpirun the
// (design, task) pairs are split across ranks; rank 0 writes the files.
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/io/summary_csv.h"
#include "fivebar/trajectory/batch.h"
#include "fivebar/trajectory/distributed.h"
#include "fivebar/trajectory/sweep.h"
#include "fivebar/trajectory/tasks.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::study_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] = "design study: optimize every task for a grid of designs";

using trajectory::TaskResult;

struct Args {
  SceneArgs scene;
  std::string tasks;
  std::vector<std::string> sweeps;
  int threads = 0;
  OptimizeSettings settings;  ///< of the inner solves (see optimize)
  bool no_plots = false;
};

// one design: its scene, or why the scene with its values is unusable
struct Design {
  std::vector<double> values;
  std::optional<Scene> scene;
  std::string error;
};

std::vector<trajectory::Sweep> parse_sweeps(const std::vector<std::string>& texts) {
  std::vector<trajectory::Sweep> sweeps;
  for (const std::string& s : texts) {
    try {
      sweeps.push_back(trajectory::parse_sweep(s));
    } catch (const std::invalid_argument& e) {
      throw InputError("command line", "--sweep " + s, e.what());
    }
  }
  return sweeps;
}

// the designs: a scene that cannot close at its initial pose is marked, a bad key is an error
std::vector<Design> make_designs(const Args& args, const std::vector<trajectory::Sweep>& sweeps) {
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
      designs[d].scene = load_scene(args.scene.scene, sets, /*four_bar_ok=*/true);
    } catch (const InputError& e) {
      // (an unknown key's reason lists the known ones, "assembly" among them: never geometry;
      // nor is a key of the other mechanism, as initial.theta2 on a four-bar)
      const bool geometry = e.reason().find("unknown key") == std::string::npos &&
                            e.reason().find("-bar key") == std::string::npos &&
                            (e.key().rfind("initial", 0) == 0 ||
                             e.reason().find("assembl") != std::string::npos ||
                             e.reason().find("singular") != std::string::npos);
      if (!geometry) throw InputError(e.file(), "--sweep " + e.key(), e.reason());
      designs[d].error = e.reason();
    }
  }
  return designs;
}

// what the study found, per design
struct Outcome {
  std::vector<double> totals;  ///< summed objective (exact law), nan unless every task is ok
  std::vector<std::string> reasons;  ///< "" for complete designs, else why not (per task)
  int best = -1;
};

Outcome summarize(const std::vector<Design>& designs,
                  const std::vector<trajectory::TaskSpec>& tasks,
                  const std::vector<TaskResult>& results, trajectory::Objective objective) {
  const int count = static_cast<int>(designs.size()), nt = static_cast<int>(tasks.size());
  Outcome o;
  o.totals.assign(count, NAN);
  o.reasons.assign(count, "");
  for (int d = 0; d < count; ++d) {
    double total = 0;
    for (int t = 0; t < nt; ++t) {
      const TaskResult& r = results[d * nt + t];
      total += trajectory::objective_value(r, objective);
      if (r.status != "ok") {
        o.reasons[d] += (o.reasons[d].empty() ? "" : " | ") + r.task + ": " + r.status + ": " +
                        r.message;
      }
    }
    if (!o.reasons[d].empty()) continue;
    o.totals[d] = total;
    if (o.best < 0 || total < o.totals[o.best]) o.best = d;
  }
  return o;
}

// study.csv: one row per design, with the reason for designs that cannot do every task
std::string study_csv(const std::vector<trajectory::Sweep>& sweeps,
                      const std::vector<Design>& designs,
                      const std::vector<trajectory::TaskSpec>& tasks,
                      const std::vector<TaskResult>& results, const Outcome& o) {
  const int nt = static_cast<int>(tasks.size());
  std::string csv = "design";
  for (const auto& s : sweeps) csv += "," + s.key;
  csv += ",status,tasks_ok,total_dissipated_energy,total_baseline_dissipated_energy,"
         "saving_percent";
  for (const auto& t : tasks) csv += ",E_" + t.name;
  for (const auto& t : tasks) csv += ",status_" + t.name;
  csv += ",best,reason,total_objective\n";
  for (size_t d = 0; d < designs.size(); ++d) {
    std::string values, energies, statuses;
    for (double v : designs[d].values) values += "," + format_double(v);
    int ok = 0;
    double base_total = 0, total = 0;
    for (int t = 0; t < nt; ++t) {
      const TaskResult& r = results[d * nt + t];
      ok += r.status == "ok";
      total += r.dissipated_energy;
      base_total += r.baseline_dissipated_energy;
      energies += "," + format_double(r.dissipated_energy);
      statuses += "," + r.status;
    }
    const bool complete = o.reasons[d].empty();
    if (!complete) base_total = total = NAN;
    const std::string status =
        complete ? "ok" : (designs[d].scene ? "incomplete" : "design_cannot_assemble");
    csv += std::to_string(d) + values + "," + status + "," + std::to_string(ok) + "," +
           format_double(total) + "," + format_double(base_total) + "," +
           format_double(100.0 * (1.0 - total / base_total)) + energies + statuses + "," +
           (static_cast<int>(d) == o.best ? "1" : "0") + "," + csv_quote(o.reasons[d]) + "," +
           format_double(o.totals[d]) + "\n";
  }
  return csv;
}

std::string per_task_csv(const std::vector<trajectory::Sweep>& sweeps,
                         const std::vector<Design>& designs, int nt,
                         const std::vector<TaskResult>& results) {
  std::string header = "design";
  for (const auto& s : sweeps) header += "," + s.key;
  std::string csv = header + "," + csv_line(summary_columns());
  for (size_t d = 0; d < designs.size(); ++d) {
    std::string values;
    for (double v : designs[d].values) values += "," + format_double(v);
    for (int t = 0; t < nt; ++t) {
      csv += std::to_string(d) + values + "," +
             csv_line(summary_fields(results[d * nt + t]));
    }
  }
  return csv;
}

// heatmap.png of a two-key study: energies, designs that cannot do every task hatched grey,
// the best design marked. Returns "" or a warning.
std::string draw_heatmap(OutputDir* out, const std::vector<trajectory::Sweep>& sweeps,
                         const std::vector<Design>& designs, const Outcome& o, int nt) {
  std::string dat, bad;
  for (int i = 0; i < sweeps[0].n; ++i) {
    for (int j = 0; j < sweeps[1].n; ++j) {
      const int d = i * sweeps[1].n + j;
      // gnuplot's `with image` wants evenly spaced coordinates: 10 digits drop the rounding
      // noise of lo + (hi - lo) i / (n - 1)
      const std::string xy = format_significant(sweeps[0].value(i), 10) + " " +
                             format_significant(sweeps[1].value(j), 10);
      dat += xy + " " + format_double(o.totals[d]) + "\n";
      if (!o.reasons[d].empty()) bad += xy + "\n";
    }
    dat += "\n";
  }
  write_text_file(out->file("heatmap.dat"), dat);
  StudyHeatmap h;
  if (!bad.empty()) {
    write_text_file(out->file("heatmap_infeasible.dat"), bad);
    h.infeasible = "heatmap_infeasible.dat";
  }
  auto cell = [](const trajectory::Sweep& s) { return s.n > 1 ? (s.hi - s.lo) / (s.n - 1) : 1.0; };
  h.cell_x = cell(sweeps[0]);
  h.cell_y = cell(sweeps[1]);
  h.x_lo = sweeps[0].lo;
  h.x_hi = sweeps[0].hi;
  h.y_lo = sweeps[1].lo;
  h.y_hi = sweeps[1].hi;
  h.x_key = sweeps[0].key;
  h.y_key = sweeps[1].key;
  h.title = "total of the objective over " + std::to_string(nt) + (nt == 1 ? " task" : " tasks");
  if (o.best >= 0) {
    h.has_best = true;
    h.best_x = designs[o.best].values[0];
    h.best_y = designs[o.best].values[1];
  }
  return run_gnuplot(out->staging(), "heatmap.gnuplot",
                     study_heatmap_script(h, gnuplot().terminal));
}

// the swept keys on whose range's edge the best design lies (none without a best design)
std::vector<BoundHit> best_on_bound(const std::vector<trajectory::Sweep>& sweeps,
                                    const std::vector<Design>& designs, const Outcome& o) {
  if (o.best < 0) return {};
  std::vector<std::string> keys;
  std::vector<double> lo, hi;
  for (const trajectory::Sweep& s : sweeps) {
    keys.push_back(s.key);
    lo.push_back(s.lo);
    hi.push_back(s.hi);
  }
  return bounds_hit(keys, designs[o.best].values, lo, hi);
}

// study.json: the objective, the best design (index, values, total) and the bounds it lies on
Json study_json(const std::vector<trajectory::Sweep>& sweeps, const std::vector<Design>& designs,
                const Outcome& o, trajectory::Objective objective) {
  Json j = Json::object();
  j.set("objective", std::string(trajectory::objective_name(objective)));
  j.set("best", o.best);
  Json values = Json::object();
  for (size_t k = 0; k < sweeps.size() && o.best >= 0; ++k) {
    values.set(sweeps[k].key, designs[o.best].values[k]);
  }
  j.set("values", values);
  j.set("total_objective", o.best >= 0 ? o.totals[o.best] : NAN);
  j.set("on_bound", Json::array_of(best_on_bound(sweeps, designs, o), [](const BoundHit& h) {
          return Json::object({{"key", h.key}, {"side", h.side}, {"bound", h.bound}});
        }));
  return j;
}

// stdout: the best design, and how many designs could not do every task, and why
void report(const std::vector<trajectory::Sweep>& sweeps, const std::vector<Design>& designs,
            const std::vector<trajectory::TaskSpec>& tasks,
            const std::vector<TaskResult>& results, const Outcome& o,
            trajectory::Objective objective) {
  const int count = static_cast<int>(designs.size()), nt = static_cast<int>(tasks.size());
  int infeasible = 0;
  std::map<std::string, int> why;  // "task: status" -> designs
  for (int d = 0; d < count; ++d) {
    if (o.reasons[d].empty()) continue;
    ++infeasible;
    for (int t = 0; t < nt; ++t) {
      const TaskResult& r = results[d * nt + t];
      if (r.status != "ok") ++why[r.task + ": " + r.status];
    }
  }
  if (o.best < 0) {
    std::printf("no design completed every task (see study.csv)\n");
  } else {
    std::printf("best design %d:", o.best);
    for (size_t k = 0; k < sweeps.size(); ++k) {
      std::printf(" %s=%s", sweeps[k].key.c_str(),
                  format_double(designs[o.best].values[k]).c_str());
    }
    std::printf("  sum of %s %.6g J over %d tasks\n", trajectory::objective_name(objective),
                o.totals[o.best], nt);
    std::printf("%s", bounds_advice(best_on_bound(sweeps, designs, o)).c_str());
  }
  std::printf("%d of %d designs cannot do every task%s\n", infeasible, count,
              infeasible ? " (reason per design in study.csv):" : "");
  for (const auto& [reason, n] : why) std::printf("  %-45s %d designs\n", reason.c_str(), n);
}

int run(const Args& args) {
  const std::vector<trajectory::Sweep> sweeps = parse_sweeps(args.sweeps);
  // bad input in the base scene: exit 2 here
  const Scene base = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  const std::vector<trajectory::TaskSpec> tasks =
      read_tasks(args.tasks, base.type == MechanismType::kFourBar);
  const trajectory::BatchOptions options =
      batch_options(args.settings, base.windings, layout_of(base).drives);
  const std::vector<Design> designs = make_designs(args, sweeps);
  const int count = static_cast<int>(designs.size());

  // every (design, task) pair, on the threads and across MPI ranks; progress on stderr
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
        return run_scene_task(*design.scene, task, with_windings(options, design.scene->windings));
      },
      [&](int done, int total) {
        if (tty) std::cerr << "\rstudy: " << done << "/" << total << " optimizations" << std::flush;
      });
  if (tty) std::cerr << "\n";
  if (rank != 0) return 0;

  const Outcome outcome = summarize(designs, tasks, results, options.problem.objective);
  OutputDir out(args.scene.out, {"study.csv", "study.json", "study_tasks.csv", "heatmap.png",
                                 "heatmap.dat",
                                 "heatmap_infeasible.dat", "heatmap.gnuplot"});
  write_text_file(out.file("study_tasks.csv"), per_task_csv(sweeps, designs, nt, results));
  if (sweeps.size() == 2 && !args.no_plots && gnuplot().available) {
    const std::string warning = draw_heatmap(&out, sweeps, designs, outcome, nt);
    if (!warning.empty()) warn(warning);
  }
  write_json_file(out.file("study.json"),
                  study_json(sweeps, designs, outcome, options.problem.objective));
  write_text_file(out.file("study.csv"), study_csv(sweeps, designs, tasks, results, outcome));
  return finish_run(&out, [&] {
    report(sweeps, designs, tasks, results, outcome, options.problem.objective);
  });
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "study");
  add_plots_flag(app, &args->no_plots, "the heatmap");
  app->add_option("--tasks", args->tasks, "tasks file (YAML, docs/formats.md)")->required();
  app->add_option("--sweep", args->sweeps, "KEY=LO:HI:N, a scene key swept over N values")
      ->required();
  app->add_option("--threads", args->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  add_inner_solve_options(app, &args->settings);
  app->add_flag("--global", args->settings.global, "multi-start optimization of every task");
  app->add_flag("--validate", args->settings.validate,
                "simulate the optimal torques forward (miss_distance in study_tasks.csv)");
}

const bool kRegistered = register_command(command_of("study", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::study_command
