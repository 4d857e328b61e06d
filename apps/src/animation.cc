// animation.html: the run's samples as compact JSON inside one page whose script draws them
// (animation_page.h).
#include "fivebar/io/animation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <yaml-cpp/yaml.h>

#include "animation_page.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/format.h"
#include "fivebar/io/json.h"
#include "fivebar/io/loads.h"
#include "fivebar/model/evaluation.h"

namespace fivebar::io {
namespace {

// relative rate of joint k from a row's link rates (docs/outputs.md): the five-bar's O, B, C,
// D, D0 or the four-bar's O, B, C, D0
double joint_rate(const sim::Row& r, int k, const TrajectoryLayout& layout) {
  return layout.joints == kJoints ? r.omega_rel(k) : sim::four_bar_omega_rel(r, k);
}

// a joint's relative rate counts as 0 up to this fraction of the fastest link's rate
constexpr double kStuckRateTolerance = 1e-6;

void push_energies(const sim::Row& r, AnimationTrack* track) {
  track->M1.push_back(r.M1);
  track->M2.push_back(r.M2);
  track->E_diss.push_back(r.E_diss);
  track->W_in.push_back(r.W_in);
  track->W_ext.push_back(r.W_ext);
}

// `x` in `digits` significant digits, "null" when not finite (JSON has no NaN)
void append_number(double x, int digits, std::string* out) {
  if (!std::isfinite(x)) {
    *out += "null";
    return;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, x);
  *out += buf;
}

// "name":[v(i0),v(i1),...] over the kept samples
template <typename Value>
void append_series(const char* name, const std::vector<size_t>& keep, Value value, int digits,
                   std::string* out) {
  *out += std::string("\"") + name + "\":[";
  for (size_t n = 0; n < keep.size(); ++n) {
    if (n > 0) *out += ',';
    append_number(value(keep[n]), digits, out);
  }
  *out += "],";
}

// every k-th sample so that at most kAnimationMaxFrames remain, and always the last one
std::vector<size_t> kept_samples(size_t count) {
  std::vector<size_t> keep;
  if (count == 0) return keep;
  const size_t stride = (count + kAnimationMaxFrames - 2) / (kAnimationMaxFrames - 1);
  for (size_t i = 0; i < count; i += std::max<size_t>(stride, 1)) keep.push_back(i);
  if (keep.back() != count - 1) keep.push_back(count - 1);
  return keep;
}

// the JSON object of one track: times, angles, and (unless `pose_only`) powers, stuck joints,
// torques, loads M3 and F, and energies
std::string track_json(const AnimationTrack& track, const LoadExpressions* loads,
                       bool pose_only) {
  const std::vector<size_t> keep = kept_samples(track.t.size());
  std::string s = "{";
  append_series("t", keep, [&](size_t i) { return track.t[i]; }, 7, &s);
  for (int j = 0; j < track.layout.links; ++j) {
    const std::string name = "th" + std::to_string(j + 1);
    append_series(name.c_str(), keep, [&](size_t i) { return track.theta[i][j]; }, 7, &s);
  }
  if (!pose_only) {
    for (int k = 0; k < track.layout.joints; ++k) {
      const std::string name = "p" + std::to_string(k + 1);
      append_series(name.c_str(), keep, [&](size_t i) { return track.friction_power[i][k]; }, 4,
                    &s);
    }
    append_series("stuck", keep, [&](size_t i) { return double(track.stuck[i]); }, 2, &s);
    append_series("M1", keep, [&](size_t i) { return track.M1[i]; }, 4, &s);
    if (track.layout.drives > 1) {
      append_series("M2", keep, [&](size_t i) { return track.M2[i]; }, 4, &s);
    }
    append_series("M3", keep, [&](size_t i) { return (*loads)(track.t[i]).M3; }, 4, &s);
    append_series("F", keep, [&](size_t i) { return (*loads)(track.t[i]).F; }, 4, &s);
    append_series("E_diss", keep, [&](size_t i) { return track.E_diss[i]; }, 5, &s);
    append_series("W_in", keep, [&](size_t i) { return track.W_in[i]; }, 5, &s);
    append_series("W_ext", keep, [&](size_t i) { return track.W_ext[i]; }, 5, &s);
  }
  s += "\"samples\":" + std::to_string(track.t.size()) + "}";
  return s;
}

// the joint C of a pose from both sides: from B along the coupler and from D (the five-bar's
// second crank and coupler) or D0 (the four-bar's rocker); a gap when the angles do not fit
double closure_gap(const Scene& scene, const std::array<double, 4>& th) {
  const bool four_bar = scene.type == MechanismType::kFourBar;
  auto length = [&](int j) {
    return four_bar ? scene.four_bar.links[j].length : scene.params.links[j].length;
  };
  const double l0 = four_bar ? scene.four_bar.ground_length : scene.params.ground_length;
  const double bx = length(0) * std::cos(th[0]), by = length(0) * std::sin(th[0]);
  if (four_bar) {  // C from B (coupler, th[1]) and from D0 (rocker, th[2])
    return std::hypot(bx + length(1) * std::cos(th[1]) - (l0 + length(2) * std::cos(th[2])),
                      by + length(1) * std::sin(th[1]) - length(2) * std::sin(th[2]));
  }
  const double dx = l0 + length(1) * std::cos(th[1]), dy = length(1) * std::sin(th[1]);
  return std::hypot(bx + length(2) * std::cos(th[2]) - (dx + length(3) * std::cos(th[3])),
                    by + length(2) * std::sin(th[2]) - (dy + length(3) * std::sin(th[3])));
}

// throws when the first finite pose of `track` does not close with the scene's link lengths
void check_closure(const Scene& scene, const AnimationTrack& track, const std::string& what) {
  const bool four_bar = scene.type == MechanismType::kFourBar;
  if (track.layout.links != (four_bar ? kFourBarLinks : kLinks)) {
    throw InputError(scene.path, "mechanism.type",
                     what + " has " + std::to_string(track.layout.links) +
                         " links, the scene's mechanism " +
                         std::to_string(four_bar ? kFourBarLinks : kLinks));
  }
  double scale = four_bar ? scene.four_bar.ground_length : scene.params.ground_length;
  for (int j = 0; j < track.layout.links; ++j) {
    scale += four_bar ? scene.four_bar.links[j].length : scene.params.links[j].length;
  }
  for (size_t i = 0; i < track.t.size(); ++i) {
    const double gap = closure_gap(scene, track.theta[i]);
    if (!std::isfinite(gap)) continue;
    if (gap > 1e-6 * scale) {
      throw InputError(scene.path, "mechanism",
                       what + " does not close with these link lengths (C from B and from " +
                           (four_bar ? "D0 " : "D ") + format_significant(gap, 3) +
                           " m apart at t = " + format_significant(track.t[i], 6) +
                           " s): was it made with another scene or other --set values?");
    }
    return;
  }
}

}  // namespace

AnimationTrack animation_track(const std::vector<sim::Row>& rows, const TrajectoryLayout& layout) {
  AnimationTrack track;
  track.layout = layout;
  for (const sim::Row& r : rows) {
    track.t.push_back(r.t);
    track.theta.push_back(r.theta);
    std::array<double, 5> power{};
    int stuck = 0;
    for (int k = 0; k < layout.joints; ++k) {
      power[k] = std::abs(r.Mf[k] * joint_rate(r, k, layout));
      if (r.mode[k] == kStuck) stuck |= 1 << k;
    }
    track.friction_power.push_back(power);
    track.stuck.push_back(stuck);
    push_energies(r, &track);
  }
  return track;
}

AnimationTrack animation_track(const CsvTable& table, const TrajectoryLayout& layout) {
  if (table.rows.empty()) {
    throw InputError(table.path, "(file)", "no data rows below the header: nothing to draw");
  }
  std::vector<sim::Row> rows(table.rows.size());
  auto fill = [&](const std::string& name, auto set) {
    const std::vector<double> v = table.column(name);
    for (size_t i = 0; i < rows.size(); ++i) set(rows[i], v[i]);
  };
  fill("t", [](sim::Row& r, double v) { r.t = v; });
  for (int j = 0; j < layout.links; ++j) {
    const std::string n = std::to_string(j + 1);
    fill("theta" + n, [j](sim::Row& r, double v) { r.theta[j] = v; });
    fill("omega" + n, [j](sim::Row& r, double v) { r.omega[j] = v; });
  }
  for (int k = 0; k < layout.joints; ++k) {
    fill("Mf" + std::to_string(k + 1), [k](sim::Row& r, double v) { r.Mf[k] = v; });
  }
  fill("M1", [](sim::Row& r, double v) { r.M1 = v; });
  if (layout.drives > 1) fill("M2", [](sim::Row& r, double v) { r.M2 = v; });
  fill("E_diss", [](sim::Row& r, double v) { r.E_diss = v; });
  fill("W_in", [](sim::Row& r, double v) { r.W_in = v; });
  fill("W_ext", [](sim::Row& r, double v) { r.W_ext = v; });
  const bool stuck_columns = table.has("stuck1");
  for (int k = 0; k < layout.joints; ++k) {
    if (stuck_columns) {
      fill("stuck" + std::to_string(k + 1), [k](sim::Row& r, double v) {
        r.mode[k] = v != 0 ? kStuck : JointMode::kRest;
      });
    } else {
      // held at 0 over two consecutive rows: a single zero (the start from rest, a reversal) is
      // no stick. 0 within kStuckRateTolerance of the row's fastest link: a stuck inner joint's
      // rate, a difference of two link rates, keeps the integration's error (about 1e-9 of it)
      auto zero = [&](size_t i) {
        double fastest = 0;
        for (int j = 0; j < layout.links; ++j) fastest = std::max(fastest, std::abs(rows[i].omega[j]));
        return std::abs(joint_rate(rows[i], k, layout)) <= kStuckRateTolerance * fastest;
      };
      for (size_t i = 0; i < rows.size(); ++i) {
        const bool held =
            zero(i) && ((i > 0 && zero(i - 1)) || (i + 1 < rows.size() && zero(i + 1)));
        rows[i].mode[k] = held ? kStuck : JointMode::kRest;
      }
    }
  }
  return animation_track(rows, layout);
}

std::string animation_html(const Scene& scene, const AnimationInput& input) {
  check_closure(scene, input.motion, "the motion");
  if (!input.ghost.t.empty()) check_closure(scene, input.ghost, input.ghost_label);
  const bool four_bar = scene.type == MechanismType::kFourBar;
  const LoadExpressions loads(scene);
  std::string data = "{\"title\":" + json_quote(input.title) +
                     ",\"label\":" + json_quote(input.label) + ",\"geometry\":{\"type\":" +
                     json_quote(mechanism_type_name(scene.type)) + ",\"l0\":";
  append_number(four_bar ? scene.four_bar.ground_length : scene.params.ground_length, 9, &data);
  data += ",\"l\":[";
  for (int j = 0; j < input.motion.layout.links; ++j) {
    if (j > 0) data += ',';
    append_number(four_bar ? scene.four_bar.links[j].length : scene.params.links[j].length, 9,
                  &data);
  }
  data += "],\"lp\":";
  append_number(four_bar ? scene.four_bar.point_p : scene.params.point_p, 9, &data);
  data += ",\"F_angle\":";
  append_number(scene.F_angle, 9, &data);
  data += "},\"motion\":" + track_json(input.motion, &loads, false);
  data += ",\"ghost\":" +
          (input.ghost.t.empty() ? std::string("null") : track_json(input.ghost, nullptr, true));
  data += ",\"ghost_label\":" + json_quote(input.ghost_label) + "}";
  std::string page = kAnimationPage;
  const std::string marker = "/*FIVEBAR_DATA*/null";
  page.replace(page.find(marker), marker.size(), data);
  return page;
}

namespace {

// the run's summary.json as a node; a null node when the file is absent
YAML::Node load_summary(const std::string& summary_json) {
  if (!std::filesystem::exists(summary_json)) return YAML::Node();
  try {
    return YAML::LoadFile(summary_json);  // JSON is YAML
  } catch (const YAML::Exception& e) {
    throw InputError(summary_json, "(read)", "not valid JSON: " + e.msg);
  }
}

}  // namespace

bool recorded_scene(const std::string& summary_json, std::string* scene,
                    std::vector<std::string>* sets) {
  const YAML::Node summary = load_summary(summary_json);
  if (!summary.IsMap() || !summary["scene"] || !summary["scene"].IsScalar()) return false;
  *scene = summary["scene"].as<std::string>();
  sets->clear();
  if (summary["sets"] && summary["sets"].IsSequence()) {
    for (const YAML::Node& s : summary["sets"]) sets->push_back(s.as<std::string>());
  }
  return true;
}

std::string recorded_mechanism(const std::string& summary_json) {
  const YAML::Node summary = load_summary(summary_json);
  if (!summary.IsMap() || !summary["mechanism"] || !summary["mechanism"].IsScalar()) return "";
  return summary["mechanism"].as<std::string>();
}

std::string recorded_command(const std::string& summary_json) {
  const YAML::Node summary = load_summary(summary_json);
  if (!summary.IsMap() || !summary["command"] || !summary["command"].IsScalar()) return "";
  return summary["command"].as<std::string>();
}

}  // namespace fivebar::io
