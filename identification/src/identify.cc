// identify(): the pipeline of the stages (identify_stages.h), the method's strategy
// (method.h) chosen once; the enum names and the logged loads.
#include "fivebar/identification/identify.h"

#include <glog/logging.h>

#include <mutex>

#include "identify_stages.h"

namespace fivebar::identification {

void stages::quiet_solver_logging() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (!google::IsGoogleLoggingInitialized()) google::InitGoogleLogging("fivebar");
    FLAGS_minloglevel = google::GLOG_FATAL;
    FLAGS_stderrthreshold = google::GLOG_FATAL;
    FLAGS_logtostderr = false;
  });
}

using namespace stages;

namespace {
constexpr Named<Method> kMethodNames[] = {{Method::kInverseDynamics, "inverse-dynamics"},
                                          {Method::kOutputError, "output-error"}};
constexpr Named<Loss> kLossNames[] = {
    {Loss::kNone, "none"}, {Loss::kHuber, "huber"}, {Loss::kCauchy, "cauchy"}};
}  // namespace

bool parse_method(const std::string& name, Method* out) { return parse_in(kMethodNames, name, out); }

const char* method_name(Method m) { return name_in(kMethodNames, m); }

bool parse_loss(const std::string& name, Loss* out) { return parse_in(kLossNames, name, out); }

const char* loss_name(Loss l) { return name_in(kLossNames, l); }

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

sim::FourBarLoadFunction logged_loads(const TorqueLog& log,
                                      const sim::FourBarLoadFunction& scene_loads, double t0,
                                      double offset) {
  const std::vector<double>* t = &log.t;
  const std::vector<double>* tau1 = &log.tau1;
  return [t, tau1, scene_loads, t0, offset](double s) {
    FourBarLoads L = scene_loads(t0 + s);
    L.M1 = interp(*t, *tau1, t0 + s) - offset;
    return L;
  };
}

namespace {

/// a torque-to-angle delay beyond this many std is corrected
constexpr double kDelaySignificance = 3.0;

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

/// Conditioning, rates and window, start values: the fit's state up to its samples; false (and
/// out->status) when a stage stops the fit.
bool prepare_fit(const Params<double>& scene_in, const sim::LoadFunction& loads,
                 const TorqueLog& log, const IdentifyOptions& opt, Fit* f,
                 std::vector<double>* x0_public, IdentifyResult* out) {
  init_fit(scene_in, loads, log, opt, f, out);
  if ((f->layout.inertia || f->layout.actuator) && !f->method->fits_groups()) {
    out->status = Status::Error(StatusCode::kInvalidInput,
                                std::string("the ") + (f->layout.inertia ? "inertia" : "actuator") +
                                    " group needs the inverse-dynamics method");
    return false;
  }
  const int P = f->layout.size();
  require_samples(log, P + 1, std::to_string(P) + " parameters + 1");
  require_uniform_sampling(log);
  // the log as encoders write it: degrees, wraps, glitches; then rates
  prepare_log(log, f, out);
  f->cost_weight = f->method->cost_weight(f->cond.log);
  f->source = rate_source(*f, log, out);
  if (!start_values(f, opt.initial, x0_public, out)) return false;
  f->prior_scale = initial_prior_scale(*f);
  return rates_window_and_samples(log, f, out);
}

/// The residual of both torque channels over their noise floors, sqrt((q1^2 + q2^2) / 2) with q_c
/// the channel's rms residual over its floor: the measure a shift of the torques must lower (each
/// fit against its own floor: the shifted torques' noise is smoothed, and so is their floor)
double both_channels_misfit(const IdentifyResult& r) {
  double sum = 0;
  for (int c = 0; c < kActuators; ++c) {
    sum += std::pow(r.rms_torque_residual[c] / r.residual_noise_floor[c], 2);
  }
  return std::sqrt(sum / kActuators);
}

/// A delay estimate beyond this many of its std is named even where the model check does not
/// evidence it (unevidenced_delay)
constexpr double kDelayNamedZ = 5;

/// "the torques seem to lag the angles by D +- s ms" of out's delay estimate
std::string delay_seen(const IdentifyResult& out) {
  return std::string("the torques seem to ") + (out.delay_s < 0 ? "lead" : "lag") +
         " the angles by " + format_significant(std::abs(out.delay_s) * 1e3) + " +- " +
         format_significant(out.delay_std_s * 1e3) + " ms";
}

/// Where the model check did not run (a log too short for its columns): why the fit with the
/// torques shifted does not explain the misfit ("" when it does): it is not usable itself, or
/// it does not lower the residual of both channels over their floors, or it leaves the residual
/// above kMisfitRatio floors and above half the unshifted fit's ratio.
/// (A light mechanism whose masses were 5 % off, no delay, read a lag of 0.67 ms at 6.8 std;
/// shifted, its residual rose from 1.36 to 1.48 floors on tau2: the mismatch, not a delay.)
std::string shift_unexplained(const IdentifyResult& unshifted, const IdentifyResult& shifted) {
  const double before = misfit_ratio(unshifted), after = misfit_ratio(shifted);
  const std::string floors =
      " times its noise floor (" + format_significant(before, 3) + " without)";
  if (!shifted.unusable.empty()) {
    return "the fit with them shifted is not to be used (" + shifted.unusable + ")";
  }
  const double lowered = both_channels_misfit(unshifted) - both_channels_misfit(shifted);
  if (!(lowered > 0)) {
    return "the fit with them shifted does not lower the residual: " +
           format_significant(after, 3) + floors;
  }
  if (after > kMisfitRatio && after > 0.5 * before) {
    return "the fit with them shifted keeps its residual at " + format_significant(after, 3) +
           floors;
  }
  return "";
}

/// A delay whose own estimate is beyond kDelayNamedZ of its std while the model check, which
/// evidences no model cause either, does not evidence it beyond the noise: named in a warning,
/// not corrected. At a noisy window the check's whitened residual drowns the delay's fall (a
/// light five-bar's torques 8 ms early: 8.58 +- 0.83 ms by its own estimate, 2.5 std in the
/// check at a half-window of 6 samples). Clean logs' estimates stay within 3 std; a model
/// error that the delay's column fits is evidenced itself, and its warning names it.
void unevidenced_delay(IdentifyResult* out) {
  if (!(std::abs(out->delay_s) > kDelayNamedZ * out->delay_std_s)) return;
  for (const IdentifyResult::MisfitCause& c : out->model_check) {
    if (stages::counts_alone(c) && c.checked && c.z > detail::kCauseZ) return;
  }
  out->warnings.push_back(delay_seen(*out) + " (" +
                          format_significant(std::abs(out->delay_s) / out->delay_std_s, 2) +
                          " std), but the model check at this window does not evidence it beyond "
                          "the noise; not corrected (a logger's known lag can be taken out of the "
                          "torques' times, or the rates logged)");
  out->delay_unexplained = true;
}

/// The torque-to-angle delay when the readings' checks leave the fit usable: the fit redone
/// with the torques shifted (true, *refit), else out's delay fields. The model check judged the
/// delay as one more candidate cause (verdict.delay: its fall of the whitened cost evidenced
/// against its own noise, and clearly beyond every other cause's); the shift is made when it
/// explains most and is over a tenth of a sample, and kept when the shifted fit is usable.
/// A delay not evidenced beyond the model causes is left silently (masses 3 % off a heavy
/// mechanism read as a lead of 2.4 ms at 23 std: the model check's warnings name the masses, the
/// delay's fall among the others); one evidenced but not clearly beyond another cause's fall is
/// named a model error, uncorrected: no output shows the shift. Without the check (a short log),
/// the estimate's significance and shift_unexplained decide.
bool delay_stage(const Params<double>& scene_in, const sim::LoadFunction& loads,
                 const TorqueLog& log, const Fit& f, const Analysis& an,
                 const ModelVerdict& verdict, IdentifyResult* out, IdentifyResult* refit) {
  using Delay = ModelVerdict::Delay;
  estimate_delay(f, an.J, an.r, an.sens, out);
  const double dt = log.duration() / std::max(1, log.size() - 1);
  const bool checked = verdict.delay != Delay::kUnchecked;
  if (checked && verdict.delay == Delay::kNotEvidenced) {
    unevidenced_delay(out);
    return false;
  }
  if (!(std::abs(out->delay_s) > 0.1 * dt) ||
      (!checked && !(std::abs(out->delay_s) > kDelaySignificance * out->delay_std_s))) {
    return false;
  }
  if (!checked && !verdict.short_log) {  // the check could not run: its warning says why
    out->warnings.push_back(delay_seen(*out) + ", but the model check did not run (" +
                            verdict.unchecked +
                            "), so nothing tells it from a model error; "
                            "not corrected");
    out->delay_unexplained = true;
    return false;
  }
  std::string why = verdict.delay_falls;
  if (verdict.delay != Delay::kNotMost) {
    IdentifyResult shifted = refit_with_delay(scene_in, loads, f.cond.log, *f.opt, *out);
    why = !checked ? shift_unexplained(*out, shifted)
          : shifted.unusable.empty()
              ? ""
              : "the fit with them shifted is not to be used (" + shifted.unusable + ")";
    if (why.empty()) {
      *refit = std::move(shifted);
      return true;
    }
  }
  out->warnings.push_back(delay_seen(*out) + ", but " + why +
                          (verdict.delay == Delay::kExplainsMost ? std::string("; not corrected")
                           : verdict.delay_tied
                               ? std::string(": a delay or a model error, the log cannot tell "
                                             "which; not corrected")
                               : std::string(": a model error, not a delay; not corrected")));
  out->delay_unexplained = true;
  return false;
}

}  // namespace

double output_error_window(double window_s, double duration) {
  return window_s > 0 ? window_s : std::min(0.2, duration / 20);
}

IdentifyResult identify(const Params<double>& scene_in, const sim::LoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& opt) {
  return identify_fit(scene_in, loads, log, opt, true);
}

bool identify_window(const Params<double>& scene, const sim::LoadFunction& loads,
                     const TorqueLog& log, const IdentifyOptions& options, SgOptions* sg,
                     std::string* choice) {
  stages::quiet_solver_logging();
  IdentifyResult out;
  Fit f;
  std::vector<double> x0_public;
  if (!prepare_fit(scene, loads, log, options, &f, &x0_public, &out)) {
    *choice = out.status.message;
    return false;
  }
  *sg = f.sg;
  *choice = out.window_choice;
  return true;
}

IdentifyResult identify_fit(const Params<double>& scene_in, const sim::LoadFunction& loads,
                            const TorqueLog& log, const IdentifyOptions& opt, bool full) {
  stages::quiet_solver_logging();
  const auto start = Clock::now();
  const auto finish = [&](IdentifyResult r) {
    r.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
    return r;
  };
  IdentifyResult out;
  Fit f;
  std::vector<double> x0_public;
  if (!prepare_fit(scene_in, loads, log, opt, &f, &x0_public, &out)) return out;
  choose_loss_scale(&f, &out);
  ceres::Problem problem;
  if (!build_problem(&f, &out, &problem)) {
    out.status = Status::Error(StatusCode::kInvalidInput, "unsupported parameter count");
    return out;
  }
  ceres::Solver::Summary summary;
  Analysis an;
  if (!solve_stage(&f, &problem, &out, &summary, &an)) return out;
  analyse(f, x0_public, summary, &an, &out);  // levels, covariance, identifiability, estimates
  if (!full) return finish(out);
  const ModelVerdict verdict = f.method->check_model(f, an, &out);
  intervals(f, &problem, an, &out);
  correct_smoothing_bias(f.layout, f.smoothing_bias, &f.x, &out, f.smoothing_bias_spread);
  out.fitted = scene_in;
  f.layout.apply(f.x.data(), &out.fitted);
  follow_static_coulomb(f.layout, scene_in, &out.fitted);
  predictions(f, &out);
  f.method->prediction_levels(f, &out);
  const bool sign_wrong = torques_fit_negated(scene_in, loads, log, opt, verdict, &out);
  const bool law_wrong =
      !sign_wrong && friction_differs_by_joint(scene_in, loads, log, opt, verdict, &out);
  IdentifyResult refit;
  if (f.method->checks_readings() && opt.estimate_delay && !sign_wrong && !law_wrong &&
      delay_stage(scene_in, loads, log, f, an, verdict, &out, &refit)) {
    return finish(refit);
  }
  unexplained_misfit(f.layout, &out);
  // last: a model error the checks above name inflates the predicted bias too
  unbiased_window_check(f, verdict, &out);
  wider_window_check(f, &out);
  return finish(out);
}

}  // namespace fivebar::identification
