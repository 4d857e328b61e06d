// The simulation types the numerics studies are made of, under their short names.
#pragma once

#include "fivebar/sim/simulator.h"

namespace fivebar::studies {

using sim::Method;
using sim::Row;
using sim::Stats;
using sim::Options;
using sim::Result;
using sim::LoadFunction;
using sim::Initial;
using sim::kAllMethods;

}  // namespace fivebar::studies
