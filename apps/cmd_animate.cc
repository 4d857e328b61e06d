// fivebar animate RUN_DIR [--scene SCENE] [--set KEY=VALUE]...
// animation.html of a run folder: RUN_DIR/trajectory.csv (simulate, inverse, one optimize task,
// with its baseline.csv as a grey ghost), or every task folder of an optimize folder.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "fivebar/io/animation.h"
#include "fivebar/io/command.h"
#include "fivebar/io/csv.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene.h"
#include "fivebar/io/scene_mechanism.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::animate_command {
namespace {

namespace fs = std::filesystem;

// the one line of `fivebar --help`
constexpr char kSummary[] = "animation.html of a run folder (simulate, inverse, optimize)";

struct Args {
  std::string dir;
  std::string scene;              ///< --scene; default: the one summary.json records
  std::vector<std::string> sets;  ///< --set, after the recorded ones
};

// --scene (with --set) when given, else the scene and --set values the run's summary.json records
Scene run_scene(const Args& args) {
  if (!args.scene.empty()) return load_scene(args.scene, args.sets, /*four_bar_ok=*/true);
  const std::string summary = (fs::path(args.dir) / "summary.json").string();
  std::string path;
  std::vector<std::string> sets;
  if (!recorded_scene(summary, &path, &sets)) {
    throw InputError(args.dir, "--scene",
                     "no summary.json here names the run's scene (optimize folders have none): "
                     "give the scene the run was made with, --scene SCENE");
  }
  if (!fs::exists(path)) {
    throw InputError(summary, "scene",
                     "'" + path + "' not found from this directory: give it with --scene");
  }
  sets.insert(sets.end(), args.sets.begin(), args.sets.end());
  return load_scene(path, sets, /*four_bar_ok=*/true);
}

// the folders to animate: RUN_DIR itself, or its subfolders that hold a trajectory.csv
std::vector<fs::path> run_folders(const std::string& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir, "RUN_DIR", "not a directory");
  if (fs::exists(fs::path(dir) / "trajectory.csv")) return {fs::path(dir)};
  std::vector<fs::path> tasks;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    if (e.is_directory() && fs::exists(e.path() / "trajectory.csv")) tasks.push_back(e.path());
  }
  std::sort(tasks.begin(), tasks.end());
  if (tasks.empty()) {
    throw InputError(dir, "trajectory.csv",
                     "not found here nor in a task folder: expected the --out folder of "
                     "simulate, inverse or optimize");
  }
  return tasks;
}

// the page of one folder: its trajectory.csv, and baseline.csv as the ghost when present
std::string folder_page(const fs::path& folder, const Scene& scene, const std::string& title) {
  const std::string summary = (folder / "summary.json").string();
  const std::string run_type = recorded_mechanism(summary);
  if (!run_type.empty() && run_type != mechanism_type_name(scene.type)) {
    throw InputError(summary, "mechanism",
                     "a " + run_type + " run, and the scene " + scene.path + " is a " +
                         mechanism_type_name(scene.type) + ": give the run's scene with --scene");
  }
  AnimationInput input;
  input.title = title;
  if (recorded_command(summary) == "inverse") input.label = "inverse dynamics";
  const TrajectoryLayout layout = layout_of(scene);
  input.motion = animation_track(read_csv((folder / "trajectory.csv").string()), layout);
  const fs::path baseline = folder / "baseline.csv";
  if (fs::exists(baseline)) {
    input.label = "optimal motion";
    input.ghost = animation_track(read_csv(baseline.string()), layout);
    input.ghost_label = "minimum jerk (baseline)";
  }
  return animation_html(scene, input);
}

int run(const Args& args) {
  const std::vector<fs::path> folders = run_folders(args.dir);
  const Scene scene = run_scene(args);
  const bool tasks = folders.size() > 1 || folders[0] != fs::path(args.dir);
  const std::string scene_name = fs::path(scene.path).filename().string();
  // every page first: a bad folder leaves no page written
  std::vector<std::string> pages;
  for (const fs::path& f : folders) {
    pages.push_back(folder_page(f, scene, tasks ? f.filename().string() + ", " + scene_name
                                                : scene_name));
  }
  for (size_t i = 0; i < folders.size(); ++i) {
    const fs::path tmp = folders[i] / ".animation.html.partial";
    write_text_file(tmp.string(), pages[i]);
    fs::rename(tmp, folders[i] / "animation.html");
    const bool ghost = fs::exists(folders[i] / "baseline.csv");
    std::cout << "  wrote " << (folders[i] / "animation.html").string() << " ("
              << pages[i].size() / 1024 << " kB"
              << (tasks && !ghost ? "; no baseline.csv, so no minimum-jerk ghost" : "") << ")\n";
  }
  return 0;
}

void add_options(CLI::App* app, Args* args) {
  app->add_option("RUN_DIR", args->dir, "the --out folder of simulate, inverse or optimize")
      ->required();
  app->add_option("--scene", args->scene,
                  "the scene of the run (default: the one its summary.json names; required for "
                  "optimize folders)");
  app->add_option("--set", args->sets, "KEY=VALUE: override a scene value (after the run's own)");
}

const bool kRegistered = register_command(command_of("animate", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::animate_command
