// The identification method (IdentifyOptions::method) as a strategy: what the inverse-dynamics
// and output-error fits do differently, each difference one member, chosen once per fit
// (Fit::method). The stages ask the strategy instead of branching on the method.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <string>
#include <vector>

#include "fivebar/identification/identify.h"

namespace fivebar::identification::stages {

struct Fit;
struct Analysis;
struct ModelVerdict;

/// The parameters off their bounds that the covariance is computed over, and what the methods'
/// errors-in-variables covariances share (covariance).
struct FreeSet {
  std::vector<int> index;  ///< internal indices of the free parameters
  Eigen::MatrixXd J;       ///< the data Jacobian's columns of the free parameters
  Eigen::MatrixXd Hp;      ///< the prior's information on them (J^T J units)
  Eigen::MatrixXd Hinv;    ///< (J^T J + Hp)^-1 on them
  double s2 = 1;           ///< the prior's noise level, squared
};

class MethodStrategy {
 public:
  virtual ~MethodStrategy() = default;

  // ---- what the residual is ----
  /// The residual blocks of the fit on f->x (without the bounds); out->residuals counts them.
  /// False for a parameter count with no compiled cost.
  virtual bool add_residuals(Fit* f, IdentifyResult* out, ceres::Problem* problem) const = 0;
  /// The solver's convergence tolerances.
  virtual void set_tolerances(ceres::Solver::Options* so) const = 0;
  /// The weight of every residual block's cost (make_loss) on the conditioned log.
  virtual double cost_weight(const TorqueLog& log) const = 0;
  /// The first sample at which the model cannot be evaluated at x, as a status naming it (ok
  /// when none fails, or when the method evaluates no per-sample model).
  virtual Status first_failure(const Fit& f, const std::vector<double>& x,
                               const std::string& at) const = 0;
  /// The robust loss's scale when none is given (a note may say how it was chosen).
  virtual double default_loss_scale(const Fit& f, IdentifyResult* out) const = 0;

  // ---- the solve and its analysis ----
  /// Before the solve: the residual levels at the start values.
  virtual void initial_levels(ceres::Problem* problem, IdentifyResult* out) const = 0;
  /// After a solve that succeeded: the noise sensitivities at the fit (an->sens), and the
  /// inertial prior's weight refined with another solve when the fit sets it; false if that
  /// solve fails (out->status).
  virtual bool refine(Fit* f, ceres::Problem* problem, IdentifyResult* out,
                      ceres::Solver::Summary* summary, Analysis* an) const = 0;
  /// The residual levels at the fit (rms and noise floor), with their warnings.
  virtual void residual_levels(const Fit& f, const Analysis& an, IdentifyResult* out) const = 0;
  /// The errors-in-variables covariance of the free parameters (empty: none, a warning says
  /// why); sets out->std_method.
  virtual Eigen::MatrixXd errors_in_variables(const Fit& f, const FreeSet& fs,
                                              const Analysis& an, IdentifyResult* out) const = 0;
  /// The model checks after the analysis, and what they leave for the refits.
  virtual ModelVerdict check_model(const Fit& f, const Analysis& an, IdentifyResult* out) const = 0;
  /// After the predictions: the method's own residual levels of the fitted scene.
  virtual void prediction_levels(const Fit& f, IdentifyResult* out) const = 0;

  // ---- the stages that apply only where there is a torque residual per sample ----
  /// The inertia and actuator groups can be fitted.
  virtual bool fits_groups() const = 0;
  /// The Savitzky-Golay window is chosen from the torque residual (choose_window).
  virtual bool chooses_window() const = 0;
  /// Samples whose filter window spans a slip reversal are left out (reversal_half_window).
  virtual bool excludes_reversals() const = 0;
  /// The Stribeck velocity is solved from several starts (best_stribeck_start).
  virtual bool restarts_stribeck() const = 0;
  /// Profile-likelihood intervals, where a Wald interval does not fit (intervals).
  virtual bool profiles_intervals() const = 0;
  /// The torque-sign and per-joint refits and the torque delay.
  virtual bool checks_readings() const = 0;
};

/// The strategy of `method` (a static instance).
const MethodStrategy& method_strategy(Method method);

}  // namespace fivebar::identification::stages
