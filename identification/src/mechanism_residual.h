// The inverse-dynamics residual over a mechanism M (model/mechanism.h): one sample's measured
// drive torques minus those of mech::inverse<M> (plus the torque sensors' offsets) with the
// parameters x laid out by a ParameterLayout. add_mechanism_terms<M> is declared here and
// instantiated per mechanism in a unit of its own (residual_blocks_four_bar.cc), with one Jet
// width: the cost is a ceres::DynamicAutoDiffCostFunction of stride kMechanismStride, so every
// parameter count runs through the same compiled evaluation. The five-bar's residual blocks
// (residual_blocks.cc) read each sample's structure instead (residual.h), which is faster for its
// five joints.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/mechanism.h"

namespace fivebar::identification::stages {

/// Jet width of the mechanism residual's passes (parameter counts above it take several passes)
inline constexpr int kMechanismStride = 8;

/// One sample of a mechanism of M::kDof driven joints: pose, rates, accelerations (measured or
/// estimated), the measured drive torques and the scene's other loads at that time.
template <class M>
struct MechanismSample {
  double t = 0;
  mech::Vec<M::kDof, double> q, v, a, tau;
  typename M::template Loads<double> loads;
};

/// The inverse-dynamics residual blocks of `samples` on the parameter block x (the friction
/// coefficients of `layout`, every other constant from `scene`): r = tau - drive torques, each
/// block under the robust `loss` at `loss_scale`, its cost times `weight` (make_loss).
template <class M>
void add_mechanism_terms(const typename M::template Params<double>& scene,
                         const ParameterLayout& layout,
                         const std::vector<MechanismSample<M>>& samples, const EvalOptions& eval,
                         double* x, ceres::Problem* problem, Loss loss = Loss::kNone,
                         double loss_scale = 1.0, double weight = 1.0);

/// The drive torques of mech::inverse<M> at the sample's motion as the sensors read them (plus
/// their offsets), the parameters x laid out by `layout` (the residual's own evaluation), and
/// with `dx` their derivatives in x (M::kDof rows, the residual's Jets); false where the model
/// fails.
template <class M>
bool mechanism_drive_torques(const typename M::template Params<double>& scene,
                             const ParameterLayout& layout, const double* x,
                             const MechanismSample<M>& s, const EvalOptions& eval,
                             mech::Vec<M::kDof, double>* torques, Eigen::MatrixXd* dx = nullptr);

}  // namespace fivebar::identification::stages
