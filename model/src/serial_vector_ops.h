// Internal: the serial N_Vector operations SUNDIALS calls per step, compiled with the project
// (serial_vector_ops.cc), bit-identical to the library's.
#pragma once

#include <nvector/nvector_serial.h>

namespace fivebar::sim::detail {

/// Replaces the per-step operations of the serial vector v by the compiled ones. Vectors the
/// solvers clone from v afterwards copy its operations, so v is the template vector, set before
/// any solver is created.
void use_compiled_serial_ops(N_Vector v);

}  // namespace fivebar::sim::detail
