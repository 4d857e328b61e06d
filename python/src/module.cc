// PYBIND11_MODULE: exceptions and the functions of the other source files.
//
// Errors: the C++ exceptions that `fivebar` turns into exit status 2 (fivebar::InputError, and
// every FieldError: scene, CSV, torque log, tasks file) become ValueError with the same one-line
// message the command line prints after `fivebar: error: `; fivebar::NumericalError (exit status
// 3) becomes fivebar.NumericalError (a RuntimeError).
#include <exception>

#include "bindings.h"
#include "fivebar/io/errors.h"

namespace fivebar::python {
namespace {

void register_errors(py::module_& m) {
  static py::exception<fivebar::NumericalError> numerical(m, "NumericalError",
                                                          PyExc_RuntimeError);
  numerical.doc() =
      "The numerics failed on valid input (singular configuration reached, friction loop did "
      "not converge, solver gave up): exit status 3 of the command line.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const fivebar::NumericalError& e) {
      numerical(e.what());
    } catch (const fivebar::FieldError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
}

}  // namespace
}  // namespace fivebar::python

PYBIND11_MODULE(_core, m) {
  using namespace fivebar::python;
  m.doc() = "fivebar: dynamics of planar five-bar mechanisms with load-dependent joint friction";
  register_errors(m);
  bind_scene(m);
  bind_inverse(m);
  bind_identify(m);
  bind_optimize(m);
}
