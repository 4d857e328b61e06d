// The double pass of the inverse dynamics, compiled once for everything that links fivebar::sim
// (inverse.h declares it `extern template` there): the inverse dynamics in double, and the
// shadow pass of every Jet evaluation.
#include "fivebar/model/inverse.h"

namespace fivebar::mech::detail {
template Status inverse_pass<FiveBar, double>(const Params<double>&, const Loads<double>&,
                                              const Vec2<double>&, const Vec2<double>&,
                                              const Vec2<double>&, const JointModes*,
                                              const EvalOptions&, Evaluation<double>*,
                                              const std::array<double, kJoints>*, LoopSolution*);
}  // namespace fivebar::mech::detail
