// fivebar: the command line of the toolkit (interfaces.md). The subcommands register themselves
// (apps/cmd_*.cc, see fivebar/io/command.h); this file parses the command line, runs the chosen
// one and turns every failure into an exit status and one line on stderr:
//   0 success, 1 usage error, 2 bad input, 3 the numerics failed
//   fivebar: error: <file>: <key>: <what and why>
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <map>
#include <string>

#include "cli_options.h"
#include "fivebar/io/command.h"
#include "fivebar/io/errors.h"
#include "version.h"

namespace {

constexpr int kUsageError = 1;
constexpr int kInputError = 2;
constexpr int kNumericalError = 3;

// the one line printed before every non-zero exit
int fail(int status, std::string message) {
  for (char& c : message) {
    if (c == '\n') c = ' ';  // exactly one line, whatever the message
  }
  std::cout.flush();
  std::cerr << "fivebar: error: " << message << std::endl;
  return status;
}

// the deepest subcommand selected on the command line, or the executable
std::string selected_name(const CLI::App& app) {
  const CLI::App* current = &app;
  while (!current->get_subcommands().empty()) current = current->get_subcommands().back();
  return current->get_name();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Dynamics of planar closed-chain mechanisms (the five-bar, and the four-bar in every command "
      "that reads a scene) with load-dependent joint friction.",
      "fivebar"};
  app.set_version_flag("--version", std::string("fivebar ") + fivebar::io::version(),
                       "print the version and exit");
  app.require_subcommand(1);

  // every registered subcommand, and what runs it
  std::map<const CLI::App*, fivebar::io::RunFunction> runs;
  for (const fivebar::io::Command& command : fivebar::io::registered_commands()) {
    CLI::App* sub = app.add_subcommand(command.name, command.description);
    runs[sub] = command.setup(sub);
  }

  // an unknown subcommand (CLI11 alone would only say that one is required)
  if (argc >= 2 && argv[1][0] != '-') {
    std::string known;
    bool found = false;
    for (const auto& [sub, run] : runs) {
      known += " " + sub->get_name();
      found = found || sub->get_name() == argv[1];
    }
    if (!found) {
      return fail(kUsageError, std::string("command line: ") + argv[1] +
                                   ": unknown subcommand (known:" + known + ")");
    }
    try {  // before parsing: the parser drops a list's empty fields
      fivebar::io::check_list_fields(*app.get_subcommand(argv[1]), argc, argv);
      fivebar::io::trim_list_values(app.get_subcommand(argv[1]));
    } catch (const fivebar::InputError& e) {
      return fail(kInputError, e.what());
    }
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --help-all, --version (derive from Success): print, exit 0
  } catch (const CLI::ValidationError& e) {
    // a value out of its option's range (positive_number() and the like): bad input
    return fail(kInputError, std::string("command line: ") + e.what());
  } catch (const CLI::ConversionError& e) {
    // a value its option cannot read (nan for a count): bad input
    return fail(kInputError, "command line: " + selected_name(app) + ": " + e.what());
  } catch (const CLI::ParseError& e) {
    return fail(kUsageError,
                "command line: " + selected_name(app) + ": " + e.what() + " (see fivebar " +
                    (selected_name(app) == "fivebar" ? "" : selected_name(app) + " ") + "--help)");
  }

  const CLI::App* sub = app.get_subcommands().front();
  try {
    fivebar::io::check_numbers(*sub);
    const int status = runs.at(sub)();
    if (status != 0) {
      return fail(status,
                  sub->get_name() + ": (run): failed with exit status " + std::to_string(status));
    }
    return 0;
  } catch (const fivebar::InputError& e) {
    return fail(kInputError, e.what());
  } catch (const fivebar::NumericalError& e) {
    return fail(kNumericalError, e.what());
  } catch (const std::exception& e) {
    // an unexpected failure (out of memory, a broken invariant): report it like the numerics
    return fail(kNumericalError, sub->get_name() + ": (internal): " + e.what());
  }
}
