// Output files of a run: trajectory.csv, text files, and the directory that receives them
// atomically.
#pragma once

#include <string>
#include <vector>

#include "fivebar/io/json.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// The columns of trajectory.csv, in order: those of interfaces.md
/// (t, theta1..4, omega1..4, alpha1..4, M1, M2, N1..5, Mf1..5, P_diss, E_diss), then W_in, W_ext.
const std::vector<std::string>& trajectory_columns();

/// How many links, drives and joints a trajectory.csv has: the five-bar's (4, 2, 5) by default;
/// the four-bar's (3, 1, 4: theta1 crank, theta2 coupler, theta3 rocker, M1, joints O, B, C,
/// D0) from four_bar_layout().
struct TrajectoryLayout {
  int links = kLinks, drives = 2, joints = kJoints;
};
inline TrajectoryLayout four_bar_layout() { return {3, 1, 4}; }
/// The columns of a trajectory.csv of that layout (the same names, fewer of them).
std::vector<std::string> trajectory_columns(const TrajectoryLayout& layout);

/// Writes the values of `row` in the order of trajectory_columns(layout) to out[0 ..
/// trajectory_columns(layout).size() - 1]; returns the end of what it wrote.
double* row_values(const sim::Row& row, double* out, const TrajectoryLayout& layout = {});

/// An extra column appended after the standard ones (one value per row).
struct Column {
  std::string name;
  std::vector<double> values;
};

/// The rest columns of inverse dynamics (rest.h), appended to trajectory.csv: at_rest (1 where
/// every crank is stuck: the pose held still), stuck1..stuck5 (1 where joint O, B, C, D, D0 is
/// stuck), M1_hold_min, M1_hold_max, M2_hold_min, M2_hold_max (sim::Row::hold_range: the torques
/// over which static friction holds the row; M itself where the crank moves). A four-bar layout
/// has stuck1..stuck4 (O, B, C, D0) and M1_hold_min, M1_hold_max.
std::vector<Column> rest_columns(const std::vector<sim::Row>& rows,
                                 const TrajectoryLayout& layout = {});

/// Writes rows as trajectory.csv: header trajectory_columns() then `extra` names, one line per
/// row, every number in shortest round-trip form (as exact as %.17g) except t, which is written
/// by format_grid_value (0.476 for 476 * 0.001, within one ulp). Throws InputError on a
/// write failure or an extra column whose length differs from rows.size().
void write_trajectory_csv(const std::string& path, const std::vector<sim::Row>& rows,
                          const std::vector<Column>& extra = {},
                          const TrajectoryLayout& layout = {});

/// Writes `text` to `path`; throws InputError(`<path>: (write): <errno text>`) on failure.
void write_text_file(const std::string& path, const std::string& text);

/// Writes json.dump() and a final newline.
void write_json_file(const std::string& path, const Json& json);

/// The output directory of one run, written atomically.
///
/// Files are created in a staging directory DIR/.partial-XXXXXX (file()) and only appear in DIR
/// at commit(), each by rename(2) within the same file system, summary.json last. The constructor
/// also deletes from DIR the files named in `outputs` (what this run will write), so after a run
/// that fails (or is killed) DIR holds none of the previous run's results under those names:
/// nothing in DIR can be mistaken for the output of the failed run. A staging directory left by
/// a killed process is hidden (leading dot) and can be deleted.
class OutputDir {
 public:
  /// Creates DIR (and parents) and the staging directory. Throws InputError(`<dir>: --out: ...`).
  OutputDir(const std::string& dir, const std::vector<std::string>& outputs);
  /// Deletes from `dir` (when it exists) the files named in `outputs`: what the constructor does
  /// first, for a command to call before any check that may refuse the run, so that a run
  /// refused before its output directory is made leaves no previous result either.
  static void remove_previous(const std::string& dir, const std::vector<std::string>& outputs);
  /// Without commit(): removes the staging directory and everything in it, and DIR itself when
  /// this run created it and it is empty.
  ~OutputDir();
  OutputDir(const OutputDir&) = delete;
  OutputDir& operator=(const OutputDir&) = delete;

  /// Path of `name` inside the staging directory (where the run writes it).
  std::string file(const std::string& name) const;
  const std::string& staging() const { return staging_; }
  const std::string& dir() const { return dir_; }

  /// Moves every regular file of the staging directory into DIR (replacing files of the same
  /// name; summary.json last) and removes the staging directory. Returns the names moved, sorted.
  std::vector<std::string> commit();

 private:
  std::string dir_, staging_;
  bool committed_ = false;
  bool created_ = false;  ///< DIR did not exist: removed again by a run that fails, when empty
};

}  // namespace fivebar::io
