// The command line's shared options and checks (cli_options.h).
#include "cli_options.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <sstream>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/scene.h"

namespace fivebar::io {

namespace {
/// the value of a numeric option's text (strtod on the whole text); false when not a number
bool read_number(const std::string& text, double* v) {
  char* end = nullptr;
  *v = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size();
}

CLI::Validator range_check(std::function<bool(double)> ok, std::string rule) {
  return CLI::Validator(
      [ok, rule](std::string& text) -> std::string {
        double v = 0;
        if (!read_number(text, &v) || ok(v)) return "";
        return "must be " + rule + ", got " + text;
      },
      "");
}
}  // namespace

void check_numbers(const CLI::App& app) {
  // no quantity of the toolkit's options comes near this (a 64-bit seed is below 2e19)
  constexpr double kLargest = 1e20;
  for (const CLI::Option* o : app.get_options()) {
    const bool no_limit = o->get_default_str() == "inf";  // inf and huge values: no limit
    for (const std::string& result : o->results()) {
      std::stringstream parts(result);
      std::string part;
      while (std::getline(parts, part, ',')) {
        double v = 0;
        if (!read_number(part, &v) || (!std::isnan(v) && no_limit)) continue;
        if (std::isnan(v) || std::isinf(v)) {
          throw InputError("command line", o->get_name(), "must be a finite number, got " + part);
        }
        if (std::abs(v) > kLargest) {
          throw InputError("command line", o->get_name(),
                           "must be at most 1e20 in magnitude, got " + part);
        }
      }
    }
  }
}

namespace {
/// Whether a list's text has an empty field: a leading or trailing comma, two in a row, or
/// only spaces between two
bool empty_field(const std::string& list) {
  std::stringstream fields(list + ",");  // (getline drops a last empty field)
  std::string field;
  while (std::getline(fields, field, ',')) {
    if (trim(field).empty()) return true;
  }
  return list.empty();
}
}  // namespace

void trim_list_values(CLI::App* sub) {
  for (CLI::Option* o : sub->get_options()) {
    if (o->get_delimiter() == ',') o->transform([](const std::string& v) { return trim(v); });
  }
}

void check_list_fields(const CLI::App& sub, int argc, const char* const* argv) {
  const CLI::Option* list = nullptr;  // the list option whose values follow, if any
  std::string joined;                 // its values so far, as one list
  const auto check = [&] {
    if (list && empty_field(joined)) {
      throw InputError("command line", list->get_name(),
                       "an empty value in '" + joined + "' (a list is values separated by commas)");
    }
  };
  for (int i = 2; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0) {
      check();
      const size_t eq = arg.find('=');
      const CLI::Option* o = sub.get_option_no_throw(arg.substr(0, eq));
      list = o && o->get_delimiter() == ',' ? o : nullptr;
      joined.clear();
      if (!list || eq == std::string::npos) continue;
      arg = arg.substr(eq + 1);
    } else if (!list) {
      continue;
    }
    if (arg.empty()) {
      joined += ",";  // an empty argument: an empty field wherever it stands
      arg = ",";
    }
    // values given as separate arguments are one list ("0.1," "0.2" is 0.1,0.2)
    const bool joins = joined.empty() || joined.back() == ',' || arg.front() == ',';
    joined += (joins ? "" : ",") + arg;
  }
  check();
}

CLI::Validator positive_number() {
  return range_check([](double v) { return v > 0; }, "> 0");
}

CLI::Validator nonnegative_number() {
  return range_check([](double v) { return v >= 0; }, ">= 0");
}

CLI::Validator positive_at_most(double limit) {
  return range_check([limit](double v) { return v > 0 && v <= limit; },
                     "> 0 and at most " + format_shortest(limit));
}

CLI::Validator within_scene_limit(const std::string& key) {
  return CLI::Validator(
      [key](std::string& text) -> std::string {
        double v = 0;
        return read_number(text, &v) && std::isfinite(v) ? limit_problem(key, v) : "";
      },
      "");
}

CLI::Validator within_a_turn() {
  return range_check([](double v) { return v >= 0 && v <= 2 * M_PI; },
                     ">= 0 and at most one turn (2 pi = 6.283185 rad)");
}

void add_out_option(CLI::App* app, std::string* out, const std::string& command) {
  *out = "results/" + command;
  app->add_option("--out", *out, "directory that receives every output file")
      ->type_name("DIR")
      ->capture_default_str();
}

void add_scene_options(CLI::App* app, SceneArgs* args, const std::string& command) {
  app->add_option("SCENE", args->scene, "scene file (YAML, see datasets/scenes/)")
      ->type_name("FILE")
      ->required();
  add_out_option(app, &args->out, command);
  app->add_option("--set", args->sets,
                  "override one scene value: dotted key, list elements by 0-based index, e.g. "
                  "--set friction.coulomb=0.2 --set mechanism.links.2.mass=1.5")
      ->type_name("KEY=VALUE")
      ->allow_extra_args(false);  // one KEY=VALUE per --set
}

void add_plots_flag(CLI::App* app, bool* no_plots, const std::string& figures) {
  app->add_flag("--no-plots", *no_plots, "do not draw " + figures + " (PNG, with gnuplot)");
}

void add_objective_options(CLI::App* app, OptimizeSettings* s) {
  app->add_option("--objective", s->objective,
                  "total_dissipation (default when the scene gives the motors' winding data), "
                  "supply_energy, dissipated_energy (default otherwise) or input_energy");
  app->add_option("--regeneration", s->regeneration,
                  "supply_energy: none (default: braking power is lost) or shared_bus (one "
                  "motor's braking feeds the other)");
  app->add_option("--end-acceleration", s->end_acceleration,
                  "free (default) or zero: the accelerations at both ends of a motion");
}

void add_inner_solve_options(CLI::App* app, OptimizeSettings* s) {
  s->refine = false;
  s->continuation = false;
  s->validate = false;
  add_objective_options(app, s);
  app->add_option("--method", s->method,
                  "NLopt algorithm of the inner solves: slsqp, mma, ccsaq (default " + s->method +
                      ")");
  app->add_option("--path-step", s->path_step,
                  "grid step [rad] of the path search (see optimize; default " +
                      format_double(s->path_step) + ")");
  app->add_flag("--continuation", s->continuation,
                "inner solves continue towards the exact friction law (see optimize)");
  app->add_flag("--refine", s->refine,
                "inner solves refine their control points (see optimize; slow)");
}

}  // namespace fivebar::io
