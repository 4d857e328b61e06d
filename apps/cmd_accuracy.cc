// fivebar accuracy SCENE [--out DIR] [--set ...] [--repeats N] [--tolerances LIST]
//                        [--methods LIST] [--reference CSV]
// Work-precision study: every integrator and friction treatment across tolerances, error against
// the toolkit's own tight reference vs wall time; work_precision.csv, work_precision.png, and the
// recommended default from the Pareto front.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/studies/accuracy.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::accuracy_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "work-precision study: error of every integrator and friction treatment vs time";

struct Args {
  SceneArgs scene;
  int repeats = 3;
  std::vector<double> tolerances;
  std::vector<std::string> methods;
  std::string reference;  ///< an external reference CSV (t, theta1..theta4) to check ours against
  bool no_plots = false;
};

const std::vector<std::string> kOutputs = {"work_precision.csv", "work_precision.png",
                                           "work_precision.gnuplot", "summary.json"};

/// The toolkit's reference against an external CSV: max |d theta| on the times both have.
struct External {
  double difference = 0;
  long times = 0;  ///< times compared
};

External against_external(const std::string& path, const Scene& scene,
                          const std::vector<sim::Row>& rows) {
  const double step = scene.options.output_step;
  const int links = layout_of(scene).links;
  const CsvTable table = read_csv(path, "--reference");
  const int t_col = table.require("t");
  int cols[kLinks];
  for (int k = 0; k < links; ++k) cols[k] = table.require("theta" + std::to_string(k + 1));
  External e;
  for (const auto& r : table.rows) {
    const long i = std::lround(r[t_col] / step);
    if (i < 0 || i >= static_cast<long>(rows.size()) || std::abs(rows[i].t - r[t_col]) > 1e-9) {
      continue;
    }
    ++e.times;
    for (int k = 0; k < links; ++k) {
      e.difference = std::max(e.difference, std::abs(rows[i].theta[k] - r[cols[k]]));
    }
  }
  if (e.times == 0) throw InputError(path, "t", "no time in common with the scene's output grid");
  return e;
}

/// An external reference this many times farther from the toolkit's own than its two
/// integrators are from each other (and above 1e-6 rad) is not a run of the scene
constexpr double kExternalExcess = 1e3;

/// What the comparison with an external reference warns of: a difference the reference's own
/// agreement cannot explain, or fewer than half the output times compared (empty: none).
std::string external_warning(const std::string& path, const External& e,
                             const studies::WorkPrecision& wp) {
  const auto g3 = [](double x) { return format_significant(x, 3); };
  const long rows = static_cast<long>(wp.exact.rows.size());
  if (e.difference > 1e-6 && e.difference > kExternalExcess * wp.exact.self_difference) {
    return path + ": differs from the toolkit's reference by " + g3(e.difference) +
           " rad, whose two integrators agree to " + g3(wp.exact.self_difference) +
           " rad: it is not a run of this scene (or of its mechanism's angles)";
  }
  if (2 * e.times < rows) {
    return path + ": only " + std::to_string(e.times) + " of the scene's " + std::to_string(rows) +
           " output times compared";
  }
  return "";
}

/// The study's options from the command line; throws InputError naming the flag.
studies::WorkPrecisionOptions study_options(const Args& args, const Scene& scene) {
  studies::WorkPrecisionOptions opt;
  if (args.repeats < 1) throw InputError(scene.path, "--repeats", "must be at least 1");
  opt.repeats = args.repeats;
  if (!args.tolerances.empty()) {
    for (double t : args.tolerances) {
      if (!(t > 0.0 && t < 1.0)) {
        throw InputError(scene.path, "--tolerances",
                         format_significant(t, 3) + ": a tolerance must be in (0, 1)");
      }
      // the scene's rtol limit: tighter than rounding, no integrator can be asked for it
      const std::string implausible = limit_problem("simulation.rtol", t);
      if (!implausible.empty()) throw InputError(scene.path, "--tolerances", implausible);
    }
    opt.tolerances = args.tolerances;
  }
  if (!args.methods.empty()) {
    opt.methods.clear();
    for (const std::string& name : args.methods) {
      sim::Method m;
      if (!sim::parse_method(name, &m)) {
        throw InputError(scene.path, "--methods", "unknown integrator '" + name + "'");
      }
      opt.methods.push_back(m);
    }
  }
  if (friction_of(scene).smoothing_velocity > 0.0) {
    opt.regularization_velocity = friction_of(scene).smoothing_velocity;
  }
  return opt;
}

/// work_precision.csv: one row per point.
std::string work_precision_csv(const studies::WorkPrecision& wp) {
  std::string csv = csv_line({"method", "treatment", "tolerance", "status", "error",
                               "error_vs_exact", "wall_time_s", "rhs_evaluations", "steps",
                               "friction_events", "pareto", "message"});
  for (const auto& p : wp.points) {
    csv += csv_line({sim::method_name(p.method), studies::treatment_name(p.treatment),
                     format_grid_value(p.tolerance), p.ok ? "ok" : "failed",
                     format_double(p.error), format_double(p.error_vs_exact),
                     format_double(p.wall_time_s), std::to_string(p.rhs_evaluations),
                     std::to_string(p.steps), std::to_string(p.friction_events),
                     p.pareto ? "1" : "0", csv_quote(p.message)});
  }
  return csv;
}

/// summary.json's recommendations: the fastest Pareto point within each target error.
Json recommendations_json(const studies::WorkPrecision& wp) {
  Json recs = Json::array();
  for (const auto& r : wp.recommendations) {
    Json j = Json::object();
    j.set("target_error", r.target);
    j.set("found", r.found);
    if (r.found) {
      j.set("integrator", sim::method_name(r.point.method));
      j.set("treatment", studies::treatment_name(r.point.treatment));
      j.set("tolerance", r.point.tolerance);
      j.set("error", r.point.error);
      j.set("wall_time_s", r.point.wall_time_s);
    }
    recs.push(std::move(j));
  }
  return recs;
}

/// summary.json: the reference (and its distance to --reference), the regularization's own
/// model error, the recommendations.
Json summary_json(const Args& args, const Scene& scene, const studies::WorkPrecisionOptions& opt,
                  const studies::WorkPrecision& wp, const External& external) {
  Json summary = Json::object();
  summary.set("command", "accuracy");
  summary.set("scene", scene.path);
  Json ref = Json::object();
  ref.set("how", "CVODE Adams and ARKODE Dormand-Prince at rtol = atol = " +
                     format_significant(opt.reference_tolerance, 3) +
                     ", exact sign with located switches; rows of the Adams run");
  ref.set("self_difference", wp.exact.self_difference);
  ref.set("friction_events", wp.exact.stats.friction_events);
  if (!args.reference.empty()) {
    ref.set("external", args.reference);
    ref.set("max_abs_difference_external", external.difference);
    ref.set("external_times_compared", external.times);
    ref.set("external_agrees", external_warning(args.reference, external, wp).empty());
  }
  summary.set("reference", std::move(ref));
  if (!wp.regularized.rows.empty()) {
    summary.set("regularization_velocity", opt.regularization_velocity);
    summary.set("regularized_model_error",
                studies::max_theta_difference(wp.regularized.rows, wp.exact.rows));
  }
  summary.set("recommendations", recommendations_json(wp));
  return summary;
}

/// The console report: the reference's self-difference, the Pareto front, the recommendations.
void print_report(const Args& args, const Scene& scene, const studies::WorkPrecisionOptions& opt,
                  const studies::WorkPrecision& wp, const External& external) {
  const auto g3 = [](double x) { return format_significant(x, 3); };
  std::cout << "fivebar accuracy: " << scene.path << ": " << wp.points.size() << " runs\n"
            << "  reference: Adams vs Dormand-Prince at " << g3(opt.reference_tolerance)
            << " differ by " << g3(wp.exact.self_difference) << " rad";
  if (!args.reference.empty()) {
    std::cout << "; vs " << args.reference << ": " << g3(external.difference) << " rad at "
              << external.times << " times";
  }
  std::cout << "\n  Pareto front (" << studies::treatment_name(wp.points.front().treatment)
            << "):\n";
  for (const auto& p : wp.points) {
    if (!p.pareto) continue;
    std::cout << "    " << sim::method_name(p.method) << " tol " << g3(p.tolerance) << ": error "
              << g3(p.error) << " rad in " << g3(p.wall_time_s * 1e3) << " ms\n";
  }
  for (const auto& r : wp.recommendations) {
    std::cout << "  for " << g3(r.target) << " rad: ";
    if (r.found) {
      std::cout << sim::method_name(r.point.method) << " at rtol = atol = "
                << g3(r.point.tolerance) << " (" << g3(r.point.error) << " rad, "
                << g3(r.point.wall_time_s * 1e3) << " ms)\n";
    } else {
      std::cout << "not reached\n";
    }
  }
}

int run(const Args& args) {
  const Scene scene = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  studies::WorkPrecisionOptions opt = study_options(args, scene);
  OutputDir out(args.scene.out, kOutputs);

  studies::WorkPrecision wp;
  Progress progress("accuracy", 1.0);
  opt.progress = [&progress](int done, int total) { progress.update(double(done) / total); };
  const Status st = with_mechanism(scene, [&](auto mech) {
    using S = decltype(mech);
    return studies::work_precision(S::params(scene), S::loads(LoadExpressions(scene)),
                                   scene.initial, scene.options, opt, &wp);
  });
  if (!st.ok()) throw NumericalError(scene.path, "reference", st.message);

  External external;
  if (!args.reference.empty()) {
    external = against_external(args.reference, scene, wp.exact.rows);
    const std::string w = external_warning(args.reference, external, wp);
    if (!w.empty()) warn(w);
  }
  write_text_file(out.file("work_precision.csv"), work_precision_csv(wp));
  const Json summary = summary_json(args, scene, opt, wp, external);
  if (!args.no_plots) {
    const std::string warning =
        run_gnuplot(out.staging(), "work_precision.gnuplot",
                    work_precision_plot_script(
                        wp, std::filesystem::path(scene.path).filename().string(),
                        gnuplot().terminal));
    if (!warning.empty()) warn(warning);
  }
  write_json_file(out.file("summary.json"), summary);
  return finish_run(&out, [&] { print_report(args, scene, opt, wp, external); });
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "accuracy");
  add_plots_flag(app, &args->no_plots, "work_precision.png");
  app->add_option("--repeats", args->repeats, "runs per point; wall time is their minimum")
      ->default_val(3);
  app->add_option("--tolerances", args->tolerances, "rtol = atol values (default 1e-3 .. 1e-12)")
      ->delimiter(',');
  app->add_option("--methods", args->methods, "integrators (default: all)")->delimiter(',');
  app->add_option("--reference", args->reference,
                  "external reference CSV (t and the link angles theta1..: 4 of a five-bar, 3 of a "
                  "four-bar) to check the toolkit's own against");
}

const bool kRegistered = register_command(command_of("accuracy", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::accuracy_command
