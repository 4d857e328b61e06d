// The simulation types the numerics studies (accuracy, stress) are made of.
#pragma once

#include "fivebar/sim/simulator.h"

namespace fivebar::studies {

// the simulation types the studies are made of
using sim::FourBarLoadFunction;
using sim::Initial;
using sim::kAllMethods;
using sim::LoadFunction;
using sim::Method;
using sim::Options;
using sim::Result;
using sim::Row;
using sim::Stats;

}  // namespace fivebar::studies
