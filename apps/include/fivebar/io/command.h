// Subcommands of the `fivebar` executable. Each lives in apps/cmd_<name>.cc and registers itself
// with a static initializer, so adding one never touches main.cc:
//
//   namespace {
//   fivebar::io::RunFunction setup(CLI::App* app) {
//     auto args = std::make_shared<Args>();
//     app->add_option(...);                      // declare the options
//     return [args] { return run(*args); };      // run after parsing
//   }
//   const bool kRegistered = fivebar::io::register_command({"name", "one line", setup});
//   }  // namespace
//
// A run returns 0 on success and reports failure by throwing InputError (exit 2) or
// NumericalError (exit 3); main() prints the one-line message.
#pragma once

#include <functional>
#include <string>
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

/// Declares SCENE, --out and --set on `app` (a subcommand named `command`).
void add_scene_options(CLI::App* app, SceneArgs* args, const std::string& command);

/// Declares --out DIR (default results/<command>) alone.
void add_out_option(CLI::App* app, std::string* out, const std::string& command);

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
