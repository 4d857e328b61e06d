// Scene files (interfaces.md, "Scene file"): YAML in, validated Scene out, and back to YAML.
#pragma once

#include <string>
#include <vector>

#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/motor.h"
#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// The mechanism a scene describes (mechanism.type).
enum class MechanismType { kFiveBar, kFourBar };
/// "five_bar", "four_bar"
const char* mechanism_type_name(MechanismType type);

/// Everything a scene file describes, validated.
struct Scene {
  MechanismType type = MechanismType::kFiveBar;
  Params<double> params;  ///< the five-bar's (type kFiveBar)
  /// the four-bar's (type kFourBar): links crank O->B, coupler B->C, rocker D0->C; friction slots
  /// O, B, C, D0. Its loads are M1, M3, F and F_angle; its initial state theta1 and omega1.
  FourBarParams four_bar;
  MotorWindings windings;  ///< actuators.M1/M2 winding data (objectives only, not the dynamics)
  /// Load expressions of t (muParser syntax, `pi` defined): M1, M2, M3 [N m], F [N].
  std::string M1 = "0", M2 = "0", M3 = "0", F = "0";
  double F_angle = 0;  ///< [rad] direction of F measured from link 3
  sim::Initial initial;
  sim::Options options;
  /// simulation.rest_rate_threshold [rad/s] and rest_acceleration_threshold [rad/s^2]: the rest
  /// rule of inverse dynamics (rest.h, docs/hold.md); -1 (absent): derived from the noise of the
  /// rates and accelerations the command uses
  double rest_rate_threshold = -1, rest_acceleration_threshold = -1;
  /// `base` with the thresholds this scene sets in their place
  RestThresholds rest_thresholds(RestThresholds base) const {
    if (rest_rate_threshold >= 0) base.rate = rest_rate_threshold;
    if (rest_acceleration_threshold >= 0) base.acceleration = rest_acceleration_threshold;
    return base;
  }
  std::string path;  ///< the file it came from, as given (used in every error message)
  /// likely unit mistakes (`<path>: <key>: <value> <why>`): load_scene prints them as warnings,
  /// read_scene leaves them here
  std::vector<std::string> warnings;
};

/// The friction of the scene's mechanism.
inline const FrictionParams<double>& friction_of(const Scene& s) {
  return s.type == MechanismType::kFourBar ? s.four_bar.friction : s.params.friction;
}

/// Reads and validates a scene file, after applying `sets` ("dotted.key=value", interfaces.md
/// `--set`) in order. Keys absent from the file get their documented default (the schema below);
/// a --set may name such a key. Throws InputError(`<path>: <dotted key>: <reason>`) on a missing
/// file, malformed YAML (with line and column), an unknown key anywhere, a value of the wrong
/// type or outside its domain, load expressions that do not compile or are not finite, and an
/// initial pose that cannot assemble or lies within `simulation.singular_margin` of a singular
/// configuration.
///
/// Schema (R: required; otherwise the default in brackets):
///   mechanism.ground_length R (> 0)   mechanism.point_p R        mechanism.assembly [elbow_up]
///   mechanism.links: 4 x {length R (> 0), mass R (> 0), inertia R (> 0), com_offset R (>= 0),
///                         com_angle [0]}
///   gravity [9.81]
///   friction.model [none]: a law of kLaws (friction.h: none, coulomb_viscous, stribeck, lugre,
///     power_viscous, ...)
///   friction.pin_radius and the coefficients (kCoefficientInfo), each one number or a list of 5
///     (O, B, C, D, D0), all >= 0: R where the model's LawDescriptor requires them, else their
///     CoefficientInfo default (docs/scene.md lists them)
///   friction.smoothing_velocity [0] (>= 0)
///   actuators.M1, .M2: offset [0], coulomb, viscous [0] (>= 0); winding_resistance,
///     torque_constant (> 0; both motors or none) [none]; gear_ratio [1] (> 0)
///   loads.M1, .M2, .M3, .F ["0"]: expressions of t.   loads.F_angle [0]
///   initial.theta1, .theta2 R; initial.omega1, .omega2 [0]
///   simulation.* [sim::Options]: duration (> 0), output_step (in (0, duration]), integrator
///     (sim::method_name), rtol, atol (in (0, 1)), locate_switches, stick, max_steps (>= 1),
///     singular_margin (in [0, 1)), friction_tol (in (0, 1)), friction_max_iter (>= 1),
///     rest_rate_threshold, rest_acceleration_threshold (>= 0; [derived], see Scene)
///
/// Four-bars (mechanism.type four_bar): mechanism.links has 3 links, per-joint lists 4 numbers
/// (O, B, C, D0); actuators.M1 is the crank's motor (Scene::four_bar.actuators, entry 0);
/// loads.M2, initial.theta2, initial.omega2 and actuators.M2 are five-bar keys and fail. Only
/// callers that pass `four_bar_ok` get four-bar scenes: for the others a four-bar scene fails on
/// mechanism.type (the commands that run four-bars: simulate, inverse, synth-log, hold, animate,
/// identify, excite, optimize, study, design).
Scene load_scene(const std::string& path, const std::vector<std::string>& sets = {},
                 bool four_bar_ok = false);

/// load_scene without printing the warnings (they stay in Scene::warnings): for callers that
/// report them their own way, as the Python module does through warnings.warn.
Scene read_scene(const std::string& path, const std::vector<std::string>& sets = {},
                 bool four_bar_ok = false);

/// Every key the schema accepts (dotted, `N` for a link index: "mechanism.links.N.mass"), in
/// schema order. `sections`: the maps and lists that hold other keys ("mechanism.links") too.
std::vector<std::string> scene_keys(bool sections = false);

/// The plausible magnitudes of a scene number: a nonzero |value| outside [low, high] (in `unit`)
/// describes no machine and is refused (exit 2) naming the key. low 0: no lower limit. Zero and
/// the sign are each key's own domain check. docs/scene.md states the same table.
struct SceneLimit {
  double low = 0;
  double high = 0;  ///< 0: the key has no limit
  const char* unit = "";
};

/// The limit of a key in scene_keys() form ("mechanism.links.N.mass"); nullptr when it has none.
const SceneLimit* scene_limit(const std::string& key);

/// Why `value` of `key` describes no machine ("must be ..., got ..."), or "" when it may.
std::string limit_problem(const std::string& key, double value);

/// Parses a scene from YAML text; `path` only names it in error messages.
Scene parse_scene(const std::string& yaml_text, const std::string& path,
                  const std::vector<std::string>& sets = {}, bool four_bar_ok = false);

/// Writes a scene as YAML in the layout of datasets/scenes/paper.yaml, every key explicit and
/// every number in shortest round-trip form: parse_scene(scene_to_yaml(s)) reproduces s.
std::string scene_to_yaml(const Scene& scene);

/// Name of an integrator (scene key `simulation.integrator`): sim::method_name.
const char* integrator_name(sim::Method method);
/// sim::parse_method: false if `name` is not an integrator name.
bool parse_integrator(const std::string& name, sim::Method* out);

/// Name of a friction law (scene key `friction.model`): none, coulomb_viscous, stribeck, lugre.
const char* friction_law_name(FrictionLaw law);

/// |sin(th4 - th3)| at (theta1, theta2) from closed-form triangle geometry, or -1 when the
/// mechanism cannot close there (|BD| outside [|l3 - l4|, l3 + l4]). Independent of the assembly.
double coupler_sine(const Params<double>& params, double theta1, double theta2);
/// The four-bar's |sin(theta3 - theta2)| at crank angle theta1, or -1 when it cannot close there
/// (|BD0| outside [|l2 - l3|, l2 + l3]).
double four_bar_sine(const FourBarParams& params, double theta1);

/// The one row limit of every command that writes rows on a grid (simulate's output rows,
/// synth-log's and excite's log): "" when `duration` s with a row every `step` s stays within
/// sim::kMaxOutputRows, else "needs <rows> rows, more than the limit of 2000000", the count to
/// three digits from 1e9 rows on (1e+303). The caller names its options.
std::string rows_beyond_limit(double duration, double step);

/// The fewest samples a torque log (synth-log's, excite's design) may have
inline constexpr int kMinLogSamples = 10;
/// The same check for a log of `duration` s at `rate_hz`, and at least kMinLogSamples samples:
/// "" or what is wrong ("gives 1 sample, fewer than the 10 of a torque log"). The caller names
/// its options.
std::string log_rows_problem(double duration, double rate_hz);

}  // namespace fivebar::io
