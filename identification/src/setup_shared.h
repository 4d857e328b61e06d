// What identify's setup (stage_setup.cc) shares with the four-bar's stages (identify_four_bar.cc)
// and the excitation design's prediction: the law to fit in a scene's friction, the neutral start
// values, the internal-to-public map of the parameters, the Savitzky-Golay noise gains, the
// residual's levels against its noise floor, the rest rule of a sample.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/identification/rates.h"
#include "fivebar/identification/residual.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/rest_rule.h"

namespace fivebar::identification::stages {

/// Ceres reports through glog on stderr ("Terminating: ..."); library code never prints: the
/// outcome is in the summary the fits return. Once per process, glog is told to keep quiet
/// (every identify entry point calls this before its first solve).
void quiet_solver_logging();

/// noise-free logs: residual levels below this fraction of the rms logged torque are what a good
/// torque sensor resolves (0.1 %), not structure
constexpr double kAbsoluteFloor = 1e-3;

/// a friction coefficient at its bound with the residual this many times its noise floor is a fit
/// driven by samples the law cannot explain (bound_and_misfit_warning)
constexpr double kMisfitRatio = 3.0;

/// The residual over its noise floor: the larger of the torque channels' rms residual over
/// their floors (the channels with a floor: one for the four-bar)
double misfit_ratio(const IdentifyResult& r);

/// The warning when channel j's rms residual is more than kStructureRatio times its noise floor
/// ("" below): structure the fitted law or the estimated rates cannot explain. `from_noise`: the
/// floor is the sensors' noise propagated (torque noise `torque_noise`), not the 0.1 % of the
/// rms logged torque of a nearly noise-free log.
std::string structure_warning(int j, double rms, double floor, double torque_noise,
                              bool from_noise);

/// The singular values of the public Jacobian with unit-norm columns (out->singular_values, from
/// its information JtJ) and the warnings they imply: a parameter with no effect; the smallest
/// direction with a condition above 100 when it involves a friction or actuator term, the others
/// when they involve an actuator term ("the log cannot separate offset_1, actuator_coulomb_1").
void identifiability(const Eigen::MatrixXd& JtJ, const ParameterLayout& layout,
                     IdentifyResult* out);

/// The last check, where no stage named a cause: a solver stopped before converging with no
/// friction coefficient determined, or every friction coefficient at its bound with the residual
/// above kAllAtBoundMisfitRatio floors, makes the fit unusable (out->unusable)
void unexplained_misfit(const ParameterLayout& layout, IdentifyResult* out);

/// Neutral start values, independent of the scene: each coefficient's CoefficientInfo::start
/// (coulomb 0.1, viscous 0.01, static 0.15, Stribeck velocity 0.2 rad/s).
inline std::vector<double> default_start(const ParameterLayout& layout) {
  std::vector<double> x(layout.friction_size());
  for (int i = 0; i < layout.friction_size(); ++i) {
    x[i] = coefficient_info(layout.group(i / layout.per_group())).start;
  }
  return x;
}

/// The scene's friction with the law to fit and the chosen Coulomb sign form; a fixed
/// coefficient the law needs > 0 (the Stribeck exponent) that the scene leaves unset takes its
/// default.
inline FrictionParams<double> fit_friction(const FrictionParams<double>& in,
                                           const ParameterLayout& layout,
                                           const IdentifyOptions& opt) {
  FrictionParams<double> fp = in;
  fp.law = layout.law;
  if (opt.smoothing_velocity >= 0) fp.smoothing_velocity = opt.smoothing_velocity;
  const LawDescriptor& d = law_descriptor(layout.law);
  for (int i = 0; i < d.count; ++i) {
    const LawCoefficient& c = d.coefficients[i];
    if (!c.positive || c.identifiable) continue;
    for (double& v : coefficient(fp, c.id)) {
      if (!(v > 0)) v = coefficient_info(c.id).default_value;
    }
  }
  return fp;
}

/// Linear map from the internal parameter vector to the public one (static_coulomb = coulomb +
/// excess for Stribeck; identity otherwise).
Eigen::MatrixXd to_public(const ParameterLayout& layout);

/// Noise gains of the Savitzky-Golay rate and acceleration at an interior sample (white noise
/// of deviation s on the angles gives s * gain): the root sum of squares of the taps of the
/// filter centred in the middle of the log.
void sg_noise_gains(const std::vector<double>& t, const SgOptions& sg, double* g1, double* g2);

/// The regressor of a torque-to-angle delay: the logged torques' rates (order-3 Savitzky-Golay
/// on the grid t) of each channel tau[c] of noise std torque_noise[c], into (*rates)[c]. The
/// rates carry the torques' noise, which attenuates a delay's estimate by the share of their
/// variance that is noise (errors in variables): the window grows from half_window_s (at least
/// 3 samples) until that share, over the samples `index`, is small on every channel.
void delay_regressor(const std::vector<double>& t,
                     const std::vector<const std::vector<double>*>& tau, const double* torque_noise,
                     const std::vector<int>& index, double half_window_s,
                     std::vector<std::vector<double>>* rates);

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
                 double angle_noise);

}  // namespace fivebar::identification::stages
