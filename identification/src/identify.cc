#include "fivebar/identification/identify.h"
#include <ceres/ceres.h>
#include <Eigen/Dense>
#include <array>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <mutex>
#include <memory>
#include <sstream>
#include <glog/logging.h>
#include "fivebar/identification/residual.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/names.h"
#include "fivebar/model/rest.h"
#include "identify_stages.h"
#include "covariance.h"
#include "fallback_cost.h"
#include "inertia.h"
#include "misfit.h"
#include "noise_model.h"
#include "profile.h"
#include "smoothing_bias.h"
#include "window_misfit.h"

namespace fivebar::identification {

using namespace stages;

constexpr Named<Method> kMethodNames[] = {{Method::kInverseDynamics, "inverse-dynamics"},
                                          {Method::kOutputError, "output-error"}};

constexpr Named<Loss> kLossNames[] = {
    {Loss::kNone, "none"}, {Loss::kHuber, "huber"}, {Loss::kCauchy, "cauchy"}};

bool parse_method(const std::string& name, Method* out) { return parse_in(kMethodNames, name, out); }

const char* method_name(Method m) { return name_in(kMethodNames, m); }

bool parse_loss(const std::string& name, Loss* out) { return parse_in(kLossNames, name, out); }

const char* loss_name(Loss l) { return name_in(kLossNames, l); }

/// a torque-to-angle delay beyond this many std is corrected
constexpr double kDelaySignificance = 3.0;

sim::LoadFunction logged_loads(const TorqueLog& log, const sim::LoadFunction& scene_loads,
                               double t0, std::array<double, kActuators> offset) {
  // the simulator calls in nearly increasing t: no shared state, just a binary search
  const std::vector<double>* t = &log.t;
  const std::vector<double>* tau1 = &log.tau1;
  const std::vector<double>* tau2 = &log.tau2;
  return [t, tau1, tau2, scene_loads, t0, offset](double s) {
    Loads<double> L = scene_loads(t0 + s);
    L.M1 = interp(*t, *tau1, t0 + s) - offset[0];
    L.M2 = interp(*t, *tau2, t0 + s) - offset[1];
    return L;
  };
}

/// Ceres reports through glog on stderr ("Terminating: ..."); library code never prints: the
/// outcome is in the summary we return. Once per process, glog is told to keep quiet.
void quiet_solver_logging() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("fivebar");
    FLAGS_minloglevel = google::GLOG_FATAL;
    FLAGS_stderrthreshold = google::GLOG_FATAL;
    FLAGS_logtostderr = false;
  });
}

/// A law fitted without static friction: the fitted scene's static Coulomb coefficient (the
/// holding bound) follows the fitted Coulomb where the scene's followed its own (its default),
/// and is never left below it (static friction below kinetic is not physical).
void follow_static_coulomb(const ParameterLayout& layout, const Params<double>& scene,
                           Params<double>* fitted) {
  if (layout.group_of(Coefficient::kStaticCoulomb) >= 0) return;
  FrictionParams<double>& fp = fitted->friction;
  for (int k = 0; k < kJoints; ++k) {
    if (fp.static_coulomb[k] == scene.friction.coulomb[k] || fp.static_coulomb[k] < fp.coulomb[k]) {
      fp.static_coulomb[k] = fp.coulomb[k];
    }
  }
}

double output_error_window(double window_s, double duration) {
  return window_s > 0 ? window_s : std::min(0.2, duration / 20);
}

IdentifyResult identify(const Params<double>& scene_in, const sim::LoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& opt) {
  return identify_fit(scene_in, loads, log, opt, true);
}

IdentifyResult identify_fit(const Params<double>& scene_in, const sim::LoadFunction& loads,
                            const TorqueLog& log, const IdentifyOptions& opt, bool full) {
  quiet_solver_logging();
  const auto start = Clock::now();
  IdentifyResult out;
  Fit f;
  init_fit(scene_in, loads, log, opt, &f, &out);
  if ((f.layout.inertia || f.layout.actuator) && opt.method != Method::kInverseDynamics) {
    out.status = Status::Error(StatusCode::kInvalidInput,
                               std::string("the ") + (f.layout.inertia ? "inertia" : "actuator") +
                                   " group needs the inverse-dynamics method");
    return out;
  }
  const int P = f.layout.size();
  require_samples(log, P + 1, std::to_string(P) + " parameters + 1");
  require_uniform_sampling(log);

  // the log as encoders write it: degrees, wraps, glitches; then rates
  prepare_log(log, &f, &out);
  f.source = !log.has_rates || opt.estimate_rates ? detail::RateSource::kFromAngles
             : !log.has_accels                    ? detail::RateSource::kAccelsFromRates
                                                  : detail::RateSource::kLogged;
  if (f.source != detail::RateSource::kFromAngles && angles_give_better_rates(f, &out)) {
    f.source = detail::RateSource::kFromAngles;
  }
  std::vector<double> x0_public;
  if (!start_values(&f, opt.initial, &x0_public, &out)) return out;
  f.prior_scale = initial_prior_scale(f);
  if (!rates_window_and_samples(log, &f, &out)) return out;
  choose_loss_scale(&f, &out);
  ceres::Problem problem;
  if (!build_problem(&f, &out, &problem)) {
    out.status = Status::Error(StatusCode::kInvalidInput, "unsupported parameter count");
    return out;
  }
  ceres::Solver::Summary summary;
  Analysis an;
  if (!solve_stage(&f, &problem, &out, &summary, &an)) return out;
  analyse(f, x0_public, summary, &an, &out);
  if (!full) {
    out.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
    return out;
  }
  ModelVerdict verdict;
  if (opt.method == Method::kInverseDynamics) {
    bound_and_misfit_warning(f, an, &out);
    verdict = model_check(f, &out);
  }
  intervals(f, &problem, an, &out);
  correct_smoothing_bias(&f, &out);
  out.fitted = scene_in;
  f.layout.apply(f.x.data(), &out.fitted);
  follow_static_coulomb(f.layout, scene_in, &out.fitted);
  predictions(f, &out);
  if (opt.method == Method::kOutputError) output_error_levels(f, &out);
  const bool sign_wrong = torques_fit_negated(scene_in, loads, log, opt, verdict, &out);
  const bool law_wrong =
      !sign_wrong && friction_differs_by_joint(scene_in, loads, log, opt, verdict, &out);
  if (opt.method == Method::kInverseDynamics && opt.estimate_delay && !sign_wrong && !law_wrong) {
    estimate_delay(f, an.J, an.r, an.sens, &out);
    const double dt = log.duration() / std::max(1, log.size() - 1);
    if (std::abs(out.delay_s) > kDelaySignificance * out.delay_std_s &&
        std::abs(out.delay_s) > 0.1 * dt) {
      IdentifyResult res = refit_with_delay(scene_in, loads, f.cond.log, opt, out);
      res.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
      return res;
    }
  }
  out.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

}  // namespace fivebar::identification
