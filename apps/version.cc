// The version `fivebar --version` prints (version.h).
#include "version.h"

namespace fivebar::io {
const char* version() { return FIVEBAR_VERSION; }
}  // namespace fivebar::io
