// The double pass of the forward dynamics, compiled once for everything that links fivebar::sim
// (forward.h declares it `extern template` there): the simulator's right-hand side, and the
// studies that evaluate the forward dynamics themselves.
#include "fivebar/model/forward.h"

namespace fivebar::mech::detail {
template Status forward_pass<FiveBar, double>(const Params<double>&, const Loads<double>&,
                                              const Vec2<double>&, const Vec2<double>&,
                                              const JointModes*, const EvalOptions&,
                                              Evaluation<double>*,
                                              const std::array<double, kJoints>*, LoopSolution*,
                                              FrictionWarmStart*);
}  // namespace fivebar::mech::detail
