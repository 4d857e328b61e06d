// Internal to identification: the state the four-bar's stages share (identify_four_bar.cc) and
// what its window stage (four_bar_window.cc) takes from them.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "fivebar/identification/condition.h"
#include "fivebar/identification/identify.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/sim/simulator.h"
#include "four_bar_rules.h"
#include "inertia.h"
#include "mechanism_residual.h"
#include "mechanism_stages.h"
#include "noise_model.h"

namespace fivebar::identification::four_bar {

using Sample = stages::MechanismSample<FourBar>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using four_bar_rules::kRestSigmas;
using four_bar_rules::kWindowOrder;

/// The state the four-bar's stages share, in the order they write it.
struct FourBarFit {
  const IdentifyOptions* opt = nullptr;
  FourBarParams scene;  ///< with the law to fit (fit_friction)
  sim::FourBarLoadFunction loads;
  ParameterLayout layout;
  EvalOptions eval;
  /// group inertia: the prior on the links' standard parameters (the scene's, relative std
  /// --inertia-prior) and its noise level (the residual's noise floor at the scene)
  detail::InertialPrior prior;
  double prior_scale = 1;
  ConditionedLog cond;        ///< conditioning
  /// the weight of every residual block's cost in the problems solved (torque_cost_weight of
  /// the conditioned log)
  double cost_weight = 1;
  detail::SensorNoise noise;  ///< channel 0: the crank's angle, rate and torque noise
  // rates, window and samples
  SgOptions sg;              ///< the Savitzky-Golay filter as used
  int hw = 0;                ///< Savitzky-Golay half-window [samples] (0: accelerations logged)
  int first = 0, last = -1;  ///< samples whose rates and accelerations are centred estimates
  std::vector<double> w, a;  ///< crank rate and acceleration at every log sample
  double rate_noise = 0, accel_noise = 0;  ///< their noise std
  /// slip reversals: reversals[i] = how many lie between samples k and k + 1 for k < i
  std::vector<int> reversals;
  std::vector<Sample> samples;
  std::vector<int> index;  ///< log index of each sample
  /// predicted smoothing bias of the public friction coefficients at the chosen window
  /// (limit_smoothing_bias; empty when not predicted)
  Eigen::VectorXd smoothing_bias;
  /// the covariance of the sensors' noise alone (errors in variables, before the block sandwich
  /// raises the reported std: at_least_block_sandwich); the model check judges a cause's move
  /// against it, not against std a model error has widened (empty: the reported one)
  Eigen::MatrixXd noise_covariance;
  // the fit
  double loss_scale = 1;  ///< the robust loss's scale as applied (--loss; unused without one)
  std::vector<double> x;  ///< internal parameter vector: the start, then the fit's
};

/// Rates and accelerations: the log's own when it has them (and the options do not ask to
/// estimate them), else Savitzky-Golay with f->sg (the edges, where the window is one-sided, are
/// left out of the fit); their noise from the angles' through the filter.
void rates(FourBarFit* f, IdentifyResult* out);

/// The samples of the fit: glitches, joints at rest (held) and, with estimated accelerations,
/// samples whose filter window spans a slip reversal are left out.
void select_samples(FourBarFit* f, IdentifyResult* out);

/// The rest rule: some joint's relative rate (its row of J_w times the crank rate w) within
/// kRestSigmas of the rate's noise through that row, or below --min-rate.
bool held(const FourBarFit& f, const std::array<double, 4>& row, double w, double rate_noise);

/// d M1 / d (theta1, omega1, alpha1) at sample s, by central differences on the drive torque,
/// in the two-channel form of the noise model (noise_model.h: row 0, the first crank's columns)
/// at the internal parameters x, *M1 the drive torque; false where an evaluation fails
/// (four_bar_window.cc).
bool kinematic_jacobian(const FourBarFit& f, const double* x, const Sample& s,
                        Eigen::Matrix<double, 2, 6>* D, double* M1);

/// The residual's noise floor at the samples and filter of f: the torque noise and the
/// acceleration noise through the crank's effective inertia, at least kAbsoluteFloor of the
/// torques' rms; *from_noise whether the noise sets it (identify_four_bar.cc).
double noise_floor(const FourBarFit& f, bool* from_noise);

/// The window chosen by its predicted bias (choose_window_by_bias, mechanism_stages.h) after a
/// preliminary fit on at most ~1500 of the samples, then the rates and samples again at the
/// window chosen; f->x back at its start. With the inertia group: on the full layout, with the
/// prior (f->prior, and f->prior_scale the noise floor before the choice) (four_bar_window.cc).
void window_stage(FourBarFit* f, IdentifyResult* out);

/// The model check's candidate causes at the fit: the five-bar's that exist for one crank (the
/// links' inertial parameters unless the fit has them, the crank encoder's zero, tau1's offset
/// and gain (the gain alone when the fit has the offset, --estimate actuator), the delay)
/// freed on the four-bar's Jacobian (with the inertias fitted, refitted with each cause under the
/// fit's prior; a warning where the log cannot tell a sensor's error from them); a warning when a
/// cause would move the friction beyond kFreedMove std of the fit with the cause corrected,
/// out->unusable beyond kUnusableMove of them, out of the coefficient's interval or at a bound, and
/// on the five-bar's decisive evidence (stages::decisive_model_error; four_bar_model_check.cc). The
/// delay's estimate in out->delay_s and delay_std_s (its column freed alone with the friction)
/// where the check has the column. Its verdict: cause_decided, and the delay kExplainsMost when it
/// names the delay (identify then refits with the torques shifted by it).
stages::ModelVerdict cause_check(const FourBarFit& f, IdentifyResult* out);

/// The residual rule: a residual more than kMisfitRatio times its noise floor is structure the
/// fit misses, and a log whose slip reversals leave too few samples between them is sampled too
/// slowly; either makes the fit not to be used (out->unusable, naming the cause).
void model_check(const FourBarFit& f, IdentifyResult* out);

/// The inverse-dynamics solver settings: the fit's and its profiles' re-fits.
ceres::Solver::Options solver_options(const FourBarFit& f);

/// The solver's record in out (iterations, message, costs unweighted by cost_weight, converged,
/// a warning when it stopped before converging); false (out->status) when it failed.
bool record_solve(const ceres::Solver::Summary& summary, double cost_weight, IdentifyResult* out);

/// The root mean square of r (0 when empty).
double rms(const std::vector<double>& r);

// ---- four_bar_covariance.cc ----

/// The singular values of J with its columns scaled to unit norm (out->singular_values).
void scaled_singular_values(const Eigen::MatrixXd& J, IdentifyResult* out);

/// The covariance of the internal parameters at the fit (out->covariance, NaN where it cannot
/// be formed), the torque residual's levels, the singular values and, with group inertia, the
/// inertial report; *Hinv the inverse information (J^T J)^-1 (the profiles' scale).
void covariance(FourBarFit& f, ceres::Problem* problem, IdentifyResult* out, Eigen::MatrixXd* Hinv);

/// Estimates, correlation and Wald intervals of the public parameters at f.x, from
/// out->covariance (internal parameters); x0: the public start values.
void estimates(const FourBarFit& f, const std::vector<double>& x0, IdentifyResult* out);

/// The fitted scene, and its inverse dynamics at every sample of the log (predicted_tau1).
void predictions(const FourBarFit& f, IdentifyResult* out);

// ---- four_bar_output_error.cc ----

/// The output-error fit on f->x from its start values, after the rates (f->w gives each
/// window's starting rate): the windows of out->window_s over [f->first, f->last], the solve,
/// the angle residual's levels and the window sandwich (out->covariance); false (out->status)
/// when a window's simulation fails at the start values, or the solver fails.
bool output_error_fit(FourBarFit* f, IdentifyResult* out);

// ---- four_bar_refits.cc ----

/// The sign check, then the per-joint check of a shared law (stages::torques_fit_negated,
/// friction_differs_by_joint: the five-bar's) when the residual is more than kMisfitRatio times
/// its floor and no cause the model check named made the fit unusable; true when one of them
/// says the fit is not to be used (out->unusable says why).
bool refit_checks(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                  const TorqueLog& log, const IdentifyOptions& opt, const stages::ModelVerdict& verdict,
                  IdentifyResult* out);

/// The delay the model check named (cause_check), corrected: the fit redone with the torques
/// shifted by it (stages::refit_with_delay, the five-bar's), true and *refit when that fit is
/// usable; else a warning that the delay is not corrected (out->delay_unexplained). Not for a
/// delay within a tenth of a sample, nor without refits left (IdentifyOptions::delay_refits).
bool delay_refit(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                 const FourBarFit& f, IdentifyResult* out, IdentifyResult* refit);

}  // namespace fivebar::identification::four_bar
