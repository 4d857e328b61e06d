// identify() of the four-bar (identify.h): the default method, inverse dynamics, over the
// mechanism FourBar, through the stages of the five-bar's fit in their one-crank form
// (docs/identification.md, "Four-bar"): conditioning (condition_log), rates and samples (logged,
// or Savitzky-Golay with the rest rule and the slip reversals left out), the data-driven window
// and its smoothing bias (the five-bar's stages, mechanism_stages.h, over FourBarWindowFit), the
// fit (the mechanism residual, mechanism_residual.h), the covariance (the five-bar's errors in
// variables, noise_model.h), the residual checks (against its noise floor, setup_shared.h), the
// model check's candidate causes (four_bar_model_check.cc), the intervals (Wald, profile
// likelihood), and the refits of the checks after it (four_bar_refits.cc).
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "covariance.h"
#include "fivebar/identification/identify.h"
#include "fivebar/model/format.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/sim/simulator.h"
#include "four_bar_fit.h"
#include "glitches.h"
#include "mechanism_residual.h"
#include "mechanism_stages.h"
#include "method.h"
#include "setup_shared.h"

namespace fivebar::identification {

namespace four_bar {

std::string line_of(const TorqueLog& log, int i) {
  return "line " + std::to_string(log.lines.empty() ? i + 1 : log.lines[i]);
}

/// The scene with the shared law coulomb_viscous at the coefficients (c, v) on its pins.
FourBarParams with_friction(const FourBarParams& scene, double c, double v) {
  FourBarParams p = scene;
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.coulomb.fill(c);
  p.friction.static_coulomb.fill(c);
  p.friction.viscous.fill(v);
  p.friction.smoothing_velocity = 0;
  return p;
}

/// y less its least-squares fit by the columns X with non-negative coefficients (two columns:
/// both, else the better one alone, else none).
std::vector<double> less_fit(const std::vector<double>& y,
                             const std::vector<std::array<double, 2>>& X) {
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < y.size(); ++i) {
    if (!std::isfinite(y[i])) continue;
    const Eigen::Vector2d x(X[i][0], X[i][1]);
    A += x * x.transpose();
    b += y[i] * x;
  }
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  if (A.determinant() > 1e-12 * A(0, 0) * A(1, 1) && A.ldlt().solve(b).minCoeff() >= 0) {
    c = A.ldlt().solve(b);
  } else {  // one column alone: the one that lowers the squares most
    double best = 0;
    for (int k = 0; k < 2; ++k) {
      if (!(A(k, k) > 0) || !(b(k) > 0) || !(b(k) * b(k) / A(k, k) > best)) continue;
      best = b(k) * b(k) / A(k, k);
      c.setZero();
      c(k) = b(k) / A(k, k);
    }
  }
  std::vector<double> r(y.size());
  for (size_t i = 0; i < y.size(); ++i) r[i] = y[i] - c(0) * X[i][0] - c(1) * X[i][1];
  return r;
}

/// The four-bar's reading of crank angles `th` at Savitzky-Golay rates over the half-window
/// `sg` against the logged torques: the median |logged torque less the frictionless inverse
/// dynamics and less the friction that fits it best| (the shared law coulomb_viscous on the
/// scene's pins, its two coefficients non-negative, by least squares), on at most ~400 samples.
double torque_mismatch(const FourBarFit& f, const TorqueLog& log, const std::vector<double>& th,
                       const SgOptions& sg, double* median_rate) {
  // unit coefficients small enough for the drive torque to be linear in them
  constexpr double kUnitCoulomb = 1e-3, kUnitViscous = 1e-4;
  const int n = log.size();
  const int step = std::max(1, n / 400);
  std::vector<double> w, a;  // at the samples read below only
  savitzky_golay(log.t, th, sg, &w, &a, step);
  const FourBarParams p0 = with_friction(f.scene, 0, 0);
  const FourBarParams pc = with_friction(f.scene, kUnitCoulomb, 0);
  const FourBarParams pv = with_friction(f.scene, 0, kUnitViscous);
  std::vector<double> y, rate;
  std::vector<std::array<double, 2>> X;
  for (int i = 0; i < n; i += step) {
    const FourBarLoadsT<double> loads = f.loads(log.t[i]);
    FourBarEvaluation e0, ec, ev;
    const bool ok = four_bar_inverse(p0, loads, th[i], w[i], a[i], EvalOptions{}, &e0).ok() &&
                    four_bar_inverse(pc, loads, th[i], w[i], a[i], EvalOptions{}, &ec).ok() &&
                    four_bar_inverse(pv, loads, th[i], w[i], a[i], EvalOptions{}, &ev).ok();
    y.push_back(ok ? log.tau1[i] - e0.M1 : glitches::kInf);
    X.push_back(
        ok ? std::array<double, 2>{(ec.M1 - e0.M1) / kUnitCoulomb, (ev.M1 - e0.M1) / kUnitViscous}
           : std::array<double, 2>{0, 0});
    rate.push_back(w[i]);
  }
  *median_rate = glitches::median_abs(rate);
  return glitches::median_abs(less_fit(y, X));
}

/// The four-bar's reading of crank angles `th` against the logged torques (TorqueMismatch,
/// condition.h): the smaller mismatch of the default 10 ms half-window and of kWideReading
/// times it. The friction fitted: a log in turns of a light crank-rocker whose friction is a
/// large share of its torque read the turns 0.35 of the radians' mismatch without it, not the
/// quarter the unit rule asks (the fit then exited 3 naming the law or the scene). The wide
/// window: a crane-sized four-bar's acceleration noise through its inertias was most of both
/// readings' mismatch at 10 ms (turns 1.3e5 N m against radians 3.9e5).
double torque_mismatch(const FourBarFit& f, const TorqueLog& log, const std::vector<double>& th,
                       double* median_rate) {
  constexpr double kWideReading = 4;
  SgOptions wide;
  wide.half_window_s *= kWideReading;
  double rate_wide = 0;
  const double m = torque_mismatch(f, log, th, SgOptions{}, median_rate);
  const double mw = torque_mismatch(f, log, th, wide, &rate_wide);
  if (mw < m) *median_rate = rate_wide;
  return std::min(m, mw);
}

/// Conditioning: angles in another unit than radians (angle_units_from_motion, with
/// check_degrees), the log's shape, unwrapping and glitches (condition_log), then every pose
/// assembles with the scene's four-bar (a LogError naming the line when one does not).
void condition(const TorqueLog& log, FourBarFit* f, IdentifyResult* out) {
  if (log.dof != 1) {
    throw LogError(log.path, "header",
                   "has the columns of " + std::to_string(log.dof) +
                       " cranks; a four_bar's log has one: t, theta1, tau1 (and optionally "
                       "omega1, alpha1)");
  }
  const int P = f->layout.size();
  require_samples(log, P + 1, std::to_string(P) + " parameters + 1");
  require_uniform_sampling(log);
  std::string unit;
  const std::string why =
      !f->opt->check_degrees ? ""
                             : angle_units_from_motion(
                                   log,
                                   [&](const std::vector<double>& th, const std::vector<double>&,
                                       double* rate) { return torque_mismatch(*f, log, th, rate); },
                                   &unit);
  if (!why.empty()) {
    throw LogError(log.path, "column theta1",
                   "angles look like " + unit + ", expected radians (" + why + ")");
  }
  f->cond = condition_log(log, f->opt->condition);
  const TorqueLog& L = f->cond.log;
  f->cost_weight = stages::torque_cost_weight(L);
  for (int i = 0; i < L.size(); ++i) {
    FourBarKinematics k;
    const Status st = four_bar_close(f->scene, L.theta1[i], &k, 0.0);
    if (!st.ok()) throw LogError(log.path, line_of(log, i) + ", column theta1", st.message);
  }
  out->notes = f->cond.notes;
  out->conditioned_log = L;
  out->glitches = f->cond.glitches;
  out->unwrapped[0] = f->cond.unwrapped[0];
  out->angle_noise[0] = f->cond.angle_noise[0];
  out->torque_noise[0] = f->cond.torque_noise[0];
  out->rate_noise[0] = f->cond.rate_noise[0];
  f->noise.angle[0] = f->cond.angle_noise[0];
  f->noise.rate[0] = f->cond.rate_noise[0];
  f->noise.torque[0] = f->cond.torque_noise[0];
}

/// Whether the rates and accelerations come from the angles through the data-driven window: the
/// angles alone (no logged rates, or --estimate-rates) and no window given.
bool data_driven_window(const TorqueLog& L, const IdentifyOptions& opt) {
  return (!L.has_rates || opt.estimate_rates) && opt.auto_window;
}

/// The Savitzky-Golay filter before the window choice, and its text: as given (--sg-window),
/// else the options' with the polynomial's order at least kWindowOrder (logged rates: over the
/// options' half-window, no data-driven choice).
SgOptions filter_options(const TorqueLog& L, const IdentifyOptions& opt, std::string* why) {
  SgOptions sg = opt.sg;
  if (!opt.auto_window) {
    *why = "given: --sg-window";
    return sg;
  }
  sg.order = std::max(sg.order, kWindowOrder);
  if (!data_driven_window(L, opt)) {
    *why = "default: the four-bar's order " + std::to_string(sg.order) +
           " over the default half-window (logged rates: no data-driven choice)";
  }
  return sg;
}

void rates(FourBarFit* f, IdentifyResult* out) {
  const TorqueLog& L = f->cond.log;
  const IdentifyOptions& opt = *f->opt;
  const int n = L.size();
  const double dt = L.duration() / std::max(1, n - 1);
  const bool logged = L.has_rates && !opt.estimate_rates;
  const bool accels_logged = logged && L.has_accels;
  const SgOptions& sg = f->sg;
  std::vector<double> w_sg, a_sg;
  savitzky_golay(L.t, L.theta1, sg, &w_sg, &a_sg);
  f->w = logged ? L.omega1 : w_sg;
  f->a = accels_logged ? L.alpha1 : a_sg;
  double g1 = 0, g2 = 0;
  stages::sg_noise_gains(L.t, sg, &g1, &g2);
  f->rate_noise = logged ? f->cond.rate_noise[0] : f->cond.angle_noise[0] * g1;
  f->accel_noise = accels_logged ? f->cond.accel_noise[0] : f->cond.angle_noise[0] * g2;
  f->hw = accels_logged ? 0 : sg_half_window(sg, dt);
  f->first = f->hw;
  f->last = n - 1 - f->hw;
  out->rates_estimated = !logged;
  out->accels_estimated = !accels_logged;
  if (out->accels_estimated) {
    out->sg_half_window = f->hw;
    out->sg_order = sg.order;
  }
  out->omega1 = f->w;
  out->alpha1 = f->a;
}

/// The torque residual's expected rms from the sensor noise: the torque noise and the
/// acceleration noise through M(q), floored at kAbsoluteFloor of the rms logged torque;
/// *from_noise: the floor is the noise's (not the 0.1 % of a nearly noise-free log).
double noise_floor(const FourBarFit& f, bool* from_noise) {
  const double tn = f.cond.torque_noise[0];
  double s2 = 0, tau2 = 0;
  for (const Sample& s : f.samples) {
    FourBarKinematics k;
    double M = 0, Q0 = 0;
    if (four_bar_kinematics(f.scene, s.q[0], &k).ok()) {
      four_bar_mass_and_force(f.scene, k, four_bar_bias(f.scene, k, s.v[0]), s.loads, &M, &Q0);
    }
    s2 += tn * tn + M * M * f.accel_noise * f.accel_noise;
    tau2 += s.tau[0] * s.tau[0];
  }
  const double m = std::max<double>(1, f.samples.size());
  const double noise = std::sqrt(s2 / m), floor = stages::kAbsoluteFloor * std::sqrt(tau2 / m);
  *from_noise = noise >= floor;
  return std::max(noise, floor);
}

double rms(const std::vector<double>& r) {
  double s = 0;
  for (double v : r) s += v * v;
  return r.empty() ? 0.0 : std::sqrt(s / r.size());
}

/// The public start values: the options' or the neutral friction ones, the other groups (given
/// the friction's values alone) at the scene's: its links' standard inertial parameters, its
/// crank motor's actuator terms.
std::vector<double> public_start(const FourBarFit& f) {
  std::vector<double> x0 =
      f.opt->initial.empty() ? stages::default_start(f.layout) : f.opt->initial;
  if (static_cast<int>(x0.size()) != f.layout.friction_size()) return x0;
  if (f.layout.inertia) {
    std::vector<double> pi(f.layout.inertial_size());
    standard_inertial_links(f.scene.links.data(), f.layout.links, pi.data());
    x0.insert(x0.end(), pi.begin(), pi.end());
  }
  if (f.layout.actuator) {
    const std::vector<double> a = f.layout.extract_actuators(f.scene.actuators);
    x0.insert(x0.end(), a.begin(), a.end());
  }
  return x0;
}

/// Start values in the internal layout (Stribeck: static_coulomb as its excess over coulomb),
/// from public_start, inside the bounds; false (out->status) when malformed.
bool start_values(FourBarFit* f, IdentifyResult* out) {
  const ParameterLayout& lay = f->layout;
  const int P = lay.size();
  const std::vector<double> x0 = public_start(*f);
  if (static_cast<int>(x0.size()) != P) {
    out->status = Status::Error(StatusCode::kInvalidInput,
                                "initial values: expected " + std::to_string(P) + " numbers");
    return false;
  }
  const Eigen::VectorXd xi =
      stages::to_public(lay).inverse() * Eigen::Map<const Eigen::VectorXd>(x0.data(), P);
  f->x.assign(xi.data(), xi.data() + P);
  for (int i = 0; i < P; ++i) f->x[i] = std::max(f->x[i], lay.lower_bound(i));
  return true;
}

/// The fit: the residual blocks on f->x (its start values), the bounds, the solve. False
/// (out->status) when the model fails at the start values, or the solver fails.
/// The five-bar's inverse-dynamics solver settings: the fit's and its profiles' re-fits.
ceres::Solver::Options solver_options(const FourBarFit& f) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = f.opt->max_iterations;
  so.num_threads = f.opt->num_threads;
  stages::method_strategy(Method::kInverseDynamics).set_tolerances(&so);
  so.logging_type = ceres::SILENT;
  return so;
}

/// The robust loss's scale (--loss): as given, else loss_scale_from_level at the residual's
/// noise floor per sample.
void choose_loss_scale(FourBarFit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  if (opt.loss == Loss::kNone) return;
  f->loss_scale = opt.loss_scale > 0
                      ? opt.loss_scale
                      : stages::loss_scale_from_level(opt.loss, out->residual_noise_floor[0], out);
  out->loss_scale = f->loss_scale;
}

bool solve(FourBarFit* f, ceres::Problem* problem, IdentifyResult* out) {
  const ParameterLayout& lay = f->layout;
  const int P = lay.size();
  stages::add_mechanism_terms<FourBar>(f->scene, lay, f->samples, f->eval, f->x.data(), problem,
                                       f->opt->loss, f->loss_scale, f->cost_weight);
  if (lay.inertia) {  // the prior's rows follow the samples'
    problem->AddResidualBlock(
        detail::inertial_prior_cost(f->prior, P, lay.inertia_offset(), &f->prior_scale),
        stages::make_loss(Loss::kNone, 0, f->cost_weight), f->x.data());
  }
  for (int i = 0; i < P; ++i) problem->SetParameterLowerBound(f->x.data(), i, lay.lower_bound(i));
  out->residuals = static_cast<int>(f->samples.size());
  std::vector<double> r;
  if (!stages::raw_residuals(problem, &r)) {
    out->status = Status::Error(StatusCode::kFrictionNotConverged,
                                "the four-bar's inverse dynamics fails at the start values");
    return false;
  }
  r.resize(f->samples.size());
  out->rms_torque_residual_initial[0] = rms(r);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options(*f), problem, &summary);
  return record_solve(summary, f->cost_weight, out);
}

bool record_solve(const ceres::Solver::Summary& summary, double cost_weight, IdentifyResult* out) {
  out->iterations = static_cast<int>(summary.iterations.size()) - 1;
  out->solver_message = summary.message;
  for (const ceres::IterationSummary& it : summary.iterations) {
    out->iteration_costs.push_back(it.cost / cost_weight);
  }
  out->converged = summary.termination_type == ceres::CONVERGENCE;
  if (summary.termination_type == ceres::FAILURE ||
      summary.termination_type == ceres::USER_FAILURE) {
    out->status = Status::Error(StatusCode::kSolverFailed, "the solver failed: " + summary.message);
    return false;
  }
  if (!out->converged)
    out->warnings.push_back("the solver stopped before converging: " + summary.message);
  return true;
}

/// The fitted scene, and its inverse dynamics at every sample of the log (sim::inverse_rows, the
/// four-bar's inverse dynamics compiled once in the simulator; NaN at every sample when a row
/// fails, which it names in a warning).
void predictions(const FourBarFit& f, IdentifyResult* out) {
  out->fitted_four_bar = f.scene;
  f.layout.apply(f.x.data(), &out->fitted_four_bar);
  const TorqueLog& L = f.cond.log;
  std::vector<sim::Row> motion(L.size()), rows;
  for (int i = 0; i < L.size(); ++i) {
    motion[i].t = L.t[i];
    motion[i].theta[0] = L.theta1[i];
    motion[i].omega[0] = f.w[i];
    motion[i].alpha[0] = f.a[i];
  }
  out->predicted_tau1.assign(L.size(), kNaN);
  const Status st = sim::inverse_rows(out->fitted_four_bar, f.loads, motion, &rows);
  if (!st.ok()) {
    out->warnings.push_back("no predicted torques: the fitted scene's inverse dynamics fails: " +
                            st.message);
    return;
  }
  const double offset = out->fitted_four_bar.actuators.offset[0];  // as the sensor reads it
  for (int i = 0; i < L.size(); ++i) out->predicted_tau1[i] = rows[i].M1 + offset;
}

/// identify() by output error after the rates (output_error_fit): the estimates, the fitted
/// scene's torques and their residual's levels.
IdentifyResult output_error(FourBarFit& f, IdentifyResult out,
                            std::chrono::steady_clock::time_point start) {
  // every sample the rates reach is in a window (slip reversals and joints at rest too)
  const int P = f.layout.size();
  require_samples(f.cond.log, P + 1 + 2 * f.hw,
                  std::to_string(P) + " parameters + 1 + the Savitzky-Golay window");
  out.used.assign(f.cond.log.size(), 0);
  std::fill(out.used.begin() + f.first, out.used.begin() + f.last + 1, 1);
  out.samples_used = f.last - f.first + 1;
  if (out.accels_estimated && out.window_choice.empty()) {
    out.window_choice = stages::fixed_window_choice(*f.opt, out.sg_half_window);
  }
  if (output_error_fit(&f, &out)) {
    estimates(f, public_start(f), &out);
    predictions(f, &out);
    stages::output_error_levels(f.cond.log, f.first, f.last, &out);
    stages::output_error_misfit(&out);
  }
  out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace four_bar

using namespace four_bar;

std::string four_bar_unsupported(const IdentifyOptions& opt) {
  if (opt.layout.inertia && opt.method != Method::kInverseDynamics) {
    return "--estimate inertia needs --method inverse-dynamics";
  }
  if (opt.layout.per_joint && opt.method != Method::kInverseDynamics) {
    return "--per-joint with --method output-error: the crank angle does not tell the joints' "
           "coefficients apart (a drag link's clean 10 s log read coulomb_3 3499 std off); use "
           "--method inverse-dynamics";
  }
  if (opt.layout.actuator && opt.method != Method::kInverseDynamics) {
    return "--estimate actuator needs --method inverse-dynamics";
  }
  return "";
}

IdentifyResult identify(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& opt) {
  stages::quiet_solver_logging();
  const auto start = std::chrono::steady_clock::now();
  IdentifyResult out;
  out.layout = opt.layout;
  out.layout.set_four_bar();
  out.layout.static_as_excess = false;
  out.method = opt.method;
  out.samples = log.size();
  out.window_s = output_error_window(opt.window_s, log.duration());
  const std::string unsupported = four_bar_unsupported(opt);
  if (!unsupported.empty()) {
    out.status = Status::Error(StatusCode::kInvalidInput, unsupported);
    return out;
  }
  FourBarFit f;
  f.opt = &opt;
  f.layout = out.layout;
  f.layout.static_as_excess = f.layout.group_of(Coefficient::kStaticCoulomb) >= 0;
  f.scene = scene;
  f.scene.friction = stages::fit_friction(scene.friction, f.layout, opt);
  f.loads = loads;
  f.eval.friction_tol = 1e-12;
  f.eval.friction_max_iter = 100;
  condition(log, &f, &out);
  if (!start_values(&f, &out)) return out;
  f.sg = filter_options(f.cond.log, opt, &out.window_choice);
  rates(&f, &out);
  if (opt.method == Method::kOutputError) return output_error(f, std::move(out), start);
  select_samples(&f, &out);
  require_usable_samples(f.cond.log, out.samples_used, f.layout.size(), opt.min_rate);
  if (f.layout.inertia) {  // the prior on the links (the window stage weighs it too)
    f.prior = detail::inertial_prior(scene.links.data(), kFourBarLinks, opt.inertia_prior);
  }
  if (data_driven_window(f.cond.log, opt) && out.samples_used >= f.layout.size() + 1) {
    window_stage(&f, &out);
  }
  if (out.samples_used < f.layout.size() + 1) {
    out.status = Status::Error(StatusCode::kInvalidInput,
                               std::to_string(out.samples_used) + " samples left for " +
                                   std::to_string(f.layout.size()) + " parameters");
    return out;
  }
  bool from_noise = true;
  out.residual_noise_floor[0] = noise_floor(f, &from_noise);
  if (f.layout.inertia) f.prior_scale = out.residual_noise_floor[0];
  choose_loss_scale(&f, &out);
  ceres::Problem problem;
  if (!solve(&f, &problem, &out)) return out;
  const std::vector<double> x0 = public_start(f);
  Eigen::MatrixXd Hinv;
  covariance(f, &problem, &out, &Hinv);
  const std::string structure = stages::structure_warning(
      0, out.rms_torque_residual[0], out.residual_noise_floor[0], f.noise.torque[0], from_noise);
  if (!structure.empty()) out.warnings.push_back(structure);
  estimates(f, x0, &out);
  // per joint, a log rarely determines every joint's coefficients, and each undetermined one
  // costs its re-fits (five of eight on a 3 s crank-rocker log: 26 re-fits, 20 s of CPU against
  // the fit's 0.5 s): a per-joint fit keeps its Wald intervals; so does a robust fit, whose
  // cost is not the likelihood the profile reads, and one with the inertial group (a drag
  // link's log with a torque offset: its profile re-fits ran past a minute)
  if (!f.layout.per_joint && !f.layout.inertia && opt.loss == Loss::kNone) {
    stages::profile_intervals({f.layout, f.x, &problem, Hinv, solver_options(f), f.cost_weight},
                              &out);
  }
  model_check(f, &out);
  const stages::ModelVerdict verdict = cause_check(f, &out);
  stages::correct_smoothing_bias(f.layout, f.smoothing_bias, &f.x, &out);
  predictions(f, &out);
  const bool rejected = refit_checks(scene, loads, log, opt, verdict, &out);
  IdentifyResult refit;
  const bool shifted =
      verdict.delay == stages::ModelVerdict::Delay::kExplainsMost && !rejected &&
      delay_refit(scene, loads, f, &out, &refit);
  if (shifted) out = std::move(refit);
  if (!shifted) stages::unexplained_misfit(f.layout, &out);
  out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace fivebar::identification
