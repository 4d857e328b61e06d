// The double pass of the inverse dynamics, the five-bar's and the four-bar's, compiled once for
// everything that links fivebar::sim (inverse.h and four_bar.h declare them `extern template`
// there): the inverse dynamics in double, and the shadow pass of every Jet evaluation.
#include "fivebar/model/four_bar.h"
#include "fivebar/model/inverse.h"

namespace fivebar::mech::detail {
template Status inverse_pass<FiveBar, double>(const Params<double>&, const Loads<double>&,
                                              const Vec2<double>&, const Vec2<double>&,
                                              const Vec2<double>&, const JointModes*,
                                              const EvalOptions&, Evaluation<double>*,
                                              const std::array<double, kJoints>*, LoopSolution*);
template Status inverse_pass<FourBar, double>(
    const FourBar::Params<double>&, const FourBar::Loads<double>&, const FourBar::Q<double>&,
    const FourBar::Q<double>&, const FourBar::Q<double>&, const JointModes*, const EvalOptions&,
    FourBar::Evaluation<double>*, const std::array<double, kJoints>*, LoopSolution*);
}  // namespace fivebar::mech::detail
