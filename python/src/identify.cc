// fivebar.identify: friction identification from a torque log, the result as a dict.
#include <pybind11/stl.h>

#include <cmath>

#include "bindings.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
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

py::array_t<double> pair(const double (&a)[2]) { return to_array({a[0], a[1]}); }

// a log given as a dict of arrays: written as CSV text and parsed, so it gets every check of a
// log file (columns, finite numbers, increasing t, degrees)
id::TorqueLog log_from_dict(const py::dict& columns) {
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
    return io::parse_torque_log(text, "log");
  } catch (const id::LogError& e) {
    throw InputError(e.file(), e.key(), e.reason());
  }
}

py::dict validation_dict(const id::Validation& v) {
  py::dict d;
  d["full_run_status"] = v.status.ok() ? "ok" : v.status.message;
  d["full_run_duration_s"] = v.full_duration_s;
  d["full_run_rms_angle_error"] = pair(v.full_rms);
  d["full_run_max_angle_error"] = pair(v.full_max);
  d["window_s"] = v.window_s;
  d["windowed_rms_angle_error"] = pair(v.window_rms);
  d["simulated_theta1"] = to_array(v.full_theta1);
  d["simulated_theta2"] = to_array(v.full_theta2);
  d["windowed_theta1"] = to_array(v.window_theta1);
  d["windowed_theta2"] = to_array(v.window_theta2);
  return d;
}

// identification.json's log_conditioning: unwrapping, noise levels, glitches rejected, notes
py::dict conditioning_dict(const id::IdentifyResult& r) {
  py::dict c;
  c["unwrapped_turns"] = py::make_tuple(r.unwrapped[0], r.unwrapped[1]);
  c["angle_noise"] = pair(r.angle_noise);
  c["torque_noise"] = pair(r.torque_noise);
  if (r.conditioned_log.has_rates) c["rate_noise"] = pair(r.rate_noise);
  py::list glitches;
  for (const id::Glitch& g : r.glitches) {
    glitches.append(py::dict(py::arg("line") = g.line, py::arg("column") = g.column,
                             py::arg("value") = g.value, py::arg("expected") = g.expected,
                             py::arg("noise_std") = g.sigmas));
  }
  c["rejected_glitches"] = glitches;
  c["notes"] = r.notes;
  return c;
}

// the fields of identification.json, the per-sample arrays of residuals.csv, the fitted scene
py::dict result_dict(const PyScene& s, const id::IdentifyResult& r, const id::Loss loss) {
  py::dict d;
  d["method"] = id::method_name(r.method);
  d["law"] = id::law_name(r.layout.law);
  d["per_joint"] = r.layout.per_joint;
  d["loss"] = id::loss_name(loss);
  py::list params;
  for (const id::ParameterEstimate& p : r.parameters) {
    // with the 95 % interval of identification.json
    params.append(py::dict(py::arg("name") = p.name, py::arg("value") = p.value,
                           py::arg("std") = p.std, py::arg("initial") = p.initial,
                           py::arg("ci95_low") = p.ci_low, py::arg("ci95_high") = p.ci_high,
                           py::arg("ci95_method") = p.ci_method));
  }
  d["parameters"] = params;
  d["covariance"] = matrix(r.covariance);
  d["correlation"] = matrix(r.correlation);
  d["singular_values"] = to_array(r.singular_values);
  d["rms_torque_residual"] = pair(r.rms_torque_residual);
  d["residual_noise_floor"] = pair(r.residual_noise_floor);
  d["rms_torque_residual_initial"] = pair(r.rms_torque_residual_initial);
  if (r.method == id::Method::kOutputError) d["rms_angle_residual"] = pair(r.rms_angle_residual);
  d["residual_sigma"] = r.residual_sigma;
  d["samples"] = r.samples;
  d["samples_used"] = r.samples_used;
  d["residuals"] = r.residuals;
  d["rates_estimated"] = r.rates_estimated;
  d["accelerations_estimated"] = r.accels_estimated;
  if (r.accels_estimated) {  // the Savitzky-Golay window used (rate_source in the JSON)
    d["sg_half_window_s"] =
        r.sg_half_window * r.conditioned_log.duration() / std::max(1, r.conditioned_log.size() - 1);
    d["sg_order"] = r.sg_order;
    d["window_choice"] = r.window_choice;  // how the half-window was chosen
  }
  d["log_conditioning"] = conditioning_dict(r);
  if (std::isfinite(r.delay_s)) {  // the logged torques at t + d match the angles at t
    py::dict delay;
    delay["value_s"] = r.delay_s;
    delay["std_s"] = r.delay_std_s;
    delay["corrected"] = r.delay_corrected;
    d["torque_delay"] = delay;
  }
  d["std_method"] = r.std_method;
  py::dict solver;
  solver["iterations"] = r.iterations;
  solver["converged"] = r.converged;
  solver["report"] = r.solver_message;
  solver["iteration_costs"] = to_array(r.iteration_costs);
  d["solver"] = solver;
  d["warnings"] = r.warnings;
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
  d["fitted_scene"] = PyScene(io::fitted_scene(s.scene, r));
  return d;
}

py::dict identify(const PyScene& s, const py::object& log, const io::IdentifySettings& settings,
                  bool validate) {
  const id::IdentifyOptions options = io::identify_options(settings, s.scene);
  const id::TorqueLog torque_log = py::isinstance<py::dict>(log)
                                       ? log_from_dict(log.cast<py::dict>())
                                       : io::read_log(py::str(log));
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
  py::dict d = result_dict(s, result, options.loss);
  if (validate) d["validation"] = validation_dict(validation);
  return d;
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
       "optionally omega1, omega2, alpha1, alpha2). Keyword options are those of `fivebar "
       "identify` with _ for - (sg_window: the Savitzky-Golay half-window [s], chosen from the "
       "log when not given), and validate=False: " +
       keyword_defaults(io::IdentifySettings{}, kIdentifyKeywords,
                        {{"sg_window", "(chosen from the log)"}}) +
       ". Returns the fields of identification.json (parameters as a list of {name, value, std, "
       "initial}, covariance and correlation as arrays, ...), the per-sample rates and "
       "predicted torques, 'fitted_scene' (a fivebar.Scene) and, with validate=True, "
       "'validation'.")
          .c_str());
}

}  // namespace fivebar::python
