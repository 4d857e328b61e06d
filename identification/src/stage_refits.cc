// Sign and per-joint checks of identify(): refits of the negated torques and of one coefficient
// per joint.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

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

/// A fit a refit check rejected: the warning of out->unusable, and no delay (the model check
/// may have estimated one on the rejected fit; it is not reported).
void no_delay(IdentifyResult* out) {
  out->warnings.push_back(out->unusable + "; no torque delay was estimated");
  out->delay_s = out->delay_std_s = std::numeric_limits<double>::quiet_NaN();
  out->delay_corrected = false;
}

/// The sign check's advice: `logged_opposite` (bit 0: tau1, bit 1: tau2) are the logged torques
/// whose sign is opposite the scene's convention, the caller's own flip already combined; a
/// mechanism of one channel (`drives` 1) has tau1 alone
std::string torque_sign_advice(unsigned logged_opposite, int drives) {
  if (drives == 1 && logged_opposite == 0u) {
    return "the torque as logged follows the scene's convention (M1 counter-clockwise on the "
           "crank); remove --flip-torque-sign";
  }
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

}  // namespace

bool torques_fit_negated(const TorqueLog& log, const IdentifyOptions& opt, int drives,
                         unsigned suspect, const Refit& refit, IdentifyResult* out) {
  const double ours = misfit_ratio(*out);
  const unsigned all = drives == 1 ? 1u : 3u;
  std::vector<unsigned> order = {all};
  if (drives == 2) order = {3u, 1u, 2u};
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
      if (!refit(negated_torques(log, channels), again, &neg)) continue;
    } catch (const LogError&) {
      continue;  // the negated log cannot be fitted: no evidence either way
    }
    if (!neg.status.ok()) continue;
    for (int j = 0; j < drives && channels == all; ++j) {
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
  out->unusable = (which == 3u   ? torques + "torques fit far better negated (residual "
                   : drives == 1 ? torques + "torque fits far better negated (residual "
                                 : torques + "tau" + std::to_string(which) +
                                       " alone fits far better negated (residual ") +
                  fit + "): " + torque_sign_advice(opt.torques_negated ^ which, drives);
  no_delay(out);
  return true;
}

bool torques_fit_negated(const Params<double>& scene, const sim::LoadFunction& loads,
                         const TorqueLog& log, const IdentifyOptions& opt,
                         const ModelVerdict& verdict, IdentifyResult* out) {
  const double ours = misfit_ratio(*out);
  const unsigned suspect = verdict.negative_readings;
  if (!opt.check_torque_sign || !method_strategy(opt.method).checks_readings() ||
      verdict.cause_decided || !(ours > kMisfitRatio || suspect != 0)) {
    return false;
  }
  const Refit refit = [&](const TorqueLog& negated, const IdentifyOptions& again,
                          IdentifyResult* fit) {
    *fit = identify_fit(scene, loads, negated, again, false);
    return true;
  };
  return torques_fit_negated(log, opt, kActuators, suspect, refit, out);
}

bool friction_differs_by_joint(const TorqueLog& log, const IdentifyOptions& opt, const Refit& refit,
                               IdentifyResult* out) {
  const double ours = misfit_ratio(*out);
  IdentifyOptions again = opt;
  again.layout.per_joint = true;
  again.initial.clear();  // the shared start values do not fit the per-joint layout
  again.check_torque_sign = again.check_per_joint = false;
  keep_window(log, *out, &again);
  IdentifyResult pj;
  try {
    if (!refit(log, again, &pj)) return false;
  } catch (const LogError&) {
    return false;  // too few samples for a coefficient per joint: no evidence either way
  }
  const double theirs = misfit_ratio(pj);
  if (!pj.status.ok() || !fits_far_better(theirs, ours)) return false;
  out->unusable = "the joints' friction differs: one coefficient per joint (--per-joint) leaves "
                  "the torque residual at " + format_significant(theirs, 2) +
                  " times its noise floor against " + format_significant(ours, 3) +
                  " with the shared law; rerun with --per-joint";
  no_delay(out);
  return true;
}

bool friction_differs_by_joint(const Params<double>& scene, const sim::LoadFunction& loads,
                               const TorqueLog& log, const IdentifyOptions& opt,
                               const ModelVerdict& verdict, IdentifyResult* out) {
  if (!opt.check_per_joint || opt.layout.per_joint ||
      !method_strategy(opt.method).checks_readings() || verdict.cause_decided ||
      !(misfit_ratio(*out) > kMisfitRatio)) {
    return false;
  }
  const Refit refit = [&](const TorqueLog& same, const IdentifyOptions& again,
                          IdentifyResult* fit) {
    *fit = identify_fit(scene, loads, same, again, false);
    return true;
  };
  return friction_differs_by_joint(log, opt, refit, out);
}

}  // namespace fivebar::identification::stages
