// Subcommands of the `fivebar` executable. Each lives in apps/cmd_<name>.cc and registers itself
// with a static initializer, so adding one never touches main.cc:
//
//   namespace {
//   struct Args { ... };                                 // what the options fill
//   int run(const Args& args) { ... }                    // runs after parsing
//   void add_options(CLI::App* app, Args* args) {
//     app->add_option(...);                              // declare the options
//   }
//   const bool kRegistered =
//       register_command(command_of("name", "one line", add_options, run));
//   }  // namespace
//
// A command whose run needs more than its Args (an option object, say) writes its own
// Command::setup. A run returns 0 on success and reports failure by throwing InputError (exit 2)
// or NumericalError (exit 3); main() prints the one-line message.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace CLI {
class App;
}  // namespace CLI

namespace fivebar::io {

class OutputDir;

/// Runs a parsed subcommand; returns the exit status (0).
using RunFunction = std::function<int()>;

struct Command {
  std::string name;         ///< the subcommand, e.g. "simulate"
  std::string description;  ///< one line, shown by `fivebar --help`
  /// Declares the subcommand's options on `app` and returns what runs it after parsing.
  std::function<RunFunction(CLI::App* app)> setup;
};

/// The Command of a subcommand whose options fill an `Args` and whose run takes them: the
/// arguments live as long as the parsed command.
template <typename Args>
Command command_of(std::string name, std::string description,
                   void (*add_options)(CLI::App*, Args*), int (*run)(const Args&)) {
  return {std::move(name), std::move(description), [add_options, run](CLI::App* app) {
            auto args = std::make_shared<Args>();
            add_options(app, args.get());
            return RunFunction([args, run] { return run(*args); });
          }};
}

/// Adds a command to the registry; returns true (for use in a static initializer).
bool register_command(Command command);

/// Every registered command, sorted by name.
std::vector<Command> registered_commands();

/// The arguments shared by the commands that read a scene.
struct SceneArgs {
  std::string scene;              ///< SCENE (positional)
  std::string out;                ///< --out DIR, default results/<command>
  std::vector<std::string> sets;  ///< --set KEY=VALUE, repeatable, applied in order
};

/// Prints the closing line of every command on stdout: `  wrote DIR/: name name ...`.
void print_written(const std::string& dir, const std::vector<std::string>& names);

/// The end of a successful run: commits `out`, then prints `report()` (the command's summary on
/// stdout, after the commit, so that it never describes files that were not written) and the
/// closing line of print_written. Returns 0, the run's exit status.
int finish_run(OutputDir* out, const std::function<void()>& report);

/// Prints `fivebar: warning: <message>` on stderr.
void warn(const std::string& message);

/// Progress of long work on stderr (interfaces.md: only when stderr is a terminal, and only
/// once the work has taken 2 s): "<label>: 42% (t = 25.2 / 60 s)", updated at most 4 times a
/// second on one line, cleared when done.
class Progress {
 public:
  Progress(std::string label, double total, std::string unit = "");
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// `done` out of total.
  void update(double done);

 private:
  std::string label_, unit_;
  double total_;
  double start_, last_ = 0;
  bool terminal_, shown_ = false;
};

}  // namespace fivebar::io
