// fivebar.Scene, fivebar.load_scene, fivebar.parse_scene, fivebar.simulate.
#include <pybind11/stl.h>

#include <algorithm>
#include <chrono>
#include <optional>

#include "bindings.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/output.h"
#include "fivebar/io/scene_mechanism.h"
#include "fivebar/io/simulate_json.h"
#include "fivebar/sim/estimate.h"

namespace fivebar::python {

py::array_t<double> to_array(const std::vector<double>& data, std::vector<py::ssize_t> shape) {
  py::array_t<double> a(shape);
  std::copy(data.begin(), data.end(), a.mutable_data());
  return a;
}

py::array_t<double> to_array(const std::vector<double>& data) {
  return to_array(data, {static_cast<py::ssize_t>(data.size())});
}

py::dict rows_dict(const std::vector<sim::Row>& rows, const io::TrajectoryLayout& layout) {
  const std::vector<std::string> names = io::trajectory_columns(layout);
  const size_t n = rows.size(), m = names.size();
  std::vector<double> table(n * m);  // row-major, as the CSV
  for (size_t i = 0; i < n; ++i) io::row_values(rows[i], &table[i * m], layout);
  py::dict d;
  for (size_t j = 0; j < m; ++j) {
    py::array_t<double> column(static_cast<py::ssize_t>(n));
    double* out = column.mutable_data();
    for (size_t i = 0; i < n; ++i) out[i] = table[i * m + j];
    d[py::str(names[j])] = std::move(column);
  }
  return d;
}

namespace {

// one override value as the text of `--set KEY=VALUE`: numbers (NumPy scalars too) as Python
// writes them, strings as they are, bools as true/false, lists and 1-D arrays as [a, b, ...]
std::string override_text(const std::string& key, const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value) ||
      py::isinstance<py::array>(value)) {
    std::string text = "[";
    for (const py::handle item : value) {
      text += (text.size() > 1 ? ", " : "") + override_text(key, item);
    }
    return text + "]";
  }
  const py::object number = py::reinterpret_borrow<py::object>(value);
  if (py::hasattr(value, "__index__")) return py::str(py::int_(number));
  if (py::hasattr(value, "__float__")) return py::repr(py::float_(number));
  throw InputError("overrides", key,
                   "expected a number, a string, a bool or a list of numbers, got " +
                       std::string(py::str(value.get_type().attr("__name__"))));
}

std::vector<std::string> override_sets(const py::object& overrides) {
  std::vector<std::string> sets;
  if (overrides.is_none()) return sets;
  if (!py::isinstance<py::dict>(overrides)) {
    throw InputError("overrides", "(argument)", "expected a dict {\"dotted.key\": value}");
  }
  for (const auto& [key, value] : overrides.cast<py::dict>()) {
    const std::string k = py::str(key);
    sets.push_back(k + "=" + override_text(k, value));
  }
  return sets;
}

PyScene load(const std::string& path, const py::object& overrides) {
  std::vector<std::string> sets = override_sets(overrides);
  io::Scene scene = io::read_scene(path, sets, /*four_bar_ok=*/true);  // warnings: __init__.py
  return PyScene(std::move(scene), std::move(sets));
}

PyScene parse(const std::string& text, const std::string& name, const py::object& overrides) {
  std::vector<std::string> sets = override_sets(overrides);
  io::Scene scene = io::parse_scene(text, name, sets, /*four_bar_ok=*/true);
  return PyScene(std::move(scene), std::move(sets));
}

// a copy of the scene with more overrides: the scene as YAML (every key explicit) parsed again
// under its own name with them, so it gets every check of a scene file
PyScene replace(const PyScene& s, const py::object& overrides) {
  std::vector<std::string> more = override_sets(overrides);
  io::Scene scene = io::parse_scene(io::scene_to_yaml(s.scene), s.scene.path, more, true);
  std::vector<std::string> sets = s.sets;
  sets.insert(sets.end(), more.begin(), more.end());
  return PyScene(std::move(scene), std::move(sets));
}

// the run with its error estimate (as `fivebar simulate`), its checks, the columns of
// trajectory.csv, the joint modes and summary.json's record; `twin`: the frictionless twin too
// (its rows as 'frictionless', its record as summary['frictionless']) when the scene has friction
template <class Mech>
py::dict simulate_mechanism(const PyScene& s, bool twin) {
  const auto start = std::chrono::steady_clock::now();
  sim::EstimatedRun er;
  sim::RunChecks checks;
  std::optional<io::TwinRun> frictionless;
  {
    py::gil_scoped_release release;
    const typename Mech::Loads loads = Mech::loads(*s.loads);
    er = sim::simulate_to_target(Mech::params(s.scene), loads, s.scene.initial, s.scene.options);
    const sim::Result& run = er.run;
    if (!run.status.ok()) throw NumericalError(s.scene.path, "simulation", run.status.message);
    if (run.rows.empty()) throw NumericalError(s.scene.path, "simulation", "no output rows");
    checks = sim::check_run(Mech::params(s.scene), loads, run, er.options.rtol, er.options.atol);
    if (twin && io::friction_of(s.scene).active()) {
      frictionless = io::frictionless_twin(s.scene, loads, er.options);
    }
  }
  const sim::Result& run = er.run;
  const io::TrajectoryLayout layout = Mech::layout();
  py::dict d = rows_dict(run.rows, layout);
  py::array_t<int> mode({static_cast<py::ssize_t>(run.rows.size()), py::ssize_t(layout.joints)});
  int* m = mode.mutable_data();
  for (const sim::Row& r : run.rows) {
    for (int k = 0; k < layout.joints; ++k) {
      *m++ = static_cast<int>(r.mode[k]);  // -1, 0, +1 slip; 2 stuck
    }
  }
  d["mode"] = std::move(mode);
  if (frictionless && frictionless->run.status.ok())
    d["frictionless"] = rows_dict(frictionless->run.rows, layout);
  py::dict summary = to_python(io::simulation_summary_json(
      s.scene, s.sets, er, checks, frictionless ? &*frictionless : nullptr));
  summary["total_wall_time_s"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  d["summary"] = summary;
  return d;
}

py::dict simulate(const PyScene& s, bool twin) {
  return io::with_mechanism(s.scene, [&](auto mech) {
    return simulate_mechanism<decltype(mech)>(s, twin);
  });
}

}  // namespace

void bind_scene(py::module_& m) {
  py::class_<PyScene>(m, "Scene",
                      "A validated scene (load it with fivebar.load_scene or fivebar.parse_scene).")
      .def_property_readonly("path", [](const PyScene& s) { return s.scene.path; })
      .def_property_readonly(
          "friction_model",
          [](const PyScene& s) { return io::friction_law_name(io::friction_of(s.scene).law); })
      .def_property_readonly(
          "mechanism", [](const PyScene& s) { return io::mechanism_type_name(s.scene.type); },
          "mechanism.type: 'five_bar' or 'four_bar'")
      .def_property_readonly(
          "integrator",
          [](const PyScene& s) {
            return io::integrator_name(
                sim::method_of(s.scene.options, io::friction_of(s.scene).law));
          })
      .def_property_readonly("duration", [](const PyScene& s) { return s.scene.options.duration; })
      .def_property_readonly("output_step",
                             [](const PyScene& s) { return s.scene.options.output_step; })
      .def_property_readonly("initial",
                             [](const PyScene& s) {
                               const sim::Initial& i = s.scene.initial;
                               py::dict d;
                               d["theta1"] = i.theta1;
                               if (s.scene.type == io::MechanismType::kFiveBar) d["theta2"] = i.theta2;
                               d["omega1"] = i.omega1;
                               if (s.scene.type == io::MechanismType::kFiveBar) d["omega2"] = i.omega2;
                               return d;
                             })
      .def_property_readonly("sets", [](const PyScene& s) { return s.sets; })
      .def_property_readonly("warnings", [](const PyScene& s) { return s.scene.warnings; })
      .def("_replace", &replace, py::arg("overrides"))
      .def(
          "to_yaml", [](const PyScene& s) { return io::scene_to_yaml(s.scene); },
          "The scene as YAML, every key explicit (parse_scene reads it back).")
      .def(py::pickle(  // as its YAML (every key explicit), its name and its overrides
          [](const PyScene& s) {
            return py::make_tuple(io::scene_to_yaml(s.scene), s.scene.path, s.sets);
          },
          [](const py::tuple& state) {
            io::Scene scene = io::parse_scene(state[0].cast<std::string>(),
                                              state[1].cast<std::string>(), {}, true);
            return PyScene(std::move(scene), state[2].cast<std::vector<std::string>>());
          }))
      .def("__repr__", [](const PyScene& s) {
        return "<fivebar.Scene '" + s.scene.path + "' " +
               (s.scene.type == io::MechanismType::kFourBar ? "four_bar, " : "") + "friction " +
               io::friction_law_name(io::friction_of(s.scene).law) + ">";
      });

  m.def("load_scene", &load, py::arg("path"), py::arg("overrides") = py::none(),
        "Reads and validates a scene file (YAML). overrides: {\"dotted.key\": value}, applied in "
        "order like `--set KEY=VALUE` (e.g. {\"mechanism.links.2.mass\": 1.5}). Bad input raises "
        "ValueError with the command line's message.");
  m.def("parse_scene", &parse, py::arg("text"), py::arg("name") = "<string>",
        py::arg("overrides") = py::none(),
        "Parses a scene from YAML text; `name` names it in error messages.");
  m.def("simulate", &simulate, py::arg("scene"), py::arg("twin") = false,
        "Forward simulation, with the error estimate of `fivebar simulate`. Returns a dict: one "
        "float64 array per trajectory.csv column (t, theta1..theta4, ..., P_diss, E_diss, W_in, "
        "W_ext; a four-bar's columns for a four-bar scene), 'mode' (N, joints) int joint modes "
        "(+1/-1 slip direction, 0 at rest, 2 stuck) and "
        "'summary' (every field of summary.json). twin=True also runs the frictionless twin "
        "('frictionless': its columns; summary['frictionless']). Raises fivebar.NumericalError "
        "when the run fails.");
}

}  // namespace fivebar::python
