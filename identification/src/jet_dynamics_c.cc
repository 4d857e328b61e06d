// The explicit instantiations of inverse_dynamics for the Jet widths of group C
// (jet_dynamics.h says why they are compiled here).
#include "jet_dynamics.h"

namespace fivebar {
#define FIVEBAR_JET_DEFINE(N) FIVEBAR_JET_INVERSE_DYNAMICS(, N)
FIVEBAR_JET_WIDTHS_C(FIVEBAR_JET_DEFINE)
}  // namespace fivebar
