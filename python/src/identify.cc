// fivebar.identify: friction identification from a torque log, the result as a dict.
#include <pybind11/stl.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "bindings.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/identify_json.h"
#include "fivebar/io/torque_log_file.h"
#include "keywords.h"

namespace fivebar::python {
namespace {

namespace id = fivebar::identification;

py::array_t<double> matrix(const Eigen::MatrixXd& a) {
  py::array_t<double> out({py::ssize_t(a.rows()), py::ssize_t(a.cols())});
  auto v = out.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    for (Eigen::Index c = 0; c < a.cols(); ++c) v(r, c) = a(r, c);
  }
  return out;
}

// a key of the CSV text log_from_dict writes ("line 12, column tau1") as the arrays' place
// ("row 10, column tau1": 0-based, the header is line 1); the header's line as "columns"
std::string array_key(const std::string& key) {
  const std::string prefix = "line ";
  if (key.compare(0, prefix.size(), prefix) != 0) return key;
  size_t end = prefix.size();
  while (end < key.size() && std::isdigit(static_cast<unsigned char>(key[end]))) ++end;
  const int line = std::stoi(key.substr(prefix.size(), end - prefix.size()));
  if (line <= 1) return "columns";
  return "row " + std::to_string(line - 2) + key.substr(end);
}

// a log given as a dict of arrays: written as CSV text and parsed, so it gets every check of a
// log file (columns, finite numbers, increasing t, degrees)
id::TorqueLog log_from_dict(const py::dict& columns, int dof) {
  std::vector<std::string> names;
  std::vector<std::vector<double>> values;
  for (const auto& [key, value] : columns) {
    names.push_back(py::str(key));
    values.push_back(value.cast<std::vector<double>>());
  }
  std::string text;
  for (size_t j = 0; j < names.size(); ++j) text += (j ? "," : "") + names[j];
  text += "\n";
  const size_t n = values.empty() ? 0 : values[0].size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < names.size(); ++j) {
      if (values[j].size() != n) {
        throw InputError("log", names[j], "expected " + std::to_string(n) + " values (as " +
                                              names[0] + "), got " +
                                              std::to_string(values[j].size()));
      }
      text += (j ? "," : "") + format_shortest(values[j][i]);
    }
    text += "\n";
  }
  try {
    return io::parse_torque_log(text, "log", dof);
  } catch (const id::LogError& e) {
    throw InputError(e.file(), array_key(e.key()), e.reason());
  }
}

// the simulated angles of the validation runs (residuals.csv's columns), beside its record
void add_validation_arrays(const id::Validation& v, py::dict* validation) {
  (*validation)["simulated_theta1"] = to_array(v.full_theta1);
  (*validation)["windowed_theta1"] = to_array(v.window_theta1);
  if (v.dof == 1) return;
  (*validation)["simulated_theta2"] = to_array(v.full_theta2);
  (*validation)["windowed_theta2"] = to_array(v.window_theta2);
}

// identification.json's record (io::identification_json), plus what only Python returns: the
// covariance, the rate estimation's settings flat, the per-sample arrays of residuals.csv, and
// the fitted scene
py::dict result_dict(const PyScene& s, const io::IdentifyRun& run, const id::TorqueLog& log,
                     const id::IdentifyResult& r, const id::Validation* validation) {
  py::dict d = to_python(io::identification_json(run, log, r, validation));
  d["covariance"] = matrix(r.covariance);
  d["rates_estimated"] = r.rates_estimated;
  d["accelerations_estimated"] = r.accels_estimated;
  if (r.accels_estimated) {  // rate_source's window, as the Python results had it
    d["sg_half_window_s"] =
        r.sg_half_window * r.conditioned_log.duration() / std::max(1, r.conditioned_log.size() - 1);
    d["sg_order"] = r.sg_order;
    d["window_choice"] = r.window_choice;
  }
  d["wall_time_s"] = r.wall_time_s;
  for (const auto& [name, v] : {std::pair{"omega1", &r.omega1}, {"omega2", &r.omega2},
                                {"alpha1", &r.alpha1}, {"alpha2", &r.alpha2},
                                {"predicted_tau1", &r.predicted_tau1},
                                {"predicted_tau2", &r.predicted_tau2}}) {
    d[name] = to_array(*v);
  }
  py::array_t<bool> used(static_cast<py::ssize_t>(r.used.size()));
  std::copy(r.used.begin(), r.used.end(), used.mutable_data());
  d["used"] = used;
  if (validation) {
    py::dict v = d["validation"];
    add_validation_arrays(*validation, &v);
  }
  d["fitted_scene"] = PyScene(io::fitted_scene(s.scene, r));
  return d;
}

// a four-bar's fit (`fivebar identify` on a four-bar scene): the options it does not run
// refused naming them
id::IdentifyResult identify_four_bar(const PyScene& s, const id::TorqueLog& log,
                                     const id::IdentifyOptions& options, bool validate,
                                     id::Validation* validation) {
  const std::string unsupported = id::four_bar_unsupported(options);
  if (!unsupported.empty()) {
    throw InputError(s.scene.path, "mechanism.type", "four_bar: " + unsupported);
  }
  py::gil_scoped_release release;
  id::IdentifyResult result = io::identify_four_bar_scene(s.scene, log, options);
  if (validate) {
    *validation = id::validate(result.fitted_four_bar, s.loads->four_bar_function(),
                               result.conditioned_log, result.omega1, result.window_s);
  }
  return result;
}

py::dict identify(const PyScene& s, const py::object& log, const io::IdentifySettings& settings,
                  bool validate) {
  const id::IdentifyOptions options = io::identify_options(settings, s.scene);
  const bool four_bar = s.scene.type == io::MechanismType::kFourBar;
  const int dof = four_bar ? 1 : 2;
  const id::TorqueLog torque_log = py::isinstance<py::dict>(log)
                                       ? log_from_dict(log.cast<py::dict>(), dof)
                                       : io::read_log(py::str(log), dof);
  const io::IdentifyRun run{s.scene.path,
                            py::isinstance<py::dict>(log) ? "(arrays)" : std::string(py::str(log)),
                            settings.estimate, options.loss, /*torque_sign_flipped=*/""};
  if (four_bar) {
    id::Validation validation;
    const id::IdentifyResult result =
        identify_four_bar(s, torque_log, options, validate, &validation);
    return result_dict(s, run, torque_log, result, validate ? &validation : nullptr);
  }
  id::IdentifyResult result;
  id::Validation validation;
  {
    py::gil_scoped_release release;
    const sim::LoadFunction loads = s.loads->function();
    result = io::identify_scene(s.scene, loads, torque_log, options);
    if (validate) {
      // on the log as fitted (unwrapped, glitches interpolated), as `fivebar identify`
      validation = id::validate(result.fitted, loads, result.conditioned_log, result.omega1,
                                result.omega2, result.window_s);
    }
  }
  return result_dict(s, run, torque_log, result, validate ? &validation : nullptr);
}

// the keywords of fivebar.identify: the options of `fivebar identify`, with _ for -
const Keywords<io::IdentifySettings> kIdentifyKeywords = {
    {"method", &io::IdentifySettings::method},
    {"law", &io::IdentifySettings::law},
    {"estimate", &io::IdentifySettings::estimate},
    {"inertia_prior", &io::IdentifySettings::inertia_prior},
    {"per_joint", &io::IdentifySettings::per_joint},
    {"loss", &io::IdentifySettings::loss},
    {"loss_scale", &io::IdentifySettings::loss_scale},
    {"smooth_sign", &io::IdentifySettings::smooth_sign},
    {"estimate_rates", &io::IdentifySettings::estimate_rates},
    {"min_rate", &io::IdentifySettings::min_rate},
    {"sg_window", &io::IdentifySettings::sg_window},
    {"sg_order", &io::IdentifySettings::sg_order},
    {"window", &io::IdentifySettings::window},
    {"threads", &io::IdentifySettings::threads},
    {"start_from_scene", &io::IdentifySettings::start_from_scene},
    {"no_unwrap", &io::IdentifySettings::no_unwrap},
    {"keep_glitches", &io::IdentifySettings::keep_glitches},
    {"keep_reversals", &io::IdentifySettings::keep_reversals},
    {"classical_std", &io::IdentifySettings::classical_std},
    {"no_delay", &io::IdentifySettings::no_delay},
};

}  // namespace

void bind_identify(py::module_& m) {
  m.def(
      "identify",
      [](const PyScene& scene, const py::object& log, const py::kwargs& kw) {
        io::IdentifySettings st;
        apply_keywords("identify", kw, kIdentifyKeywords, {"validate"}, &st);
        st.sg_window_given = kw.contains("sg_window");  // else chosen from the log
        return identify(scene, log, st, own_keyword(kw, "validate", false));
      },
      py::arg("scene"), py::arg("log"),
      ("Identifies the friction coefficients of `scene` from a torque log: a CSV path, or a dict "
       "of equal-length arrays with the log's columns (t, theta1, theta2, tau1, tau2 and "
       "optionally omega1, omega2, alpha1, alpha2; a four-bar's: t, theta1, tau1 and optionally "
       "omega1, alpha1). Keyword options are those of `fivebar "
       "identify` with _ for - (sg_window: the Savitzky-Golay half-window [s], chosen from the "
       "log when not given), and validate=False: " +
       keyword_defaults(io::IdentifySettings{}, kIdentifyKeywords,
                        {{"sg_window", "(chosen from the log)"}}) +
       ". Returns every field of identification.json (parameters as a list of {name, unit, value, "
       "std, initial, ci95_low, ci95_high, true, error, ...}, correlation as an array, "
       "condition_number, residual_to_noise_ratio, model_check, truth_in_log, ...), the "
       "covariance, the per-sample rates and predicted torques, 'fitted_scene' (a "
       "fivebar.Scene) and, with validate=True, 'validation'.")
          .c_str());
}

}  // namespace fivebar::python
