// What identify's setup (stage_setup.cc) shares with the four-bar's stages (identify_four_bar.cc):
// the law to fit in a scene's friction, the neutral start values, the internal-to-public map of
// the parameters, the Savitzky-Golay noise gains, the residual's levels against its noise floor.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/identification/rates.h"
#include "fivebar/model/friction.h"

namespace fivebar::identification::stages {

/// noise-free logs: residual levels below this fraction of the rms logged torque are what a good
/// torque sensor resolves (0.1 %), not structure
constexpr double kAbsoluteFloor = 1e-3;

/// a friction coefficient at its bound with the residual this many times its noise floor is a fit
/// driven by samples the law cannot explain (bound_and_misfit_warning)
constexpr double kMisfitRatio = 3.0;

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
/// of deviation s on the angles gives s * gain): the root sum of squares of the filter
/// coefficients, read off its response to a unit impulse in the middle of the log.
void sg_noise_gains(const std::vector<double>& t, const SgOptions& sg, double* g1, double* g2);

}  // namespace fivebar::identification::stages
