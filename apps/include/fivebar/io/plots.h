// Figures with gnuplot, run as a subprocess on a generated script that reads the CSV files of a
// run. Plots are not essential: every function here reports problems as warnings (returned
// strings) and never throws.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "fivebar/io/output.h"
#include "fivebar/studies/accuracy.h"

namespace fivebar::io {

/// The gnuplot found on PATH (or named by the environment variable FIVEBAR_GNUPLOT), probed once.
struct Gnuplot {
  bool available = false;
  std::string executable;  ///< full path
  std::string terminal;    ///< "pngcairo" if gnuplot has it, else "png"
};
const Gnuplot& gnuplot();

/// How run_gnuplot draws a script of several figures (each from a `set output` line to the next).
enum class Figures {
  kInOrder,  ///< one gnuplot process, in the order of the script
  /// each figure sets, after its `set output` line, whatever it draws with beyond what precedes
  /// the first figure: the script written holds each figure in a block
  /// `if (!exists("part") || part == P) { ... }`, the first half of the figures part 1, the rest
  /// part 2, and two gnuplot processes draw the parts at once (one process draws all on a
  /// machine of one core, as `gnuplot SCRIPT` does)
  kStandAlone,
};

/// Writes `script` to dir/`script_name` and runs gnuplot on it with `dir` as working directory,
/// so the script reads and writes files by their names in `dir`. Returns "" on success, else a
/// one-line warning (gnuplot missing, or the first error line of the first part that failed);
/// figures a failure left empty or unfinished are removed and named.
std::string run_gnuplot(const std::string& dir, const std::string& script_name,
                        const std::string& script, Figures figures = Figures::kInOrder);

/// The numeric CSV files a script draws, read by gnuplot from binary copies: NAME.bin beside
/// NAME.csv holds the same rows and columns as float64 numbers (native byte order). A script
/// reads a file many times (a stats pass for each panel's range, then the plot), and gnuplot
/// reads binary numbers many times faster than it parses text. A file without a copy (not
/// converted, or not all numbers) is read as CSV, its columns by name.
class PlotData {
 public:
  /// Writes dir/NAME.bin (plot_copy_name) from dir/`csv`; false, and the CSV is read, when `csv`
  /// cannot be read or holds a field that is not a number (nan and inf are numbers), or the copy
  /// cannot be written.
  bool convert(const std::string& dir, const std::string& csv);
  /// The data of a plot or stats command: "\"x.csv\"", or
  /// "\"x.bin\" binary format=\"%31float64\"" once converted.
  std::string file(const std::string& csv) const;
  /// Column `name` of `csv` in a `using` list: "\"theta1\"", or its number "2" once converted.
  std::string column(const std::string& csv, const std::string& name) const;
  /// The value of column `name` in a `using` expression: "column(\"theta1\")", or "$2".
  std::string value(const std::string& csv, const std::string& name) const;
  /// Comment lines for a script's reader: each binary copy, the CSV it copies and its columns'
  /// numbers ("# trajectory.bin: trajectory.csv as float64, columns 1 t, 2 theta1, ...").
  std::string key() const;

 private:
  std::map<std::string, std::vector<std::string>> headers_;  ///< the converted files' columns
};
/// The binary copy of a CSV for the figures: "trajectory.csv" -> "trajectory.bin".
std::string plot_copy_name(const std::string& csv);

/// The figures of `simulate`, from the files in one directory.
struct SimulationFigures {
  std::string trajectory = "trajectory.csv";
  std::string frictionless;  ///< the frictionless twin's trajectory, or "" when there is none
  bool inverse = true;       ///< trajectory has M1_inverse, M2_inverse: draw fig5
  std::string title;         ///< shown in every figure title (e.g. the scene file name)
  /// the mechanism's columns: the five-bar's (default) or four_bar_layout() (links crank,
  /// coupler, rocker; drive M1; joints O, B, C, D0)
  TrajectoryLayout layout;
  PlotData data;  ///< the binary copies of the trajectories (plot_simulation makes them)
};

/// gnuplot script drawing fig2_angles.png, fig3_rates.png, fig4_accelerations.png (theta,
/// omega, alpha of links 1..4 vs t; friction solid, frictionless twin dashed), and, when
/// asked, fig5_inverse_torques.png (input M1, M2 against the inverse-dynamics torques and their
/// difference) and fig6_friction_torques.png (Mf1..Mf5 vs t).
std::string simulation_plot_script(const SimulationFigures& figures, const std::string& terminal);

/// Draws the figures of simulation_plot_script in `dir` (script kept as dir/plots.gnuplot).
/// Returns "" or a warning.
std::string plot_simulation(const std::string& dir, const SimulationFigures& figures);

/// The figures of `inverse`: fig5_inverse_torques.png (M1, M2 of `trajectory`; against the
/// columns M1_input, M2_input and their difference when `has_input`) and
/// fig6_friction_torques.png. plot_inverse draws them from the binary copy of `trajectory`.
/// Returns "" or a warning.
std::string inverse_plot_script(const std::string& trajectory, bool has_input,
                                const std::string& title, const std::string& terminal,
                                const PlotData& data = {});
std::string plot_inverse(const std::string& dir, const std::string& trajectory, bool has_input,
                         const std::string& title);

/// The figure of `hold --grid`: hold_map.png, a heatmap over (theta1, theta2) of the column
/// `required` of `map_csv` (the torque the motors need to hold each pose), poses that cannot be
/// held within `torque_limit` (column within_limit = 0) marked with crosses; blank where the
/// mechanism cannot assemble or is singular. Returns "" or a warning.
std::string hold_map_plot_script(const std::string& map_csv, double torque_limit,
                                 const std::string& title, const std::string& terminal);
std::string plot_hold_map(const std::string& dir, const std::string& map_csv, double torque_limit,
                          const std::string& title);
/// The four-bar's hold_map.png from its hold_map.csv (theta1, M1, M1_hold_min, M1_hold_max): the
/// held range as a band around the equilibrium over theta1, the torque limit dashed.
std::string hold_curve_plot_script(const std::string& map_csv, double torque_limit,
                                   const std::string& title, const std::string& terminal);
std::string plot_hold_curve(const std::string& dir, const std::string& map_csv,
                            double torque_limit, const std::string& title);
/// A readable name of a scene key for axis labels, links 1-based as in the README and the
/// figures, with units: `mechanism.links.2.length` -> "l3: length of link 3 (coupler B-C) [m]".
/// Keys it does not know come back as they are.
std::string scene_key_label(const std::string& key);

/// The heatmap of a two-key design study (`study`).
struct StudyHeatmap {
  std::string data = "heatmap.dat";  ///< "x y value" rows, blank line between x values; nan blank
  /// "x y" of the designs that cannot do every task, drawn grey and hatched; "" when none
  std::string infeasible;
  double cell_x = 0, cell_y = 0;     ///< grid spacing (the size of a hatched cell)
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;  ///< first and last grid values
  bool has_best = false;
  double best_x = 0, best_y = 0;     ///< the best design, marked
  std::string x_key, y_key;          ///< scene keys of the axes
  std::string title;
};
/// gnuplot script drawing heatmap.png.
std::string study_heatmap_script(const StudyHeatmap& heatmap, const std::string& terminal);

/// gnuplot script of `fivebar accuracy`: work_precision.png from work_precision.csv (in the
/// same directory), log-log error against wall time, one colour per integrator and one dash type
/// per friction treatment, the Pareto front (an inline data block, sorted by time) joined and
/// circled, each recommendation labelled with its target errors, the targets as horizontal lines.
std::string work_precision_plot_script(const studies::WorkPrecision& wp, const std::string& title,
                                       const std::string& terminal);

/// The figures of `excite`: fig_motion.png (angles, rates, accelerations of the cranks),
/// fig_torques.png (M1, M2 against the torque limit) from `excitation`, and fig_std.png (the
/// predicted relative std of each parameter, designed motion beside the multi-sine) from
/// `std_csv` (columns name, relative_std, multisine_relative_std).
struct ExcitationFigures {
  std::string excitation = "excitation.csv";
  std::string std_csv = "predicted_std.csv";
  double torque_limit = 0;
  std::string title;
  bool baseline = true;  ///< the std csv's multisine columns hold values (false: all nan, not drawn)
  int cranks = 2;        ///< the excitation's cranks: 2 (theta1, theta2, M1, M2) or 1 (theta1, M1)
  PlotData data;         ///< the binary copy of the excitation (plot_excitation makes it)
};
std::string excitation_plot_script(const ExcitationFigures& figures, const std::string& terminal);
/// Draws them in `dir` (script kept as dir/plots.gnuplot). Returns "" or a warning.
std::string plot_excitation(const std::string& dir, const ExcitationFigures& figures);

}  // namespace fivebar::io
