// Equations of motion of the planar 5R five-bar with load-dependent joint friction: one include
// for the whole dynamics. Each concept has its own header:
//   evaluation.h    EvalOptions (settings) and Evaluation (everything one evaluation computes)
//   appell.h        Appell's equations: mass matrix, generalized forces, relative joint rates
//   reactions.h     Newton-Euler joint reactions
//   friction_loop.h the reaction/friction loop (fixed point, Newton fallback, failure reasons)
//   reduced_loop.h  the loop of forward dynamics in the four numbers the torques act through
//   forward.h       forward dynamics, with stuck joints held by constraint torques
//   inverse.h       inverse dynamics, with the rest rule
//   energy.h        kinetic and potential energy
#pragma once

#include "fivebar/model/actuator.h"
#include "fivebar/model/appell.h"
#include "fivebar/model/energy.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/forward.h"
#include "fivebar/model/friction_loop.h"
#include "fivebar/model/inverse.h"
#include "fivebar/model/reactions.h"
