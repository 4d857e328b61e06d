// The version `fivebar --version` prints.
#pragma once

namespace fivebar::io {

/// The project version of the top-level CMakeLists.txt, e.g. "0.1.0" (version.cc: compiled
/// alone, so that a version bump recompiles one small file).
const char* version();

}  // namespace fivebar::io
