// fivebar hold SCENE [--pose THETA1,THETA2] [--grid N] [--torque-limit NM] [--time T]
//                    [--out DIR] [--set KEY=VALUE]... [--no-plots]
// What torques hold the mechanism still at a pose (rest.h, docs/hold.md): the frictionless
// equilibrium against gravity and the scene's loads M3, F (at time T), the range of M1 and of M2
// (the other at its equilibrium) over which static friction holds the pose, and the region of
// (M1, M2) as a polygon. One pose (default the scene's initial one) -> hold.json; a
// grid of N x N poses over the whole circle of both cranks -> hold_map.csv and hold_map.png.
// A four-bar scene: its one crank (--pose THETA1, --grid N poses of theta1), the equilibrium M1
// and the range of M1 static friction holds (four_bar_rest.h).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>

#include "cli_options.h"
#include "fivebar/identification/degrees.h"
#include "fivebar/io/command.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/plots.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/four_bar_rest.h"
#include "fivebar/model/rest.h"

// a namespace of its own: the subcommands compile as one unit (apps/CMakeLists.txt)
namespace fivebar::io::hold_command {
namespace {

// the one line of `fivebar --help`
constexpr char kSummary[] =
    "torques that hold a pose at rest, and their range under static friction";

struct Args {
  SceneArgs scene;
  std::string pose;  // "theta1,theta2" (a four-bar: "theta1"); empty: the scene's initial pose
  int grid = -1;     // > 0: map over N x N poses; -1: not given
  double torque_limit = std::numeric_limits<double>::infinity();
  double time = 0;  // when the loads M3, F are evaluated
  bool no_plots = false;
};

const std::vector<std::string> kOutputs = {"hold.json", "hold_map.csv", "hold_map.png",
                                           "plots.gnuplot", "summary.json"};

// a pose beyond two turns is refused on --pose: within 360, angles that look like degrees
// (start_looks_like_degrees, as the goals of optimize), beyond, angles in another unit (a
// static pose in radians needs no more than a turn)
void refuse_degrees(const std::string& scene, const std::vector<double>& pose) {
  double largest = 0;
  std::string given;
  for (double a : pose) {
    largest = std::max(largest, std::abs(a));
    given += (given.empty() ? "" : ",") + format_double(a);
  }
  if (!(largest > identification::kDegreesBeyond)) return;
  throw InputError(scene, "--pose",
                   given + (start_looks_like_degrees(pose).empty()
                                ? ": angles beyond two turns, expected radians within a turn "
                                  "(another unit?)"
                                : ": angles look like degrees, expected radians"));
}

// "a,b" -> two finite numbers, else InputError on --pose
std::array<double, 2> parse_pose(const std::string& text, const std::string& scene) {
  std::stringstream in(text);
  std::array<double, 2> pose{};
  char comma = 0;
  std::string rest;
  if (!(in >> pose[0] >> comma >> pose[1]) || comma != ',' || (in >> rest) ||
      !std::isfinite(pose[0]) || !std::isfinite(pose[1]) || std::abs(pose[0]) > 1e3 ||
      std::abs(pose[1]) > 1e3) {
    throw InputError(scene, "--pose", "expected THETA1,THETA2 (two numbers in rad, |theta| <= 1000), got '" +
                                          text + "'");
  }
  refuse_degrees(scene, {pose[0], pose[1]});
  return pose;
}

std::string pose_text(double th1, double th2) {
  return "theta1 = " + format_double(th1) + ", theta2 = " + format_double(th2);
}

// the one pose of the command: assembles (else exit 2) and is away from the singularity (else 3)
void check_pose(const Scene& scene, double th1, double th2) {
  const double sine = coupler_sine(scene.params, th1, th2);
  if (sine < 0) {
    throw InputError(scene.path, "--pose", "the mechanism cannot assemble at " +
                                               pose_text(th1, th2) +
                                               ": |BD| outside [|l3 - l4|, l3 + l4]");
  }
  if (sine < std::max(scene.options.singular_margin, 1e-12)) {
    throw NumericalError(scene.path, "--pose",
                         "singular configuration at " + pose_text(th1, th2) +
                             " (couplers aligned: |sin(th4 - th3)| = " + format_double(sine) +
                             " < simulation.singular_margin): no finite holding torques");
  }
}

EvalOptions eval_options(const Scene& scene) {
  EvalOptions o;
  o.singular_margin = scene.options.singular_margin;
  o.friction_tol = scene.options.friction_tol;
  o.friction_max_iter = scene.options.friction_max_iter;
  return o;
}

// least |M| over [lo, hi]
double least_magnitude(double lo, double hi) {
  if (lo <= 0 && hi >= 0) return 0.0;
  return std::min(std::fabs(lo), std::fabs(hi));
}

// torque the motors need to hold: the larger of the two least |M_i| that hold with both
// actuators moved at once, i.e. within the crank joints' bounds (a rectangle inside the region;
// each actuator's own range assumes the other at its equilibrium)
double required_torque(const Holding<double>& h) {
  return std::max(least_magnitude(h.M1 - h.bound[0], h.M1 + h.bound[0]),
                  least_magnitude(h.M2 - h.bound[4], h.M2 + h.bound[4]));
}

Json pair(double a, double b) {
  Json j = Json::array();
  j.push(a);
  j.push(b);
  return j;
}

Json pose_json(const Holding<double>& h, const HoldingPolygon& poly, double limit) {
  Json j = Json::object();
  j.set("M1", h.M1);
  j.set("M2", h.M2);
  j.set("range_M1", pair(h.M1_min, h.M1_max));
  j.set("range_M2", pair(h.M2_min, h.M2_max));
  j.set("N", Json::array_of(h.N));
  j.set("static_friction_bound", Json::array_of(h.bound));
  j.set("crank_joint_range_M1", pair(h.M1 - h.bound[0], h.M1 + h.bound[0]));
  j.set("crank_joint_range_M2", pair(h.M2 - h.bound[4], h.M2 + h.bound[4]));
  j.set("stuck_joints", "O, B, C, D, D0 (all at rest)");
  j.set("required_torque", required_torque(h));
  j.set("holdable_within_limit", required_torque(h) <= limit);
  Json vertices = Json::array();
  for (const auto& v : poly.vertices) vertices.push(pair(v[0], v[1]));
  j.set("polygon_all_joints", std::move(vertices));
  j.set("polygon_range_M1_at_M2_eq", pair(poly.M1_min, poly.M1_max));
  j.set("polygon_range_M2_at_M1_eq", pair(poly.M2_min, poly.M2_max));
  return j;
}

/// The console's line on a pose's torque limit (--torque-limit given): whether the torque needed
/// to hold it is within the limit; "" without a limit.
std::string limit_line(double required, double limit) {
  if (!std::isfinite(limit)) return "";
  return "  within the torque limit " + format_double(limit) +
         " N m: " + (required <= limit ? "yes" : "no, the pose needs more") + "\n";
}

int run_pose(const Args& args, const Scene& scene, const Loads<double>& L,
             const std::array<double, 2>& pose) {
  const EvalOptions eval = eval_options(scene);
  Holding<double> h;
  HoldingPolygon poly;
  Status st = holding_torques(scene.params, L, pose[0], pose[1], eval, &h);
  if (st.ok()) st = holding_polygon(scene.params, L, pose[0], pose[1], eval, h, &poly);
  if (!st.ok()) throw NumericalError(scene.path, "--pose", pose_text(pose[0], pose[1]) + ": " + st.message);

  OutputDir dir(args.scene.out, kOutputs);
  OutputDir* out = &dir;
  Json j = pose_json(h, poly, args.torque_limit);
  j.set("theta1", pose[0]);
  j.set("theta2", pose[1]);
  j.set("scene", scene.path);
  j.set("loads_time", args.time);
  j.set("torque_limit", args.torque_limit);
  write_json_file(out->file("hold.json"), j);
  const std::vector<std::string> written = out->commit();

  char line[1024];
  std::snprintf(line, sizeof line,
                " at theta1 = %.10g, theta2 = %.10g rad (loads at t = %g s)\n"
                "  frictionless equilibrium: M1 = %.10f N m, M2 = %.10f N m\n"
                "  static friction holds M1 in [%.6f, %.6f] (M2 = M2_eq), "
                "M2 in [%.6f, %.6f] N m (M1 = M1_eq)\n"
                "  the crank joints alone hold M1 +- %.6f, M2 +- %.6f N m; region: %zu-gon\n"
                "  torque needed to hold: %.6g N m\n",
                pose[0], pose[1], args.time, h.M1, h.M2, h.M1_min, h.M1_max, h.M2_min, h.M2_max,
                h.bound[0], h.bound[4], poly.vertices.size(), required_torque(h));
  std::cout << "fivebar hold: " << scene.path << line
            << limit_line(required_torque(h), args.torque_limit) << "  wrote " << out->dir()
            << "/:";
  for (const std::string& name : written) std::cout << " " << name;
  std::cout << std::endl;
  return 0;
}

// status of a map cell: 0 held, 1 cannot assemble, 2 singular, 3 numerics failed
int map_cell(const Scene& scene, const Loads<double>& L, double th1, double th2,
             Holding<double>* h) {
  const double sine = coupler_sine(scene.params, th1, th2);
  if (sine < 0) return 1;
  if (sine < std::max(scene.options.singular_margin, 1e-12)) return 2;
  return holding_torques(scene.params, L, th1, th2, eval_options(scene), h).ok() ? 0 : 3;
}

int run_grid(const Args& args, const Scene& scene, const Loads<double>& L) {
  const int n = args.grid;
  OutputDir dir(args.scene.out, kOutputs);
  OutputDir* out = &dir;
  std::vector<Column> cols;
  for (const char* name : {"theta1", "theta2", "status", "M1", "M2", "M1_hold_min",
                           "M1_hold_max", "M2_hold_min", "M2_hold_max", "required",
                           "within_limit"}) {
    cols.push_back({name, {}});
  }
  long held = 0, over = 0, blank = 0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double th1 = -M_PI + 2 * M_PI * (i + 0.5) / n, th2 = -M_PI + 2 * M_PI * (j + 0.5) / n;
      Holding<double> h;
      const int status = map_cell(scene, L, th1, th2, &h);
      const bool ok = status == 0;
      const double req = ok ? required_torque(h) : nan;
      const bool within = ok && req <= args.torque_limit;
      held += within;
      over += ok && !within;
      blank += !ok;
      const double values[] = {th1, th2, double(status), ok ? h.M1 : nan, ok ? h.M2 : nan,
                               ok ? h.M1_min : nan, ok ? h.M1_max : nan, ok ? h.M2_min : nan,
                               ok ? h.M2_max : nan, req, ok ? double(within) : nan};
      for (size_t c = 0; c < cols.size(); ++c) cols[c].values.push_back(values[c]);
    }
  }
  std::string csv;
  for (size_t c = 0; c < cols.size(); ++c) csv += (c ? "," : "") + cols[c].name;
  for (size_t r = 0; r < cols[0].values.size(); ++r) {
    csv += "\n";
    for (size_t c = 0; c < cols.size(); ++c) csv += (c ? "," : "") + format_double(cols[c].values[r]);
  }
  write_text_file(out->file("hold_map.csv"), csv + "\n");
  if (!args.no_plots) {
    const std::string warning =
        plot_hold_map(out->staging(), "hold_map.csv", args.torque_limit, scene.path);
    if (!warning.empty()) warn(warning);
  }
  Json j = Json::object();
  j.set("command", "hold");
  j.set("scene", scene.path);
  j.set("grid", n);
  j.set("loads_time", args.time);
  j.set("torque_limit", args.torque_limit);
  j.set("poses_held_within_limit", held);
  j.set("poses_over_limit", over);
  j.set("poses_not_assembled_or_singular", blank);
  write_json_file(out->file("summary.json"), j);
  const std::vector<std::string> written = out->commit();
  std::cout << "fivebar hold: " << scene.path << ", " << n << " x " << n << " poses: " << held
            << " held within the limit, " << over << " over it, " << blank
            << " cannot assemble or singular\n  wrote " << out->dir() << "/:";
  for (const std::string& name : written) std::cout << " " << name;
  std::cout << std::endl;
  return 0;
}

// ---- the four-bar: one crank, one drive torque ----

// "a" -> one finite number, else InputError on --pose
double parse_crank(const std::string& text, const std::string& scene) {
  std::stringstream in(text);
  double th = NAN;
  std::string rest;
  if (!(in >> th) || (in >> rest) || !std::isfinite(th) || std::abs(th) > 1e3) {
    throw InputError(scene, "--pose", "expected THETA1 (a four-bar has one crank angle, in rad, "
                                      "|theta1| <= 1000), got '" + text + "'");
  }
  refuse_degrees(scene, {th});
  return th;
}

// the four-bar's holding at th1: the pose assembles (else exit 2 when `strict`) and is away from
// the singular pose (else exit 3 when `strict`), and the range settles (else exit 3); a map
// cell's status otherwise (as map_cell)
int four_bar_cell(const Scene& scene, const FourBarLoads& L, double th1, bool strict,
                  FourBarHolding* h) {
  EvalOptions eval = eval_options(scene);
  eval.singular_margin = std::max(eval.singular_margin, 1e-12);
  const Status st = four_bar_holding(scene.four_bar, L, th1, eval, h);
  const int status = st.ok() ? 0
                     : st.code == StatusCode::kCannotAssemble ? 1
                     : st.code == StatusCode::kNearSingular   ? 2
                                                              : 3;
  if (status != 0 && strict) {
    const std::string why = "at theta1 = " + format_double(th1) + ": " + st.message;
    if (status == 1) throw InputError(scene.path, "--pose", why);
    throw NumericalError(scene.path, "--pose",
                         status == 2 ? why + ": no finite holding torque" : why);
  }
  return status;
}

int run_four_bar_pose(const Args& args, const Scene& scene, const FourBarLoads& L, double th1) {
  FourBarHolding h;
  four_bar_cell(scene, L, th1, true, &h);
  OutputDir dir(args.scene.out, kOutputs);
  const double required = least_magnitude(h.M1_min, h.M1_max);
  Json j = Json::object();
  j.set("mechanism", "four_bar");
  j.set("M1", h.M1);
  j.set("range_M1", pair(h.M1_min, h.M1_max));
  j.set("N", Json::array_of(h.N));
  j.set("static_friction_bound", Json::array_of(h.bound));
  j.set("crank_joint_range_M1", pair(h.M1 - h.bound[0], h.M1 + h.bound[0]));
  j.set("stuck_joints", "O, B, C, D0 (all at rest)");
  j.set("required_torque", required);
  j.set("holdable_within_limit", required <= args.torque_limit);
  j.set("theta1", th1);
  j.set("scene", scene.path);
  j.set("loads_time", args.time);
  j.set("torque_limit", args.torque_limit);
  write_json_file(dir.file("hold.json"), j);
  const std::vector<std::string> written = dir.commit();
  char line[512];
  std::snprintf(line, sizeof line,
                " (four-bar) at theta1 = %.10g rad (loads at t = %g s)\n"
                "  frictionless equilibrium: M1 = %.10g N m\n"
                "  static friction holds M1 in [%.6g, %.6g] N m (joint O alone: +- %.6g)\n"
                "  torque needed to hold: %.6g N m\n",
                th1, args.time, h.M1, h.M1_min, h.M1_max, h.bound[0], required);
  std::cout << "fivebar hold: " << scene.path << line << limit_line(required, args.torque_limit)
            << "  wrote " << dir.dir() << "/:";
  for (const std::string& name : written) std::cout << " " << name;
  std::cout << std::endl;
  return 0;
}

int run_four_bar_grid(const Args& args, const Scene& scene, const FourBarLoads& L) {
  OutputDir dir(args.scene.out, kOutputs);
  std::string csv = "theta1,status,M1,M1_hold_min,M1_hold_max,required,within_limit";
  long held = 0, over = 0, blank = 0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < args.grid; ++i) {
    const double th1 = -M_PI + 2 * M_PI * (i + 0.5) / args.grid;
    FourBarHolding h;
    const int status = four_bar_cell(scene, L, th1, false, &h);
    const bool ok = status == 0;
    const double req = ok ? least_magnitude(h.M1_min, h.M1_max) : nan;
    const bool within = ok && req <= args.torque_limit;
    held += within;
    over += ok && !within;
    blank += !ok;
    csv += "\n";
    const double values[] = {th1, double(status), ok ? h.M1 : nan, ok ? h.M1_min : nan,
                             ok ? h.M1_max : nan, req, ok ? double(within) : nan};
    for (size_t c = 0; c < std::size(values); ++c) csv += (c ? "," : "") + format_double(values[c]);
  }
  write_text_file(dir.file("hold_map.csv"), csv + "\n");
  if (!args.no_plots) {
    const std::string warning =
        plot_hold_curve(dir.staging(), "hold_map.csv", args.torque_limit, scene.path);
    if (!warning.empty()) warn(warning);
  }
  Json j = Json::object();
  j.set("command", "hold");
  j.set("mechanism", "four_bar");
  j.set("scene", scene.path);
  j.set("grid", args.grid);
  j.set("loads_time", args.time);
  j.set("torque_limit", args.torque_limit);
  j.set("poses_held_within_limit", held);
  j.set("poses_over_limit", over);
  j.set("poses_not_assembled_or_singular", blank);
  write_json_file(dir.file("summary.json"), j);
  const std::vector<std::string> written = dir.commit();
  std::cout << "fivebar hold: " << scene.path << " (four-bar), " << args.grid << " poses: " << held
            << " held within the limit, " << over << " over it, " << blank
            << " cannot assemble or singular\n  wrote " << dir.dir() << "/:";
  for (const std::string& name : written) std::cout << " " << name;
  std::cout << std::endl;
  return 0;
}

int run(const Args& args) {
  const Scene scene = load_scene(args.scene.scene, args.scene.sets, /*four_bar_ok=*/true);
  if (args.grid != -1 && (args.grid < 1 || args.grid > 2000)) {
    throw InputError(scene.path, "--grid", "expected 1 to 2000 poses per crank, got " +
                                               std::to_string(args.grid));
  }
  if (args.grid > 0 && !args.pose.empty()) {
    throw InputError(scene.path, "--pose", "give either --pose or --grid, not both");
  }
  if (!(args.torque_limit > 0)) {
    throw InputError(scene.path, "--torque-limit", "must be > 0, got " +
                                                       format_double(args.torque_limit));
  }
  const LoadExpressions expressions(scene);
  expressions.require_finite({args.time});
  if (scene.type == MechanismType::kFourBar) {
    FourBarLoads L = expressions.four_bar_function()(args.time);
    L.M1 = 0;  // the unknown
    if (args.grid > 0) return run_four_bar_grid(args, scene, L);
    const double th1 = args.pose.empty() ? scene.initial.theta1 : parse_crank(args.pose, scene.path);
    return run_four_bar_pose(args, scene, L, th1);
  }
  Loads<double> L = expressions(args.time);
  L.M1 = L.M2 = 0;  // the unknowns
  if (args.grid > 0) return run_grid(args, scene, L);
  // the pose is checked before any output exists
  std::array<double, 2> pose = {scene.initial.theta1, scene.initial.theta2};
  if (!args.pose.empty()) pose = parse_pose(args.pose, scene.path);
  check_pose(scene, pose[0], pose[1]);
  return run_pose(args, scene, L, pose);
}

void add_options(CLI::App* app, Args* args) {
  add_scene_options(app, &args->scene, "hold");
  add_plots_flag(app, &args->no_plots, "the map");
  app->add_option("--pose", args->pose,
                  "the pose to hold (default: the scene's initial pose; a four-bar: THETA1)")
      ->type_name("THETA1,THETA2");
  app->add_option("--grid", args->grid,
                  "map N x N poses over theta1, theta2 in [-pi, pi) (a four-bar: N poses of theta1)")
      ->type_name("N")
      ->check(positive_number());
  app->add_option("--torque-limit", args->torque_limit,
                  "motor torque limit [N m]: poses that need more are marked on the map")
      ->type_name("NM")
      ->capture_default_str()
      ->check(positive_number());
  app->add_option("--time", args->time,
                  "time at which the scene's loads M3, F are evaluated [s] (>= 0)")
      ->type_name("T")
      ->capture_default_str()
      ->check(nonnegative_number());
}

const bool kRegistered = register_command(command_of("hold", kSummary, add_options, run));

}  // namespace
}  // namespace fivebar::io::hold_command
