// fivebar.optimize: energy-optimal rest-to-rest trajectories for a tasks file or list.
#include <pybind11/stl.h>

#include <cstdlib>

#include "bindings.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/io/summary_csv.h"
#include "fivebar/io/tasks_file.h"
#include "keywords.h"

namespace fivebar::python {
namespace {

// a summary.csv field as a Python value: an integer, a float, or the text itself
py::object field_value(const std::string& text) {
  if (text.empty()) return py::str(text);
  char* end = nullptr;
  const long long i = std::strtoll(text.c_str(), &end, 10);
  if (*end == '\0') return py::int_(i);
  const double x = std::strtod(text.c_str(), &end);
  if (*end == '\0') return py::float_(x);
  return py::str(text);
}

// the row of summary.csv as a dict, the optimal control points and, when asked, the rows
py::dict task_dict(const PyScene& s, const trajectory::TaskResult& r,
                   const trajectory::BatchOptions& options, bool trajectories) {
  py::dict d;
  const std::vector<std::string>& names = io::summary_columns();
  const std::vector<std::string> fields = io::summary_fields(r);
  for (size_t j = 0; j < names.size(); ++j) d[py::str(names[j])] = field_value(fields[j]);
  d["task"] = r.task;  // text fields as they are (summary.csv quotes the message)
  d["status"] = r.status;
  d["solver_status"] = r.solver_status;
  d["message"] = r.message;
  d["continuation"] = r.continuation;  // "w_s:E;..." of the stages (docs/optimize.md)
  d["refinement"] = r.refinement;
  d["dissipated_energy_exact"] = r.dissipated_energy_exact;
  d["baseline_dissipated_energy_exact"] = r.baseline_dissipated_energy_exact;
  d["x"] = to_array(r.x);
  if (trajectories && r.solved()) {
    std::vector<sim::Row> optimal, baseline;
    const Status st = io::task_rows(s.scene, r, options, &optimal, &baseline);
    if (!st.ok()) throw NumericalError(s.scene.path, r.task, "trajectory rows: " + st.message);
    d["trajectory"] = rows_dict(optimal, io::layout_of(s.scene));
    d["baseline"] = rows_dict(baseline, io::layout_of(s.scene));
  }
  return d;
}

py::dict optimize(const PyScene& s, const std::vector<trajectory::TaskSpec>& tasks,
                  const io::OptimizeSettings& settings, int threads, bool trajectories) {
  const trajectory::BatchOptions options =
      io::batch_options(settings, s.scene.windings, io::layout_of(s.scene).drives);
  std::vector<trajectory::TaskResult> results;
  {
    py::gil_scoped_release release;
    results = trajectory::run_parallel(static_cast<int>(tasks.size()), threads, [&](int i) {
      return io::run_scene_task(s.scene, tasks[i], options);  // (its own load expressions)
    });
  }
  io::add_objective_note(options, &results);
  py::dict d;
  for (const trajectory::TaskResult& r : results) {
    d[py::str(r.task)] = task_dict(s, r, options, trajectories);
  }
  return d;
}

bool four_bar(const PyScene& s) { return s.scene.type == io::MechanismType::kFourBar; }

// the keywords of fivebar.optimize: the options of `fivebar optimize`, with _ for -
const Keywords<io::OptimizeSettings> kOptimizeKeywords = {
    {"method", &io::OptimizeSettings::method},
    {"objective", &io::OptimizeSettings::objective},
    {"regeneration", &io::OptimizeSettings::regeneration},
    {"end_acceleration", &io::OptimizeSettings::end_acceleration},
    {"global_search", &io::OptimizeSettings::global},
    {"starts", &io::OptimizeSettings::starts},
    {"control_points", &io::OptimizeSettings::control_points},
    {"quadrature_points", &io::OptimizeSettings::quadrature_points},
    {"max_evaluations", &io::OptimizeSettings::max_evaluations},
    {"singular_margin", &io::OptimizeSettings::singular_margin},
    {"path_step", &io::OptimizeSettings::path_step},
    {"refine", &io::OptimizeSettings::refine},
    {"continuation", &io::OptimizeSettings::continuation},
    {"refine_tol", &io::OptimizeSettings::refine_tol},
    {"refine_levels", &io::OptimizeSettings::refine_levels},
    {"validate", &io::OptimizeSettings::validate},
};

// the settings of keywords `kw` over the command line's defaults
io::OptimizeSettings settings_of(const py::kwargs& kw) {
  io::OptimizeSettings st = io::optimize_defaults();
  apply_keywords("optimize", kw, kOptimizeKeywords, {"threads", "trajectories"}, &st);
  return st;
}

}  // namespace

void bind_optimize(py::module_& m) {
  m.def(
      "optimize_text",
      [](const PyScene& scene, const std::string& yaml, const py::kwargs& kw) {
        return optimize(scene, io::parse_tasks(yaml, "tasks", four_bar(scene)), settings_of(kw),
                        own_keyword(kw, "threads", 0), own_keyword(kw, "trajectories", true));
      },
      py::arg("scene"), py::arg("tasks_yaml"), "optimize() with the tasks file's YAML text");
  m.def(
      "optimize",
      [](const PyScene& scene, const std::string& tasks, const py::kwargs& kw) {
        return optimize(scene, io::read_tasks(tasks, four_bar(scene)), settings_of(kw),
                        own_keyword(kw, "threads", 0), own_keyword(kw, "trajectories", true));
      },
      py::arg("scene"), py::arg("tasks"),
      ("Optimizes every task of a tasks file (YAML path) for `scene`. Keyword options are those "
       "of `fivebar optimize` with _ for - (global_search is --global), with its defaults, "
       "threads=0 (all cores) and trajectories=True: " +
       keyword_defaults(io::optimize_defaults(), kOptimizeKeywords) +
       ". Returns {task name: dict} with the columns of summary.csv, 'x' (the optimal free "
       "control points) and, for solved tasks with trajectories=True, 'trajectory' and "
       "'baseline' (the minimum-jerk motion), each a dict of arrays keyed by the trajectory.csv "
       "columns.")
          .c_str());
}

}  // namespace fivebar::python
