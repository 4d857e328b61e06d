// Internal to identification: the inertial group (ParameterLayout::inertia). The prior that holds
// what the log cannot determine at the scene's values, the physical-consistency term, and the
// base (identifiable) combinations of the 16 standard inertial parameters.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/model/inertial.h"

namespace fivebar::identification::detail {

/// Gaussian prior on the standard inertial parameters: centre the scene's values, std
/// `relative` times a per-link scale (m: m; mx, my: m times the link length; J: J_O), so a
/// first moment that is 0 in the scene still has a prior of the size of the link.
struct InertialPrior {
  int links = kLinks;  ///< the links held (the four-bar's 3: entries 0 .. 4 links - 1 in use)
  std::array<double, kInertialParams> centre{}, sigma{};
  /// the consistency term keeps the inertia about each link's COM above this [kg m^2]
  std::array<double, kLinks> min_com_inertia{};
};
InertialPrior inertial_prior(const Params<double>& scene, double relative);
/// The prior of the n links `links` (the four-bar's three).
InertialPrior inertial_prior(const Link<double>* links, int n, double relative);

/// The prior's information in J^T J units over a parameter vector of size P whose inertial
/// parameters start at `offset`: s^2 / sigma_i^2 on their diagonal (s the prior's noise level,
/// as inertial_prior_cost weighs it), zero elsewhere.
Eigen::MatrixXd prior_information(const InertialPrior& prior, double s, int P, int offset);

/// Residuals (4 prior per link + 1 consistency per link: 16 + 4 for the five-bar) on the inertial
/// part of the parameter vector (size P, inertial parameters from `offset`): r_i = s (pi_i -
/// centre_i) / sigma_i, s = *noise_scale (the torque residual's noise level, so the prior weighs as
/// 1/sigma^2 against the data), and per link a stiff hinge that is 0 while the inertia about the
/// COM stays above its minimum. `noise_scale` is read at every evaluation: identify() refines it
/// after a first solve.
ceres::CostFunction* inertial_prior_cost(const InertialPrior& prior, int P, int offset,
                                         const double* noise_scale);

/// Posterior analysis of the inertial parameters: the regressor W = d r / d pi (data rows), the
/// prior std and the noise level s. Directions whose prior-scaled singular value
/// (sigma_k(W diag(sigma) / s)) is above kDeterminedRatio are determined by the log; the base
/// combinations are read off a column-pivoted QR of the scaled regressor at that rank. W has the
/// prior's 4 prior.links columns.
constexpr double kDeterminedRatio = 3.0;
void inertial_report(const Eigen::MatrixXd& W, const InertialPrior& prior, double s,
                     const std::vector<double>& pi, const Eigen::MatrixXd& covariance,
                     InertialReport* out);

/// Group inertia's findings into out->inertial (inertial_report at the fitted pi, covariance C
/// of pi, prior relative std `prior_relative`), and its warnings: the parameters left at their
/// prior, a fit not physically consistent. Nothing but `estimated` when C is not finite.
void inertial_stage(const Eigen::MatrixXd& W, const InertialPrior& prior, double s,
                    const std::vector<double>& pi, const Eigen::MatrixXd& C, double prior_relative,
                    IdentifyResult* out);

}  // namespace fivebar::identification::detail
