// fivebar stress [--out DIR] [--cases LIST] [--methods LIST] [--budget S] [--reduced]
// The built-in catalogue of stiff and extreme cases, each run with every
// integrator; each run ends `ok`, `rejected` (the exit code and message a user would get) or
// `failed`. Writes DIR/stress.csv and DIR/stress.md; exits 0 with no `failed` row, 3 otherwise.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/output.h"
#include "fivebar/studies/stress.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::stress_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "stiff and extreme cases with every integrator: ok, rejected, never failed";

struct Args {
  std::string out;
  std::vector<std::string> cases;
  std::vector<std::string> methods;
  double budget = 20.0;
  bool reduced = false;
};

const std::vector<std::string> kOutputs = {"stress.csv", "stress.md"};

/// A number column: empty where the value does not exist (negative marks "none").
std::string opt_num(double x, const char* format = "%.3g") {
  return x < 0 ? "" : format_printf(x, format);
}

/// A markdown table cell: pipes escaped, a newline written as a space (one row per line).
std::string md_cell(const std::string& s) {
  std::string out;
  for (char c : s) out += c == '|' ? std::string("\\|") : std::string(1, c == '\n' ? ' ' : c);
  return out;
}

std::string stress_csv(const studies::StressReport& report) {
  std::string csv = csv_line({"case", "integrator", "status", "exit_code", "error",
                               "energy_balance", "wall_time_s", "steps", "rhs_evaluations",
                               "final_time", "displacement", "message"});
  for (const auto& r : report.rows) {
    csv += csv_line({r.case_name, sim::method_name(r.method),
                     studies::stress_outcome_name(r.outcome), std::to_string(r.exit_code),
                     opt_num(r.error, "%.3e"), opt_num(r.energy_balance, "%.3e"),
                     format_printf(r.wall_time_s, "%.4f"), std::to_string(r.steps),
                     std::to_string(r.rhs_evaluations), format_printf(r.final_time, "%.6g"),
                     opt_num(r.displacement, "%.3e"), csv_quote(r.message)});
  }
  return csv;
}

std::string stress_md(const std::vector<studies::StressCase>& cases, const studies::StressReport& report,
                      const studies::StressOptions& opt, double total_s) {
  std::ostringstream s;
  s << "# fivebar stress\n\n"
    << "Runs at rtol = atol = 1e-8 on a 1 ms output grid; `error` is max |d theta_1..4| over the "
       "grid against the case's reference (the same case at rtol = atol = "
    << format_printf(opt.reference_tolerance, "%.3g")
    << " with the integrator named under each case). `ok` also "
       "requires finite rows and an energy balance residual <= "
    << format_printf(opt.max_energy_balance, "%.3g")
    << "; each run is a child process killed after " << format_printf(opt.run_budget_s, "%.3g")
    << " s.\n\n"
    << "**" << report.count(studies::StressOutcome::kOk) << " ok, "
    << report.count(studies::StressOutcome::kRejected) << " rejected, "
    << report.count(studies::StressOutcome::kFailed) << " failed** (" << report.rows.size()
    << " runs, " << format_printf(total_s, "%.1f") << " s)\n";
  for (size_t i = 0; i < cases.size(); ++i) {
    const studies::StressCase& c = cases[i];
    const studies::StressReference& ref = report.references[i];
    s << "\n## " << c.name << "\n\n"
      << c.description << ".\n\nReference: " << sim::method_name(ref.method) << " at "
      << format_printf(ref.tolerance, "%.3g") << ": "
      << (ref.ok ? "ok (" + format_printf(ref.wall_time_s, "%.2f") + " s, " +
                       std::to_string(ref.steps) + " steps)"
                 : "did not finish: " + md_cell(ref.message))
      << ".\n\n"
      << "| integrator | status | exit | error [rad] | energy balance | wall [s] | steps | "
         "rhs | message |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : report.rows) {
      if (r.case_name != c.name) continue;
      s << "| " << sim::method_name(r.method) << " | " << studies::stress_outcome_name(r.outcome)
        << " | " << r.exit_code << " | " << opt_num(r.error, "%.2e") << " | "
        << opt_num(r.energy_balance, "%.2e") << " | " << format_printf(r.wall_time_s, "%.3f")
        << " | " << r.steps << " | " << r.rhs_evaluations << " | " << md_cell(r.message) << " |\n";
    }
  }
  return s.str();
}

/// One line per case on stdout, its outcomes by integrator, and the totals.
void print_report(const std::vector<studies::StressCase>& cases, const studies::StressOptions& opt,
                  const studies::StressReport& report, double total_s) {
  std::cout << "fivebar stress: " << cases.size() << " cases x " << opt.methods.size()
            << " integrators in " << format_printf(total_s, "%.1f") << " s\n";
  for (const auto& c : cases) {
    std::map<std::string, int> counts;
    for (const auto& r : report.rows) {
      if (r.case_name == c.name) ++counts[studies::stress_outcome_name(r.outcome)];
    }
    std::cout << "  " << c.name << ":";
    for (const auto& [name, n] : counts) std::cout << " " << n << " " << name;
    std::cout << "\n";
  }
  std::cout << "  total: " << report.count(studies::StressOutcome::kOk) << " ok, "
            << report.count(studies::StressOutcome::kRejected) << " rejected, "
            << report.count(studies::StressOutcome::kFailed) << " failed\n";
}

int run(const Args& args) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<studies::StressCase> cases = studies::stress_catalogue(args.reduced);
  if (!args.cases.empty()) {
    std::vector<studies::StressCase> chosen;
    for (const std::string& name : args.cases) {
      const auto it = std::find_if(cases.begin(), cases.end(),
                                   [&](const studies::StressCase& c) { return c.name == name; });
      if (it == cases.end()) throw InputError("stress", "--cases", "unknown case '" + name + "'");
      chosen.push_back(*it);
    }
    cases = std::move(chosen);
  }
  studies::StressOptions opt;
  if (!args.methods.empty()) {
    opt.methods.clear();
    for (const std::string& name : args.methods) {
      sim::Method m;
      if (!sim::parse_method(name, &m)) {
        throw InputError("stress", "--methods", "unknown integrator '" + name + "'");
      }
      opt.methods.push_back(m);
    }
  }
  if (!(args.budget > 0.0)) throw InputError("stress", "--budget", "must be positive");
  opt.run_budget_s = args.budget;
  // progress on a terminal only
  const bool tty = isatty(STDERR_FILENO);
  const size_t total = cases.size() * opt.methods.size();
  size_t done = 0;
  opt.on_row = [&](const studies::StressRow& r) {
    ++done;
    if (tty) {
      std::cerr << "\r[" << done << "/" << total << "] " << r.case_name << " "
                << sim::method_name(r.method) << ": " << studies::stress_outcome_name(r.outcome)
                << "                    " << std::flush;
    }
  };
  OutputDir out(args.out, kOutputs);
  const studies::StressReport report = studies::run_stress(cases, opt);
  if (tty) std::cerr << "\n";
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  write_text_file(out.file("stress.csv"), stress_csv(report));
  write_text_file(out.file("stress.md"), stress_md(cases, report, opt, total_s));
  finish_run(&out, [&] { print_report(cases, opt, report, total_s); });
  const int failed = report.count(studies::StressOutcome::kFailed);
  if (failed > 0) {
    throw NumericalError("stress", "failed",
                         std::to_string(failed) + " run(s) failed: see " + out.dir() +
                             "/stress.csv");
  }
  return 0;
}

void add_options(CLI::App* app, Args* args) {
  add_out_option(app, &args->out, "stress");
  app->add_option("--cases", args->cases, "only these cases (default: the whole catalogue)")
      ->delimiter(',');
  app->add_option("--methods", args->methods, "integrators (default: all)")->delimiter(',');
  app->add_option("--budget", args->budget, "wall-time limit of one run [s]; beyond: failed")
      ->capture_default_str();
  app->add_flag("--reduced", args->reduced, "short durations (the test catalogue)");
}

const bool kRegistered = register_command(command_of("stress", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::stress_command
