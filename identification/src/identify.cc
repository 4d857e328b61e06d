// Ceres problems of the two identification methods, covariance and identifiability analysis.
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
#include "covariance.h"
#include "fallback_cost.h"
#include "inertia.h"
#include "misfit.h"
#include "noise_model.h"
#include "profile.h"
#include "smoothing_bias.h"
#include "window_misfit.h"

namespace fivebar::identification {

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

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// noise-free logs: residual levels below this fraction of the rms logged torque are what a good
/// torque sensor resolves (0.1 %), not structure
constexpr double kAbsoluteFloor = 1e-3;
/// residual rms above this multiple of the expected noise level is structure: the noise levels
/// are robust estimates good to a few % on a few thousand samples
constexpr double kStructureRatio = 1.15;
/// window choice: a residual/noise ratio this much above the least one is smoothing bias
constexpr double kWindowExcess = 0.04;
/// the least ratio over the windows beyond which the estimated rates are biased at every window,
/// when the smallest is the best (a frictionless scene's 6-10 s logs read 4.67, a smoothing bias
/// that must not be blamed on the masses, the encoders or the torque sensors; a misfit of the
/// model reads about the same at every window instead)
constexpr double kBiasedRates = 1.5;
/// a friction coefficient at its bound with the residual this many times its noise floor is a fit
/// driven by samples the law cannot explain (bound_and_misfit_warning)
constexpr double kMisfitRatio = 3.0;
/// model_check: a friction move beyond this many std (its own, or the move's) is a warning
constexpr double kFreedMove = 3.0;
/// a torque-to-angle delay beyond this many std is corrected
constexpr double kDelaySignificance = 3.0;
/// output error: below this many windows the block sandwich's std are themselves uncertain
/// (their relative error is about 1 / sqrt(2 (windows - 1)), 24 % for 10 windows)
constexpr int kFewWindows = 10;
/// logged rates this much noisier than the angles' (through the noisiest window) are not used
constexpr double kNoisierRates = 2.0;
/// Stribeck law: further start values of the Stribeck velocity [rad/s] (best_stribeck_start)
constexpr double kStribeckStarts[] = {0.05, 0.5, 2.0};

/// Linear interpolation of y(t) on the sorted grid ts (clamped at the ends).
double interp(const std::vector<double>& ts, const std::vector<double>& y, double t) {
  if (t <= ts.front()) return y.front();
  if (t >= ts.back()) return y.back();
  const size_t i = std::upper_bound(ts.begin(), ts.end(), t) - ts.begin();
  const double s = (t - ts[i - 1]) / (ts[i] - ts[i - 1]);
  return y[i - 1] + s * (y[i] - y[i - 1]);
}

ceres::LossFunction* make_loss(Loss loss, double scale) {
  switch (loss) {
    case Loss::kNone:
      return nullptr;
    case Loss::kHuber:
      return new ceres::HuberLoss(scale);
    case Loss::kCauchy:
      return new ceres::CauchyLoss(scale);
  }
  return nullptr;
}

/// Neutral start values, independent of the scene: each coefficient's CoefficientInfo::start
/// (coulomb 0.1, viscous 0.01, static 0.15, Stribeck velocity 0.2 rad/s).
std::vector<double> default_start(const ParameterLayout& layout) {
  std::vector<double> x(layout.friction_size());
  for (int i = 0; i < layout.friction_size(); ++i) {
    x[i] = coefficient_info(layout.group(i / layout.per_group())).start;
  }
  return x;
}

/// Noise gains of the Savitzky-Golay rate and acceleration at an interior sample (white noise
/// of deviation s on the angles gives s * gain): the root sum of squares of the filter
/// coefficients, read off its response to a unit impulse in the middle of the log.
void sg_noise_gains(const std::vector<double>& t, const SgOptions& sg, double* g1, double* g2) {
  const int n = static_cast<int>(t.size());
  const int hw = sg_half_window(sg, (t.back() - t.front()) / std::max(1, n - 1));
  const int lo = std::max(0, n / 2 - 2 * hw), hi = std::min(n - 1, n / 2 + 2 * hw);
  const std::vector<double> ts(t.begin() + lo, t.begin() + hi + 1);
  std::vector<double> x(ts.size(), 0.0), d1, d2;
  x[n / 2 - lo] = 1.0;
  savitzky_golay(ts, x, sg, &d1, &d2);
  *g1 = *g2 = 0.0;
  for (size_t i = 0; i < ts.size(); ++i) {
    *g1 += d1[i] * d1[i];
    *g2 += d2[i] * d2[i];
  }
  *g1 = std::sqrt(*g1);
  *g2 = std::sqrt(*g2);
}

double larger_noise(const std::vector<double>& a, const std::vector<double>& b) {
  return std::max(series_noise(a), series_noise(b));
}

/// Thresholds of the rest rule for this log (IdentifyOptions::rest_rate_threshold).
/// The Savitzky-Golay noise gains are those of the window in use, `sg` (the data-driven one once
/// chosen: at 3 samples each side the rate noise is 6 times that at the default 10, and stuck
/// joints escaped the rule). Logged rates: never below the model's thresholds for computed rates
/// (RestThresholds{}): noise-free rates from a simulation keep a stuck joint's relative rate only
/// to its integration tolerance (synth-log: ~1e-10 rad/s, where the rounding reads 5e-13).
RestThresholds rest_rule(const TorqueLog& log, const IdentifyResult& out,
                         const IdentifyOptions& opt, const SgOptions& sg) {
  double g1 = 0, g2 = 0;
  if (out.accels_estimated) sg_noise_gains(log.t, sg, &g1, &g2);
  double rate_noise = 0, accel_noise = 0;
  if (out.rates_estimated) {
    const double s = larger_noise(log.theta1, log.theta2);
    rate_noise = g1 * s;
    accel_noise = g2 * s;
  } else {
    // logged series: never below the rounding of the angles over one sample step
    const int n = log.size();
    const double h = n > 1 ? (log.t.back() - log.t.front()) / (n - 1) : 1.0;
    const double rounding = std::max(rounding_noise(log.theta1), rounding_noise(log.theta2));
    rate_noise = std::max(larger_noise(out.omega1, out.omega2), rounding / h);
    accel_noise = out.accels_estimated
                      ? g1 * rate_noise
                      : std::max(larger_noise(out.alpha1, out.alpha2), rounding / (h * h));
  }
  RestThresholds r = rest_thresholds(rate_noise, accel_noise);
  if (!out.rates_estimated) {
    const RestThresholds computed;
    r.rate = std::max(r.rate, computed.rate);
    r.acceleration = std::max(r.acceleration, computed.acceleration);
  }
  if (opt.rest_rate_threshold >= 0) r.rate = opt.rest_rate_threshold;
  if (opt.rest_acceleration_threshold >= 0) r.acceleration = opt.rest_acceleration_threshold;
  return r;
}

/// The inverse-dynamics residual blocks, one per sample: from the sample's structure
/// (residual.h: the Jets carry only the P active parameters through a five-number loop), or the
/// full model where the structure cannot be read off.
template <int P>
void add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem) {
  for (const Sample& s : samples) {
    SampleStructure st;
    ceres::CostFunction* cost = nullptr;
    if (sample_structure(scene, s, eval, &st)) {
      cost = new ceres::AutoDiffCostFunction<StructuredResidual, 2, P>(
          new StructuredResidual(scene, layout, st, s, eval));
    } else {
      cost = new FallbackCost<P>(InverseDynamicsResidual(scene, layout, s, eval));
    }
    problem->AddResidualBlock(cost, make_loss(loss, loss_scale), x);
  }
}

/// Output error over one window [i0, i1]: simulated minus logged angles at samples i0+1..i1.
class WindowResidual {
 public:
  WindowResidual(const Params<double>& scene, const ParameterLayout& layout, const TorqueLog& log,
                 const sim::LoadFunction& loads, const std::vector<double>& w1,
                 const std::vector<double>& w2, int i0, int i1, const sim::Options& sim)
      : scene_(scene), layout_(layout), log_(log), i0_(i0), i1_(i1), sim_(sim) {
    loads_ = logged_loads(log, loads, log.t[i0], scene.actuators.offset);
    initial_ = {log.theta1[i0], log.theta2[i0], w1[i0], w2[i0]};
    sim_.duration = log.t[i1] - log.t[i0];
    sim_.output_step = sim_.duration / (i1 - i0);
  }
  int residuals() const { return 2 * (i1_ - i0_); }

  bool operator()(double const* const* x, double* r) const {
    Params<double> p = scene_;
    layout_.apply(x[0], &p);
    const sim::Result res = sim::simulate(p, loads_, initial_, sim_);
    if (!res.status.ok() || res.rows.size() < 2) return false;
    std::vector<double> ts, a, b;
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      a.push_back(row.theta[0]);
      b.push_back(row.theta[1]);
    }
    for (int i = i0_ + 1, k = 0; i <= i1_; ++i, ++k) {
      const double tt = log_.t[i] - log_.t[i0_];
      if (tt > ts.back() + 1e-9) return false;
      r[2 * k] = interp(ts, a, tt) - log_.theta1[i];
      r[2 * k + 1] = interp(ts, b, tt) - log_.theta2[i];
    }
    return true;
  }

 private:
  const Params<double>& scene_;
  ParameterLayout layout_;
  const TorqueLog& log_;
  int i0_, i1_;
  sim::Options sim_;
  sim::LoadFunction loads_;
  sim::Initial initial_;
};

/// Consecutive windows [i0, i1] of about window_s over the samples [first, last].
std::vector<std::pair<int, int>> make_windows(const TorqueLog& log, int first, int last,
                                              double window_s) {
  std::vector<std::pair<int, int>> out;
  int i0 = first;
  while (i0 < last) {
    int i1 = i0;
    while (i1 < last && log.t[i1 + 1] - log.t[i0] <= window_s * (1 + 1e-9)) ++i1;
    if (i1 == i0) ++i1;
    // fold a short tail into the previous window
    if (!out.empty() && log.t[last] - log.t[i0] < 0.5 * window_s) {
      out.back().second = last;
      break;
    }
    out.push_back({i0, i1});
    i0 = i1;
  }
  return out;
}

sim::Options window_sim_options(double rtol) {
  sim::Options o;
  o.rtol = rtol;
  o.atol = rtol;
  o.method = sim::Method::kCvodeAdams;
  return o;
}

// ---- stages of identify() ----

/// The state the stages of identify() share.
struct Fit {
  const IdentifyOptions* opt = nullptr;
  sim::LoadFunction loads;
  Params<double> scene;    ///< the law to fit and the Coulomb sign form
  ParameterLayout layout;  ///< internal (Stribeck: static_coulomb as excess over coulomb)
  ConditionedLog cond;     ///< the log as fitted
  std::vector<int> window_sizes;  ///< output error: residuals of each window, in problem order
  detail::RateSource source = detail::RateSource::kLogged;
  SgOptions sg;              ///< as used
  int first = 0, last = -1;  ///< samples with a centred Savitzky-Golay window
  EvalOptions eval;
  std::vector<Sample> samples;
  std::vector<int> index;  ///< log index of each sample in the fit
  /// slip reversals of the rates of the fit: reversals[i] = how many lie between samples k and
  /// k + 1 for k < i (reversal_counts)
  std::vector<int> reversals;
  std::vector<double> x;   ///< internal parameter vector
  detail::SensorNoise noise;
  detail::InertialPrior prior;  ///< group inertia
  /// the torque residual's noise level that weighs the prior against the data [N m]
  double prior_scale = 1;
  /// predicted smoothing bias of the public friction coefficients at the chosen window
  /// (limit_smoothing_bias; empty when not predicted), taken off the estimates
  Eigen::VectorXd smoothing_bias;
  double loss_scale = 0;  ///< the robust loss's scale as applied (choose_loss_scale)
  /// the estimated accelerations' smoothing shows at every window (choose_window): model_check
  /// names no cause, the misfit being the rates' as much as the model's
  bool rates_biased = false;
};

/// Calls f(std::integral_constant<int, P>) for the parameter counts the layouts give (friction
/// 2, 4, 10, 20, each with or without the 16 inertial parameters, and with the 6 actuator terms
/// except after per-joint Stribeck with inertia); false for another count.
template <typename F>
bool with_size(int P, F&& f) {
  switch (P) {
    case 2: f(std::integral_constant<int, 2>()); return true;
    case 4: f(std::integral_constant<int, 4>()); return true;
    case 10: f(std::integral_constant<int, 10>()); return true;
    case 20: f(std::integral_constant<int, 20>()); return true;
    case 18: f(std::integral_constant<int, 18>()); return true;
    case 26: f(std::integral_constant<int, 26>()); return true;
    case 36: f(std::integral_constant<int, 36>()); return true;
    // with the 6 actuator terms
    case 8: f(std::integral_constant<int, 8>()); return true;
    case 16: f(std::integral_constant<int, 16>()); return true;
    case 24: f(std::integral_constant<int, 24>()); return true;
    case 32: f(std::integral_constant<int, 32>()); return true;
    default: return false;
  }
}

/// Group inertia: the prior and consistency residuals (inertia.h) on the parameter block x.
void add_inertial_prior(Fit* f, double* x, ceres::Problem* problem) {
  if (!f->layout.inertia) return;
  problem->AddResidualBlock(detail::inertial_prior_cost(f->prior, f->layout.size(),
                                                        f->layout.inertia_offset(),
                                                        &f->prior_scale),
                            nullptr, x);
}

/// Linear map from the internal parameter vector to the public one (static_coulomb = coulomb +
/// excess for Stribeck; identity otherwise).
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

/// The scene with the law to fit and the chosen Coulomb sign form.
Params<double> fit_scene(const Params<double>& scene_in, const ParameterLayout& layout,
                         const IdentifyOptions& opt) {
  Params<double> scene = scene_in;
  scene.friction.law = layout.law;
  if (opt.smoothing_velocity >= 0) scene.friction.smoothing_velocity = opt.smoothing_velocity;
  // a fixed coefficient the law needs > 0 (the Stribeck exponent) that the scene leaves unset
  // takes its default
  const LawDescriptor& d = law_descriptor(layout.law);
  for (int i = 0; i < d.count; ++i) {
    const LawCoefficient& c = d.coefficients[i];
    if (!c.positive || c.identifiable) continue;
    for (double& v : coefficient(scene.friction, c.id)) {
      if (!(v > 0)) v = coefficient_info(c.id).default_value;
    }
  }
  return scene;
}

/// Degrees told by the motion, then unwrapping and glitch rejection, then the poses.
void prepare_log(const TorqueLog& log, Fit* f, IdentifyResult* out) {
  // with rates too: degrees with deg/s rates agree with each other
  if (f->opt->check_degrees) {
    std::string unit;
    const std::string why = angle_units_from_motion(f->scene, f->loads, log, &unit);
    if (!why.empty()) {
      throw LogError(log.path, "columns theta1, theta2",
                     "angles look like " + unit + ", expected radians (" + why + ")");
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

/// Rates and accelerations: logged, else Savitzky-Golay with f->sg (the edges, where the window
/// is one-sided, are left out of the fit).
void estimate_rates(Fit* f, IdentifyResult* out) {
  const TorqueLog& log = f->cond.log;
  const int n = log.size();
  f->first = 0;
  f->last = n - 1;
  out->omega1 = log.omega1;
  out->omega2 = log.omega2;
  out->alpha1 = log.alpha1;
  out->alpha2 = log.alpha2;
  out->rates_estimated = out->accels_estimated = false;
  std::vector<double> unused;
  if (f->source == detail::RateSource::kFromAngles) {
    out->rates_estimated = out->accels_estimated = true;
    savitzky_golay(log.t, log.theta1, f->sg, &out->omega1, &out->alpha1);
    savitzky_golay(log.t, log.theta2, f->sg, &out->omega2, &out->alpha2);
  } else if (f->source == detail::RateSource::kAccelsFromRates) {
    out->accels_estimated = true;
    savitzky_golay(log.t, log.omega1, f->sg, &out->alpha1, &unused);
    savitzky_golay(log.t, log.omega2, f->sg, &out->alpha2, &unused);
  }
  out->sg_half_window = 0;
  out->sg_order = out->accels_estimated ? f->sg.order : 0;
  if (out->accels_estimated) {
    const double dt = n > 1 ? log.duration() / (n - 1) : 1.0;
    out->sg_half_window = sg_half_window(f->sg, dt);
    f->first = std::min(out->sg_half_window, n);
    f->last = n - 1 - out->sg_half_window;
  }
}

/// Sample i of the conditioned log: time, angles, torques and loads (rates left at 0).
Sample logged_sample(const Fit& f, int i) {
  const TorqueLog& log = f.cond.log;
  Sample s;
  s.t = log.t[i];
  s.th1 = log.theta1[i];
  s.th2 = log.theta2[i];
  s.tau1 = log.tau1[i];
  s.tau2 = log.tau2[i];
  s.loads = f.loads(s.t);
  return s;
}

/// Sample i with the fit's rates and accelerations.
Sample make_sample(const Fit& f, const IdentifyResult& out, int i) {
  Sample s = logged_sample(f, i);
  s.w1 = out.omega1[i];
  s.w2 = out.omega2[i];
  s.a1 = out.alpha1[i];
  s.a2 = out.alpha2[i];
  return s;
}

/// Slip reversals, where the accelerations jump (Coulomb friction flips): prefix counts of the
/// sample steps (i, i + 1) over which some joint's relative rate changes sign; a joint whose pose
/// cannot be solved counts as reversing.
std::vector<int> reversal_counts(const Fit& f, const IdentifyResult& out) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  std::vector<int> pre(n + 1, 0);
  std::array<double, kJoints> prev{};
  for (int i = 0; i < n; ++i) {
    Kinematics<double> k;
    std::array<double, kJoints> w{};
    const bool solved = solve_kinematics(f.scene, log.theta1[i], log.theta2[i], &k).ok();
    if (solved) {
      Bias<double> b;
      compute_bias(f.scene, k, out.omega1[i], out.omega2[i], &b);
      w = fivebar::relative_rates(out.omega1[i], out.omega2[i], b.w3, b.w4);
    }
    bool flip = !solved;
    for (int j = 0; i > 0 && j < kJoints; ++j) flip = flip || (w[j] > 0) != (prev[j] > 0);
    pre[i + 1] = pre[i] + (i > 0 && flip ? 1 : 0);
    prev = w;
  }
  return pre;
}

/// Whether the Savitzky-Golay window of half-width hw centred on sample i spans a slip reversal
/// (f.reversals): its accelerations then smear the jump, a bias that correlates with the Coulomb
/// sign (it reads as less Coulomb friction) and that no window is small enough to remove.
bool spans_reversal(const Fit& f, int i, int hw) {
  const int n = static_cast<int>(f.reversals.size()) - 1;
  if (hw <= 0 || n <= 0) return false;
  const int a = std::clamp(i - hw, 0, n - 1), b = std::clamp(i + hw, 0, n - 1);
  return f.reversals[b] - f.reversals[a] > 0;  // steps (k, k + 1) with a <= k < b
}

/// Half-width of the acceleration filter whose windows must not span a slip reversal, after
/// finding the reversals (f->reversals); 0 keeps every sample: accelerations from the log, the
/// option off, or reversals so dense that more than half of the samples would go (a warning
/// then says that the accelerations near them are smoothed).
int reversal_half_window(Fit* f, IdentifyResult* out) {
  f->reversals.clear();
  out->slip_reversals = 0;
  // a raised order (choose_window: even the smallest window shows smoothing bias) means the log
  // is sampled too slowly for the filter to follow the smooth motion either: its bias there has
  // the other sign and, measured at 200 Hz, offsets the smearing at the reversals, so leaving
  // them out would leave the smooth parts' bias alone
  // (Coulomb-viscous only: a Stribeck peak lives at the reversals, and smeared it reads as no
  // peak: on a noise-free 500 Hz log, static_coulomb 0.130 for 0.2 with them, 0.199 without)
  const bool raised = f->sg.order > f->opt->sg.order &&
                      f->layout.group_of(Coefficient::kStaticCoulomb) < 0;  // no fitted peak
  if (!out->accels_estimated || !f->opt->exclude_reversals ||
      f->opt->method != Method::kInverseDynamics || raised) {
    return 0;
  }
  f->reversals = reversal_counts(*f, *out);
  out->slip_reversals = f->reversals.back();
  const int hw = out->sg_half_window;
  int near = 0, total = 0;
  for (int i = f->first; i <= f->last; ++i, ++total) near += spans_reversal(*f, i, hw) ? 1 : 0;
  if (2 * near <= total) return hw;
  f->reversals.clear();
  return 0;
}

/// Relative rates of the joints (O, B, C, D, D0) at the angles (th1, th2) and the sample's crank
/// rates, and the kinematics there; false if the pose fails.
bool joint_rates(const Params<double>& p, double th1, double th2, const Sample& s,
                 std::array<double, kJoints>* w, Kinematics<double>* k) {
  if (!solve_kinematics(p, th1, th2, k).ok()) return false;
  Bias<double> b;
  compute_bias(p, *k, s.w1, s.w2, &b);
  *w = relative_rates(s.w1, s.w2, b.w3, b.w4);
  return true;
}

/// The rest rule at sample s with each joint's rate threshold set for its own noise: the rates'
/// noise through its row of J_w (the thresholds are set for one crank's rate; an inner joint's
/// relative rate combines both), in quadrature with the angle noise `angle_noise` through the
/// kinematics (with exact logged rates and 1e-5 rad on the angles, a stuck inner joint of the
/// paper mechanism reads ~1e-5 rad/s). True (the sample is left out) when a joint's relative
/// rate is within its threshold: whether it is stuck, slips from rest, or still turns slowly
/// either way, the log cannot tell, and each gives its friction another direction. (Keeping such
/// a joint when it accelerates, taken to slip the way of its acceleration, is wrong: with logged
/// rates 0.001 rad/s noisy, a joint turning slowly while it decelerates, or a stuck one whose
/// acceleration reads the rates' noise through the velocity products, gets the wrong direction;
/// a breakaway log then gives coulomb -25 std, at 0.01 rad/s -42.)
bool held_sample(const Params<double>& p, const Sample& s, const RestThresholds& rest,
                 double angle_noise) {
  Kinematics<double> k, kd;
  std::array<double, kJoints> w, dw[2], w2;
  if (!joint_rates(p, s.th1, s.th2, s, &w, &k)) return false;
  constexpr double h = 1e-7;  // [rad]: the angles' derivatives by forward differences
  for (int c = 0; c < 2 && angle_noise > 0; ++c) {
    if (!joint_rates(p, s.th1 + (c == 0 ? h : 0), s.th2 + (c == 1 ? h : 0), s, &w2, &kd))
      return false;
    for (int j = 0; j < kJoints; ++j) dw[c][j] = (w2[j] - w[j]) / h;
  }
  for (int j = 0; j < kJoints; ++j) {
    const double g = std::max(1.0, joint_row(k, j).norm());
    const double a = angle_noise > 0 ? kRestSigmas * angle_noise : 0.0;
    const double rate =
        std::hypot(g * rest.rate, a > 0 ? a * std::hypot(dw[0][j], dw[1][j]) : 0.0);
    if (std::abs(w[j]) < rate) return true;  // a threshold of 0 (the exact rule) holds none
  }
  return false;
}

/// Samples that enter the fit: a centred rate window, not a glitch, above --min-rate.
void select_samples(Fit* f, IdentifyResult* out) {
  const TorqueLog& log = f->cond.log;
  const int P = f->layout.size();
  out->used.assign(log.size(), 0);
  f->samples.clear();
  f->index.clear();
  // the rest rule (model/rest.h): samples with a stuck joint are left out (their friction is a
  // holding torque, not the law); a joint at rest that accelerates slips that way
  const RestThresholds rest = rest_rule(log, *out, *f->opt, f->sg);
  out->rest_rate_threshold = rest.rate;
  out->rest_acceleration_threshold = rest.acceleration;
  f->eval.rest_rate = rest.rate;
  out->samples_at_rest = 0;
  const int hw = reversal_half_window(f, out);
  out->samples_near_reversals = 0;
  // rejected samples were interpolated: their neighbours' estimated accelerations carry the
  // interpolation's error (a frozen encoder's run, bridged by a line), so those are left out too
  std::vector<int> rejected(log.size() + 1, 0);
  for (int i = 0; i < log.size(); ++i) rejected[i + 1] = rejected[i] + f->cond.rejected[i];
  const int rw = out->accels_estimated ? out->sg_half_window : 0;
  for (int i = f->first; i <= f->last; ++i) {
    const int a = std::max(0, i - rw), b = std::min(log.size() - 1, i + rw);
    if (rejected[b + 1] - rejected[a] > 0) continue;
    if (spans_reversal(*f, i, hw)) {
      ++out->samples_near_reversals;
      continue;
    }
    const Sample s = make_sample(*f, *out, i);
    if (held_sample(f->scene, s, rest, std::max(f->noise.angle[0], f->noise.angle[1]))) {
      ++out->samples_at_rest;
      continue;
    }
    if (f->opt->min_rate > 0) {
      Kinematics<double> k;
      if (!solve_kinematics(f->scene, s.th1, s.th2, &k).ok()) continue;
      Bias<double> b;
      compute_bias(f->scene, k, s.w1, s.w2, &b);
      bool slow = false;
      for (double wk : fivebar::relative_rates(s.w1, s.w2, b.w3, b.w4)) {
        slow = slow || std::abs(wk) < f->opt->min_rate;
      }
      if (slow) continue;
    }
    out->used[i] = 1;
    f->samples.push_back(s);
    f->index.push_back(i);
  }
  out->samples_used = static_cast<int>(f->samples.size());
  if (out->samples_used < P + 1) {
    throw LogError(log.path, "samples",
                   "only " + std::to_string(out->samples_used) +
                       " samples usable (rate threshold, glitches and filter edges), fewer than "
                       "the " +
                       std::to_string(P + 1) + " needed for " + std::to_string(P) + " parameters");
  }
}

/// The first sample of the fit whose inverse dynamics fails at the parameters x, as a status
/// naming it and the reason (ok if none fails).
Status first_failure(const Fit& f, const std::vector<double>& x, const std::string& at) {
  Params<double> p = f.scene;
  f.layout.apply(x.data(), &p);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    const Sample& s = f.samples[u];
    Evaluation<double> ev;
    const Status st =
        inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr, f.eval, &ev);
    std::string why = st.message;
    if (st.ok() && !(std::isfinite(ev.M1) && std::isfinite(ev.M2))) why = "torque not finite";
    if (st.ok() && why.empty()) continue;
    return Status::Error(
        StatusCode::kSolverFailed,
        "inverse dynamics fails at " + sample_name(f.cond.log, f.index[u]) + " " + at + " (theta " +
            format_significant(s.th1) + ", " + format_significant(s.th2) + " rad, omega " +
            format_significant(s.w1) + ", " + format_significant(s.w2) + " rad/s, alpha " +
            format_significant(s.a1) + ", " + format_significant(s.a2) + " rad/s^2): " + why);
  }
  return Status::Ok();
}

/// rms residual and expected noise level of each actuator over up to ~200 samples of the fit
/// (log indices `probe`), with the rates of half-window `sg`, at the parameters f.x.
void window_levels(const Fit& f, const std::vector<int>& probe, const SgOptions& sg,
                   const RestThresholds& rest, double rms[2], double floor[2]) {
  const TorqueLog& log = f.cond.log;
  Params<double> p = f.scene;
  f.layout.apply(f.x.data(), &p);
  Eigen::Vector2d r2 = Eigen::Vector2d::Zero(), v = Eigen::Vector2d::Zero(), t2 = v;
  int count = 0;
  for (int i : probe) {
    Sample s = logged_sample(f, i);
    int lo = 0;
    std::vector<double> d1, d2;
    savitzky_golay_taps(log.t, i, sg, &lo, &d1, &d2);
    const std::vector<double>& x1 =
        f.source == detail::RateSource::kFromAngles ? log.theta1 : log.omega1;
    const std::vector<double>& x2 =
        f.source == detail::RateSource::kFromAngles ? log.theta2 : log.omega2;
    double e1 = 0, e2 = 0, f1 = 0, f2 = 0;
    for (size_t k = 0; k < d1.size(); ++k) {
      e1 += d1[k] * x1[lo + k];
      e2 += d1[k] * x2[lo + k];
      f1 += d2[k] * x1[lo + k];
      f2 += d2[k] * x2[lo + k];
    }
    if (f.source == detail::RateSource::kFromAngles) {
      s.w1 = e1, s.w2 = e2, s.a1 = f1, s.a2 = f2;
    } else {
      s.w1 = log.omega1[i], s.w2 = log.omega2[i], s.a1 = e1, s.a2 = e2;
    }
    // a held joint's friction is a static torque, not the law: at every window a misfit
    if (held_sample(f.scene, s, rest, std::max(f.noise.angle[0], f.noise.angle[1]))) continue;
    Evaluation<double> ev;
    Eigen::Matrix<double, 2, 6> D;
    if (!inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr, f.eval, &ev)
             .ok() ||
        !detail::kinematic_jacobian(f.scene, f.layout, f.x.data(), s, f.eval, &D)) {
      continue;
    }
    const auto& o = p.actuators.offset;  // measured = motor + offset
    r2 += Eigen::Vector2d(std::pow(s.tau1 - o[0] - ev.M1, 2), std::pow(s.tau2 - o[1] - ev.M2, 2));
    t2 += Eigen::Vector2d(s.tau1 * s.tau1, s.tau2 * s.tau2);
    v += detail::propagated_variance(detail::sensitivity(log.t, i, f.source, sg, f.noise, D));
    ++count;
  }
  for (int j = 0; j < kActuators; ++j) {
    const double c = std::max(1, count);
    rms[j] = std::sqrt(r2(j) / c);
    floor[j] = std::max(std::sqrt(f.noise.torque[j] * f.noise.torque[j] + v(j) / c),
                        kAbsoluteFloor * std::sqrt(t2(j) / c));
  }
}

/// Candidate half-windows [samples] of choose_window: from the polynomial's minimum to 50 ms,
/// growing by 25 %, each fitting in the log's n samples (at least the minimum).
std::vector<int> window_candidates(int n, double dt, int order) {
  const int min_half = order / 2 + 1;
  const int max_half = std::max(min_half, static_cast<int>(std::lround(0.05 / dt)));
  std::vector<int> cand;
  for (int m = min_half; m <= max_half; m = std::max(m + 1, static_cast<int>(m * 1.25))) {
    if (2 * m + 2 < n) cand.push_back(m);
  }
  if (cand.empty()) cand.push_back(min_half);
  return cand;
}

/// The window table of choose_window: the rms residual and noise floor of candidate k, evaluated
/// on demand in increasing order (probes: samples with a centred window for the largest
/// candidate, not glitches).
class WindowTable {
 public:
  explicit WindowTable(const Fit& f, const IdentifyResult& out) : f_(f), out_(out) {
    const TorqueLog& log = f.cond.log;
    const int n = log.size();
    dt_ = n > 1 ? log.duration() / (n - 1) : 1.0;
    cand_ = window_candidates(n, dt_, f.sg.order);
    const int edge = cand_.back();
    const int step = std::max(1, (n - 2 * edge) / 800);
    for (int i = edge; i < n - edge; i += step) {
      if (!f.cond.rejected[i]) probe_.push_back(i);
    }
  }
  double dt() const { return dt_; }
  size_t candidates() const { return cand_.size(); }
  const std::vector<detail::WindowLevel>& levels() const { return levels_; }
  /// the next candidate's levels: every probe, those near slip reversals included (the fit
  /// leaves them out): their bias keeps the window small, which the smooth parts' bias, below
  /// what the ratio detects, needs too (measured: judged without them, the per-joint multisine
  /// fits chose 7-8 samples instead of 4-6 and the coverage of their 95 % intervals fell from
  /// 0.97 to 0.90)
  const detail::WindowLevel& evaluate_next() {
    detail::WindowLevel l;
    l.half = cand_[levels_.size()];
    SgOptions sg = f_.sg;
    sg.half_window_s = l.half * dt_;
    window_levels(f_, probe_, sg, rest_rule(f_.cond.log, out_, *f_.opt, sg), l.rms, l.floor);
    levels_.push_back(l);
    return levels_.back();
  }

 private:
  const Fit& f_;
  const IdentifyResult& out_;
  double dt_ = 1;
  std::vector<int> cand_, probe_;
  std::vector<detail::WindowLevel> levels_;
};

double level_ratio(const detail::WindowLevel& l) {
  return std::max(l.rms[0] / l.floor[0], l.rms[1] / l.floor[1]);
}

/// choose_window when the window table shows a misfit of the law (window_misfit.h): the largest
/// window up to which the excess over the noise level stays flat (the misfit, not bias), where
/// the fit's residual shows the misfit above a floor near the torque noise.
void misfit_window(Fit* f, const WindowTable& tab, const detail::WindowMisfit& m,
                   IdentifyResult* out) {
  const std::vector<detail::WindowLevel>& lv = tab.levels();
  const detail::WindowLevel &a = lv[m.from], &b = lv[m.to];
  const int j = m.actuator;
  f->sg.half_window_s = b.half * tab.dt();
  out->window_choice =
      "data-driven, misfit: half-window " + std::to_string(b.half) + " samples (" +
      format_significant(b.half * tab.dt() * 1e3) + " ms): the tau" + std::to_string(j + 1) +
      " residual's excess over the level the measured noise explains is the same from " +
      std::to_string(a.half) + " to " + std::to_string(b.half) + " samples (" +
      format_significant(std::sqrt(std::max(0.0, a.excess(j)))) + ", " +
      format_significant(std::sqrt(std::max(0.0, b.excess(j)))) +
      " N m in quadrature with the noise level " + format_significant(a.floor[j]) + ", " +
      format_significant(b.floor[j]) +
      " N m): not smoothing bias, which grows with the window, but torques the law does not fit; "
      "the largest window where it stays so";
}

/// The data-driven Savitzky-Golay half-window. Smoothing bias shows in the torque residual as
/// an excess over the level the sensor noise explains (that level is predicted per window by
/// propagating the measured noise): the window chosen is the largest whose residual/noise ratio
/// stays within kWindowExcess of the reference, 1 or the least ratio over the candidates when
/// that is above 1 (a mismatch of the law that no window removes). Candidates evaluated at the
/// parameters of a preliminary fit (f.x). When the excess is flat in the window instead (a
/// misfit that the small windows' noise hides, window_misfit.h), misfit_window chooses.
void choose_window(Fit* f, IdentifyResult* out) {
  WindowTable tab(*f, *out);
  std::vector<double> ratio;
  for (size_t k = 0; k < tab.candidates(); ++k) {
    ratio.push_back(level_ratio(tab.evaluate_next()));
    // smoothing bias only grows with the window: stop once it clearly dominates
    if (k >= 2 &&
        ratio[k] > 1.5 * std::max(1.0, *std::min_element(ratio.begin(), ratio.begin() + k))) {
      break;
    }
  }
  // a misfit hidden by the noise of the small windows: its excess is flat in the window
  detail::WindowMisfit m;
  while ((m = detail::window_misfit(tab.levels(), tab.levels().size() < tab.candidates())).state ==
         detail::WindowMisfit::kNeedMore) {
    tab.evaluate_next();
  }
  if (m.state == detail::WindowMisfit::kMisfit) {
    misfit_window(f, tab, m, out);
    return;
  }
  // the rule below sees the candidates up to the stop above
  std::vector<int> cand;
  std::vector<std::array<double, 4>> levels;
  for (size_t k = 0; k < ratio.size(); ++k) {
    const detail::WindowLevel& l = tab.levels()[k];
    cand.push_back(l.half);
    levels.push_back({l.rms[0], l.rms[1], l.floor[0], l.floor[1]});
  }
  const double dt = tab.dt();
  // the reference: 1 when the noise explains the residual (a ratio below 1 is a fluctuation of
  // the estimate), the least ratio when a mismatch of the law shows at every window
  const double best = std::max(1.0, *std::min_element(ratio.begin(), ratio.end()));
  // the largest window without detectable excess, then one candidate smaller: the bias just
  // below detection still counts against the std (relative to it, it scales as ~h^3.5)
  size_t chosen = 0;
  for (size_t k = 0; k < cand.size(); ++k) {
    if (ratio[k] <= best * (1 + kWindowExcess)) chosen = k;
  }
  // only the smallest window without detectable bias: the log is sampled too slowly for this
  // order. The back-off never lands on the smallest window: over order/2 + 1 samples each side
  // the polynomial nearly interpolates the noise (one degree of freedom; twice the acceleration
  // noise of the next window at order 5), a cost the margin against bias does not justify.
  // Measured on Stribeck logs at 500 Hz (30 seeds), whose second window was still unbiased:
  // backed off to the smallest, coverage of static_coulomb 0.77; at the second, 0.90.
  const bool undersampled = chosen == 0 && ratio.size() > 1;
  f->rates_biased = undersampled && best > kBiasedRates;
  const bool backed_off = chosen > 1;
  if (backed_off) --chosen;
  std::string table;
  for (size_t k = 0; k < cand.size(); ++k) {
    table += (k ? ", " : "") + std::to_string(cand[k]) + ": " + format_significant(ratio[k]);
  }
  f->sg.half_window_s = cand[chosen] * dt;
  // every window but the smallest of this order shows bias: the log is sampled too slowly for
  // it, and a higher order over the next smallest span bends better at the kinks
  std::string raised;
  if (undersampled) {
    f->sg.order += 2;
    f->sg.half_window_s = (f->sg.order / 2 + 1) * dt;
    raised = "; the smallest window being the choice, order raised to " +
             std::to_string(f->sg.order) + " over " + std::to_string(f->sg.order / 2 + 1) +
             " samples each side";
  }
  const std::array<double, 4>& l = levels[chosen];
  out->window_choice = "data-driven: half-window " + std::to_string(cand[chosen]) + " samples (" +
                       format_significant(cand[chosen] * dt * 1e3) + " ms), " +
                       (backed_off ? "one below " : "") + "the largest whose torque residual (" +
                       format_significant(l[0]) + ", " + format_significant(l[1]) +
                       " N m) shows no smoothing bias over the level the measured noise " +
                       "explains (" + format_significant(l[2]) + ", " + format_significant(l[3]) +
                       " N m), ratio " + format_significant(ratio[chosen]) +
                       " against the reference " + format_significant(best) +
                       " (ratio by half-window: " + table + ")" + raised;
}

/// A quick fit on at most ~1500 of the selected samples (plain least squares) that sets f->x for
/// the window choice; keeps the start values if it fails.
void preliminary_fit(Fit* f) {
  const int P = f->layout.size();
  Fit g = *f;
  g.samples.clear();
  const size_t step = std::max<size_t>(1, f->samples.size() / 1500);
  for (size_t u = 0; u < f->samples.size(); u += step) g.samples.push_back(f->samples[u]);
  ceres::Problem problem;
  std::vector<double> x = f->x;
  const bool sized = with_size(P, [&](auto n) {
    add_inverse_dynamics_terms<decltype(n)::value>(g.scene, g.layout, g.samples, g.eval,
                                                   Loss::kNone, 1, x.data(), &problem);
  });
  if (!sized) return;
  add_inertial_prior(f, x.data(), &problem);
  for (int i = 0; i < P; ++i) problem.SetParameterLowerBound(x.data(), i, f->layout.lower_bound(i));
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = 20;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (summary.IsSolutionUsable()) f->x = x;
}

/// Adds the residual blocks of the method to `problem`; false for an unsupported size.
bool build_problem(Fit* f, IdentifyResult* out, ceres::Problem* problem) {
  const IdentifyOptions& opt = *f->opt;
  const int P = f->layout.size();
  if (opt.method == Method::kInverseDynamics) {
    const bool sized = with_size(P, [&](auto n) {
      add_inverse_dynamics_terms<decltype(n)::value>(f->scene, f->layout, f->samples, f->eval,
                                                     opt.loss, f->loss_scale, f->x.data(),
                                                     problem);
    });
    if (!sized) return false;
    add_inertial_prior(f, f->x.data(), problem);
    out->residuals = 2 * out->samples_used;
  } else {
    const sim::Options so = window_sim_options(opt.sim_rtol);
    // output error: windows over the used range (the rate threshold does not apply)
    for (auto [i0, i1] : make_windows(f->cond.log, f->first, f->last, out->window_s)) {
      auto* w = new WindowResidual(f->scene, f->layout, f->cond.log, f->loads, out->omega1,
                                   out->omega2, i0, i1, so);
      ceres::NumericDiffOptions nd;
      nd.relative_step_size = opt.relative_step;
      auto* cost = new ceres::DynamicNumericDiffCostFunction<WindowResidual, ceres::CENTRAL>(
          w, ceres::TAKE_OWNERSHIP, nd);
      cost->AddParameterBlock(P);
      cost->SetNumResiduals(w->residuals());
      out->residuals += w->residuals();
      f->window_sizes.push_back(w->residuals());
      problem->AddResidualBlock(cost, make_loss(opt.loss, f->loss_scale), f->x.data());
    }
  }
  for (int i = 0; i < P; ++i)
    problem->SetParameterLowerBound(f->x.data(), i, f->layout.lower_bound(i));
  return true;
}

/// Raw (unweighted) residuals; false where an evaluation fails.
bool raw_residuals(ceres::Problem* problem, std::vector<double>* r,
                   ceres::CRSMatrix* jac = nullptr) {
  ceres::Problem::EvaluateOptions eo;
  eo.apply_loss_function = false;
  double cost = 0;
  return problem->Evaluate(eo, &cost, r, nullptr, jac);
}

void rms_pair(const std::vector<double>& r, double* out2) {
  double s[2] = {0, 0};
  for (size_t i = 0; i < r.size(); ++i) s[i % 2] += r[i] * r[i];
  for (int j = 0; j < kActuators; ++j)
    out2[j] = std::sqrt(s[j] / std::max<size_t>(1, r.size() / 2));
}

ceres::Solver::Options solver_options(const IdentifyOptions& opt) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = opt.max_iterations;
  so.num_threads = opt.num_threads;
  // output error: the simulated residual carries integrator noise (~rtol), so ask less of it
  const bool oe = opt.method == Method::kOutputError;
  so.function_tolerance = oe ? 1e-3 : 1e-12;  // OE cost noise ~1e-4 relative
  so.gradient_tolerance = oe ? 1e-10 : 1e-14;
  so.parameter_tolerance = oe ? 1e-7 : 1e-10;
  so.logging_type = ceres::SILENT;
  return so;
}

/// Stribeck law, inverse dynamics: the cost has local minima where the Stribeck velocity
/// collapses onto its bound (a peak narrower than the rates of any sample left in the fit, whose
/// static_coulomb is then undetermined). Measured on 500 Hz logs: from the neutral start (0.2
/// rad/s) 3 of 30 fits ended there although a start at the truth reached a lower cost with a
/// determined peak. The fit is solved from the given start and from kStribeckStarts; the end
/// with the least cost is the start of the final solve. f->x is left at that start.
void best_stribeck_start(Fit* f, ceres::Problem* problem) {
  const int g = f->layout.group_of(Coefficient::kStribeckVelocity);
  if (g < 0 || f->opt->method != Method::kInverseDynamics) return;
  const ceres::Solver::Options so = solver_options(*f->opt);
  const std::vector<double> x0 = f->x;
  std::vector<double> best = x0;
  double best_cost = std::numeric_limits<double>::infinity();
  const int per = f->layout.per_group();
  for (int k = -1; k < static_cast<int>(std::size(kStribeckStarts)); ++k) {
    std::copy(x0.begin(), x0.end(), f->x.begin());  // the problem holds f->x.data()
    for (int j = 0; k >= 0 && j < per; ++j) {
      const int i = g * per + j;
      f->x[i] = std::max(kStribeckStarts[k], f->layout.lower_bound(i));
    }
    ceres::Solver::Summary summary;
    ceres::Solve(so, problem, &summary);
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best = f->x;
    }
  }
  std::copy(best.begin(), best.end(), f->x.begin());
}

/// Solves; a solver that gives up or an evaluation that fails is a status naming the sample.
void solve(Fit* f, ceres::Problem* problem, IdentifyResult* out, ceres::Solver::Summary* summary) {
  ceres::Solve(solver_options(*f->opt), problem, summary);
  out->iterations += static_cast<int>(summary->iterations.size());
  out->converged = summary->termination_type == ceres::CONVERGENCE;
  out->solver_message = summary->BriefReport();
  for (const ceres::IterationSummary& it : summary->iterations)
    out->iteration_costs.push_back(it.cost);
  std::vector<double> r;
  const bool evaluates = raw_residuals(problem, &r);
  bool finite = evaluates;
  for (double v : r) finite = finite && std::isfinite(v);
  if (summary->IsSolutionUsable() && finite) return;
  Status st = f->opt->method == Method::kInverseDynamics
                  ? first_failure(*f, f->x, "at the solver's last iterate")
                  : Status::Ok();
  if (st.ok()) {
    st = Status::Error(StatusCode::kSolverFailed,
                       std::string("Ceres: ") +
                           (finite ? summary->message : "residuals not finite at the solution"));
  }
  out->status = st;
}

/// Sensor-noise sensitivities of every sample of the fit at the parameters f->x.
std::vector<detail::Sensitivity> noise_sensitivities(const Fit& f) {
  std::vector<detail::Sensitivity> sens;
  sens.reserve(f.samples.size());
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!detail::kinematic_jacobian(f.scene, f.layout, f.x.data(), f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    sens.push_back(detail::sensitivity(f.cond.log.t, f.index[u], f.source, f.sg, f.noise, D));
  }
  return sens;
}

/// Residual levels and the structure warning: the rms against the level the sensor noise alone
/// gives (torque noise plus angle/rate noise through the rate estimation), floored for noise-free
/// logs at kAbsoluteFloor of the rms logged torque.
/// The residual's expected level from the sensor noise (noise[j]) and the floor for noise-free
/// logs (absolute[j], kAbsoluteFloor of the rms logged torque); floor[j] the larger.
void noise_floor(const Fit& f, const std::vector<detail::Sensitivity>& sens, double floor[2],
                 double noise[2] = nullptr, double absolute[2] = nullptr) {
  const TorqueLog& log = f.cond.log;
  Eigen::Vector2d prop = Eigen::Vector2d::Zero();
  for (const detail::Sensitivity& s : sens) prop += detail::propagated_variance(s);
  prop /= std::max<size_t>(1, sens.size());
  for (int j = 0; j < kActuators; ++j) {
    const std::vector<double>& tau = j == 0 ? log.tau1 : log.tau2;
    double s2 = 0;
    for (int i : f.index) s2 += tau[i] * tau[i] / f.index.size();
    // the torques' per-sample noise (after a delay's shift, smoothed by the interpolation)
    const double t2 = f.noise.torque[j] * f.noise.torque[j] * f.cond.torque_variance_factor;
    const double n = std::sqrt(t2 + prop(j));
    const double a = kAbsoluteFloor * std::sqrt(s2);
    floor[j] = std::max(n, a);
    if (noise != nullptr) noise[j] = n;
    if (absolute != nullptr) absolute[j] = a;
  }
}

/// The robust loss's scale: as given, else (0) from the noise: inverse dynamics kLossScaleHuber or
/// kLossScaleCauchy times a sample's expected residual level at the start values (the two
/// actuators' noise floors in quadrature: the loss sees the block's norm), output error 0.1 rad.
/// Costs one pass of noise_sensitivities over the samples.
void choose_loss_scale(Fit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  f->loss_scale = opt.loss_scale;
  if (opt.loss != Loss::kNone && !(opt.loss_scale > 0)) {
    f->loss_scale = 0.1;
    if (opt.method == Method::kInverseDynamics) {
      double floor[2];
      noise_floor(*f, noise_sensitivities(*f), floor);
      const double level = std::hypot(floor[0], floor[1]);
      const double k = opt.loss == Loss::kHuber ? kLossScaleHuber : kLossScaleCauchy;
      if (level > 0 && std::isfinite(level)) f->loss_scale = k * level;
      out->notes.push_back(std::string(loss_name(opt.loss)) + " loss at scale " +
                           format_significant(f->loss_scale) + " N m: " + format_significant(k, 4) +
                           " times the residual's noise level per sample " +
                           format_significant(level) + " N m (--loss-scale sets it)");
    }
  }
  out->loss_scale = opt.loss == Loss::kNone ? 0.0 : f->loss_scale;
}

void residual_levels(const Fit& f, const std::vector<double>& r,
                     const std::vector<detail::Sensitivity>& sens, IdentifyResult* out) {
  rms_pair(r, out->rms_torque_residual);
  double noises[2], floors[2];
  noise_floor(f, sens, out->residual_noise_floor, noises, floors);
  for (int j = 0; j < kActuators; ++j) {
    const double noise = noises[j], floor = floors[j];
    const double ratio = out->rms_torque_residual[j] / out->residual_noise_floor[j];
    if (ratio > kStructureRatio) {
      out->warnings.push_back(
          "tau" + std::to_string(j + 1) + " residual rms " +
          format_significant(out->rms_torque_residual[j]) + " N m is " + format_significant(ratio) +
          " times the noise floor " + format_significant(out->residual_noise_floor[j]) + " N m (" +
          (noise >= floor ? "torque noise " + format_significant(f.noise.torque[j]) +
                                " N m with the sensor noise propagated through the rates"
                          : "0.1 % of the rms logged torque, the log being nearly noise-free") +
          "): the residual has structure the fitted law (or the estimated rates) cannot "
          "explain; see fig_residual_vs_rate.png");
    }
  }
}

/// J^T J of the CRS Jacobian and the dense Jacobian itself (2 rows per sample).
Eigen::MatrixXd dense(const ceres::CRSMatrix& crs, int P) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, P);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int a = crs.rows[row]; a < crs.rows[row + 1]; ++a) J(row, crs.cols[a]) = crs.values[a];
  }
  return J;
}

/// The prior's information in J^T J units (group inertia: s^2 / sigma_i^2 on the diagonal of the
/// inertial parameters, s the prior's noise level; zero elsewhere).
Eigen::MatrixXd prior_information(const Fit& f) {
  const int P = f.layout.size();
  Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(P, P);
  if (!f.layout.inertia) return Hp;
  for (int i = 0; i < kInertialParams; ++i) {
    const int k = f.layout.inertia_offset() + i;
    Hp(k, k) = std::pow(f.prior_scale / f.prior.sigma[i], 2);
  }
  return Hp;
}

// ---- the smoothing bias of the data-driven window ----

/// The reconstruction of the motion for the bias prediction reaches this many times the residual
/// rule's half-window each side (the polynomial of degree order + kReconExtra then averages the
/// angle noise far below the filter's own noise, while following the motion over the filter's
/// span)
constexpr double kReconSpan = 2.0;
/// The largest predicted smoothing bias of a friction coefficient, in its std, that a window may
/// carry: a bias b moves the coverage of a 95 % interval from 0.95 to 0.945 at b = 0.2, 0.943 at
/// 0.25 and 0.92 at 0.5
constexpr double kBiasFraction = 0.2;

/// The inputs of the bias prediction at the preliminary fit (f.x, f.samples): the Jacobians, and
/// the motion's high-order terms from local polynomials over +-reach samples, cut short (not
/// below +-min_half) where they would span a slip reversal (the motion is not smooth across it).
detail::BiasInputs bias_inputs(const Fit& f, int reach, int min_half) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size(), P = f.layout.size();
  const double dt = log.duration() / std::max(1, n - 1);
  detail::BiasInputs in;
  in.index = f.index;
  ceres::Problem problem;
  std::vector<double> x = f.x;
  with_size(P, [&](auto k) {
    add_inverse_dynamics_terms<decltype(k)::value>(f.scene, f.layout, f.samples, f.eval,
                                                   Loss::kNone, 1, x.data(), &problem);
  });
  ceres::CRSMatrix crs;
  std::vector<double> r;
  if (problem.NumResidualBlocks() > 0 && raw_residuals(&problem, &r, &crs)) in.J = dense(crs, P);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!detail::kinematic_jacobian(f.scene, f.layout, f.x.data(), f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    in.D.push_back(D);
    const int i = f.index[u];
    int a = std::max(0, i - reach), b = std::min(n - 1, i + reach);
    while (!f.reversals.empty() && a < i - min_half && f.reversals[i] - f.reversals[a] > 0) ++a;
    while (!f.reversals.empty() && b > i + min_half && f.reversals[b] - f.reversals[i] > 0) --b;
    in.terms[0].push_back(detail::high_order_terms(log.t, log.theta1, i, a, b, dt, f.sg.order));
    in.terms[1].push_back(detail::high_order_terms(log.t, log.theta2, i, a, b, dt, f.sg.order));
  }
  in.Hp = prior_information(f);
  in.s2 = f.prior_scale * f.prior_scale;
  in.T = to_public(f.layout);
  in.friction_size = f.layout.friction_size();
  in.source = f.source;
  in.noise = f.noise;
  return in;
}

/// After the residual rule (choose_window): the largest window up to its choice whose predicted
/// smoothing bias (smoothing_bias.h) is within kBiasFraction of the std for every friction
/// coefficient, from the rule's choice down to the second smallest window; the rule's choice
/// when none is. Angles only, the filter's order as given (not raised).
void limit_smoothing_bias(Fit* f, IdentifyResult* out) {
  const TorqueLog& log = f->cond.log;
  const int n = log.size();
  if (f->source != detail::RateSource::kFromAngles || f->sg.order != f->opt->sg.order || n < 2) {
    return;
  }
  const double dt = log.duration() / (n - 1);
  const std::vector<int> cand = window_candidates(n, dt, f->sg.order);
  const int rule = static_cast<int>(
      std::find(cand.begin(), cand.end(), sg_half_window(f->sg, dt)) - cand.begin());
  if (rule < 1 || rule >= static_cast<int>(cand.size())) return;
  const detail::BiasInputs in = bias_inputs(*f, std::lround(kReconSpan * cand[rule]), cand[1]);
  if (in.J.rows() != 2 * static_cast<int>(f->samples.size())) return;
  std::string table;
  int chosen = -1;
  Eigen::VectorXd at_rule, at_chosen;
  for (int k = rule; k >= 1 && chosen < 0; --k) {
    const int m = cand[k];
    std::vector<char> keep(f->index.size(), 0);
    for (size_t u = 0; u < keep.size(); ++u) {
      const int i = f->index[u];
      keep[u] = i - m >= 0 && i + m < n && !spans_reversal(*f, i, m);
    }
    SgOptions sg = f->sg;
    sg.half_window_s = m * dt;
    Eigen::VectorXd bias, std;
    if (!detail::smoothing_bias(log.t, in, keep, sg, &bias, &std)) break;
    double worst = 0;
    for (int p = 0; p < bias.size(); ++p) {
      if (std(p) > 0) worst = std::max(worst, std::abs(bias(p)) / std(p));
    }
    table += (table.empty() ? "" : ", ") + std::to_string(m) + ": " + format_significant(worst);
    if (k == rule) at_rule = bias;
    if (worst <= kBiasFraction) chosen = k, at_chosen = bias;
  }
  if (table.empty()) return;
  const int pick = chosen < 0 ? rule : chosen;
  f->sg.half_window_s = cand[pick] * dt;
  f->smoothing_bias = chosen < 0 ? at_rule : at_chosen;
  out->window_choice +=
      "; then half-window " + std::to_string(cand[pick]) + " samples, " +
      (chosen < 0 ? "the rule's (no window down to " + std::to_string(cand[1]) +
                        " samples keeps it within " + format_significant(kBiasFraction) + " std)"
                  : "the largest up to the rule's whose predicted smoothing bias is within " +
                        format_significant(kBiasFraction) + " std of every friction coefficient") +
      " (predicted |bias| / std by half-window, the motion's higher terms from local polynomials "
      "of degree " +
      std::to_string(f->sg.order + detail::kReconExtra) + " over +-" +
      std::to_string(std::lround(kReconSpan * cand[rule])) + " samples: " + table + ")";
}

/// The predicted smoothing bias at the chosen window (f->smoothing_bias) taken off the friction
/// estimates, their intervals and the fitted parameters. Coefficients at a bound, or whose std
/// the log does not determine, are left as fitted, and no correction takes a coefficient past
/// its bound (a Stribeck static_coulomb stays >= coulomb): the correction is limited there, and
/// says so. Its own error, from the angle noise through the reconstruction, is a small part of
/// the bias (over two noisy paper logs at half-window 8: 0.078 and 0.136 std predicted for 0.088
/// measured), so a few hundredths of the std, and is not added to the std.
void correct_smoothing_bias(Fit* f, IdentifyResult* out) {
  const Eigen::VectorXd& b = f->smoothing_bias;
  const int P = f->layout.size();
  if (b.size() == 0 || static_cast<int>(out->parameters.size()) < b.size()) return;
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(P);
  for (int p = 0; p < b.size(); ++p) {
    const ParameterEstimate& e = out->parameters[p];
    if (!e.at_bound && std::isfinite(e.std) && std::isfinite(b(p))) shift(p) = b(p);
  }
  if (shift.isZero(0.0)) return;
  const Eigen::MatrixXd T = to_public(f->layout);
  const Eigen::VectorXd dx = T.inverse() * shift;
  Eigen::VectorXd x_old(P), x_new(P);
  for (int i = 0; i < P; ++i) {
    x_old(i) = f->x[i];
    f->x[i] = std::max(f->layout.lower_bound(i), f->x[i] - dx(i));
    x_new(i) = f->x[i];
  }
  const Eigen::VectorXd applied = T * (x_old - x_new);  // the shift each public value took
  std::string list;
  for (int p = 0; p < b.size(); ++p) {
    if (shift(p) == 0 && applied(p) == 0) continue;
    ParameterEstimate& e = out->parameters[p];
    e.value -= applied(p);
    e.ci_low -= applied(p);  // an open side (+-inf) stays open
    e.ci_high -= applied(p);
    list += (list.empty() ? "" : ", ") + e.name + " " + format_significant(-applied(p));
    if (std::abs(applied(p) - shift(p)) > 1e-12 * std::abs(shift(p))) {
      list += " (limited by its bound: predicted " + format_significant(-shift(p)) + ")";
    }
  }
  if (list.empty()) return;
  out->window_choice += "; the predicted bias at it taken off the estimates (" + list + ")";
}

/// Group inertia: base combinations, the parameters left at their prior (a warning), consistency.
void inertial_stage(const Fit& f, const Eigen::MatrixXd& J, IdentifyResult* out) {
  const int off = f.layout.inertia_offset();
  InertialReport& rep = out->inertial;
  rep.estimated = true;
  rep.prior_relative = f.opt->inertia_prior;
  const Eigen::MatrixXd C = out->covariance.block(off, off, kInertialParams, kInertialParams);
  if (!C.allFinite()) return;
  const std::vector<double> pi(f.x.begin() + off, f.x.end());
  detail::inertial_report(J.middleCols(off, kInertialParams), f.prior, f.prior_scale, pi, C, &rep);
  if (!rep.at_prior.empty()) {
    std::string list;
    for (const std::string& n : rep.at_prior) list += (list.empty() ? "" : ", ") + n;
    out->warnings.push_back("the log determines " + std::to_string(rep.rank) +
                            " of the 16 inertial directions; " +
                            "left at their prior (the scene's values, relative std " +
                            format_significant(rep.prior_relative) + "): " + list);
  }
  if (!rep.consistent) {
    out->warnings.push_back(
        "the fitted inertial parameters are not physically consistent (some link has m <= 0 or "
        "an inertia about its COM <= 0)");
  }
}

/// Output error: the block sandwich over the windows (covariance.h), whose residuals are
/// correlated within a window (they integrate the torque noise from the logged start) and
/// independent between windows. Empty when too few windows carry residuals (a warning).
Eigen::MatrixXd window_covariance(const Fit& f, const Eigen::MatrixXd& Jf,
                                  const std::vector<double>& r, IdentifyResult* out) {
  const std::vector<int>& sizes = f.window_sizes;
  const Eigen::VectorXd rv = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  const detail::BlockCovariance bc = detail::block_sandwich(Jf, rv, sizes);
  if (bc.covariance.size() == 0) {
    out->warnings.push_back("output error: " + std::to_string(sizes.size()) +
                            " windows are too few to estimate the correlated residuals' "
                            "covariance: standard deviations not given (use a longer log or a "
                            "shorter --window)");
    return {};
  }
  const auto [lo, hi] = std::minmax_element(bc.inflation.begin(), bc.inflation.end());
  out->std_method = "window-sandwich";
  // the variance is estimated from G independent windows: Student's t with G - 1 degrees of
  // freedom for the 95 % intervals (the cluster-robust standard; 2.09 for 20 windows)
  out->ci_dof = bc.blocks - 1;
  out->ci_quantile = detail::t_quantile_975(out->ci_dof);
  out->std_detail = "block sandwich over the residuals of " + std::to_string(bc.blocks) +
                    " windows (correlated within a window, independent between windows): " +
                    format_significant(*lo) + "-" + format_significant(*hi) +
                    " times the std that treats the angle residuals as independent";
  if (bc.blocks < kFewWindows) {
    out->warnings.push_back("output error: the std come from the residuals of only " +
                            std::to_string(bc.blocks) +
                            " windows and are themselves uncertain (a longer log, or a shorter "
                            "--window, gives more)");
  }
  return bc.covariance;
}

/// Covariance of the internal parameters, only on a converged solution with a full-rank
/// Jacobian (of the parameters off their bounds): errors in variables (sandwich) for inverse
/// dynamics, the window sandwich for output error, else s^2 (J^T J)^-1.
void covariance(const Fit& f, const Eigen::MatrixXd& J, const Eigen::MatrixXd& Hp,
                const std::vector<detail::Sensitivity>& sens, const std::vector<double>& r,
                IdentifyResult* out, Eigen::MatrixXd* hinv) {
  const int P = f.layout.size();
  out->covariance = Eigen::MatrixXd::Constant(P, P, kNaN);
  *hinv = out->covariance;  // (J^T J + Hp)^-1 of the free parameters
  if (!out->converged) {
    out->warnings.push_back("the solver did not converge (" + out->solver_message +
                            "): no covariance, standard deviations not given");
    return;
  }
  // parameters at a bound are held there (active constraints), and parameters without effect
  // on the residuals are left out: the covariance is that of the others
  std::vector<int> free;
  for (int i = 0; i < P; ++i) {
    if (f.x[i] > f.layout.lower_bound(i) + 1e-12 && J.col(i).squaredNorm() > 0) free.push_back(i);
  }
  if (free.empty()) return;
  Eigen::MatrixXd Jf(J.rows(), free.size()), Hpf(free.size(), free.size());
  for (size_t a = 0; a < free.size(); ++a) {
    Jf.col(a) = J.col(free[a]);
    for (size_t b = 0; b < free.size(); ++b) Hpf(a, b) = Hp(free[a], free[b]);
  }
  // the prior (group inertia) as a pseudo-observation of noise level s: information Hp = s^2 /
  // sigma^2, score covariance s^2 Hp; the covariance is then the posterior one (a direction the
  // log cannot determine gets its prior std, the CAD error it may carry)
  const double s2 = f.prior_scale * f.prior_scale;
  const Eigen::MatrixXd H = Jf.transpose() * Jf + Hpf;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  const double emax = es.eigenvalues().maxCoeff(), emin = es.eigenvalues().minCoeff();
  if (!(emax > 0) || !(emin > 1e-14 * emax) || !H.allFinite()) {
    out->warnings.push_back("covariance could not be computed (Jacobian rank deficient)");
    // a fit with no std cannot say how far to trust it
    if (out->unusable.empty()) {
      out->unusable = "the covariance could not be computed (the log does not determine the "
                      "free coefficients apart): the estimates have no std";
    }
    return;
  }
  const Eigen::MatrixXd Hinv = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                               es.eigenvectors().transpose();
  const auto scatter_into = [&](const Eigen::MatrixXd& Cf, Eigen::MatrixXd* C) {
    for (size_t a = 0; a < free.size(); ++a) {
      for (size_t b = 0; b < free.size(); ++b) (*C)(free[a], free[b]) = Cf(a, b);
    }
  };
  const auto scatter = [&](const Eigen::MatrixXd& Cf) { scatter_into(Cf, &out->covariance); };
  scatter_into(Hinv, hinv);  // the profile intervals' noise scale (intervals)
  if (f.opt->errors_in_variables && f.opt->method == Method::kOutputError) {
    const Eigen::MatrixXd Cw = window_covariance(f, Jf, r, out);
    if (Cw.size() > 0) scatter(Cw);
    return;
  }
  if (!f.opt->errors_in_variables) {
    const double sig2 = out->residual_sigma * out->residual_sigma;
    // the prior at the residual's level: H = J^T J + sig2 / sigma^2
    const Eigen::MatrixXd H2 = Jf.transpose() * Jf + Hpf * (sig2 / s2);
    scatter(H2.ldlt().solve(Eigen::MatrixXd::Identity(H2.rows(), H2.cols())) * sig2);
    out->std_method = "residual-variance";
    return;
  }
  Eigen::MatrixXd S = detail::score_covariance(Jf, sens, f.noise, f.cond.log.size()) + s2 * Hpf;
  // residual beyond the modelled noise (model mismatch, unmodelled noise) counted as white
  for (int j = 0; j < kActuators; ++j) {
    const double excess = std::max(
        0.0, std::pow(out->rms_torque_residual[j], 2) - std::pow(out->residual_noise_floor[j], 2));
    for (int row = j; row < Jf.rows(); row += 2) {
      S += excess * Jf.row(row).transpose() * Jf.row(row);
    }
  }
  scatter(Hinv * S * Hinv);
  out->std_method = "errors-in-variables";
  // Cramer-Rao bound for white torque noise alone (the logged level; angle noise ignored): a
  // lower bound the reported std should approach when the rates are logged
  const double st2 = std::max(f.noise.torque[0], f.noise.torque[1]);
  if (st2 > 0) {
    const Eigen::MatrixXd Hc = Jf.transpose() * Jf / (st2 * st2) + Hpf / s2;
    const Eigen::MatrixXd Cc = Hc.ldlt().solve(Eigen::MatrixXd::Identity(Hc.rows(), Hc.cols()));
    out->cramer_rao_std.assign(P, kNaN);
    for (size_t a = 0; a < free.size(); ++a) out->cramer_rao_std[free[a]] = std::sqrt(Cc(a, a));
  }
}

/// Singular values of the (public) Jacobian with unit-norm columns, and the warnings they imply.
void identifiability(const Eigen::MatrixXd& JtJ, const ParameterLayout& layout,
                     IdentifyResult* out) {
  const std::vector<std::string> names = layout.names();
  const int P = static_cast<int>(JtJ.rows());
  Eigen::VectorXd scale(P);
  for (int i = 0; i < P; ++i) {
    scale(i) = std::sqrt(JtJ(i, i));
    if (!(scale(i) > 0) || !std::isfinite(scale(i))) {
      out->warnings.push_back("parameter " + names[i] +
                              " has no effect on the residuals: the log does not excite it");
      scale(i) = 1;
    }
  }
  const Eigen::MatrixXd S = scale.asDiagonal().inverse() * JtJ * scale.asDiagonal().inverse();
  if (!S.allFinite()) return;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  // eigenvalues of J^T J ascending: singular values are their square roots
  for (int i = P - 1; i >= 0; --i) {
    out->singular_values.push_back(std::sqrt(std::max(0.0, es.eigenvalues()(i))));
  }
  // every direction with a condition above 100 (unit-norm columns): the smallest is reported
  // when it involves a friction or actuator term (inertial-only directions: the inertial report
  // covers them), the others when they involve an actuator term
  for (int d = 0; d < P; ++d) {
    const double ratio = out->singular_values[P - 1 - d] / out->singular_values.front();
    if (!(ratio < 1e-2)) break;
    const Eigen::VectorXd v = es.eigenvectors().col(d);
    std::string who;
    bool friction = false, motor = false;
    for (int i = 0; i < P; ++i) {
      if (!(std::abs(v(i)) > 0.3)) continue;
      who += (who.empty() ? "" : ", ") + names[i];
      friction = friction || !layout.is_inertial(i);
      motor = motor || layout.is_actuator(i);
    }
    if (d == 0 ? friction : motor) {
      out->warnings.push_back("the log cannot separate " + who +
                              " (smallest/largest scaled singular value " +
                              format_significant(ratio) + ")");
    }
  }
}

/// Public estimates, correlation, bounds: a parameter at a bound has no meaningful std (NaN),
/// and a std that is not > 0 is never reported as a number.
void estimates(const Fit& f, const std::vector<double>& x0_public, IdentifyResult* out) {
  const int P = f.layout.size();
  const std::vector<std::string> names = f.layout.names();
  const Eigen::MatrixXd T = to_public(f.layout);
  const Eigen::VectorXd xp = T * Eigen::Map<const Eigen::VectorXd>(f.x.data(), P);
  // to the public parameters; one is determined when every internal one it sums is
  Eigen::MatrixXd C0 = out->covariance;
  std::vector<bool> known(P);
  for (int i = 0; i < P; ++i) known[i] = std::isfinite(C0(i, i));
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      if (!std::isfinite(C0(i, j))) C0(i, j) = 0;
    }
  }
  out->covariance = T * C0 * T.transpose();
  for (int i = 0; i < P; ++i) {
    bool ok = true;
    for (int j = 0; j < P; ++j) ok = ok && (T(i, j) == 0 || known[j]);
    if (!ok) {
      out->covariance.row(i).setConstant(kNaN);
      out->covariance.col(i).setConstant(kNaN);
    }
  }
  out->correlation = Eigen::MatrixXd::Constant(P, P, kNaN);
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      out->correlation(i, j) =
          out->covariance(i, j) / std::sqrt(out->covariance(i, i) * out->covariance(j, j));
    }
  }
  for (int i = 0; i < P; ++i) {
    for (int j = i + 1; j < P; ++j) {
      // inertial pairs: the base combinations say which the log separates
      if (f.layout.is_inertial(i) && f.layout.is_inertial(j)) continue;
      if (std::abs(out->correlation(i, j)) > 0.98) {
        out->warnings.push_back("strong correlation " + format_significant(out->correlation(i, j)) +
                                " between " + names[i] + " and " + names[j]);
      }
    }
  }
  const bool excess = f.layout.static_as_excess;
  for (int i = 0; i < P; ++i) {
    ParameterEstimate e;
    e.name = names[i];
    e.value = xp(i);
    e.std = std::sqrt(out->covariance(i, i));
    e.initial = x0_public[i];
    e.at_bound = f.x[i] <= f.layout.lower_bound(i) + 1e-12;
    const bool static_group =
        excess && i < f.layout.friction_size() &&
        f.layout.group(i / f.layout.per_group()) == Coefficient::kStaticCoulomb;
    if (e.at_bound) {
      out->warnings.push_back(
          names[i] + " is at its bound" +
          (static_group ? " static_coulomb = coulomb (static friction cannot be below kinetic)"
                        : " " + format_significant(f.layout.lower_bound(i))) +
          ": its std is not meaningful (not reported); the log may not support this law or "
          "coefficient");
      e.std = kNaN;
    } else if (!(e.std > 0) || !std::isfinite(e.std)) {
      if (out->converged) out->warnings.push_back("std of " + names[i] + " not determined");
      e.std = kNaN;
    } else if (e.std > std::abs(e.value) && !f.layout.is_inertial(i)) {
      out->warnings.push_back(names[i] + " is poorly determined (std " + format_significant(e.std) +
                              " > value " + format_significant(e.value) + ")");
    }
    out->parameters.push_back(e);
  }
}

/// Predicted torques at every sample of the (conditioned) log, at the fit.
void predictions(const Fit& f, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  out->predicted_tau1.assign(n, kNaN);
  out->predicted_tau2.assign(n, kNaN);
  Params<double> p = f.scene;
  f.layout.apply(f.x.data(), &p);
  for (int i = 0; i < n; ++i) {
    Evaluation<double> ev;
    const Status st =
        inverse_dynamics(p, f.loads(log.t[i]), log.theta1[i], log.theta2[i], out->omega1[i],
                         out->omega2[i], out->alpha1[i], out->alpha2[i], nullptr, f.eval, &ev);
    if (st.ok()) {
      out->predicted_tau1[i] = ev.M1 + p.actuators.offset[0];  // as the sensor reads it
      out->predicted_tau2[i] = ev.M2 + p.actuators.offset[1];
    }
  }
}

/// Output error: the torque residual of the fitted scene and its white-noise level.
void output_error_levels(const Fit& f, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  double s[2] = {0, 0};
  int c = 0;
  for (int i = f.first; i <= f.last; ++i) {
    if (std::isnan(out->predicted_tau1[i])) continue;
    s[0] += std::pow(log.tau1[i] - out->predicted_tau1[i], 2);
    s[1] += std::pow(log.tau2[i] - out->predicted_tau2[i], 2);
    ++c;
  }
  for (int j = 0; j < kActuators; ++j)
    out->rms_torque_residual[j] = std::sqrt(s[j] / std::max(1, c));
  for (int j = 0; j < kActuators; ++j) {
    const std::vector<double>& tau = j == 0 ? log.tau1 : log.tau2;
    const std::vector<double>& pred = j == 0 ? out->predicted_tau1 : out->predicted_tau2;
    std::vector<double> d;
    for (int i = f.first + 1; i <= f.last; ++i) {
      const double e = (tau[i] - pred[i]) - (tau[i - 1] - pred[i - 1]);
      if (std::isfinite(e)) d.push_back(e);
    }
    out->residual_noise_floor[j] = robust_std(d) / std::sqrt(2.0);
  }
}

/// Torque-to-angle delay d: one Gauss-Newton step of the fit with d as an extra parameter
/// (d r_i / d d = tau'(t_i), tau' by Savitzky-Golay on the logged torques), its std from the
/// errors-in-variables covariance of that augmented step.
/// The delay's regressor, the logged torques' rates, carries their noise: it attenuates the
/// estimate by the share of the rates' variance that is noise (errors in variables). The window
/// of the rates doubles from the fit's (at least 3 samples) until that share is at most this on
/// both channels, or the window reaches kDelayWindowMax (a light mechanism's torques of 0.08 N m
/// with 0.02 N m of noise: at 3 samples the rates' noise was 14 times their signal, and a lag of
/// 20 ms read 1.4 ms)
constexpr double kDelayRateNoise = 0.05;
/// ... [s], and at most a twentieth of the log
constexpr double kDelayWindowMax = 0.1;

/// The logged torques' rates (order-3 Savitzky-Golay) for the delay estimate (kDelayRateNoise)
void delay_regressor(const Fit& f, std::vector<double>* g1, std::vector<double>* g2) {
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  const double widest = std::min(kDelayWindowMax, log.duration() / 20);
  SgOptions sg;
  sg.order = 3;
  sg.half_window_s = std::max(f.sg.half_window_s, 3 * dt);
  std::vector<double> unused;
  for (;;) {
    savitzky_golay(log.t, log.tau1, sg, g1, &unused);
    savitzky_golay(log.t, log.tau2, sg, g2, &unused);
    double gain = 0, acc_gain = 0;
    sg_noise_gains(log.t, sg, &gain, &acc_gain);
    bool quiet = true;
    for (int c = 0; c < kActuators; ++c) {
      const std::vector<double>& g = c == 0 ? *g1 : *g2;
      double power = 0;
      for (int i : f.index) power += g[i] * g[i];
      power /= std::max<size_t>(1, f.index.size());
      quiet = quiet && std::pow(f.noise.torque[c] * gain, 2) <= kDelayRateNoise * power;
    }
    if (quiet || 2 * sg.half_window_s > widest) return;
    sg.half_window_s *= 2;
  }
}

void estimate_delay(const Fit& f, const Eigen::MatrixXd& J, const std::vector<double>& r,
                    const std::vector<detail::Sensitivity>& sens, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  const int P = static_cast<int>(J.cols()), m = static_cast<int>(J.rows());
  std::vector<double> g1, g2;
  delay_regressor(f, &g1, &g2);
  Eigen::MatrixXd Ja(m, P + 1);
  Ja.leftCols(P) = J;
  for (size_t u = 0; u < f.index.size(); ++u) {
    Ja(2 * u, P) = g1[f.index[u]];
    Ja(2 * u + 1, P) = g2[f.index[u]];
  }
  const Eigen::MatrixXd H = Ja.transpose() * Ja;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  const double emax = es.eigenvalues().maxCoeff(), emin = es.eigenvalues().minCoeff();
  if (!H.allFinite() || !(emax > 0) || !(emin > 1e-14 * emax)) return;
  const Eigen::MatrixXd Hinv = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                               es.eigenvectors().transpose();
  const Eigen::VectorXd step =
      -Hinv * (Ja.transpose() * Eigen::Map<const Eigen::VectorXd>(r.data(), m));
  Eigen::MatrixXd S = detail::score_covariance(Ja, sens, f.noise, log.size());
  for (int j = 0; j < kActuators; ++j) {
    const double excess = std::max(
        0.0, std::pow(out->rms_torque_residual[j], 2) - std::pow(out->residual_noise_floor[j], 2));
    for (int row = j; row < m; row += 2) S += excess * Ja.row(row).transpose() * Ja.row(row);
  }
  const Eigen::MatrixXd C = Hinv * S * Hinv;
  out->delay_s = step(P);
  out->delay_std_s = std::sqrt(C(P, P));
}

/// `log` with its torques read at t + d (cubic through the four nearest samples, clamped at the
/// ends): torques that lag the angles by d brought in line. The interpolation smooths their
/// noise: *variance_factor is the sum of the squared weights at the middle sample (0.64 for half
/// a sample), the per-sample variance left of white noise; its low-frequency level, which the
/// std of the coefficients see, is unchanged (the weights sum to 1).
TorqueLog shift_torques(const TorqueLog& log, double d, double* variance_factor) {
  TorqueLog out = log;
  const int n = log.size();
  *variance_factor = 1;
  for (int i = 0; i < n; ++i) {
    const double t = log.t[i] + d;
    const int k = static_cast<int>(std::upper_bound(log.t.begin(), log.t.end(), t) - log.t.begin());
    const int lo = std::clamp(k - 2, 0, std::max(0, n - 4));
    const int hi = std::min(n, lo + 4);
    const double tc = std::clamp(t, log.t.front(), log.t.back());
    double v1 = 0, v2 = 0, g = 0;
    for (int a = lo; a < hi; ++a) {
      double w = 1;
      for (int b = lo; b < hi; ++b) {
        if (b != a) w *= (tc - log.t[b]) / (log.t[a] - log.t[b]);
      }
      v1 += w * log.tau1[a];
      v2 += w * log.tau2[a];
      g += w * w;
    }
    if (i == n / 2) *variance_factor = g;
    out.tau1[i] = v1;
    out.tau2[i] = v2;
  }
  return out;
}

/// The fit redone on the conditioned log with the torques shifted by the delay `first` found,
/// carrying over what the first pass reported about the log.
IdentifyResult refit_with_delay(const Params<double>& scene_in, const sim::LoadFunction& loads,
                                const TorqueLog& conditioned, const IdentifyOptions& opt,
                                const IdentifyResult& first) {
  IdentifyOptions again = opt;
  again.delay_refits = opt.delay_refits - 1;
  again.estimate_delay = again.delay_refits > 0;
  // the sign was checked on the log as logged (a shift does not change it), and so was the
  // friction per joint: no refit repeats them
  again.check_torque_sign = false;
  again.check_per_joint = false;
  for (const Glitch& g : first.glitches) again.condition.rejected_before.push_back(g.index);
  // samples whose shifted torque would lie beyond the samples that have torques have none: left
  // out. In a chain of refits those are the log's ends less the end blocks an earlier refit left
  // out (its shifted torques there were clamped), and only the samples not left out before are
  // counted (else a chain of refits reports more samples left out than the log has)
  const int n = conditioned.size();
  const std::vector<int>& before = opt.condition.rejected_before;
  auto left_out = [&](int i) { return std::find(before.begin(), before.end(), i) != before.end(); };
  int lo = 0, hi = n - 1;
  while (lo < hi && left_out(lo)) ++lo;
  while (hi > lo && left_out(hi)) --hi;
  const double tol = 1e-9 * std::max(1.0, conditioned.duration());
  int beyond = 0;
  for (int i = 0; i < n; ++i) {
    const double t = conditioned.t[i] + first.delay_s;
    if (t > conditioned.t[hi] + tol || t < conditioned.t[lo] - tol) {
      again.condition.rejected_before.push_back(i);
      beyond += !left_out(i);
    }
  }
  // the shift smooths the torques' noise, which the refit would then measure too small (a 0.5 ms
  // lag would give std 22 % small and a false structure warning): it keeps the noise measured
  // before (the level the coefficients' std see) and scales the per-sample level by the
  // interpolation's sum of squared weights (a product over a chain of refits, approximately)
  double factor = 1;
  const TorqueLog shifted = shift_torques(conditioned, first.delay_s, &factor);
  for (int j = 0; j < kActuators; ++j) again.condition.torque_noise[j] = first.torque_noise[j];
  again.condition.torque_variance_factor = opt.condition.torque_variance_factor * factor;
  IdentifyResult res = identify(scene_in, loads, shifted, again);
  // the refit estimated the delay left after the shift (and corrected it when significant): the
  // total is their sum, with the std of the last estimate
  if (res.delay_corrected) res.warnings.erase(res.warnings.begin());
  res.samples = first.samples;
  // (a refit whose estimate is not finite keeps the first, so no "lag by nan +- nan ms")
  const bool refit_estimate =
      again.estimate_delay && std::isfinite(res.delay_s) && std::isfinite(res.delay_std_s);
  res.delay_s = first.delay_s + (refit_estimate ? res.delay_s : 0.0);
  res.delay_std_s = refit_estimate ? res.delay_std_s : first.delay_std_s;
  res.delay_corrected = true;
  res.notes.insert(res.notes.begin(), first.notes.begin(), first.notes.end());
  // one note for the whole chain of refits (a deeper refit's count is included in this one)
  const char* const kBeyond = " samples at an end of the log left out: their torques, shifted by "
                              "the delay, fall beyond the log";
  int total_beyond = beyond;
  for (auto it = res.notes.begin(); it != res.notes.end();) {
    if (it->find(kBeyond) == std::string::npos) {
      ++it;
      continue;
    }
    total_beyond += std::stoi(*it);
    it = res.notes.erase(it);
  }
  if (total_beyond > 0) res.notes.push_back(std::to_string(total_beyond) + kBeyond);
  res.glitches.insert(res.glitches.begin(), first.glitches.begin(), first.glitches.end());
  for (int j = 0; j < kDof; ++j) res.unwrapped[j] += first.unwrapped[j];
  // the significance that decided the correction is the first estimate's (the refit's std is
  // that of the delay left after the shift)
  std::vector<std::string> w = {std::string("the torques ") + (res.delay_s < 0 ? "lead" : "lag") +
                                " the angles by " +
                                format_significant(std::abs(res.delay_s) * 1e3) + " +- " +
                                format_significant(res.delay_std_s * 1e3) + " ms (first estimate " +
                                format_significant(std::abs(first.delay_s) / first.delay_std_s) +
                                " std): refitted with the torques shifted by it"};
  if (!first.glitches.empty()) w.push_back(first.warnings.front());
  res.warnings.insert(res.warnings.begin(), w.begin(), w.end());
  return res;
}

/// Slip reversals too dense to leave out the samples near them: a warning (the left-out count is
/// in the result).
void reversal_note(const Fit& f, IdentifyResult* out) {
  if (out->samples_near_reversals == 0 && out->slip_reversals > 0 && f.reversals.empty()) {
    out->warnings.push_back(
        "the " + std::to_string(out->slip_reversals) +
        " slip reversals are too dense to leave out the samples whose Savitzky-Golay window "
        "spans one (more than half of the log): the estimated accelerations are smoothed across "
        "them, which biases the Coulomb coefficients low; log the rates or sample faster");
  }
}

/// Rates (logged or Savitzky-Golay), the data-driven window when it applies, the samples of the
/// fit, and a check that the model evaluates at every one at the start values (false: status).
bool rates_window_and_samples(const TorqueLog& log, Fit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  const int P = f->layout.size();
  const bool id = opt.method == Method::kInverseDynamics;
  const auto rates_and_samples = [&]() {
    estimate_rates(f, out);
    require_samples(log, P + 1 + (out->accels_estimated ? 2 * out->sg_half_window : 0),
                    std::to_string(P) + " parameters + 1" +
                        (out->accels_estimated ? " + the Savitzky-Golay window" : std::string()));
    select_samples(f, out);
    // a sample the model cannot evaluate at the start values is a numerical failure, named
    if (id) out->status = first_failure(*f, f->x, "at the start values");
    return out->status.ok();
  };
  if (!rates_and_samples()) return false;
  if (out->accels_estimated && opt.auto_window && id) {
    const std::vector<double> x_start = f->x;
    preliminary_fit(f);
    choose_window(f, out);
    limit_smoothing_bias(f, out);
    f->x = x_start;
    if (!rates_and_samples()) return false;
  } else if (out->accels_estimated) {
    out->window_choice = "given: half-window " + std::to_string(out->sg_half_window) + " samples";
  }
  reversal_note(*f, out);
  return true;
}

/// Start values in the internal layout, from the public `initial` (or the neutral defaults).
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


/// The fit's shared state from the options: the internal layout, the scene with the law to fit,
/// the inertial prior.
void init_fit(const Params<double>& scene_in, const sim::LoadFunction& loads, const TorqueLog& log,
              const IdentifyOptions& opt, Fit* f, IdentifyResult* out) {
  out->layout = opt.layout;
  out->method = opt.method;
  out->samples = log.size();
  out->window_s = output_error_window(opt.window_s, log.duration());
  f->opt = &opt;
  f->loads = loads;
  f->layout = opt.layout;
  f->layout.static_as_excess = f->layout.group_of(Coefficient::kStaticCoulomb) >= 0;
  f->scene = fit_scene(scene_in, f->layout, opt);
  f->sg = opt.sg;
  f->eval.friction_tol = 1e-12;
  f->eval.friction_max_iter = 100;
  if (f->layout.inertia) f->prior = detail::inertial_prior(scene_in, opt.inertia_prior);
}

/// The prior's weight before the fit: the logged torque noise (refined after a first solve).
double initial_prior_scale(const Fit& f) {
  const double s = std::max(f.noise.torque[0], f.noise.torque[1]);
  return s > 0 ? s : 1e-3;
}

/// Logged rates noisier than those the angles give, even through the noisiest Savitzky-Golay
/// window of the choice (order 5 over 3 samples each side): their noise enters the friction's
/// sign and viscous terms and the reactions (errors in variables), so the rates and
/// accelerations are estimated from the angles instead, with a note saying so.
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

/// What the stages after the solve share: the data residuals and their Jacobian at the fit, and
/// the sensor-noise sensitivities (inverse dynamics).
struct Analysis {
  std::vector<double> r;
  Eigen::MatrixXd J;
  std::vector<detail::Sensitivity> sens;
  /// (J^T J + Hp)^-1 over the parameters off their bounds (internal layout; NaN elsewhere)
  Eigen::MatrixXd Hinv;
};

/// Data residuals and Jacobian (the prior's rows, added last, left out).
void data_residuals(ceres::Problem* problem, int P, int m, Analysis* an) {
  ceres::CRSMatrix crs;
  raw_residuals(problem, &an->r, &crs);
  an->r.resize(m);
  an->J = dense(crs, P).topRows(m);
}

/// Solves. Group inertia: the prior's weight is then set to the residual's noise level (the torque
/// noise plus the angle noise through the rates) and, if that differs, the fit is refined.
bool solve_stage(Fit* f, ceres::Problem* problem, IdentifyResult* out,
                 ceres::Solver::Summary* summary, Analysis* an) {
  const bool id = f->opt->method == Method::kInverseDynamics;
  const int P = f->layout.size();
  if (id) {  // the residual level at the start (the Jacobian is needed only after the solve)
    std::vector<double> r0;
    raw_residuals(problem, &r0);
    r0.resize(out->residuals);
    rms_pair(r0, out->rms_torque_residual_initial);
  }
  best_stribeck_start(f, problem);
  solve(f, problem, out, summary);
  if (!out->status.ok()) return false;
  if (id) an->sens = noise_sensitivities(*f);
  if (id && f->layout.inertia) {
    double floor[2];
    noise_floor(*f, an->sens, floor);
    const double s = std::max(floor[0], floor[1]);
    if (s > 1.2 * f->prior_scale || s < f->prior_scale / 1.2) {
      f->prior_scale = s;
      solve(f, problem, out, summary);
      if (!out->status.ok()) return false;
      an->sens = noise_sensitivities(*f);
    }
  }
  data_residuals(problem, P, out->residuals, an);
  return true;
}

/// Residual levels, covariance (converged solutions only), identifiability, estimates, and the
/// inertial report.
void analyse(const Fit& f, const std::vector<double>& x0_public,
             const ceres::Solver::Summary& summary, Analysis* an, IdentifyResult* out) {
  const int P = f.layout.size();
  const bool id = f.opt->method == Method::kInverseDynamics;
  out->residual_sigma =
      std::sqrt(2.0 * summary.final_cost / std::max(1, summary.num_residuals - P));
  if (!id && !f.opt->errors_in_variables) {
    out->warnings.push_back(
        "output-error standard deviations treat the angle residuals as independent; within a "
        "window they are correlated (they integrate the torque noise), so the reported std "
        "understate the uncertainty");
  }
  if (id) {
    residual_levels(f, an->r, an->sens, out);
  } else {
    rms_pair(an->r, out->rms_angle_residual);
  }
  const Eigen::MatrixXd Hp = prior_information(f);
  covariance(f, an->J, Hp, an->sens, an->r, out, &an->Hinv);
  const Eigen::MatrixXd Tinv = to_public(f.layout).inverse();
  identifiability(Tinv.transpose() * (an->J.transpose() * an->J + Hp) * Tinv, f.layout, out);
  estimates(f, x0_public, out);
  if (f.layout.inertia) inertial_stage(f, an->J, out);
}

/// The larger of the two channels' rms torque residual over its noise floor
double misfit_ratio(const IdentifyResult& r) {
  return std::max(r.rms_torque_residual[0] / r.residual_noise_floor[0],
                  r.rms_torque_residual[1] / r.residual_noise_floor[1]);
}

/// A friction coefficient at its bound while the residual is far above the noise floor (as from
/// two adjacent bad samples, an acceleration spike or a step in an angle, which can put Coulomb at
/// 0): the fit is driven by samples the law cannot explain. One
/// warning names the coefficients, the ratio, the lines of the largest residuals (in units of
/// the floor) and the likely causes.
void bound_and_misfit_warning(const Fit& f, const Analysis& an, IdentifyResult* out) {
  std::string at;
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    if (out->parameters[i].at_bound) at += (at.empty() ? "" : ", ") + out->parameters[i].name;
  }
  const double* fl = out->residual_noise_floor;
  const double ratio = misfit_ratio(*out);
  if (at.empty() || !(ratio > kMisfitRatio)) return;
  const size_t m = f.index.size();
  std::vector<std::pair<double, int>> q(m);  // per sample: residual in floors, log index
  for (size_t u = 0; u < m; ++u) {
    q[u] = {std::hypot(an.r[2 * u] / fl[0], an.r[2 * u + 1] / fl[1]) / std::sqrt(2.0), f.index[u]};
  }
  const size_t top = std::min<size_t>(3, m);
  std::partial_sort(q.begin(), q.begin() + top, q.end(), std::greater<>());
  std::string lines;
  for (size_t k = 0; k < top; ++k) {
    lines += (k ? ", " : "") + sample_name(f.cond.log, q[k].second) + " (" +
             format_significant(q[k].first, 2) + " times)";
  }
  // which cause cannot be told from the residual: a glitch that drags a coefficient to its bound
  // leaves the whole residual off the floor, as a wrong scene does
  out->unusable = at + " at its bound while the torque residual is " +
                  format_significant(ratio, 3) + " times its noise floor (more than " +
                  format_significant(kMisfitRatio) + ")";
  out->warnings.push_back(
      at + " at its bound while the torque residual is " + format_significant(ratio) +
      " times the noise floor: the fit is driven by samples the law cannot explain (largest at " +
      lines + "). Likely causes: glitches the rejection missed (check those lines; --loss cauchy "
      "fits past them), or a scene (masses, geometry, loads) or law that does not match the log "
      "(--estimate friction,inertia, another --law). A coefficient at its bound has no "
      "meaningful std; do not use this fit as it is");
}

// ---- model checks (misfit.h) ----

/// The fit's residual blocks under `layout2` on the parameter vector *x2 (kept alive by the
/// caller, who may change it between evaluations); false for an unsupported size.
bool check_problem(const Fit& f, const ParameterLayout& layout2, std::vector<double>* x2,
                   ceres::Problem* problem) {
  return with_size(layout2.size(), [&](auto n) {
    add_inverse_dynamics_terms<decltype(n)::value>(f.scene, layout2, f.samples, f.eval,
                                                   Loss::kNone, 1, x2->data(), problem);
  });
}

/// The Jacobian of `problem`'s residuals (P parameters) at its current values, rows whitened by
/// the noise floors `fl`, and the whitened residual; false if an evaluation fails.
bool whitened_jacobian(ceres::Problem* problem, int P, const double fl[2], Eigen::MatrixXd* J,
                       Eigen::VectorXd* r) {
  std::vector<double> rv;
  ceres::CRSMatrix crs;
  if (!raw_residuals(problem, &rv, &crs)) return false;
  *J = dense(crs, P);
  *r = Eigen::Map<const Eigen::VectorXd>(rv.data(), rv.size());
  for (Eigen::Index row = 0; row < J->rows(); ++row) {
    J->row(row) /= fl[row % 2];
    (*r)(row) /= fl[row % 2];
  }
  return J->allFinite() && r->allFinite();
}

/// The fit's vector under `layout2`, which differs from f.layout in its friction part or by the
/// inertial group: `friction` then the scene's inertial parameters (or the fitted ones), then
/// the fitted actuator terms.
std::vector<double> with_layout(const Fit& f, const ParameterLayout& layout2,
                                std::vector<double> friction) {
  const auto mid = f.x.begin() + f.layout.friction_size();
  if (f.layout.inertia) {
    friction.insert(friction.end(), mid, mid + kInertialParams);
  } else if (layout2.inertia) {
    const detail::InertialPrior prior = detail::inertial_prior(f.scene, f.opt->inertia_prior);
    friction.insert(friction.end(), prior.centre.begin(), prior.centre.end());
  }
  if (f.layout.actuator) friction.insert(friction.end(), f.x.end() - kActuatorTerms, f.x.end());
  return friction;
}

/// Columns of the residual's Jacobian on offsets d of the logged angles (theta1, theta2 read d
/// more than the scene's angles: the model is evaluated at theta - d), by central differences at
/// the fit, rows whitened by the floors `fl`; false if an evaluation fails.
bool offset_columns(const Fit& f, const double fl[2], Eigen::MatrixXd* Jo) {
  constexpr double h = 1e-6;  // [rad]
  const int m = 2 * static_cast<int>(f.samples.size());
  Jo->setZero(m, 2);
  for (int c = 0; c < 2; ++c) {
    for (double sgn : {1.0, -1.0}) {
      std::vector<Sample> shifted = f.samples;
      for (Sample& s : shifted) (c == 0 ? s.th1 : s.th2) -= sgn * h;
      std::vector<double> x = f.x, r;
      ceres::Problem problem;
      const bool sized = with_size(f.layout.size(), [&](auto n) {
        add_inverse_dynamics_terms<decltype(n)::value>(f.scene, f.layout, shifted, f.eval,
                                                       Loss::kNone, 1, x.data(), &problem);
      });
      if (!sized || !raw_residuals(&problem, &r) || static_cast<int>(r.size()) != m) return false;
      for (int row = 0; row < m; ++row) (*Jo)(row, c) += sgn * r[row] / (2 * h * fl[row % 2]);
    }
  }
  return Jo->allFinite();
}

/// The friction coefficients a freed step moves beyond kFreedMove std, as "name from a to b
/// (k std)": the std of the estimate, or with `own` the larger of it and the move's own std (the
/// test of Hausman); empty if none moves so, or one is at its bound (which has its own warning).
std::string friction_moves(const Fit& f, const IdentifyResult& out, const detail::FreedStep& fs,
                           bool own, double* largest = nullptr) {
  const int nf = f.layout.friction_size();
  const Eigen::MatrixXd T = to_public(f.layout).topLeftCorner(nf, nf);
  const Eigen::VectorXd move = T * fs.fitted_step.head(nf);
  const Eigen::MatrixXd cov = T * fs.fitted_cov.topLeftCorner(nf, nf) * T.transpose();
  std::string moved;
  for (int i = 0; i < nf; ++i) {
    const ParameterEstimate& e = out.parameters[i];
    if (e.at_bound) return "";
    const double sd = own ? std::max(std::sqrt(std::max(0.0, cov(i, i))), e.std) : e.std;
    if (!(std::abs(move(i)) > kFreedMove * sd)) continue;
    if (largest) *largest = std::max(*largest, std::abs(move(i)) / sd);
    moved += (moved.empty() ? "" : ", ") + e.name + " from " + format_significant(e.value) +
             " to " + format_significant(e.value + move(i)) + " (" +
             format_significant(std::abs(move(i)) / sd, 2) + " std)";
  }
  return moved;
}

/// The clause of a model_check warning on the friction: "the friction would move: ..." when a
/// freed step moves a coefficient beyond kFreedMove std (friction_moves). When a coefficient is
/// at its bound no move is given; for a cause the log evidences (`evidenced`) the warning is
/// still due, and says so (a crank inertia 10 % off puts coulomb at 0 and viscous 23 std off,
/// which the bound's warning alone does not explain). Empty: no warning.
std::string friction_clause(const Fit& f, const IdentifyResult& out, const detail::FreedStep& fs,
                            bool own, bool evidenced, double* largest = nullptr) {
  const std::string moved = friction_moves(f, out, fs, own, largest);
  if (!moved.empty()) return "the friction would move: " + moved;
  const int nf = f.layout.friction_size();
  bool bound = false;
  for (int i = 0; i < nf; ++i) bound = bound || out.parameters[i].at_bound;
  if (!evidenced || !bound) return "";
  return "a friction coefficient is at its bound, so the fit cannot say how far the friction "
         "would move";
}

/// Columns of the whitened residual's Jacobian on errors of the torque readings (TorqueColumns)
struct TorqueColumns {
  Eigen::MatrixXd J;
  /// column of channel c's offset and gain in J (-1: left out)
  std::array<int, 2> offset{-1, -1}, gain{-1, -1};
};

/// A gain is left out when the model's torque of its channel varies by less than this fraction
/// of its mean: then it is nearly an offset (with both free, constant drive torques of 40 N m
/// read back an offset of -170 N m and a gain of 424 %)
constexpr double kGainSpread = 0.1;

/// The columns (r: the whitened residual at the fit, fl: the noise floors) on errors of the
/// torque readings, tau_c = (1 + g_c) M_c + o_c: the offsets o1, o2 (left out when the fit has
/// them, --estimate actuator) then the gains g1, g2 (kGainSpread), with M_c the fitted model's
/// torque (tau_c - o_c - r_c).
TorqueColumns torque_columns(const Fit& f, const Eigen::VectorXd& r, const double fl[2]) {
  const double* o = f.layout.actuator ? &f.x[f.layout.actuator_offset()] : nullptr;
  const Eigen::Index n = static_cast<Eigen::Index>(f.samples.size());
  Eigen::MatrixXd model(n, kDof);
  for (Eigen::Index u = 0; u < n; ++u) {
    for (int c = 0; c < kDof; ++c) {
      const double tau = c == 0 ? f.samples[u].tau1 : f.samples[u].tau2;
      model(u, c) = tau - (o ? o[c] : 0.0) - r(2 * u + c) * fl[c];
    }
  }
  TorqueColumns tc;
  int k = 0;
  for (int c = 0; c < kDof && !o; ++c) tc.offset[c] = k++;
  for (int c = 0; c < kDof; ++c) {
    const double mean = model.col(c).mean();
    const double spread = std::sqrt((model.col(c).array() - mean).square().mean());
    if (spread >= kGainSpread * std::abs(mean)) tc.gain[c] = k++;
  }
  tc.J = Eigen::MatrixXd::Zero(r.size(), k);
  for (Eigen::Index u = 0; u < n; ++u) {
    for (int c = 0; c < kDof; ++c) {
      if (tc.offset[c] >= 0) tc.J(2 * u + c, tc.offset[c]) = -1.0 / fl[c];
      if (tc.gain[c] >= 0) tc.J(2 * u + c, tc.gain[c]) = -model(u, c) / fl[c];
    }
  }
  return tc;
}

/// The residual's Jacobian at the fit, whitened by the noise floors, with the links' 16 inertial
/// parameters (columns idx[1], prior information in `info`), the two angle offsets (idx[2])
/// and the torque readings' offsets and gains (idx[3], `tc`) added to the fitted ones (idx[0]);
/// false if an evaluation fails.
bool check_jacobian(const Fit& f, const IdentifyResult& out, Eigen::MatrixXd* J, Eigen::VectorXd* r,
                    std::vector<int> idx[4], Eigen::VectorXd* info, TorqueColumns* tc) {
  const int nf = f.layout.friction_size();
  ParameterLayout l2 = f.layout;
  l2.inertia = true;
  std::vector<double> x2 = with_layout(f, l2, std::vector<double>(f.x.begin(), f.x.begin() + nf));
  ceres::Problem problem;
  Eigen::MatrixXd Ji, Jo;
  if (!check_problem(f, l2, &x2, &problem) ||
      !whitened_jacobian(&problem, l2.size(), out.residual_noise_floor, &Ji, r) ||
      !offset_columns(f, out.residual_noise_floor, &Jo) || Jo.rows() != Ji.rows()) {
    return false;
  }
  *tc = torque_columns(f, *r, out.residual_noise_floor);
  const Eigen::MatrixXd& Jt = tc->J;
  J->resize(Ji.rows(), Ji.cols() + 2 + Jt.cols());
  *J << Ji, Jo, Jt;
  for (int i = 0; i < l2.size(); ++i) {
    idx[l2.is_inertial(i) && !f.layout.inertia ? 1 : 0].push_back(i);
  }
  idx[2] = {l2.size(), l2.size() + 1};
  for (Eigen::Index k = 0; k < Jt.cols(); ++k) idx[3].push_back(l2.size() + 2 + k);
  const detail::InertialPrior prior = detail::inertial_prior(f.scene, f.opt->inertia_prior);
  info->resize(kInertialParams);
  for (int k = 0; k < kInertialParams; ++k) (*info)(k) = 1.0 / std::pow(prior.sigma[k], 2);
  return true;
}

/// The sum of the squared taps through which a noise channel (an angle, or a logged rate) reaches
/// the estimated acceleration at log sample i (noise of std s on the channel: s^2 times it on the
/// acceleration): the Savitzky-Golay d2 of the angles, or d1 of logged rates; 0 when the
/// accelerations are logged (their own noise is not modelled).
double accel_tap_power(const Fit& f, int i) {
  if (f.source == detail::RateSource::kLogged) return 0.0;
  int lo = i;
  std::vector<double> d1, d2;
  savitzky_golay_taps(f.cond.log.t, i, f.sg, &lo, &d1, &d2);
  const std::vector<double>& d = f.source == detail::RateSource::kFromAngles ? d2 : d1;
  double power = 0;
  for (double w : d) power += w * w;
  return power;
}

/// d J / d alpha_c and d r / d alpha_c (c: crank 1, 2; each moved at every sample at once) of
/// the whitened Jacobian on the fitted and inertial parameters (check_jacobian's columns but the
/// offsets') and of the whitened residual, by forward differences from J, r at the fit (the
/// residual is nearly linear in the accelerations: only the load-dependent friction is not);
/// false if an evaluation fails.
bool accel_derivatives(const Fit& f, const IdentifyResult& out, const Eigen::MatrixXd& J,
                       const Eigen::VectorXd& r, Eigen::MatrixXd dJ[2], Eigen::VectorXd dr[2]) {
  constexpr double h = 1e-2;  // [rad/s^2]
  ParameterLayout l2 = f.layout;
  l2.inertia = true;
  Fit g = f;
  for (int c = 0; c < kDof; ++c) {
    for (size_t u = 0; u < f.samples.size(); ++u) {
      g.samples[u].a1 = f.samples[u].a1 + (c == 0 ? h : 0.0);
      g.samples[u].a2 = f.samples[u].a2 + (c == 1 ? h : 0.0);
    }
    const auto friction_end = f.x.begin() + f.layout.friction_size();
    std::vector<double> x2 = with_layout(g, l2, std::vector<double>(f.x.begin(), friction_end));
    ceres::Problem problem;
    Eigen::MatrixXd Jh;
    Eigen::VectorXd rh;
    if (!check_problem(g, l2, &x2, &problem) ||
        !whitened_jacobian(&problem, l2.size(), out.residual_noise_floor, &Jh, &rh) ||
        Jh.rows() != J.rows() || Jh.cols() > J.cols()) {
      return false;
    }
    dJ[c] = (Jh - J.leftCols(Jh.cols())) / h;
    dr[c] = (rh - r) / h;
  }
  return true;
}

/// The expectation of the check's score J' r (J: check_jacobian's columns, b: one entry each)
/// that the noise of estimated accelerations gives when the model holds. That noise is in the
/// residual (-M(q) times the acceleration's) and, through the accelerations the inverse dynamics
/// is evaluated at, in the inertial columns too (errors in variables), so E[J' r] = sum over
/// samples and cranks c of sigma_c^2 m_c dJ_c' dr_c (dJ_c, dr_c: accel_derivatives; m_c: the sum
/// of the squared acceleration taps, accel_tap_power). It grows with the log's length while the
/// score's noise grows with its square root (uncorrected, clean 10 s logs drop the cost by 104
/// against 15 +- 5.3 from white noise). Left out as measured negligible on a clean 10 s log of
/// the paper scene: the rate noise's path (under 1 % of the acceleration's on every column) and
/// the offset columns' bias (below 0.03 of their score's std). The torque gains' columns carry
/// the model's torque, so the same noise biases them too. Zero when the accelerations are
/// logged. Costs two Jacobians on the fitted and inertial parameters.
bool score_bias(const Fit& f, const IdentifyResult& out, const Eigen::MatrixXd& J,
                const Eigen::VectorXd& r, const TorqueColumns& tc, Eigen::VectorXd* b) {
  b->setZero(J.cols());
  // the std of each crank's noise channel
  const double* sigma = f.source == detail::RateSource::kFromAngles ? f.noise.angle : f.noise.rate;
  if (f.source == detail::RateSource::kLogged || !(sigma[0] > 0 || sigma[1] > 0)) return true;
  Eigen::MatrixXd dJ[2];
  Eigen::VectorXd dr[2];
  if (!accel_derivatives(f, out, J, r, dJ, dr)) return false;
  // the torque gains' columns (the last of J, torque_columns) hold minus the model's torque,
  // whose derivative in the accelerations is the residual's: dr_c on their crank's rows
  const Eigen::Index first = J.cols() - tc.J.cols();
  for (size_t u = 0; u < f.samples.size(); ++u) {
    const Eigen::Index row = 2 * static_cast<Eigen::Index>(u);
    const double m = accel_tap_power(f, f.index[u]);
    for (int c = 0; c < kDof; ++c) {
      const double v = sigma[c] * sigma[c] * m;
      b->head(dJ[c].cols()) += v * dJ[c].middleRows(row, 2).transpose() * dr[c].segment(row, 2);
      for (int k = 0; k < kDof; ++k) {
        if (tc.gain[k] >= 0) (*b)(first + tc.gain[k]) += v * std::pow(dr[c](row + k), 2);
      }
    }
  }
  return b->allFinite();
}

/// The candidate causes of model_check, in the order of check_jacobian's idx[1..3].
enum CauseId { kCauseInertia, kCauseAngles, kCauseTorque, kCauseCount };

/// The freed step with the columns of every cause in `mask` (bit id: CauseId) freed together.
detail::FreedStep freed_set(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                            const std::vector<int> idx[4], const Eigen::VectorXd& info,
                            const Eigen::VectorXd& bias, unsigned mask) {
  std::vector<int> cols;
  std::vector<double> prior;
  for (int id = 0; id < kCauseCount; ++id) {
    if (!(mask & (1u << id))) continue;
    const std::vector<int>& c = idx[id + 1];
    cols.insert(cols.end(), c.begin(), c.end());
    for (size_t e = 0; e < c.size(); ++e) {
      prior.push_back(id == kCauseInertia ? info(static_cast<Eigen::Index>(e)) : 0.0);
    }
  }
  const Eigen::Map<const Eigen::VectorXd> p(prior.data(), static_cast<Eigen::Index>(prior.size()));
  return detail::freed_step(J, r, idx[0], cols, p, bias);
}

/// model_check runs only with at least this many residuals per column of its Jacobian (25
/// samples of a 0.05 s log against 22 freed columns read offsets of 43 N m)
constexpr int kCheckRowsPerColumn = 10;

/// A cause is named only when its parameters remove at least this fraction of the residual's
/// excess over its noise floor, when there is one (a scene with per-joint friction fitted with
/// the shared law leaves the residual 4 to 5 times its floor; every cause clears its evidence bar
/// by thousands of std, and without this the torque sensors would be blamed)
constexpr double kExplainedExcess = 0.5;
/// ... when the excess is at least this fraction of the residual's length (the residual's rms
/// 1.12 times its floor or more): below, the floor's own error is a large part of the excess
/// (measured: a 1 % torque gain on a 4 s angles-only log, ratio 1.02, explained 0.43 of it)
constexpr double kExcessShows = 0.25;
/// ... and, when the rates are biased at every window (Fit::rates_biased), a cause is named only
/// when it removes this fraction of the excess (a 5 N m torque offset, which also spoils the
/// window rule, explained 0.99 of it)
constexpr double kExplainsAll = 0.9;

/// model_check's freed steps: each candidate cause whose columns the check has (the inertias
/// only when they are not fitted) freed alone, all of them together, and the causes the log
/// evidences (detail::model_causes: each beyond what the others' parameters explain, and
/// explaining kExplainedExcess of the whitened residual's excess over its length).
struct CauseSteps {
  std::array<detail::FreedStep, kCauseCount> alone;  ///< not ok: no candidate
  detail::FreedStep all;
  std::vector<IdentifyResult::MisfitCause> report;  ///< IdentifyResult::model_check ("any" last)
  std::array<int, kCauseCount> slot{-1, -1, -1};    ///< each cause's entry in `report`
  bool named(int id) const { return slot[id] >= 0 && report[slot[id]].evidenced; }
  /// evidence alone [std of noise's]
  double z(int id) const { return slot[id] >= 0 ? report[slot[id]].z : 0.0; }
  bool any() const { return named(0) || named(1) || named(2); }
};

/// model_check's candidate causes by CauseId: the name in identification.json, and the words
struct CauseText {
  const char* name;
  const char* what;
};
constexpr CauseText kCauseText[kCauseCount] = {
    {"inertia", "the links' inertial parameters"},
    {"angle_offsets", "the encoders' zeros"},
    {"torque_readings", "the torque sensors' offsets and gains"}};

IdentifyResult::MisfitCause misfit_cause(const char* name, const detail::FreedStep& fs,
                                         double z, double z_given, double excess) {
  IdentifyResult::MisfitCause m;
  m.name = name;
  m.checked = fs.ok;
  m.drop = fs.drop - fs.drop_mean;
  m.z = z;
  m.z_given = z_given;
  m.explained = excess > 0 ? fs.drop / excess : NAN;
  return m;
}

CauseSteps cause_steps(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                       const std::vector<int> idx[4], const Eigen::VectorXd& info,
                       const Eigen::VectorXd& bias, bool attributable) {
  const double excess = r.squaredNorm() - static_cast<double>(r.size());
  unsigned present = 0;
  std::vector<int> ids;
  std::vector<detail::FreedStep> alone, all_but;
  for (int id = 0; id < kCauseCount; ++id) {
    if (idx[id + 1].empty()) continue;
    present |= 1u << id;
    ids.push_back(id);
    alone.push_back(freed_set(J, r, idx, info, bias, 1u << id));
  }
  CauseSteps cs;
  cs.all = freed_set(J, r, idx, info, bias, present);
  for (int id : ids) all_but.push_back(freed_set(J, r, idx, info, bias, present & ~(1u << id)));
  const detail::Causes c = detail::model_causes(alone, cs.all, all_but);
  for (size_t k = 0; k < ids.size(); ++k) {
    IdentifyResult::MisfitCause m =
        misfit_cause(kCauseText[ids[k]].name, alone[k], c.z[k], c.z_given[k], excess);
    m.evidenced = c.named[k] &&
                  !(excess > kExcessShows * r.size() && m.explained < kExplainedExcess) &&
                  (attributable || m.explained >= kExplainsAll);
    cs.alone[ids[k]] = alone[k];
    cs.slot[ids[k]] = static_cast<int>(cs.report.size());
    cs.report.push_back(m);
  }
  const double z_all = detail::evidence(cs.all, cs.all.drop);
  cs.report.push_back(misfit_cause("any", cs.all, z_all, z_all, excess));
  return cs;
}

/// "falls by D (noise alone: m +- s)" of a freed step
std::string drop_clause(const detail::FreedStep& fs) {
  return "the residual falls by " + format_significant(fs.drop - fs.drop_mean, 3) +
         " (noise alone: " + format_significant(fs.drop_mean, 2) + " +- " +
         format_significant(fs.drop_sd, 2) + ")";
}

/// "a, b (+- sa, sb)" of extras k and k + 1 of a freed step, each times `scale`
std::string pair_clause(const detail::FreedStep& fs, int k, double scale) {
  return format_significant(scale * fs.extra_step(k)) + ", " +
         format_significant(scale * fs.extra_step(k + 1)) + " (+- " +
         format_significant(scale * fs.extra_std(k), 2) + ", " +
         format_significant(scale * fs.extra_std(k + 1), 2) + ")";
}

/// A gain is advised only from this size on (gains of 0.1 to 0.2 % are merely significant on
/// logs with rates, and not worth advising)
constexpr double kSmallestGain = 0.005;

/// model_check's warning on the torque readings (so that a torque sensor's offset is not blamed
/// on the masses, and a 3 % gain error, read at +13 to +18 std, is not silent):
/// the offsets o_c and gains g_c of tau_c = (1 + g_c) M_c + o_c that the refit reads beyond
/// kFreedMove of their std (gains also from kSmallestGain on), with what to do about each.
std::string torque_warning(const TorqueColumns& tc, const detail::FreedStep& fs,
                           const std::string& moved) {
  const auto beyond = [&](int k) {
    return k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k);
  };
  std::vector<std::string> advice;
  for (int c = 0; c < kDof; ++c) {
    const std::string tau = "tau" + std::to_string(c + 1);
    if (beyond(tc.offset[c])) {
      const double o = fs.extra_step(tc.offset[c]);
      advice.push_back("a torque sensor's zero may be off: " + tau + " reads " +
                       format_significant(o, 3) + " +- " +
                       format_significant(fs.extra_std(tc.offset[c]), 2) +
                       " N m more than the model (subtract it, or fit the offsets with "
                       "--estimate friction,actuator)");
    }
    if (beyond(tc.gain[c]) && std::abs(fs.extra_step(tc.gain[c])) >= kSmallestGain) {
      const double g = fs.extra_step(tc.gain[c]);
      advice.push_back("a torque sensor's gain may be off: " + tau + " reads " +
                       format_significant(100 * g, 3) + " +- " +
                       format_significant(100 * fs.extra_std(tc.gain[c]), 2) +
                       " % more than the model (divide " + tau + " by " +
                       format_significant(1 + g, 5) + ", or check its torque constant)");
    }
  }
  if (advice.empty()) advice.push_back("the torque readings may be off");
  std::string w = "with offsets and gains of the logged torques free (one linearized refit) " +
                  drop_clause(fs) + " and " + moved;
  for (const std::string& a : advice) w += "; " + a;
  return w;
}

/// The torque readings' gains and offsets of torque_warning in short: "tau1 reads 0.5 times the
/// model"
/// (gains beyond kFreedMove of their std, from kSmallestGain on), offsets "tau1 +0.15 N m".
std::string torque_reading(const TorqueColumns& tc, const detail::FreedStep& fs) {
  std::string out;
  const auto beyond = [&](int k) {
    return k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k);
  };
  for (int c = 0; c < kDof; ++c) {
    const std::string tau = "tau" + std::to_string(c + 1);
    if (beyond(tc.gain[c]) && std::abs(fs.extra_step(tc.gain[c])) >= kSmallestGain) {
      out += (out.empty() ? "" : ", ") + tau + " reads " +
             format_significant(1 + fs.extra_step(tc.gain[c]), 3) + " times the model";
    } else if (beyond(tc.offset[c])) {
      out += (out.empty() ? "" : ", ") + tau + " reads " +
             format_significant(fs.extra_step(tc.offset[c]), 2) + " N m more than the model";
    }
  }
  return out.empty() ? "see the warnings" : out;
}

/// A torque reading's gain off by more than this fraction (read beyond kUnusableMove of its std)
/// makes the fit unusable: the friction estimates are off by about as much (torques logged at
/// half the model's: gains -0.5, coulomb 0.067 for 0.134, a move of 3 std only at the small
/// window's noise)
constexpr double kUnusableGain = 0.1;

/// The largest |gain| of the torque readings that the refit fs reads beyond kUnusableMove std.
double largest_gain(const TorqueColumns& tc, const detail::FreedStep& fs) {
  double g = 0;
  for (int c = 0; c < kDof; ++c) {
    const int k = tc.gain[c];
    if (k >= 0 && std::abs(fs.extra_step(k)) > kUnusableMove * fs.extra_std(k)) {
      g = std::max(g, std::abs(fs.extra_step(k)));
    }
  }
  return g;
}

/// A model error (what: its cause, or that none is named) that would move a friction
/// coefficient by `largest` std makes the fit unusable beyond kUnusableMove; largest 0: a
/// friction coefficient is at its bound, so the move cannot be given. The first reason stays.
void unusable_move(double largest, const std::string& what, IdentifyResult* out) {
  if (!out->unusable.empty() || !(largest > kUnusableMove || largest == 0)) return;
  if (largest == 0) {
    out->unusable = what + ": it holds a friction coefficient at its bound (see the warnings)";
    return;
  }
  out->unusable = what + ": it would move the friction by " + format_significant(largest, 2) +
                  " std (more than " + format_significant(kUnusableMove) + "; see the warnings)";
}

/// Whether a friction coefficient of the fit is at its bound
bool friction_at_bound(const Fit& f, const IdentifyResult& out) {
  for (int i = 0; i < f.layout.friction_size(); ++i) {
    if (out.parameters[i].at_bound) return true;
  }
  return false;
}

/// The candidate cause with the strongest evidence alone (kCauseCount: none)
int strongest_cause(const CauseSteps& cs) {
  int best = kCauseCount;
  for (int id = 0; id < kCauseCount; ++id) {
    if (cs.alone[id].ok && (best == kCauseCount || cs.z(id) > cs.z(best))) best = id;
  }
  return best;
}

/// model_check's warning when a candidate cause alone is evidenced and would move the friction,
/// but no cause stands out beyond the others' parameters or explains the misfit (with per-joint
/// friction fitted by the shared law, every cause reduces a misfit none explains; on a 2 s
/// angles-only log of the paper
/// scene, a torque offset of 0.1 N m on tau1 gave coulomb +24 std without a word: the offsets'
/// evidence, 14 std alone, was 4.7 std beyond the inertias' and the encoders' zeros')
std::string unresolved_warning(const CauseSteps& cs, int strongest, const std::string& moved,
                               bool rates_biased) {
  std::vector<IdentifyResult::MisfitCause> causes(cs.report.begin(), cs.report.end() - 1);
  std::sort(causes.begin(), causes.end(), [](const auto& a, const auto& b) { return a.z > b.z; });
  std::string each;
  for (const IdentifyResult::MisfitCause& c : causes) {
    each += (each.empty() ? "" : ", ") + c.name + " " + format_significant(c.z, 2);
  }
  return "the friction estimates absorbed a model error the log cannot attribute: with " +
         std::string(kCauseText[strongest].what) + " free (one linearized refit) " +
         drop_clause(cs.alone[strongest]) + " and " + moved +
         ", but no cause stands out from the others or explains the misfit (evidence of each "
         "alone, in std: " + each + "). Check the friction law (--per-joint, --law), the "
         "scene's masses (--estimate friction,inertia), the encoders' zeros and the torque "
         "sensors (--estimate friction,actuator), or log a longer motion" +
         (rates_biased ? std::string("; the estimated accelerations show smoothing bias at "
                                     "every window: log the rates, or sample faster")
                       : std::string());
}

/// Evidence of the torque readings beyond the other causes' parameters this many times kCauseZ
/// makes the fit unusable even with the residual at its floor (the light mechanism's multi-sine
/// log with tau1 x 0.9: 69 std, coulomb 0.048 for 0.12, and no warning; clean logs read -2 to 2)
constexpr double kDecisiveCauseZ = 4 * detail::kCauseZ;

/// Whether the refit fs reads both torque readings' gains (beyond kFreedMove std, from
/// kSmallestGain on) off alike: the same sign, both readings positive (1 + g_c > 0: a negative
/// one is a sign, torque_signs) and within a factor 2 of each other (or within kFreedMove of
/// their difference's std): a common scale of the logged torques (gains read 0.828 and -0.976 are
/// no common scale)
bool common_gain(const TorqueColumns& tc, const detail::FreedStep& fs) {
  std::array<double, kDof> g{}, sd{};
  for (int c = 0; c < kDof; ++c) {
    const int k = tc.gain[c];
    if (k < 0 || !(std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k)) ||
        std::abs(fs.extra_step(k)) < kSmallestGain || !(1 + fs.extra_step(k) > 0)) {
      return false;
    }
    g[c] = fs.extra_step(k);
    sd[c] = fs.extra_std(k);
  }
  const double small = std::min(std::abs(g[0]), std::abs(g[1]));
  const double large = std::max(std::abs(g[0]), std::abs(g[1]));
  return g[0] * g[1] > 0 && (2 * small >= large || std::abs(g[0] - g[1]) <=
                                                       kFreedMove * std::hypot(sd[0], sd[1]));
}

/// The torque channels (bit 0: tau1, bit 1: tau2) whose reading the refit fs reads negative,
/// 1 + g_c < 0 with g_c beyond kFreedMove of its std: logged with the sign opposite the model's
/// (a light mechanism's tau1 negated read -1.02 times the model, its residual 2.6 times its floor,
/// below the sign check's kMisfitRatio)
unsigned torque_signs(const TorqueColumns& tc, const detail::FreedStep& fs) {
  unsigned out = 0;
  for (int c = 0; c < kDof && fs.ok; ++c) {
    const int k = tc.gain[c];
    if (k >= 0 && std::abs(fs.extra_step(k)) > kFreedMove * fs.extra_std(k) &&
        1 + fs.extra_step(k) < 0) {
      out |= 1u << c;
    }
  }
  return out;
}

/// model_check on the encoders' zeros: the warning when the log evidences them and the friction
/// would move, unusable beyond kUnusableMove
void angles_check(const Fit& f, const CauseSteps& cs, IdentifyResult* out) {
  const detail::FreedStep& fo = cs.alone[kCauseAngles];
  double largest = 0;
  std::string moved;
  if (!cs.named(kCauseAngles) ||
      (moved = friction_clause(f, *out, fo, false, true, &largest)).empty()) {
    return;
  }
  out->warnings.push_back(
      "with offsets of the logged angles free (one linearized refit) " + drop_clause(fo) +
      " and " + moved + ". theta1, theta2 read " + pair_clause(fo, 0, 1.0) +
      " rad more than the scene's angles: an encoder's zero may be off; subtract the offsets "
      "from the logged angles");
  // evidenced zeros that hold a coefficient at its bound make the fit unusable, whatever the
  // other coefficients' move (theta1 0.02 rad off on the light mechanism: viscous at 0, coulomb
  // 4 std)
  unusable_move(friction_at_bound(f, *out) ? 0 : largest, "the logged angles' zeros are off",
                out);
}

/// The torque readings' step of model_check and the indices of its offsets and gains
struct ReadingStep {
  detail::FreedStep fs;
  TorqueColumns tc;  ///< offset and gain indices into fs's extras (-1: left out)
};

/// model_check on the torque readings, when the log evidences them: the warning when the
/// friction would move, a gain is off by kUnusableGain, the residual is far above its floor
/// (kMisfitRatio; evidenced, the readings explain at least half of that excess) or the evidence
/// is decisive (kDecisiveCauseZ). Each of these but a move within kUnusableMove makes the fit
/// unusable, naming the readings (a common scale of both when both gains are off alike).
void torque_check(const Fit& f, const CauseSteps& cs, const ReadingStep& rs,
                  IdentifyResult* out) {
  if (!cs.named(kCauseTorque)) return;
  const detail::FreedStep& ft = rs.fs;
  const TorqueColumns& tc = rs.tc;
  double largest = 0;
  const std::string moved = friction_clause(f, *out, ft, false, true, &largest);
  // a gain off by kUnusableGain scales the friction with it, whatever the move's std
  const bool scaled = largest_gain(tc, ft) > kUnusableGain;
  const double ratio = misfit_ratio(*out), z = cs.report[cs.slot[kCauseTorque]].z_given;
  const bool far = ratio > kMisfitRatio, decisive = z > kDecisiveCauseZ;
  if (moved.empty() && !scaled && !far && !decisive) return;
  out->warnings.push_back(torque_warning(tc, ft,
                                         !moved.empty() ? moved
                                         : scaled ? "the friction estimates scale with the gains"
                                                  : "the friction moves less than " +
                                                        format_significant(kFreedMove) + " std"));
  const std::string what =
      (common_gain(tc, ft) ? "both logged torques' gains are off, a common scale ("
                           : "the logged torques' zeros or gains are off (") +
      torque_reading(tc, ft) + ")";
  if (!out->unusable.empty()) return;
  if (scaled) {
    out->unusable = what + ": the friction estimates scale with them (see the warnings)";
  } else if (!moved.empty()) {
    unusable_move(friction_at_bound(f, *out) ? 0 : largest, what, out);
  }
  if (!out->unusable.empty() || !(far || decisive)) return;
  out->unusable =
      what + ": " +
      (far ? "they explain the residual, " + format_significant(ratio, 3) +
                 " times its noise floor (more than " + format_significant(kMisfitRatio) + ")"
           : "the log evidences them by " + format_significant(z, 2) +
                 " std beyond the other causes (more than " +
                 format_significant(kDecisiveCauseZ) + ")") +
      "; see the warnings";
}

/// No cause named, but the torque readings alone are evidenced decisively (kDecisiveCauseZ) and
/// read a common gain beyond kUnusableGain: both torques scaled alike read as the links' masses
/// and inertias scaled alike (the friction's normal forces scale with them), which the log
/// cannot tell apart when the external loads are small. Either way the friction estimates are
/// off by that scale: the fit is unusable (a light mechanism's multi-sine log with rates, both
/// torques x 0.75: coulomb -4.8 std, viscous +5.0 std, residual 1.2 times its floor, evidence
/// alone 1520 std for the readings, 871 for the inertias). True when it says so.
bool scale_ambiguity(const CauseSteps& cs, const ReadingStep& rs, IdentifyResult* out) {
  if (!out->unusable.empty() || cs.slot[kCauseTorque] < 0 || !rs.fs.ok ||
      !(cs.z(kCauseTorque) > kDecisiveCauseZ) || !common_gain(rs.tc, rs.fs) ||
      !(largest_gain(rs.tc, rs.fs) > kUnusableGain)) {
    return false;
  }
  out->unusable = "both logged torques' gains are off alike (" + torque_reading(rs.tc, rs.fs) +
                  "), or the links' masses and inertias are by that scale: the log cannot tell "
                  "them apart (evidence alone, in std: torque_readings " +
                  format_significant(cs.z(kCauseTorque), 2) + ", inertia " +
                  format_significant(cs.z(kCauseInertia), 2) +
                  "); either way the friction estimates scale with them. Check the torque "
                  "sensors' gains and the scene's masses";
  out->warnings.push_back(out->unusable);
  return true;
}

/// What model_check leaves for the refits after it (the sign and per-joint checks)
struct ModelVerdict {
  /// torque channels read negative (torque_signs; bit 0: tau1, bit 1: tau2): the sign check
  /// fits them negated whatever the residual
  unsigned negative_readings = 0;
  /// a named cause (the encoders' zeros, the torque readings' offsets or positive gains, a
  /// common scale) made the fit unusable: the sign and per-joint refits have nothing left to
  /// decide (they tripled the time of such rejected runs)
  bool cause_decided = false;
};

/// Wrong masses or inertias, an encoder's zero offset, or a torque sensor's offset or gain
/// (masses +-5 % give Coulomb +5 %, 10 std; theta1 + 0.005 rad gives Coulomb -8 %, 14 std, and
/// must not be blamed on the masses, nor must a torque offset):
/// linearized refits at the fit with the 16 inertial parameters free (under the prior of
/// --estimate inertia), the two angle offsets free, the torque readings' offsets and gains free,
/// and combinations (cause_steps). A cause the log evidences (detail::model_causes, misfit.h: its
/// parameters lower the whitened cost by more than kCauseZ std above what noise gives them, also
/// with the other causes free) that would move a friction coefficient beyond kFreedMove of its
/// std is a warning naming it. Without such evidence, the earlier rule: the inertias' move
/// beyond kFreedMove times the larger of the estimate's std and the move's own. The score is
/// taken net of what the noise of estimated accelerations puts in it (score_bias: without, clean
/// angles-only logs of 6 s and more warned). Costs one Jacobian with 16 more columns, four
/// evaluations of the residual and a few small solves, and two more such Jacobians when the
/// accelerations are estimated.
ModelVerdict model_check(const Fit& f, IdentifyResult* out) {
  ModelVerdict verdict;
  if (!out->converged) return verdict;
  Eigen::MatrixXd J;
  Eigen::VectorXd r, info, bias;
  std::vector<int> idx[4];  // fitted, inertial, angle offsets, torque offsets and gains
  TorqueColumns tc;
  if (!check_jacobian(f, *out, &J, &r, idx, &info, &tc) ||
      J.rows() < kCheckRowsPerColumn * J.cols() || !score_bias(f, *out, J, r, tc, &bias)) {
    return verdict;
  }
  const CauseSteps cs = cause_steps(J, r, idx, info, bias, !f.rates_biased);
  out->model_check = cs.report;
  const detail::FreedStep& fi = cs.alone[kCauseInertia];
  verdict.negative_readings = torque_signs(tc, cs.alone[kCauseTorque]);
  const ReadingStep rs{cs.alone[kCauseTorque], tc};
  // both torques' gains off alike also read as the encoders' zeros (a common scale of the
  // logged torques on the light mechanism read theta1, theta2 2.4, 1.3 rad off): the gains come
  // first, so that the verdict names them
  const bool open = out->unusable.empty();  // (a bound's rule may have decided before)
  if (cs.named(kCauseTorque) && common_gain(rs.tc, rs.fs)) {
    torque_check(f, cs, rs, out);
    angles_check(f, cs, out);
  } else {
    angles_check(f, cs, out);
    torque_check(f, cs, rs, out);
  }
  verdict.cause_decided = open && !out->unusable.empty();
  if (!cs.any() && scale_ambiguity(cs, rs, out)) verdict.cause_decided = true;
  verdict.cause_decided = verdict.cause_decided && verdict.negative_readings == 0;
  std::string moved;
  double largest = 0;  // [std] the cause's largest move of the friction (0: at its bound)
  const bool masses = cs.named(kCauseInertia);
  const int top = strongest_cause(cs);
  if (!cs.any() && top < kCauseCount && cs.z(top) > detail::kCauseZ &&
      !(moved = friction_clause(f, *out, cs.alone[top], false, true, &(largest = 0))).empty()) {
    out->warnings.push_back(unresolved_warning(cs, top, moved, f.rates_biased));
    const double ratio = misfit_ratio(*out);
    if (out->unusable.empty() && ratio > kMisfitRatio) {  // an error the misfit shows, no cause
      out->unusable = "a model error the log cannot attribute: it moves the friction while the "
                      "torque residual is " + format_significant(ratio, 3) +
                      " times its noise floor (more than " + format_significant(kMisfitRatio) +
                      "; see the warnings)";
    }
    unusable_move(largest, "a model error the log cannot attribute", out);
    return verdict;
  }
  const bool old_rule = !cs.any() && !idx[1].empty() && fi.ok;
  if ((masses || old_rule) && !(moved = friction_clause(f, *out, fi, old_rule, masses)).empty()) {
    out->warnings.push_back(
        "with the links' inertial parameters free (one linearized refit, prior std " +
        format_significant(f.opt->inertia_prior) + " of the scene's values) " +
        (masses ? drop_clause(fi) + " and " : std::string()) + moved +
        ". The scene's masses or inertias may not match the mechanism; try --estimate "
        "friction,inertia");
  }
  return verdict;
}

// ---- 95 % intervals ----

/// Whether public parameter i gets a profile-likelihood interval: a nonlinear coefficient of the
/// Stribeck law (static_coulomb, stribeck_velocity: a peak's height and width trade off, and
/// the cost is far from quadratic in them), or a friction or actuator term whose Wald interval
/// reaches below its lower bound (values the law cannot take, where the curvature at the fit
/// says little). Only with a std, off its bounds; not the inertial parameters.
bool wants_profile(const ParameterLayout& layout, int i, const ParameterEstimate& e) {
  if (e.at_bound || !std::isfinite(e.std) || layout.is_inertial(i)) return false;
  if (i < layout.friction_size()) {
    const LawCoefficient* c =
        law_coefficient(law_descriptor(layout.law), layout.group(i / layout.per_group()));
    if (c && c->profiled) return true;
  }
  return e.ci_low < layout.lower_bound(i);
}

/// The re-fits of a profile: every residual block of the fit's problem (no robust loss), on the
/// coordinates y other than y_i, y_i held at theta. x = M y: for static_coulomb (internally
/// coulomb + excess) y are the public parameters and each joint's coulomb is bounded above by
/// the static value (static >= kinetic); otherwise y are the internal parameters.
class ProfileFits {
 public:
  ProfileFits(const Fit& f, ceres::Problem* problem, int i) : f_(f) {
    const int P = f.layout.size();
    const Eigen::MatrixXd T = to_public(f.layout);
    const bool stat = f.layout.static_as_excess && i < f.layout.friction_size() &&
                      f.layout.group(i / f.layout.per_group()) == Coefficient::kStaticCoulomb;
    const Eigen::MatrixXd M = stat ? Eigen::MatrixXd(T.inverse()) : Eigen::MatrixXd::Identity(P, P);
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(f.x.data(), P);
    const Eigen::VectorXd y = stat ? Eigen::VectorXd(T * x) : x;
    theta_ = y(i);
    Eigen::MatrixXd B(P, P - 1);
    for (int k = 0, c = 0; k < P; ++k) {
      if (k != i) B.col(c) = M.col(k), z_hat_.push_back(y(k)), ++c;
    }
    std::vector<ceres::ResidualBlockId> blocks;
    problem->GetResidualBlocks(&blocks);
    z_ = z_hat_;
    for (ceres::ResidualBlockId id : blocks) {
      reduced_.AddResidualBlock(new detail::AffineCost(problem->GetCostFunctionForResidualBlock(id),
                                                       M.col(i), B, &theta_),
                                nullptr, z_.data());
    }
    for (int k = 0; k < P; ++k) {
      if (k != i) reduced_.SetParameterLowerBound(z_.data(), k < i ? k : k - 1, f.layout.lower_bound(k));
    }
    if (stat) coulomb_ = f.layout.group_of(Coefficient::kCoulomb) * f.layout.per_group() +
                         i % f.layout.per_group();
    double cost = 0;
    reduced_.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
    cost_hat_ = cost;
    start_[0] = start_[1] = z_hat_;
  }

  /// The least cost with y_i = theta, warm-started from the last re-fit on `side`, minus the
  /// fit's; NaN when the re-fit fails.
  double rise(double theta, int side) {
    std::vector<double>& start = start_[side > 0];
    theta_ = theta;
    std::copy(start.begin(), start.end(), z_.begin());
    if (coulomb_ >= 0) {  // static >= kinetic: the coulomb of the joint below the static value
      z_[coulomb_] = std::min(z_[coulomb_], theta);
      reduced_.SetParameterUpperBound(z_.data(), coulomb_, theta);
    }
    ceres::Solver::Options so = solver_options(*f_.opt);
    so.max_num_iterations = 50;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &reduced_, &summary);
    if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) return kNaN;
    start = z_;
    return summary.final_cost - cost_hat_;
  }

 private:
  const Fit& f_;
  int coulomb_ = -1;  ///< static profile: index (in z) of the same joint's coulomb
  double theta_ = 0, cost_hat_ = 0;
  std::vector<double> z_hat_, z_;
  std::vector<double> start_[2];
  ceres::Problem reduced_;
};

/// The profile-likelihood interval of public parameter i: the values whose re-fit raises the
/// cost by at most q^2 / 2 times its noise scale V_ii / Hinv_ii (V the reported covariance, Hinv
/// that of J^T J: for a quadratic cost this is exactly value +- q std, so the interval agrees
/// with the covariance model wherever the Wald interval is right). Warnings for an open side.
void profile_parameter(const Fit& f, ceres::Problem* problem, const Analysis& an, int i,
                       IdentifyResult* out) {
  ParameterEstimate& e = out->parameters[i];
  const Eigen::VectorXd t = to_public(f.layout).row(i).transpose();
  const Eigen::MatrixXd Hinv = an.Hinv.unaryExpr([](double v) { return std::isfinite(v) ? v : 0.0; });
  const double h = t.dot(Hinv * t), q = out->ci_quantile;
  if (!(h > 0)) return;
  const double threshold = 0.5 * q * q * e.std * e.std / h;
  ProfileFits fits(f, problem, i);
  const auto rise = [&](double theta, int side) { return fits.rise(theta, side); };
  const detail::ProfileInterval pi =
      detail::profile_interval(rise, e.value, q * e.std, threshold, f.layout.lower_bound(i),
                               std::numeric_limits<double>::infinity(), 0.02 * e.std);
  out->profile_refits += pi.refits;
  if (pi.low.failed || pi.high.failed) {
    out->warnings.push_back("the profile-likelihood interval of " + e.name +
                            " failed (a re-fit did not converge): the Wald interval is reported");
    return;
  }
  e.ci_low = pi.low.value;
  e.ci_high = pi.high.value;
  e.ci_method = "profile-likelihood";
  for (const detail::ProfileEnd* end : {&pi.low, &pi.high}) {
    if (!end->unbounded) continue;
    out->warnings.push_back(
        "the log does not bound " + e.name + (end == &pi.low ? " from below" : " from above") +
        ": its profile-likelihood 95 % interval is open on that side (the cost stays within the "
        "95 % threshold up to 32 times the Wald half-width)");
  }
}

/// 95 % intervals of the public parameters: Wald, value +- ci_quantile std; profile likelihood
/// where wants_profile (inverse dynamics without a robust loss, converged).
void intervals(const Fit& f, ceres::Problem* problem, const Analysis& an, IdentifyResult* out) {
  for (ParameterEstimate& e : out->parameters) {
    if (!std::isfinite(e.std)) continue;
    e.ci_low = e.value - out->ci_quantile * e.std;
    e.ci_high = e.value + out->ci_quantile * e.std;
    e.ci_method = "wald";
  }
  if (f.opt->method != Method::kInverseDynamics || f.opt->loss != Loss::kNone || !out->converged) {
    return;
  }
  for (int i = 0; i < static_cast<int>(out->parameters.size()); ++i) {
    if (wants_profile(f.layout, i, out->parameters[i])) profile_parameter(f, problem, an, i, out);
  }
}

}  // namespace

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

namespace {
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
}  // namespace

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

/// The sign check fits the negated torques only when the residual is more than kMisfitRatio
/// times its floor (or model_check reads a channel negative), and calls the sign wrong when that
/// fit's residual (in floors, the worse channel) is this many times smaller (paper_angles.csv
/// negated: 6.1 floors, negated back 0.99), or its excess over the floor (ratio^2 - 1) this many
/// squared times smaller (a light mechanism's multi-sine log with rates, both negated: 3.95
/// floors, negated back 1.00)
constexpr double kSignGain = 4.0;

/// Whether a refit whose residual is `theirs` floors (the worse channel) fits far better than
/// the fit at `ours` (kSignGain, on the ratio or on its excess over the floor)
bool fits_far_better(double theirs, double ours) {
  return theirs * kSignGain < ours ||
         (theirs * theirs - 1) * kSignGain * kSignGain < ours * ours - 1;
}

/// identify; `full` false: only the fit and its residual over the noise floor (the sign check's
/// refits need no checks, intervals, predictions, sign check or delay)
IdentifyResult identify_fit(const Params<double>& scene_in, const sim::LoadFunction& loads,
                            const TorqueLog& log, const IdentifyOptions& opt, bool full);

/// The options of a check's refit (IdentifyOptions::check_torque_sign, check_per_joint): the
/// fit's Savitzky-Golay window (no search of its own), no delay estimate
void keep_window(const TorqueLog& log, const IdentifyResult& fit, IdentifyOptions* again) {
  again->estimate_delay = false;
  if (fit.sg_half_window > 0 && log.size() > 1) {
    again->auto_window = false;
    again->sg.half_window_s = fit.sg_half_window * log.duration() / (log.size() - 1);
  }
}

/// The log with the torques of `channels` negated (bit 0: tau1, bit 1: tau2)
TorqueLog negated_torques(const TorqueLog& log, unsigned channels) {
  TorqueLog negated = log;
  if (channels & 1u) {
    for (double& v : negated.tau1) v = -v;
  }
  if (channels & 2u) {
    for (double& v : negated.tau2) v = -v;
  }
  return negated;
}

/// The sign check's advice: `logged_opposite` (bit 0: tau1, bit 1: tau2) are the logged torques
/// whose sign is opposite the scene's convention, the caller's own flip already combined
std::string torque_sign_advice(unsigned logged_opposite) {
  switch (logged_opposite) {
    case 0u:
      return "the torques as logged follow the scene's convention (M1, M2 counter-clockwise on "
             "the cranks); remove --flip-torque-sign";
    case 3u:
      return "the logged torques' sign is opposite the scene's convention (M1, M2 "
             "counter-clockwise on the cranks); rerun with --flip-torque-sign both";
    default: {
      const std::string k = std::to_string(logged_opposite);
      return "the logged tau" + k + "'s sign is opposite the scene's convention (M" + k +
             " counter-clockwise on its crank); rerun with --flip-torque-sign " + k;
    }
  }
}

/// IdentifyOptions::check_torque_sign: true (and out->unusable says why) when the log's torques
/// fit far better (fits_far_better) with both negated, or else with one of them negated (a
/// channel wired the other way read as "coulomb at its bound"); the fit with both negated puts
/// its residual in out. Runs when the residual is above kMisfitRatio floors, or when model_check
/// read channels negative (`suspect`, tried first); not when a cause it named decided
/// (ModelVerdict::cause_decided). The refits keep the fit's Savitzky-Golay window
/// (no search of their own) and estimate no delay.
bool torques_fit_negated(const Params<double>& scene, const sim::LoadFunction& loads,
                         const TorqueLog& log, const IdentifyOptions& opt,
                         const ModelVerdict& verdict, IdentifyResult* out) {
  const double ours = misfit_ratio(*out);
  const unsigned suspect = verdict.negative_readings;
  if (!opt.check_torque_sign || opt.method != Method::kInverseDynamics ||
      verdict.cause_decided || !(ours > kMisfitRatio || suspect != 0)) {
    return false;
  }
  std::vector<unsigned> order = {3u, 1u, 2u};
  if (suspect != 0) {  // the channels read negative first
    order.erase(std::find(order.begin(), order.end(), suspect));
    order.insert(order.begin(), suspect);
  }
  IdentifyOptions again = opt;
  again.check_torque_sign = false;
  keep_window(log, *out, &again);
  double best = ours;
  unsigned which = 0;
  for (unsigned channels : order) {
    IdentifyResult neg;
    try {
      neg = identify_fit(scene, loads, negated_torques(log, channels), again, false);
    } catch (const LogError&) {
      continue;  // the negated log cannot be fitted: no evidence either way
    }
    if (!neg.status.ok()) continue;
    for (int j = 0; j < kActuators && channels == 3u; ++j) {
      out->negated_rms_torque_residual[j] = neg.rms_torque_residual[j];
    }
    if (misfit_ratio(neg) < best) {
      best = misfit_ratio(neg);
      which = channels;
    }
    if (fits_far_better(best, ours)) break;  // the first that fits: the others need no try
  }
  if (!fits_far_better(best, ours)) return false;
  const std::string fit = format_significant(best, 2) + " times its noise floor against " +
                          format_significant(ours, 2);
  const std::string torques = opt.torques_negated == 0 ? "the logged " : "the flipped ";
  out->unusable = (which == 3u ? torques + "torques fit far better negated (residual "
                               : torques + "tau" + std::to_string(which) +
                                     " alone fits far better negated (residual ") +
                  fit + "): " + torque_sign_advice(opt.torques_negated ^ which);
  out->warnings.push_back(out->unusable + "; no torque delay was estimated");
  return true;
}

/// IdentifyOptions::check_per_joint: true (and out->unusable says why, replacing the reason
/// model_check gave) when a shared-law fit's misfit goes away with one coefficient per joint.
/// It runs when the residual is more than kMisfitRatio times its floor and no cause named by
/// model_check decided, and names the joints' differing friction when the fit with one
/// coefficient per joint fits far better (fits_far_better, as the sign check's refits;
/// offset_friction.yaml, whose five joints' coefficients differ by up to 2.5 times, multi-sine
/// log with rates: 18.3 floors shared, 1.00 per joint).
/// The refit keeps the fit's Savitzky-Golay window and estimates no delay.
bool friction_differs_by_joint(const Params<double>& scene, const sim::LoadFunction& loads,
                               const TorqueLog& log, const IdentifyOptions& opt,
                               const ModelVerdict& verdict, IdentifyResult* out) {
  const double ours = misfit_ratio(*out);
  if (!opt.check_per_joint || opt.layout.per_joint || opt.method != Method::kInverseDynamics ||
      verdict.cause_decided || !(ours > kMisfitRatio)) {
    return false;
  }
  IdentifyOptions again = opt;
  again.layout.per_joint = true;
  again.initial.clear();  // the shared start values do not fit the per-joint layout
  again.check_torque_sign = again.check_per_joint = false;
  keep_window(log, *out, &again);
  IdentifyResult pj;
  try {
    pj = identify_fit(scene, loads, log, again, false);
  } catch (const LogError&) {
    return false;  // too few samples for ten coefficients: no evidence either way
  }
  const double theirs = misfit_ratio(pj);
  if (!pj.status.ok() || !fits_far_better(theirs, ours)) return false;
  out->unusable = "the joints' friction differs: one coefficient per joint (--per-joint) leaves "
                  "the torque residual at " + format_significant(theirs, 2) +
                  " times its noise floor against " + format_significant(ours, 3) +
                  " with the shared law; rerun with --per-joint";
  out->warnings.push_back(out->unusable + "; no torque delay was estimated");
  return true;
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

Validation validate(const Params<double>& params, const sim::LoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1,
                    const std::vector<double>& omega2, double window_s, double rtol,
                    double budget_s) {
  const auto start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  Validation v;
  v.window_s = window_s;
  const int n = log.size();
  v.full_theta1.assign(n, kNaN);
  v.full_theta2.assign(n, kNaN);
  v.window_theta1.assign(n, kNaN);
  v.window_theta2.assign(n, kNaN);
  if (n < 2) return v;
  auto run = [&](int i0, int i1, bool full, double* s2, int* count) {
    sim::Options o = window_sim_options(rtol);
    // a fitted scene far from the log (absurd logs) can make the simulation crawl: bounded
    o.max_wall_time_s = std::max(1e-3, (full ? 0.5 : 1.0) * budget_s - elapsed());
    o.max_steps = 50000;  // per output interval (a sample step): normal runs take a few
    o.duration = log.t[i1] - log.t[i0];
    o.output_step = o.duration / (i1 - i0);
    const sim::Result res =
        sim::simulate(params, logged_loads(log, loads, log.t[i0], params.actuators.offset),
                      {log.theta1[i0], log.theta2[i0], omega1[i0], omega2[i0]}, o);
    std::vector<double> ts, a, b;
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      a.push_back(row.theta[0]);
      b.push_back(row.theta[1]);
    }
    if (full) {
      v.status = res.status;
      v.full_duration_s = ts.empty() ? 0.0 : ts.back();
    }
    if (ts.size() < 2) return;
    for (int i = i0; i <= i1; ++i) {
      const double tt = log.t[i] - log.t[i0];
      if (tt > ts.back() + 1e-9) break;
      const double e1 = interp(ts, a, tt) - log.theta1[i];
      const double e2 = interp(ts, b, tt) - log.theta2[i];
      s2[0] += e1 * e1;
      s2[1] += e2 * e2;
      ++*count;
      (full ? v.full_theta1 : v.window_theta1)[i] = interp(ts, a, tt);
      (full ? v.full_theta2 : v.window_theta2)[i] = interp(ts, b, tt);
      if (full) {
        if (std::isnan(v.divergence_time_s) &&
            std::max(std::abs(e1), std::abs(e2)) > Validation::kDivergedAngle) {
          v.divergence_time_s = tt;
        }
        v.full_max[0] = std::max(v.full_max[0], std::abs(e1));
        v.full_max[1] = std::max(v.full_max[1], std::abs(e2));
      }
    }
  };
  double s2[2] = {0, 0};
  int count = 0;
  run(0, n - 1, true, s2, &count);
  for (int j = 0; j < kActuators; ++j) v.full_rms[j] = std::sqrt(s2[j] / std::max(1, count));
  double w2[2] = {0, 0};
  int wc = 0;
  for (auto [i0, i1] : make_windows(log, 0, n - 1, window_s)) {
    if (elapsed() > budget_s) {
      ++v.windows_skipped;
      continue;
    }
    run(i0, i1, false, w2, &wc);
  }
  for (int j = 0; j < kActuators; ++j) v.window_rms[j] = std::sqrt(w2[j] / std::max(1, wc));
  return v;
}

}  // namespace fivebar::identification
