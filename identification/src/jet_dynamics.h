// inverse_dynamics for the ceres::Jet widths that identification differentiates through
// (excitation's group widths, and identify's fallback residual padded to one of them). Each width
// takes ~7 s to compile (-O2), so they are compiled once, in src/jet_dynamics_*.cc (explicit
// instantiations split over several units that build in parallel), instead of again in every unit
// that calls them: this header declares them `extern template`. Including it is enough; a width not
// listed is instantiated as usual (the noise model's 6 motion variables, in noise_model.cc).
#pragma once

#include <array>

#include <ceres/jet.h>

#include "fivebar/model/dynamics.h"

// KEYWORD `extern`: the declaration; empty: the explicit instantiation (src/jet_dynamics_*.cc)
#define FIVEBAR_JET_INVERSE_DYNAMICS(KEYWORD, N)                                              \
  KEYWORD template Status inverse_dynamics<ceres::Jet<double, N>>(                            \
      const Params<ceres::Jet<double, N>>&, const Loads<ceres::Jet<double, N>>&,              \
      const ceres::Jet<double, N>&, const ceres::Jet<double, N>&,                             \
      const ceres::Jet<double, N>&, const ceres::Jet<double, N>&,                             \
      const ceres::Jet<double, N>&, const ceres::Jet<double, N>&, const JointModes*,          \
      const EvalOptions&, Evaluation<ceres::Jet<double, N>>*,                                 \
      const std::array<ceres::Jet<double, N>, kJoints>*);

// the widths, each in one group; a group is compiled by one unit (jet_dynamics_<group>.cc):
// excitation's group widths (2, 10, 16, 18, 26; a design of the actuator terms alone, which
// need no derivative of the model, runs at width 2), 5 (the fallback's 4 parameters; the five
// pin radii the tests differentiate sample_structure's reference through), and nothing else.
// Identify's fallback residual (fallback_cost.h) pads its parameter count to one of them
// (compiled_jet_width); each further width would cost ~7 s of compilation for no gain.
// Width 6 is left out: the trajectory problem's node Jets have it, and through the explicit
// instantiation here its evaluations took 15% more instructions and 20% more time than through
// the implicit one its own unit compiles (optimize's median task, paper_motors.yaml: 25 ms
// against 20.5 ms)
#define FIVEBAR_JET_WIDTHS_A(X) X(2) X(5)
#define FIVEBAR_JET_WIDTHS_B(X) X(10) X(16)
#define FIVEBAR_JET_WIDTHS_C(X) X(18) X(26)

namespace fivebar {
#define FIVEBAR_JET_EXTERN(N) FIVEBAR_JET_INVERSE_DYNAMICS(extern, N)
FIVEBAR_JET_WIDTHS_A(FIVEBAR_JET_EXTERN)
FIVEBAR_JET_WIDTHS_B(FIVEBAR_JET_EXTERN)
FIVEBAR_JET_WIDTHS_C(FIVEBAR_JET_EXTERN)
#undef FIVEBAR_JET_EXTERN

#define FIVEBAR_JET_LIST(N) N,
/// the compiled widths, ascending
inline constexpr int kCompiledJetWidths[] = {FIVEBAR_JET_WIDTHS_A(FIVEBAR_JET_LIST)
                                                 FIVEBAR_JET_WIDTHS_B(FIVEBAR_JET_LIST)
                                                     FIVEBAR_JET_WIDTHS_C(FIVEBAR_JET_LIST)};
#undef FIVEBAR_JET_LIST

/// The smallest compiled width >= n, or the widest when none is.
constexpr int compiled_jet_width(int n) {
  int widest = 0;
  for (int w : kCompiledJetWidths) {
    if (w >= n) return w;
    widest = w;
  }
  return widest;
}
}  // namespace fivebar
