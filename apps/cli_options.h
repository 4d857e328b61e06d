// The command line's shared options and checks (CLI11), used by main.cc and the subcommands.
// They are compiled into the executable alone (cli_options.cc, with the subcommands), so that
// the libraries behind it (fivebar::io, fivebar::commands) and the Python module never parse
// CLI11.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "fivebar/io/command.h"
#include "fivebar/io/commands.h"

namespace fivebar::io {

/// The one rule for every numeric option of every command, run after parsing: a value (or a
/// comma-separated element) that reads as NaN or infinite (1e400 included), or beyond 1e20 in
/// magnitude, throws InputError(`command line: --opt: must be a finite number, got nan`); where
/// the option's default is inf (no limit), inf and huge values are accepted.
void check_numbers(const CLI::App& app);

/// The rule for comma-separated list options (those declared with `->delimiter(',')`), run on
/// the command line before parsing, because the parser drops empty fields: a value of such an
/// option with an empty field (`0.1,,0.2`, a leading or trailing comma) throws
/// InputError(`command line: --opt: an empty value in '0.1,,0.2' ...`) instead of being read as
/// fewer values. `sub`: the subcommand named by argv[1]; an option's values are the text after
/// `--opt=` or the arguments after `--opt` up to the next one starting with `--`, joined into one
/// list (`--opt 0.1, 0.2`, as a shell splits it, is the list 0.1,0.2).
void check_list_fields(const CLI::App& sub, int argc, const char* const* argv);

/// Each value of a comma-separated list option is read without its leading and trailing spaces
/// (`--methods 'cvode_adams, arkode_erk45'` names two integrators).
void trim_list_values(CLI::App* sub);

/// The plausibility limit of scene key `key` (scene_limit, docs/scene.md) for an option that
/// stands for that key's quantity: the same bound and message as the scene's.
CLI::Validator within_scene_limit(const std::string& key);

/// Range checks of numeric options, shared by the commands (`->check(positive_number())`): a
/// value out of range fails the parse with `--opt: must be > 0, got -1`, which `fivebar` reports
/// as bad input (exit 2). Non-numeric text is left to the option's own conversion.
CLI::Validator positive_number();
CLI::Validator nonnegative_number();
/// at most `limit` (and > 0): e.g. durations, so that a typo such as 1e300 is refused at once
CLI::Validator positive_at_most(double limit);
/// >= 0 and at most one turn (2 pi rad): the angle noise and encoder step of a log, which beyond
/// a turn say nothing of the angle
CLI::Validator within_a_turn();

/// Declares SCENE, --out and --set on `app` (a subcommand named `command`).
void add_scene_options(CLI::App* app, SceneArgs* args, const std::string& command);

/// Declares --no-plots, which skips drawing `figures` (the PNG files gnuplot draws).
void add_plots_flag(CLI::App* app, bool* no_plots, const std::string& figures);

/// Declares --out DIR (default results/<command>) alone.
void add_out_option(CLI::App* app, std::string* out, const std::string& command);

/// --objective, --regeneration and --end-acceleration (optimize, study and design), into
/// `settings`.
void add_objective_options(CLI::App* app, OptimizeSettings* settings);

/// The options of the inner trajectory solves of `study` and `design` (the objective options,
/// --method, --path-step, --continuation, --refine), into `settings`, whose defaults become
/// theirs: a first solve only, no continuation, no refinement and no validation unless asked
/// for.
void add_inner_solve_options(CLI::App* app, OptimizeSettings* settings);

}  // namespace fivebar::io
