// The four-bar's refits after its model check (four_bar_fit.h): the sign and per-joint checks
// and the delay's correction, each a fit of this identify on a changed log or layout.
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "fivebar/model/format.h"
#include "four_bar_fit.h"
#include "mechanism_stages.h"

namespace fivebar::identification::four_bar {

namespace {

/// A refit by this identify: the delay's, with the checks `opt` asks for; with `plain`, the sign
/// and per-joint checks' (a refit of theirs runs no such refits of its own)
stages::Refit refit_by(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                       bool plain = false) {
  return [&scene, &loads, plain](const TorqueLog& log, const IdentifyOptions& opt,
                                 IdentifyResult* fit) {
    IdentifyOptions again = opt;
    if (plain) again.check_torque_sign = again.check_per_joint = false;
    *fit = identify(scene, loads, log, again);
    return true;
  };
}

}  // namespace

/// The sign check, then the per-joint check of a shared law (stages::torques_fit_negated,
/// friction_differs_by_joint: the five-bar's) when the residual is more than kMisfitRatio times
/// its floor and no cause the model check named made the fit unusable; true when one of them
/// says the fit is not to be used (out->unusable says why).
bool refit_checks(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                  const TorqueLog& log, const IdentifyOptions& opt, const stages::ModelVerdict& verdict,
                  IdentifyResult* out) {
  if (verdict.cause_decided ||
      !(out->rms_torque_residual[0] > stages::kMisfitRatio * out->residual_noise_floor[0])) {
    return false;
  }
  const stages::Refit refit = refit_by(scene, loads, /*plain=*/true);
  if (opt.check_torque_sign && stages::torques_fit_negated(log, opt, 1, 0u, refit, out)) {
    return true;
  }
  return opt.check_per_joint && !opt.layout.per_joint &&
         stages::friction_differs_by_joint(log, opt, refit, out);
}

/// The delay the model check named (cause_check), corrected: the fit redone with the torques
/// shifted by it (stages::refit_with_delay, the five-bar's), true and *refit when that fit is
/// usable; else a warning that the delay is not corrected (out->delay_unexplained). Not for a
/// delay within a tenth of a sample, nor without refits left (IdentifyOptions::delay_refits).
bool delay_refit(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                 const FourBarFit& f, IdentifyResult* out, IdentifyResult* refit) {
  const TorqueLog& L = f.cond.log;
  const double dt = L.duration() / std::max(1, L.size() - 1);
  if (!f.opt->estimate_delay || f.opt->delay_refits <= 0 || !(std::abs(out->delay_s) > 0.1 * dt)) {
    return false;
  }
  IdentifyResult shifted = stages::refit_with_delay(L, *f.opt, *out, refit_by(scene, loads));
  if (shifted.unusable.empty()) {
    *refit = std::move(shifted);
    return true;
  }
  out->warnings.push_back("the torques seem to " + std::string(out->delay_s < 0 ? "lead" : "lag") +
                          " the angles by " + format_significant(std::abs(out->delay_s) * 1e3) +
                          " ms, but the fit with them shifted is not to be used (" +
                          shifted.unusable + "); not corrected");
  out->delay_unexplained = true;
  return false;
}

}  // namespace fivebar::identification::four_bar
