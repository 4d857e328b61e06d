// The double pass of the forward dynamics, the five-bar's and the four-bar's, compiled once for
// everything that links fivebar::sim (forward.h and four_bar.h declare them `extern template`
// there): the simulator's right-hand side, and the studies that evaluate the forward dynamics.
#include "fivebar/model/four_bar.h"
#include "fivebar/model/forward.h"

namespace fivebar::mech::detail {
template Status forward_pass<FiveBar, double>(const Params<double>&, const Loads<double>&,
                                              const Vec2<double>&, const Vec2<double>&,
                                              const JointModes*, const EvalOptions&,
                                              Evaluation<double>*,
                                              const std::array<double, kJoints>*, LoopSolution*,
                                              FrictionWarmStart*);
template Status forward_pass<FourBar, double>(
    const FourBar::Params<double>&, const FourBar::Loads<double>&, const FourBar::Q<double>&,
    const FourBar::Q<double>&, const JointModes*, const EvalOptions&,
    FourBar::Evaluation<double>*, const std::array<double, kJoints>*, LoopSolution*,
    FrictionWarmStart*);
}  // namespace fivebar::mech::detail
