// fivebar design SCENE --tasks TASKS.yaml --vary KEY=LO:HI [--vary ...] [--out DIR]
//   [--threads N] [--set KEY=VALUE]... [--max-designs N] [--method ...] [--continuation]
//   [--refine] [--no-plots]
// Continuous design optimization: the summed minimum dissipated energy over the
// tasks, minimized over the varied scene keys within their bounds. Nested: every design
// evaluation optimizes every task (warm-started from the same task's optimum of the best design
// so far); the outer loop is derivative-free (NLopt BOBYQA, trajectory/design.h). A design that
// cannot do every task gets a penalty and is reported in design_history.csv. Writes
// design.json, scene.yaml (the winning scene), design_history.csv, design_tasks.csv and
// convergence.png. Tasks of one design run on the threads and across MPI ranks; every rank
// runs the same outer loop, rank 0 writes the files.
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <chrono>
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
#include "fivebar/trajectory/design.h"
#include "fivebar/trajectory/distributed.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::design_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] = "continuous design optimization of scene keys over a tasks file";

using trajectory::TaskResult;
const char* const kFlags = "command line";

struct Args {
  SceneArgs scene;
  std::string tasks;
  std::vector<std::string> varies;
  int threads = 0;
  int max_designs = 40;
  OptimizeSettings settings;
  bool no_plots = false;
};

// one --vary KEY=LO:HI
struct Vary {
  std::string key;
  double lo = 0, hi = 0;
};

double parse_bound(const std::string& text, const std::string& what, const std::string& arg) {
  double v = NAN;
  if (!parse_finite(text, &v)) {
    throw InputError(kFlags, "--vary " + arg, what + " '" + text + "' is not a finite number");
  }
  return v;
}

// a design key: a number of the mechanism (lengths, masses, inertias, centres of mass, P)
Vary parse_vary(const std::string& arg) {
  const auto eq = arg.find('='), colon = arg.find(':', eq == std::string::npos ? 0 : eq);
  if (eq == std::string::npos || colon == std::string::npos ||
      arg.find(':', colon + 1) != std::string::npos) {
    throw InputError(kFlags, "--vary " + arg, "expected KEY=LO:HI");
  }
  Vary v;
  v.key = trim(arg.substr(0, eq));
  if (v.key.rfind("mechanism.", 0) != 0 || v.key == "mechanism.assembly") {
    throw InputError(kFlags, "--vary " + arg,
                     "'" + v.key + "' is not a number of the mechanism (design keys: "
                     "mechanism.ground_length, mechanism.point_p, "
                     "mechanism.links.I.{length,mass,inertia,com_offset,com_angle})");
  }
  v.lo = parse_bound(arg.substr(eq + 1, colon - eq - 1), "LO", arg);
  v.hi = parse_bound(arg.substr(colon + 1), "HI", arg);
  if (!(v.lo < v.hi)) {
    throw InputError(kFlags, "--vary " + arg, "LO must be below HI");
  }
  return v;
}

// the scene's own value of a design key (the start of the search, clamped into the bounds)
template <class P>
double mechanism_value(const P& p, const std::string& key, const std::string& arg) {
  if (key == "mechanism.ground_length") return p.ground_length;
  if (key == "mechanism.point_p") return p.point_p;
  const std::string prefix = "mechanism.links.";
  const char last = static_cast<char>('0' + p.links.size() - 1);
  if (key.rfind(prefix, 0) == 0 && key.size() > prefix.size() + 2 &&
      key[prefix.size() + 1] == '.' && key[prefix.size()] >= '0' && key[prefix.size()] <= last) {
    const Link<double>& l = p.links[key[prefix.size()] - '0'];
    const std::string f = key.substr(prefix.size() + 2);
    if (f == "length") return l.length;
    if (f == "mass") return l.mass;
    if (f == "inertia") return l.inertia;
    if (f == "com_offset") return l.com_offset;
    if (f == "com_angle") return l.com_angle;
  }
  throw InputError(kFlags, "--vary " + arg, "'" + key + "' is not a number of the mechanism");
}

// the scene's value of a varied key (its mechanism's: the five-bar's or the four-bar's)
double scene_value(const Scene& s, const std::string& key, const std::string& arg) {
  return s.type == MechanismType::kFourBar ? mechanism_value(s.four_bar, key, arg)
                                           : mechanism_value(s.params, key, arg);
}

// one evaluated design
struct Design {
  std::vector<double> values;
  std::vector<TaskResult> results;  ///< one per task (status design_cannot_assemble if so)
  std::string status;               ///< ok, incomplete, design_cannot_assemble
  double total = NAN;               ///< summed exact-law energy of the tasks that ended ok
  double objective = NAN;           ///< total, or the penalty of a design that fails a task
  int failed = 0;
  std::string reason;
};

class Search {
 public:
  Search(const Args& args, std::vector<Vary> varies, std::vector<trajectory::TaskSpec> tasks,
         trajectory::BatchOptions options)
      : args_(args), varies_(std::move(varies)), tasks_(std::move(tasks)),
        options_(std::move(options)) {}

  std::vector<std::string> sets(const std::vector<double>& values) const {
    std::vector<std::string> s = args_.scene.sets;
    for (size_t k = 0; k < varies_.size(); ++k) {
      s.push_back(varies_[k].key + "=" + format_double(values[k]));
    }
    return s;
  }

  // the tasks of one design, warm-started from the best design so far
  Design evaluate(const std::vector<double>& values, bool warm = true);
  // a design evaluated before (BOBYQA's first point is the start) is not solved again
  double objective(const std::vector<double>& values, bool warm = true) {
    for (const Design& d : history_) {
      if (warm && d.values == values) return d.objective;
    }
    history_.push_back(evaluate(values, warm));
    return history_.back().objective;
  }
  const std::vector<Design>& history() const { return history_; }
  const std::vector<Vary>& varies() const { return varies_; }
  const std::vector<trajectory::TaskSpec>& tasks() const { return tasks_; }
  const trajectory::BatchOptions& options() const { return options_; }
  int best() const;
  double penalty_scale = 1.0;  ///< [J], from the start design

 private:
  std::optional<Scene> scene_of(const std::vector<double>& values, std::string* error) const;
  const Args& args_;
  std::vector<Vary> varies_;
  std::vector<trajectory::TaskSpec> tasks_;
  trajectory::BatchOptions options_;
  std::vector<Design> history_;
};

std::optional<Scene> Search::scene_of(const std::vector<double>& values,
                                      std::string* error) const {
  try {
    return load_scene(args_.scene.scene, sets(values), /*four_bar_ok=*/true);
  } catch (const InputError& e) {
    *error = e.key() + ": " + e.reason();
    return std::nullopt;
  }
}

int Search::best() const {
  int b = -1;
  for (size_t i = 0; i < history_.size(); ++i) {
    if (history_[i].status == "ok" && (b < 0 || history_[i].total < history_[b].total)) {
      b = static_cast<int>(i);
    }
  }
  return b;
}

Design Search::evaluate(const std::vector<double>& values, bool warm_start) {
  Design d;
  d.values = values;
  std::string error;
  const std::optional<Scene> scene = scene_of(values, &error);
  const int nt = static_cast<int>(tasks_.size()), b = warm_start ? best() : -1;
  if (scene) {
    d.results = trajectory::run_distributed(nt, args_.threads, [&](int i) {
      const TaskResult* warm = b >= 0 ? &history_[b].results[i] : nullptr;
      return run_scene_task(*scene, tasks_[i], with_windings(options_, scene->windings), warm);
    });
    trajectory::broadcast_results(&d.results);
  } else {
    d.results.resize(nt);
    for (int i = 0; i < nt; ++i) {
      d.results[i].task = tasks_[i].name;
      d.results[i].status = "design_cannot_assemble";
      d.results[i].message = error;
    }
  }
  d.total = 0;
  for (const TaskResult& r : d.results) {
    if (r.status == "ok") {
      d.total += trajectory::objective_value(r, options_.problem.objective);
    } else {
      ++d.failed;
      d.reason += (d.reason.empty() ? "" : " | ") + r.task + ": " + r.status + ": " + r.message;
    }
  }
  d.status = d.failed == 0 ? "ok" : (scene ? "incomplete" : "design_cannot_assemble");
  if (history_.empty()) {
    // the start design sets the penalty scale: its energies (the baseline's for a failed task)
    double scale = 0;
    for (const TaskResult& r : d.results) {
      scale += r.status == "ok" ? r.dissipated_energy : r.baseline_dissipated_energy;
    }
    penalty_scale = std::isfinite(scale) && scale > 0 ? scale : 1.0;
  }
  // a design that fails a task ranks behind every complete one, the more failures the further
  d.objective = d.failed == 0 ? d.total : penalty_scale * (2.0 + d.failed);
  return d;
}

// design_history.csv: every design evaluated, in order, failures with their reasons
std::string history_csv(const Search& s) {
  std::string csv = "evaluation";
  for (const Vary& v : s.varies()) csv += "," + v.key;
  csv += ",status,tasks_ok,total_energy,objective,best_total_energy";
  for (const auto& t : s.tasks()) csv += ",E_" + t.name;
  csv += ",reason\n";
  double best = NAN;
  for (size_t i = 0; i < s.history().size(); ++i) {
    const Design& d = s.history()[i];
    if (d.status == "ok" && !(d.total >= best)) best = d.total;
    csv += std::to_string(i);
    for (double v : d.values) csv += "," + format_double(v);
    csv += "," + d.status + "," + std::to_string(d.results.size() - d.failed) + "," +
           format_double(d.status == "ok" ? d.total : NAN) + "," + format_double(d.objective) +
           "," + format_double(best);
    for (const TaskResult& r : d.results) csv += "," + format_double(r.dissipated_energy);
    csv += "," + csv_quote(d.reason) + "\n";
  }
  return csv;
}

// design_tasks.csv: the summary.csv row of every (design, task)
std::string tasks_csv(const Search& s) {
  std::string csv = "evaluation";
  for (const Vary& v : s.varies()) csv += "," + v.key;
  csv += "," + csv_line(summary_columns());
  for (size_t i = 0; i < s.history().size(); ++i) {
    std::string values;
    for (double v : s.history()[i].values) values += "," + format_double(v);
    for (const TaskResult& r : s.history()[i].results) {
      csv += std::to_string(i) + values + "," +
             csv_line(summary_fields(r));
    }
  }
  return csv;
}

// the varied keys whose best value lies on a bound of its range
std::vector<BoundHit> on_bound(const Search& s, int best) {
  std::vector<std::string> keys;
  std::vector<double> lo, hi;
  for (const Vary& v : s.varies()) {
    keys.push_back(v.key);
    lo.push_back(v.lo);
    hi.push_back(v.hi);
  }
  return bounds_hit(keys, s.history()[best].values, lo, hi);
}

Json design_json(const Search& s, int best, const trajectory::BoxResult& box, double seconds) {
  Json j = Json::object();
  const Design& d = s.history()[best];
  const Design& start = s.history().front();
  Json values = Json::object(), bounds = Json::object(), start_values = Json::object();
  for (size_t k = 0; k < s.varies().size(); ++k) {
    values.set(s.varies()[k].key, d.values[k]);
    start_values.set(s.varies()[k].key, start.values[k]);
    Json b = Json::array();
    b.push(s.varies()[k].lo);
    b.push(s.varies()[k].hi);
    bounds.set(s.varies()[k].key, b);
  }
  j.set("values", values);
  j.set("total_energy", d.total);
  j.set("tasks", Json::array_of(d.results, [](const TaskResult& r) {
          return Json::object({{"task", r.task},
                               {"status", r.status},
                               {"dissipated_energy", r.dissipated_energy},
                               {"baseline_dissipated_energy", r.baseline_dissipated_energy},
                               {"peak_torque", r.peak_torque},
                               {"min_coupler_sine", r.min_coupler_sine}});
        }));
  j.set("bounds", bounds);
  j.set("on_bound", Json::array_of(on_bound(s, best), [](const BoundHit& h) {
          return Json::object({{"key", h.key}, {"side", h.side}, {"bound", h.bound}});
        }));
  j.set("start_values", start_values);
  j.set("start_total_energy", start.status == "ok" ? start.total : NAN);
  j.set("evaluation", best);
  j.set("designs_evaluated", static_cast<int>(s.history().size()));
  int failed = 0;
  for (const Design& h : s.history()) failed += h.status != "ok";
  j.set("designs_failing_a_task", failed);
  j.set("outer_solver", "nlopt_bobyqa");
  j.set("outer_status", trajectory::outcome_name(box.solver.outcome));
  j.set("outer_message", box.solver.message);
  j.set("wall_time_s", seconds);
  return j;
}

std::string draw_convergence(OutputDir* out, int tasks) {
  const std::string script =
      "# Generated by fivebar design. Redraw with `gnuplot convergence.gnuplot` here.\n"
      "set terminal " + gnuplot().terminal + " size 900,600 noenhanced\n"
      "set output 'convergence.png'\nset datafile separator ','\nset grid\n"
      "set title 'design search: total dissipated energy over " + std::to_string(tasks) +
      " tasks'\nset xlabel 'design evaluated'\nset ylabel 'total dissipated energy [J]'\n"
      "set key top right\nset xrange [-0.5:*]\nset offsets 0, 0.5, graph 0.1, graph 0.1\n"
      "plot 'design_history.csv' using 'evaluation':'total_energy' with points pt 7 ps 1.2 "
      "title 'design (every task ok)', "
      "'' using 'evaluation':'best_total_energy' with steps lw 2 title 'best so far', "
      "'' using 'evaluation':(stringcolumn('status') eq 'ok' ? NaN : "
      "column('best_total_energy')) with points pt 2 ps 1.5 lc 'grey50' "
      "title 'design failing a task (at the best so far)'\n";
  return run_gnuplot(out->staging(), "convergence.gnuplot", script);
}

void report(const Search& s, int best, const trajectory::BoxResult& box) {
  const Design& d = s.history()[best];
  std::printf("best design (evaluation %d of %zu):", best, s.history().size());
  for (size_t k = 0; k < s.varies().size(); ++k) {
    std::printf(" %s=%s", s.varies()[k].key.c_str(), format_double(d.values[k]).c_str());
  }
  std::printf("\n  sum of %s %.6g J over %zu tasks (start %.6g J); outer %s\n",
              trajectory::objective_name(s.options().problem.objective), d.total, d.results.size(), s.history().front().total,
              trajectory::outcome_name(box.solver.outcome));
  std::printf("%s", bounds_advice(on_bound(s, best)).c_str());
  std::map<std::string, int> why;
  int failed = 0;
  for (const Design& h : s.history()) {
    if (h.status == "ok") continue;
    ++failed;
    for (const TaskResult& r : h.results) {
      if (r.status != "ok") ++why[r.task + ": " + r.status];
    }
  }
  std::printf("%d of %zu designs evaluated could not do every task%s\n", failed,
              s.history().size(), failed ? " (reasons in design_history.csv):" : "");
  for (const auto& [reason, n] : why) std::printf("  %-45s %d designs\n", reason.c_str(), n);
}

// the varied keys, their start values (the scene's, clamped into the bounds) and the checks of
// the start design: it must assemble
std::vector<double> start_values(const Args& args, const std::vector<Vary>& varies) {
  const Scene base = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  std::vector<double> x0;
  std::vector<std::string> sets = args.scene.sets;
  for (size_t k = 0; k < varies.size(); ++k) {
    const double v = scene_value(base, varies[k].key, args.varies[k]);
    x0.push_back(std::min(std::max(v, varies[k].lo), varies[k].hi));
    sets.push_back(varies[k].key + "=" + format_double(x0.back()));
  }
  try {
    load_scene(args.scene.scene, sets, /*four_bar_ok=*/true);
  } catch (const InputError& e) {
    throw InputError(kFlags, "--vary",
                     "the start design (the scene's values clamped into the bounds) is unusable: " +
                         e.key() + ": " + e.reason());
  }
  return x0;
}

int write_outputs(const Args& args, const Search& search, const trajectory::BoxResult& box,
                  std::chrono::steady_clock::time_point t0) {
  const int best = search.best();
  OutputDir out(args.scene.out, {"design.json", "scene.yaml", "design_history.csv",
                                 "design_tasks.csv", "convergence.png", "convergence.gnuplot"});
  write_text_file(out.file("design_history.csv"), history_csv(search));
  write_text_file(out.file("design_tasks.csv"), tasks_csv(search));
  if (!args.no_plots && gnuplot().available) {
    const std::string warning = draw_convergence(&out, static_cast<int>(search.tasks().size()));
    if (!warning.empty()) warn(warning);
  }
  if (best < 0) {
    const std::vector<std::string> written = out.commit();
    print_written(out.dir(), written);
    throw NumericalError(args.tasks, "tasks",
                         "no design evaluated could do every task (" +
                             std::to_string(search.history().size()) +
                             " designs; reasons in design_history.csv)");
  }
  Scene scene = load_scene(args.scene.scene, search.sets(search.history()[best].values),
                           /*four_bar_ok=*/true);
  write_text_file(out.file("scene.yaml"), scene_to_yaml(scene));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_json_file(out.file("design.json"), design_json(search, best, box, seconds));
  return finish_run(&out, [&] { report(search, best, box); });
}

int run(const Args& args) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Vary> varies;
  for (const std::string& a : args.varies) {
    varies.push_back(parse_vary(a));
    for (size_t k = 0; k + 1 < varies.size(); ++k) {
      if (varies[k].key == varies.back().key) {
        throw InputError(kFlags, "--vary " + a, "the key is varied twice");
      }
    }
  }
  if (args.max_designs < 2 * static_cast<int>(varies.size()) + 1) {
    throw InputError(kFlags, "--max-designs",
                     "at least 2 k + 1 = " + std::to_string(2 * varies.size() + 1) + " needed");
  }
  const std::vector<double> x0 = start_values(args, varies);
  const Scene base = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  Search search(args, varies, read_tasks(args.tasks, base.type == MechanismType::kFourBar),
                batch_options(args.settings, base.windings, layout_of(base).drives));
  std::vector<double> lo, hi;
  for (const Vary& v : varies) {
    lo.push_back(v.lo);
    hi.push_back(v.hi);
  }
  const bool tty = trajectory::process_rank() == 0 && isatty(STDERR_FILENO);
  search.objective(x0);  // the start design first (BOBYQA may start a little inside the box)
  trajectory::BoxOptions bo;
  bo.max_evaluations = args.max_designs - 1;  // the start design is one
  const trajectory::BoxResult box = trajectory::minimize_box(
      [&](const std::vector<double>& x) {
        const double f = search.objective(x);
        if (tty) {
          std::cerr << "\rdesign: " << search.history().size() << "/" << args.max_designs
                    << " designs" << std::flush;
        }
        return f;
      },
      lo, hi, x0, bo);
  // the best design once more from the cold start of `optimize` (warm starts make the inner
  // optima depend a little on the path): the lower of the two stands
  if (search.best() >= 0) search.objective(search.history()[search.best()].values, false);
  if (tty) std::cerr << "\n";
  if (trajectory::process_rank() != 0) return 0;
  return write_outputs(args, search, box, t0);
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "design");
  add_plots_flag(app, &args->no_plots, "convergence.png");
  app->add_option("--tasks", args->tasks, "tasks file (YAML, docs/formats.md)")->required();
  app->add_option("--vary", args->varies,
                  "KEY=LO:HI, a number of the mechanism varied within [LO, HI]")
      ->required();
  app->add_option("--threads", args->threads, "worker threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  app->add_option("--max-designs", args->max_designs,
                  "designs evaluated at most, the start included (default 40)");
  add_inner_solve_options(app, &args->settings);
}

const bool kRegistered = register_command(command_of("design", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::design_command
