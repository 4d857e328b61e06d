// Rates and samples stage of identify(): rates and accelerations (logged or Savitzky-Golay),
// the rest rule, slip reversals, the samples of the fit.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

double larger_noise(const std::vector<double>& a, const std::vector<double>& b) {
  return std::max(series_noise(a), series_noise(b));
}

}  // namespace

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

namespace {

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

}  // namespace

bool spans_reversal(const Fit& f, int i, int hw) {
  return window_spans_reversal(f.reversals, i, hw);
}

namespace {

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
      !f->method->excludes_reversals() || raised) {
    return 0;
  }
  f->reversals = reversal_counts(*f, *out);
  out->slip_reversals = f->reversals.back();
  const int hw = out->sg_half_window;
  int near = 0, total = 0;
  for (int i = f->first; i <= f->last; ++i, ++total) near += spans_reversal(*f, i, hw) ? 1 : 0;
  if (leaves_out_reversals(near, total)) return hw;
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

}  // namespace

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

namespace {

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
  require_usable_samples(log, out->samples_used, P, f->opt->min_rate);
}

}  // namespace

Status first_failing_sample(const Fit& f, const std::vector<double>& x, const std::string& at) {
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

namespace {

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

}  // namespace

bool rates_window_and_samples(const TorqueLog& log, Fit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  const int P = f->layout.size();
  const auto rates_and_samples = [&]() {
    estimate_rates(f, out);
    require_samples(log, P + 1 + (out->accels_estimated ? 2 * out->sg_half_window : 0),
                    std::to_string(P) + " parameters + 1" +
                        (out->accels_estimated ? " + the Savitzky-Golay window" : std::string()));
    select_samples(f, out);
    // a sample the model cannot evaluate at the start values is a numerical failure, named
    out->status = f->method->first_failure(*f, f->x, "at the start values");
    return out->status.ok();
  };
  if (!rates_and_samples()) return false;
  if (out->accels_estimated && opt.auto_window && f->method->chooses_window()) {
    const std::vector<double> x_start = f->x;
    preliminary_fit(f);
    const FiveBarWindowFit w(*f, *out);
    choose_window(w, &f->sg, &f->rates_biased, &out->window_choice);
    // a log sampled too slowly for its motion (the rule raised the order): not the slow motion
    // the window check is for (a misfit of the masses there read as the angle noise's bias)
    const bool raised = f->sg.order != opt.sg.order;
    limit_smoothing_bias(w, opt.sg.order, f->rates_biased, &f->sg, &f->smoothing_bias,
                         &out->window_choice, &f->window_bias_left, &f->smoothing_bias_spread);
    f->x = x_start;
    if (!rates_and_samples()) return false;
    if (!raised && !widen_window(f, out, rates_and_samples)) return false;
  } else if (out->accels_estimated) {
    out->window_choice = fixed_window_choice(opt, out->sg_half_window);
  }
  reversal_note(*f, out);
  return true;
}

}  // namespace fivebar::identification::stages
