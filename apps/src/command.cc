#include "fivebar/io/command.h"
#include "fivebar/io/output.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"

namespace fivebar::io {
namespace {

// constructed on first use, so that registration from any translation unit's static
// initializers is safe
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

}  // namespace

bool register_command(Command command) {
  registry().push_back(std::move(command));
  return true;
}

std::vector<Command> registered_commands() {
  std::vector<Command> commands = registry();
  std::sort(commands.begin(), commands.end(),
            [](const Command& a, const Command& b) { return a.name < b.name; });
  return commands;
}

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

void print_written(const std::string& dir, const std::vector<std::string>& names) {
  std::cout << "  wrote " << dir << "/:";
  for (const std::string& name : names) std::cout << " " << name;
  std::cout << std::endl;
}

int finish_run(OutputDir* out, const std::function<void()>& report) {
  const std::vector<std::string> written = out->commit();
  report();
  print_written(out->dir(), written);
  return 0;
}

void warn(const std::string& message) { std::cerr << "fivebar: warning: " << message << "\n"; }

namespace {
double seconds_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
}  // namespace

Progress::Progress(std::string label, double total, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), total_(total), start_(seconds_now()),
      terminal_(::isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() {
  if (shown_) std::cerr << "\r\033[K" << std::flush;
}

void Progress::update(double done) {
  if (!terminal_) return;
  const double now = seconds_now();
  if (now - start_ < 2.0 || now - last_ < 0.25) return;
  last_ = now;
  shown_ = true;
  const double pct = total_ > 0 ? 100.0 * done / total_ : 0.0;
  char buf[160];
  std::snprintf(buf, sizeof buf, "\r\033[K%s: %3.0f%% (%.4g / %.4g%s%s)", label_.c_str(), pct,
                done, total_, unit_.empty() ? "" : " ", unit_.c_str());
  std::cerr << buf << std::flush;
}

}  // namespace fivebar::io
