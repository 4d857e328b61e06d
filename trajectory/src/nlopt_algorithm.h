// Internal: the NLopt algorithm of each local method (shared by the trajectory optimizer and the
// general multi-start driver; NLopt is included only in trajectory/src).
#pragma once

#include <nlopt.hpp>

#include "fivebar/trajectory/optimizer.h"

namespace fivebar::trajectory {

inline nlopt::algorithm nlopt_algorithm(Method m) {
  switch (m) {
    case Method::kMma:
      return nlopt::LD_MMA;
    case Method::kCcsaq:
      return nlopt::LD_CCSAQ;
    case Method::kSlsqp:
      break;
  }
  return nlopt::LD_SLSQP;
}

}  // namespace fivebar::trajectory
