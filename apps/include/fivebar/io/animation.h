// animation.html: a self-contained page (inline script and style, no network) that plays a run of
// the linkage to scale, with its joints coloured by their friction power, stuck joints marked,
// point P and the loads, and an optional ghost motion (an optimize task's minimum-jerk baseline).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "fivebar/io/csv.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// One motion to draw, one entry per sample (every vector has t.size() entries).
struct AnimationTrack {
  std::vector<double> t;                              ///< [s]
  std::vector<std::array<double, 4>> theta;           ///< link angles [rad]
  std::vector<std::array<double, 5>> friction_power;  ///< |Mf_k w_k| of joints O, B, C, D, D0 [W]
  std::vector<int> stuck;  ///< bit k set when joint k is stuck (held at w_k = 0)
  std::vector<double> M1, M2, E_diss, W_in, W_ext;    ///< [N m], [J]
  /// the mechanism's links, drives and joints (the four-bar: angles of crank, coupler, rocker
  /// in theta[0..2], joints O, B, C, D0 in friction_power[0..3], M2 zero)
  TrajectoryLayout layout;
};

/// The track of simulated or inverse-dynamics rows; a joint is stuck where its mode says so.
AnimationTrack animation_track(const std::vector<sim::Row>& rows,
                               const TrajectoryLayout& layout = {});

/// The track of a trajectory.csv (docs/outputs.md). A joint is stuck where the column
/// stuck1..stuck5 is 1 when the file has them (optimize, inverse), else where its relative rate
/// is 0 (within 1e-6 of the fastest link's rate) on this row and a neighbouring one (the
/// simulator holds a stuck joint's rate at 0; a single zero, as at a start from rest, is no
/// stick). Throws InputError for a missing
/// column or a table without rows.
AnimationTrack animation_track(const CsvTable& table, const TrajectoryLayout& layout = {});

/// What the page shows.
struct AnimationInput {
  std::string title;            ///< heading, e.g. the scene file or the task name
  std::string label = "simulation";  ///< what the motion is, shown after the title
  AnimationTrack motion;
  AnimationTrack ghost;         ///< drawn grey behind the motion; empty: none
  std::string ghost_label;      ///< e.g. "minimum jerk (baseline)"
};

/// At most this many frames are kept (every k-th sample, the last one always): 2 s at 1 kHz
/// gives a page of about 250 kB.
constexpr size_t kAnimationMaxFrames = 1000;

/// The page: the scene gives the geometry and the loads M3(t), F(t) (M1, M2 come from the
/// track). Throws InputError(`<scene>: mechanism: ...`) when the first pose of the motion does
/// not close with the scene's link lengths (a trajectory made with another scene).
std::string animation_html(const Scene& scene, const AnimationInput& input);

/// The scene file and --set values a run recorded in its summary.json (`scene`, `sets`: simulate,
/// inverse). False when the file is absent or names no scene; throws InputError when it is not
/// valid JSON.
bool recorded_scene(const std::string& summary_json, std::string* scene,
                    std::vector<std::string>* sets);

/// The `mechanism` a run's summary.json records ("five_bar", "four_bar"); empty when the file is
/// absent or names none. Throws InputError when it is not valid JSON.
std::string recorded_mechanism(const std::string& summary_json);

/// The `command` a run's summary.json records ("simulate", "inverse", ...); empty when the file
/// is absent or names none. Throws InputError when it is not valid JSON.
std::string recorded_command(const std::string& summary_json);

}  // namespace fivebar::io
