// The parts of a scene that belong to its mechanism (mechanism.type), as one small traits type
// per mechanism, so that a command or binding writes its run once over both:
//   scene.type == kFourBar ? f(FourBarScene{}) : f(FiveBarScene{})   (with_mechanism below)
#pragma once

#include <vector>

#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/status.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::io {

/// The five-bar's: Params, its loads, the trajectory.csv columns, inverse dynamics along rows.
struct FiveBarScene {
  using Loads = sim::LoadFunction;
  static const Params<double>& params(const Scene& s) { return s.params; }
  static Loads loads(const LoadExpressions& e) { return e.function(); }
  static TrajectoryLayout layout() { return {}; }
  static Status inverse(const Scene& s, const Loads& loads, const std::vector<sim::Row>& rows,
                        std::vector<sim::Row>* out) {
    return sim::inverse_rows(s.params, loads, rows, out);
  }
};

/// The four-bar's.
struct FourBarScene {
  using Loads = sim::FourBarLoadFunction;
  static const FourBarParams& params(const Scene& s) { return s.four_bar; }
  static Loads loads(const LoadExpressions& e) { return e.four_bar_function(); }
  static TrajectoryLayout layout() { return four_bar_layout(); }
  static Status inverse(const Scene& s, const Loads& loads, const std::vector<sim::Row>& rows,
                        std::vector<sim::Row>* out) {
    return sim::inverse_rows(s.four_bar, loads, rows, out);
  }
};

/// The trajectory.csv columns of the scene's mechanism.
inline TrajectoryLayout layout_of(const Scene& scene) {
  return scene.type == MechanismType::kFourBar ? FourBarScene::layout() : FiveBarScene::layout();
}

/// f(FiveBarScene{}) or f(FourBarScene{}), by the scene's mechanism.type.
template <class F>
auto with_mechanism(const Scene& scene, F&& f) {
  return scene.type == MechanismType::kFourBar ? f(FourBarScene{}) : f(FiveBarScene{});
}

}  // namespace fivebar::io
