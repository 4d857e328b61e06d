// The `fivebar` Python module (pybind11): shared declarations of its source files.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "fivebar/io/json.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/loads.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::python {

namespace py = pybind11;

/// fivebar.Scene: a validated scene with its load expressions compiled once (calls share them;
/// LoadExpressions is safe to call from several threads).
struct PyScene {
  io::Scene scene;
  /// the overrides applied to the file, as `--set KEY=VALUE` (summary.json's "sets")
  std::vector<std::string> sets;
  std::shared_ptr<const io::LoadExpressions> loads;
  /// M3 and F do not depend on t (the loads inverse dynamics uses): constant_loads holds them
  bool loads_constant = false;
  Loads<double> constant_loads;

  explicit PyScene(io::Scene s, std::vector<std::string> overrides = {})
      : scene(std::move(s)),
        sets(std::move(overrides)),
        loads(std::make_shared<const io::LoadExpressions>(scene)) {
    using L = io::LoadExpressions;
    loads_constant = loads->constant(L::kM3) && loads->constant(L::kF);
    if (loads_constant) constant_loads = (*loads)(0.0);
  }
  /// Raises ValueError (`<scene>: mechanism.type: ...`) for a four-bar scene: `function` takes
  /// five-bars only so far.
  void require_five_bar(const char* function) const {
    if (scene.type == io::MechanismType::kFiveBar) return;
    throw InputError(scene.path, "mechanism.type",
                     std::string(io::mechanism_type_name(scene.type)) + ": fivebar." + function +
                         " takes five-bars only so far");
  }
};

/// A float64 NumPy array of the given shape, filled from `data` (copied).
py::array_t<double> to_array(const std::vector<double>& data, std::vector<py::ssize_t> shape);
py::array_t<double> to_array(const std::vector<double>& data);

/// A record the command line writes as JSON, as Python objects: objects as dicts, arrays of
/// numbers (and of equal-length rows of numbers) as NumPy arrays, other arrays as lists, null as
/// None, numbers written as null (NaN) as float('nan').
py::object to_python(const io::Json& json);

/// The columns of trajectory.csv (io::trajectory_columns) of `rows`, one array each.
py::dict rows_dict(const std::vector<sim::Row>& rows, const io::TrajectoryLayout& layout = {});

void bind_scene(py::module_& m);     // Scene, load_scene, parse_scene, simulate
void bind_inverse(py::module_& m);   // inverse, _time_inverse_cpp
void bind_identify(py::module_& m);  // identify
void bind_optimize(py::module_& m);  // optimize

}  // namespace fivebar::python
