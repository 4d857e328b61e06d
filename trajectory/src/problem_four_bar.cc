// The four-bar's trajectory problem (TrajectoryProblemT<FourBar>): its Jet inverse dynamics
// compile here, apart from the five-bar's (problem.cc).
#include "fivebar/trajectory/four_bar_problem.h"

#include "problem_impl.h"

namespace fivebar::trajectory {

template class TrajectoryProblemT<FourBar>;

}  // namespace fivebar::trajectory
