// Setup and conditioning stages of identify(): the layout and scene to fit, the start values,
// the conditioned log and where the rates come from.
#include <numeric>

#include "identify_stages.h"
#include "setup_shared.h"

namespace fivebar::identification::stages {

namespace {

/// logged rates this much noisier than the angles' (through the noisiest window) are not used
constexpr double kNoisierRates = 2.0;

}  // namespace

void sg_noise_gains(const std::vector<double>& t, const SgOptions& sg, double* g1, double* g2) {
  int lo = 0;
  std::vector<double> d1, d2;
  savitzky_golay_taps(t, static_cast<int>(t.size()) / 2, sg, &lo, &d1, &d2);
  *g1 = std::sqrt(std::inner_product(d1.begin(), d1.end(), d1.begin(), 0.0));
  *g2 = std::sqrt(std::inner_product(d2.begin(), d2.end(), d2.begin(), 0.0));
}

Eigen::MatrixXd to_public(const ParameterLayout& layout) {
  const int P = layout.size(), G = layout.per_group();
  Eigen::MatrixXd T = Eigen::MatrixXd::Identity(P, P);
  const int g_static = layout.group_of(Coefficient::kStaticCoulomb);
  const int g_coulomb = layout.group_of(Coefficient::kCoulomb);
  if (layout.static_as_excess && g_static >= 0) {
    for (int j = 0; j < G; ++j) T(g_static * G + j, g_coulomb * G + j) = 1.0;
  }
  return T;
}

std::string sample_name(const TorqueLog& log, int i) {
  return "line " + std::to_string(log.lines.empty() ? i + 1 : log.lines[i]) +
         " (t = " + format_significant(log.t[i], 6) + " s)";
}

namespace {

/// The scene with the law to fit and the chosen Coulomb sign form (fit_friction).
Params<double> fit_scene(const Params<double>& scene_in, const ParameterLayout& layout,
                         const IdentifyOptions& opt) {
  Params<double> scene = scene_in;
  scene.friction = fit_friction(scene_in.friction, layout, opt);
  return scene;
}

}  // namespace

void prepare_log(const TorqueLog& log, Fit* f, IdentifyResult* out) {
  // with rates too: degrees with deg/s rates agree with each other
  if (f->opt->check_degrees) {
    std::string unit;
    const std::string why = angle_units_from_motion(f->scene, f->loads, log, &unit);
    if (!why.empty()) {
      const std::string what = unit == kSwappedAngles
                                   ? "the two angles look swapped: the scene's motion fits theta1 "
                                     "in the theta2 column and theta2 in the theta1 column"
                                   : "angles look like " + unit + ", expected radians";
      throw LogError(log.path, "columns theta1, theta2", what + " (" + why + ")");
    }
  }
  f->cond = condition_log(log, f->opt->condition);
  check_poses(f->cond.log, f->scene);
  out->notes = f->cond.notes;
  out->conditioned_log = f->cond.log;
  out->glitches = f->cond.glitches;
  for (int j = 0; j < kDof; ++j) {
    out->unwrapped[j] = f->cond.unwrapped[j];
    out->angle_noise[j] = f->noise.angle[j] = f->cond.angle_noise[j];
    out->torque_noise[j] = f->noise.torque[j] = f->cond.torque_noise[j];
    out->rate_noise[j] = f->noise.rate[j] = f->cond.rate_noise[j];
  }
  if (!f->cond.glitches.empty()) out->warnings.push_back(f->cond.notes.back());
}

bool start_values(Fit* fp, const std::vector<double>& initial, std::vector<double>* x0_public,
                  IdentifyResult* out) {
  const Fit& f = *fp;
  const int P = f.layout.size();
  ParameterLayout pub = f.layout;
  pub.static_as_excess = false;
  *x0_public = initial.empty() ? default_start(pub) : initial;
  if (static_cast<int>(x0_public->size()) == pub.friction_size()) {
    // the other groups start at the scene's values
    const std::vector<double> rest = pub.extract(f.scene);
    x0_public->insert(x0_public->end(), rest.begin() + pub.friction_size(), rest.end());
  }
  if (static_cast<int>(x0_public->size()) != P) {
    out->status = Status::Error(StatusCode::kInvalidInput,
                                "initial values: expected " + std::to_string(P) + " numbers");
    return false;
  }
  const Eigen::VectorXd xi =
      to_public(f.layout).inverse() * Eigen::Map<const Eigen::VectorXd>(x0_public->data(), P);
  std::vector<double> x(xi.data(), xi.data() + P);
  // inside the bounds (a static start below the kinetic one starts at the bound)
  for (int i = 0; i < P; ++i) x[i] = std::max(x[i], f.layout.lower_bound(i));
  fp->x = x;
  return true;
}

void init_fit(const Params<double>& scene_in, const sim::LoadFunction& loads, const TorqueLog& log,
              const IdentifyOptions& opt, Fit* f, IdentifyResult* out) {
  out->layout = opt.layout;
  out->method = opt.method;
  out->samples = log.size();
  out->window_s = output_error_window(opt.window_s, log.duration());
  f->opt = &opt;
  f->method = &method_strategy(opt.method);
  f->loads = loads;
  f->layout = opt.layout;
  f->layout.static_as_excess = f->layout.group_of(Coefficient::kStaticCoulomb) >= 0;
  f->scene = fit_scene(scene_in, f->layout, opt);
  f->sg = opt.sg;
  f->eval.friction_tol = 1e-12;
  f->eval.friction_max_iter = 100;
  if (f->layout.inertia) f->prior = detail::inertial_prior(scene_in, opt.inertia_prior);
}

double initial_prior_scale(const Fit& f) {
  const double s = std::max(f.noise.torque[0], f.noise.torque[1]);
  return s > 0 ? s : 1e-3;
}

bool angles_give_better_rates(const Fit& f, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  SgOptions sg = f.sg;
  sg.half_window_s = (sg.order / 2 + 1) * dt;
  double g1 = 0, g2 = 0;
  sg_noise_gains(log.t, sg, &g1, &g2);
  double from_angles[2];
  for (int j = 0; j < kDof; ++j) {
    from_angles[j] = g1 * f.noise.angle[j];
    if (!(f.noise.rate[j] > kNoisierRates * from_angles[j])) return false;
  }
  out->notes.push_back("the logged rates (noise " + format_significant(f.noise.rate[0]) + ", " +
                       format_significant(f.noise.rate[1]) +
                       " rad/s) are noisier than rates estimated from the "
                       "angles (at most " +
                       format_significant(from_angles[0]) + ", " +
                       format_significant(from_angles[1]) +
                       " rad/s): rates and accelerations estimated from the angles, the logged "
                       "rates not used");
  return true;
}

detail::RateSource rate_source(const Fit& f, const TorqueLog& log, IdentifyResult* out) {
  const detail::RateSource given = !log.has_rates || f.opt->estimate_rates
                                       ? detail::RateSource::kFromAngles
                                   : !log.has_accels ? detail::RateSource::kAccelsFromRates
                                                     : detail::RateSource::kLogged;
  if (given != detail::RateSource::kFromAngles && angles_give_better_rates(f, out)) {
    return detail::RateSource::kFromAngles;
  }
  return given;
}

}  // namespace fivebar::identification::stages
