// The stages of identify() (identify.cc), one file each (docs/architecture.md): the state they
// share (Fit, Analysis, ModelVerdict) and the functions one stage takes from another.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>

#include "covariance.h"
#include "fivebar/identification/identify.h"
#include "fivebar/identification/residual.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/names.h"
#include "fivebar/model/rest.h"
#include "inertia.h"
#include "mechanism_stages.h"
#include "method.h"
#include "misfit.h"
#include "model_check_causes.h"
#include "noise_model.h"
#include "profile.h"
#include "setup_shared.h"
#include "smoothing_bias.h"
#include "window_misfit.h"

namespace fivebar::identification {

/// identify; `full` false: only the fit and its residual over the noise floor
IdentifyResult identify_fit(const Params<double>& scene_in, const sim::LoadFunction& loads,
                            const TorqueLog& log, const IdentifyOptions& opt, bool full);

namespace stages {

using Clock = std::chrono::steady_clock;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---- stages of identify() ----

/// The state the stages of identify() share, grouped by the stage that writes it; each stage
/// reads what the stages before it wrote.
struct Fit {
  // setup (init_fit, start_values): what the options and the scene decide
  const IdentifyOptions* opt = nullptr;
  const MethodStrategy* method = nullptr;  ///< the method's strategy (method_strategy)
  sim::LoadFunction loads;
  Params<double> scene;    ///< the law to fit and the Coulomb sign form
  ParameterLayout layout;  ///< internal (Stribeck: static_coulomb as excess over coulomb)
  EvalOptions eval;             ///< the model's evaluation (rest_rate set by select_samples)
  detail::InertialPrior prior;  ///< group inertia
  std::vector<double> x;        ///< internal parameter vector: the start, then the fit's

  // conditioning (prepare_log, rate_source)
  ConditionedLog cond;  ///< the log as fitted
  detail::SensorNoise noise;
  detail::RateSource source = detail::RateSource::kLogged;
  /// the weight of every residual block's cost in the problems solved (make_loss): the method's
  /// cost_weight of the conditioned log
  double cost_weight = 1;

  // rates, window and samples (rates_window_and_samples)
  SgOptions sg;              ///< as used
  int first = 0, last = -1;  ///< samples with a centred Savitzky-Golay window
  std::vector<Sample> samples;
  std::vector<int> index;  ///< log index of each sample in the fit
  /// slip reversals of the rates of the fit: reversals[i] = how many lie between samples k and
  /// k + 1 for k < i (reversal_counts)
  std::vector<int> reversals;
  /// the estimated accelerations' smoothing shows at every window (choose_window): model_check
  /// names no cause, the misfit being the rates' as much as the model's
  bool rates_biased = false;
  /// predicted smoothing bias of the public friction coefficients at the chosen window
  /// (limit_smoothing_bias; empty when not predicted), taken off the estimates
  Eigen::VectorXd smoothing_bias;
  /// the std of that prediction from the angle noise (limit_smoothing_bias; empty when not
  /// predicted), added to the std of the estimates it is taken off
  Eigen::VectorXd smoothing_bias_spread;
  /// the largest predicted |bias| / std of a friction coefficient at the chosen window where no
  /// window keeps it within kBiasFraction (limit_smoothing_bias; 0 otherwise)
  double window_bias_left = 0;

  /// why the fit is not to be used when the window check (widen_window) found the angle noise's
  /// bias at every window it tried ("" otherwise)
  std::string window_unusable;

  // the fit (choose_loss_scale, build_problem, solve_stage)
  double loss_scale = 0;  ///< the robust loss's scale as applied (choose_loss_scale)
  std::vector<int> window_sizes;  ///< output error: residuals of each window, in problem order
  /// the torque residual's noise level that weighs the prior against the data [N m]
  double prior_scale = 1;
};

/// What the stages after the solve share: the data residuals and their Jacobian at the fit, and
/// the sensor-noise sensitivities (inverse dynamics).
struct Analysis {
  std::vector<double> r;
  Eigen::MatrixXd J;
  std::vector<detail::Sensitivity> sens;
  /// (J^T J + Hp)^-1 over the parameters off their bounds (internal layout; NaN elsewhere)
  Eigen::MatrixXd Hinv;
};

/// Columns of the whitened residual's Jacobian on errors of the torque readings (TorqueColumns)
struct TorqueColumns {
  Eigen::MatrixXd J;
  /// column of channel c's offset and gain in J (-1: left out)
  std::array<int, 2> offset{-1, -1}, gain{-1, -1};
  /// the actuator term (actuator_term_name) of each of the motors' columns beside them
  /// (check_jacobian's idx[4]: the drives' friction, where the fit leaves it out)
  std::vector<int> motor_terms;
};

// ---- residual_blocks.cc ----

/// The inverse-dynamics residual blocks, one per sample: from the sample's structure
/// (residual.h: the Jets carry only the P active parameters through a five-number loop), or the
/// full model where the structure cannot be read off; each block's loss make_loss(loss,
/// loss_scale, weight).
bool add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem,
                                double weight = 1);

/// One sample's inverse-dynamics residual r and its Jacobian J = d r / d x (2 x P) at the
/// parameters x, with the cost add_inverse_dynamics_terms gives it; false where it fails.
bool sample_residual(const Params<double>& scene, const ParameterLayout& layout, const Sample& s,
                     const EvalOptions& eval, const double* x, Eigen::Vector2d* r,
                     Eigen::MatrixXd* J);

/// Group inertia: the prior and consistency residuals (inertia.h) on the parameter block x, at
/// the fit's cost weight.
void add_inertial_prior(Fit* f, double* x, ceres::Problem* problem);

/// Output error: the window [i0, i1] (add_window_block) on f->x, rates w1, w2 at its start;
/// returns its residual count.
int add_window_residual(Fit* f, const std::vector<double>& w1, const std::vector<double>& w2,
                        int i0, int i1, const sim::Options& so, ceres::Problem* problem);

// ---- stage_setup.cc ----

/// "line L (t = T s)" of log sample i, for messages.
std::string sample_name(const TorqueLog& log, int i);

/// Degrees told by the motion, then unwrapping and glitch rejection, then the poses.
void prepare_log(const TorqueLog& log, Fit* f, IdentifyResult* out);

/// Start values in the internal layout, from the public `initial` (or the neutral defaults).
bool start_values(Fit* fp, const std::vector<double>& initial, std::vector<double>* x0_public,
                  IdentifyResult* out);

/// The fit's shared state from the options: the internal layout, the scene with the law to fit,
/// the inertial prior.
void init_fit(const Params<double>& scene_in, const sim::LoadFunction& loads, const TorqueLog& log,
              const IdentifyOptions& opt, Fit* f, IdentifyResult* out);

/// The prior's weight before the fit: the logged torque noise (refined after a first solve).
double initial_prior_scale(const Fit& f);

/// Logged rates noisier than those the angles give, even through the noisiest Savitzky-Golay
/// window of the choice (order 5 over 3 samples each side): their noise enters the friction's
/// sign and viscous terms and the reactions (errors in variables), so the rates and
/// accelerations are estimated from the angles instead, with a note saying so.
bool angles_give_better_rates(const Fit& f, IdentifyResult* out);

/// Where the rates and accelerations come from: the log's own when it has them (and the
/// options do not ask to estimate them), unless the angles give better ones
/// (angles_give_better_rates, which notes it).
detail::RateSource rate_source(const Fit& f, const TorqueLog& log, IdentifyResult* out);

// ---- stage_samples.cc ----

/// Thresholds of the rest rule for this log (IdentifyOptions::rest_rate_threshold).
/// The Savitzky-Golay noise gains are those of the window in use, `sg` (the data-driven one once
/// chosen: at 3 samples each side the rate noise is 6 times that at the default 10, and stuck
/// joints escaped the rule). Logged rates: never below the model's thresholds for computed rates
/// (RestThresholds{}): noise-free rates from a simulation keep a stuck joint's relative rate only
/// to its integration tolerance (synth-log: ~1e-10 rad/s, where the rounding reads 5e-13).
RestThresholds rest_rule(const TorqueLog& log, const IdentifyResult& out,
                         const IdentifyOptions& opt, const SgOptions& sg);

/// Rates and accelerations: logged, else Savitzky-Golay with f->sg (the edges, where the window
/// is one-sided, are left out of the fit).
void estimate_rates(Fit* f, IdentifyResult* out);

/// Sample i of the conditioned log: time, angles, torques and loads (rates left at 0).
Sample logged_sample(const Fit& f, int i);

/// Whether the Savitzky-Golay window of half-width hw centred on sample i spans a slip reversal
/// (f.reversals): its accelerations then smear the jump, a bias that correlates with the Coulomb
/// sign (it reads as less Coulomb friction) and that no window is small enough to remove.
bool spans_reversal(const Fit& f, int i, int hw);

/// The first sample of the fit whose inverse dynamics fails at the parameters x, as a status
/// naming it and the reason (ok if none fails).
Status first_failing_sample(const Fit& f, const std::vector<double>& x, const std::string& at);

/// Rates (logged or Savitzky-Golay), the data-driven window when it applies, the samples of the
/// fit, and a check that the model evaluates at every one at the start values (false: status).
bool rates_window_and_samples(const TorqueLog& log, Fit* f, IdentifyResult* out);

// ---- stage_window.cc, stage_smoothing_bias.cc (mechanism_stages.h; window_candidates:
// noise_model.h) ----

/// The five-bar's fit as the window stages read it (mechanism_stages.h): its residual levels at a
/// window (stage_window.cc) and the inputs of the bias prediction (stage_smoothing_bias.cc), at
/// the parameters of the preliminary fit.
class FiveBarWindowFit : public WindowFit {
 public:
  FiveBarWindowFit(const Fit& f, const IdentifyResult& out) : f_(f), out_(out) {}
  const TorqueLog& log() const override { return f_.cond.log; }
  const std::vector<char>& rejected() const override { return f_.cond.rejected; }
  detail::RateSource source() const override { return f_.source; }
  const std::vector<int>& index() const override { return f_.index; }
  bool spans_reversal(int i, int hw) const override { return stages::spans_reversal(f_, i, hw); }
  /// over the probes, the rest rule (held_sample) at the thresholds of the window `sg`
  void levels(const std::vector<int>& probe, const SgOptions& sg, double rms[2],
              double floor[2]) const override;
  /// (the Jacobians, which do not depend on the reach, evaluated once: fit_inputs)
  detail::BiasInputs bias_inputs(int reach, int min_half, int order) const override;
  /// each crank's angle noise and its filtered rate and acceleration, by a 3-point Gauss-Hermite
  /// rule along the principal axes of their covariance (the two cranks' noises independent)
  detail::NoiseBias noise_bias(const SgOptions& sg) const override;

 private:
  /// bias_inputs without the motion's terms, at the preliminary fit (on the first call)
  const detail::BiasInputs& fit_inputs() const;
  /// the residual and its Jacobian at sample u of the preliminary fit, unperturbed (noise_bias;
  /// evaluated once, false where the model fails)
  bool base_residual(int u, Eigen::Vector2d* r, Eigen::MatrixXd* J) const;
  const Fit& f_;
  const IdentifyResult& out_;
  mutable std::unique_ptr<detail::BiasInputs> fit_inputs_;
  mutable std::vector<Eigen::Vector2d> base_r_;  ///< base_residual's, by sample
  mutable std::vector<Eigen::MatrixXd> base_J_;
  mutable std::vector<signed char> base_ok_;  ///< -1: not evaluated, 0: failed, 1: evaluated
};

/// The motion's terms above the filter's order (high_order_terms, `extra` of them) of both
/// cranks' angles at log sample i over +-reach samples, cut short where they would span one of
/// f's slip reversals (the motion is not smooth across it), though never to fewer than min_half
/// samples each side. With `weights`: the terms as weights of the angles from log sample *lo
/// (high_order_weights). With `cache` (of f's log, order and extra): the windows' factorizations
/// shared between the samples.
void motion_terms(const Fit& f, int i, int reach, int min_half, int order, int extra,
                  std::array<Eigen::VectorXd, kDof>* terms,
                  std::array<Eigen::MatrixXd, kDof>* weights = nullptr, int* lo = nullptr,
                  detail::HighOrderCache* cache = nullptr);

// ---- stage_check_window.cc ----

/// The Savitzky-Golay window of model_check and the noise floors there (CheckWindow).
struct CheckWindow {
  SgOptions sg;
  double floor[2] = {0, 0};
  /// the whitened cost of the smoothing error predicted at the fit's window and at sg
  double fit_cost = 0, cost = 0;
  bool changed() const { return cost != fit_cost; }
};

/// The model check's window: the fit's, unless the smoothing error it puts in the estimated
/// accelerations shows in the residual (its predicted whitened cost above kCheckSmoothingCost):
/// then the largest smaller half-window of the same order where it does not (or, none, the one
/// where it is least), with the noise floors of that window. Angles-only logs only.
CheckWindow check_window(const Fit& f, const IdentifyResult& out);

/// The largest evidence alone [std] of a check's report's model causes (the delay's and the
/// motors' friction's left out).
double largest_evidence(const std::vector<IdentifyResult::MisfitCause>& causes);

/// The mean over the torque channels of (the fit's floor / cw's floor)^2: what a model error's
/// fall, and so its evidence, is multiplied by at cw's window.
double floor_ratio(const IdentifyResult& out, const CheckWindow& cw);

/// model_check's note when the first check's verdict stands: the check at cw evidences a model
/// error too (its report `again`), or would not see the first one's (`seen`: its evidence there,
/// largest_evidence times floor_ratio, not above kCauseZ).
std::string confirmed_note(const Fit& f, const CheckWindow& cw,
                           const std::vector<IdentifyResult::MisfitCause>& again, double seen);

/// model_check's warning when the check at the fit's window evidenced a model error (the causes'
/// report `first`) and the check at cw evidences none: the smoothing error of the fit's window
/// explains it.
std::string smoothing_warning(const Fit& f, const CheckWindow& cw,
                              const std::vector<IdentifyResult::MisfitCause>& first);

/// f with its samples' rates and accelerations estimated with the filter sg, those the rest rule
/// holds at sg's thresholds left out.
Fit refiltered(const Fit& f, const IdentifyResult& out, const SgOptions& sg);

/// A quick fit on at most ~1500 of the selected samples (plain least squares) that sets f->x for
/// the window choice; keeps the start values if it fails.
void preliminary_fit(Fit* f);

/// A per-joint fit is unusable (out->unusable, unless a reason is already there; the model
/// check's reason for an error no cause explains, ModelVerdict::unattributed, it replaces) when
/// no window keeps the predicted bias of the friction coefficients within kUnusableBias std
/// (Fit::window_bias_left): the motion is too fast for accelerations estimated from its angles
/// at the log's rate.
void unbiased_window_check(const Fit& f, const ModelVerdict& verdict, IdentifyResult* out);

// ---- stage_wider_window.cc ----

/// The chosen window checked against a wider one (wider_window).
struct WiderWindow {
  bool checked = false;  ///< false: no wider window fits in the log, or no prediction
  bool moves = false;    ///< the wider window is to be taken
  SgOptions sg;          ///< the wider window
  double z = 0;          ///< the predicted bias of coefficient `worst` at f.sg [its std]
  int worst = -1;        ///< the public coefficient that moves the window (-1: none)
  double largest = 0;    ///< the largest predicted bias at f.sg of a public coefficient [its std]
  /// the predicted bias of the public friction coefficients at the wider window, and its spread
  Eigen::VectorXd bias, spread;
  /// the same at the checked window (f.sg)
  Eigen::VectorXd bias_here, spread_here;
  std::string text;  ///< the check's figures, for window_choice
};

/// The chosen window f.sg checked at the preliminary fit f.x: the bias of the public friction
/// coefficients predicted (predicted_biases: the smoothing's and the angle noise's through the
/// reactions) from the rates of f.sg itself, not those of the window the walk read (the rule's
/// small window, whose noisy rates the second-order prediction expands about: on a light, slow
/// five-bar's 3 s logs at 1e-4-3e-4 rad it read 0.17 std at 33 samples where the fit was 3-5 std
/// off, and read again here 1.4-5.5 std), and the friction refitted (one Gauss-Newton step each
/// from f.x, on the samples both windows keep) at f.sg and at kWiderFactor times its
/// half-window. The wider window is to be taken (`moves`) when a coefficient's predicted bias
/// is beyond kWindowBias of the refit's std and the refit at the wider window moves it against
/// that bias by more than kWindowMoveZ std of the move's noise (the torque noise enters both
/// refits alike, the angle noise through both filters' taps).
WiderWindow wider_window(const Fit& f, const IdentifyResult& out);

/// After the window choice (angles only, an order the rule did not raise, a friction-only fit
/// of one Coulomb-viscous law, whose
/// coefficients one Gauss-Newton step refits): while wider_window, at a
/// preliminary fit at each window, moves the window, the wider window is taken (f->sg,
/// f->smoothing_bias and its spread) and the rates and samples estimated again
/// (`rates_and_samples`, false: stop); the bias taken off at the window kept is the one
/// predicted from its own rates. After kWiderSteps such moves, f->window_unusable says why the
/// fit is not to be used. The check's figures are appended to out->window_choice. False when
/// `rates_and_samples` fails.
bool widen_window(Fit* f, IdentifyResult* out, const std::function<bool()>& rates_and_samples);

/// The fit is not to be used (out->unusable, unless a reason is already there) when
/// widen_window found the angle noise's bias at every window it tried (Fit::window_unusable).
void wider_window_check(const Fit& f, IdentifyResult* out);

// ---- stage_solve.cc ----

void rms_pair(const std::vector<double>& r, double* out2);

/// Solves; a solver that gives up or an evaluation that fails is a status naming the sample.
void solve(Fit* f, ceres::Problem* problem, IdentifyResult* out, ceres::Solver::Summary* summary);

/// Residual levels and the structure warning: the rms against the level the sensor noise alone
/// gives (torque noise plus angle/rate noise through the rate estimation), floored for noise-free
/// logs at kAbsoluteFloor of the rms logged torque.
/// The residual's expected level from the sensor noise (noise[j]) and the floor for noise-free
/// logs (absolute[j], kAbsoluteFloor of the rms logged torque); floor[j] the larger.
void noise_floor(const Fit& f, const std::vector<detail::Sensitivity>& sens, double floor[2],
                 double noise[2] = nullptr, double absolute[2] = nullptr);

/// The robust loss's scale: as given, else (0) from the noise: inverse dynamics kLossScaleHuber or
/// kLossScaleCauchy times a sample's expected residual level at the start values (the two
/// actuators' noise floors in quadrature: the loss sees the block's norm), output error 0.1 rad.
/// Costs one pass of noise_sensitivities over the samples.
void choose_loss_scale(Fit* f, IdentifyResult* out);

/// Solves. Group inertia: the prior's weight is then set to the residual's noise level (the torque
/// noise plus the angle noise through the rates) and, if that differs, the fit is refined.
bool solve_stage(Fit* f, ceres::Problem* problem, IdentifyResult* out,
                 ceres::Solver::Summary* summary, Analysis* an);

/// The fit's problem: the method's residual blocks on f->x, the parameters' lower bounds; false
/// for a parameter count with no compiled cost.
bool build_problem(Fit* f, IdentifyResult* out, ceres::Problem* problem);
/// The solver's options: dense QR, the options' iteration limit and threads, the method's
/// tolerances.
ceres::Solver::Options solver_options(const Fit& f);
/// Sensor-noise sensitivities of every sample of the fit at the parameters f.x.
std::vector<detail::Sensitivity> noise_sensitivities(const Fit& f);

// ---- stage_analysis.cc ----

/// The prior's information in J^T J units (group inertia: s^2 / sigma_i^2 on the diagonal of the
/// inertial parameters, s the prior's noise level; zero elsewhere).
Eigen::MatrixXd prior_information(const Fit& f);

/// Public estimates, correlation, bounds: a parameter at a bound has no meaningful std (NaN),
/// and a std that is not > 0 is never reported as a number.
void estimates(const Fit& f, const std::vector<double>& x0_public, IdentifyResult* out);

/// Residual levels, covariance (converged solutions only), identifiability, estimates, and the
/// inertial report.
void analyse(const Fit& f, const std::vector<double>& x0_public,
             const ceres::Solver::Summary& summary, Analysis* an, IdentifyResult* out);

/// Inverse dynamics: the torque residual's rms and noise floor (noise_floor) per actuator, and
/// the structure warning.
void torque_residual_levels(const Fit& f, const std::vector<double>& r,
                            const std::vector<detail::Sensitivity>& sens, IdentifyResult* out);
/// Covariance of the internal parameters (out->covariance) and an->Hinv.
void covariance(const Fit& f, const Eigen::MatrixXd& Hp, Analysis* an, IdentifyResult* out);
/// Inverse dynamics: the errors-in-variables sandwich over the free parameters.
Eigen::MatrixXd score_sandwich(const Fit& f, const FreeSet& fs, const Analysis& an,
                               IdentifyResult* out);

// ---- stage_predictions.cc ----

/// Predicted torques at every sample of the (conditioned) log, at the fit.
void predictions(const Fit& f, IdentifyResult* out);

/// A friction coefficient at its bound while the residual is far above the noise floor (as from
/// two adjacent bad samples, an acceleration spike or a step in an angle, which can put Coulomb at
/// 0): the fit is driven by samples the law cannot explain. One
/// warning names the coefficients, the ratio, the lines of the largest residuals (in units of
/// the floor) and the likely causes.
void bound_and_misfit_warning(const Fit& f, const Analysis& an, IdentifyResult* out);

// ---- stage_delay.cc ----

/// The logged torques' rates (order-3 Savitzky-Golay, its window widened until their noise is
/// a small share of them): the delay's column, d r / d d, per log sample.
void delay_regressor(const Fit& f, std::vector<double>* g1, std::vector<double>* g2);

void estimate_delay(const Fit& f, const Eigen::MatrixXd& J, const std::vector<double>& r,
                    const std::vector<detail::Sensitivity>& sens, IdentifyResult* out);

/// The five-bar's refit_with_delay (mechanism_stages.h): the fit redone by this identify.
IdentifyResult refit_with_delay(const Params<double>& scene_in, const sim::LoadFunction& loads,
                                const TorqueLog& conditioned, const IdentifyOptions& opt,
                                const IdentifyResult& first);

// ---- stage_model_check_columns.cc ----

/// The residual's Jacobian at the fit, whitened by the noise floors, with the links' 16 inertial
/// parameters (columns idx[1], prior information in `info`), the two angle offsets (idx[2]),
/// the torque readings' offsets and gains (idx[3], `tc`) and, where the fit leaves them out,
/// the motors' friction coefficients (idx[4], motor_columns) added to the fitted ones (idx[0]);
/// false if an evaluation fails. `at_fit`: the data residuals and Jacobian of f's own problem at
/// f.x (solve_stage), taken as they are when f fits the inertial parameters itself.
bool check_jacobian(const Fit& f, const double fl[2], Eigen::MatrixXd* J, Eigen::VectorXd* r,
                    CauseColumns& idx, Eigen::VectorXd* info, TorqueColumns* tc,
                    const Analysis* at_fit = nullptr);

/// The expectation of the check's score J' r (J: check_jacobian's columns, b: one entry each)
/// that the noise of estimated accelerations gives when the model holds. That noise is in the
/// residual (-M(q) times the acceleration's) and, through the accelerations the inverse dynamics
/// is evaluated at, in the inertial and angle offsets' columns too (errors in variables), so
/// E[J' r] = sum over samples and cranks c of sigma_c^2 m_c dJ_c' dr_c (dJ_c, dr_c:
/// accel_derivatives; m_c: the sum of the squared acceleration taps, accel_tap_power). It grows
/// with the log's length while the score's noise grows with its square root (uncorrected, clean
/// 10 s logs drop the cost by 104 against 15 +- 5.3 from white noise). The offsets' share is
/// small on the paper scene (below 0.03 of their score's std on a clean 10 s log) but not at a
/// light mechanism's small window (a clean 3 s log at 4 samples: the offsets' fall 92 against 2
/// +- 2 without it, 6.1 with it). Left out as measured negligible on a clean 10 s log of the
/// paper scene: the rate noise's path (under 1 % of the acceleration's on every column). The
/// torque gains' columns carry the model's torque, so the same noise biases them too. Zero when
/// the accelerations are logged. Costs two Jacobians on the fitted and inertial parameters and
/// two sets of offset columns.
bool score_bias(const Fit& f, const double fl[2], const Eigen::MatrixXd& J,
                const Eigen::VectorXd& r, const TorqueColumns& tc, Eigen::VectorXd* b);

/// The samples (indices into f.samples) whose residual does not evaluate under one of the
/// check's changes (check_jacobian's inertial layout, offset_columns' angle steps,
/// accel_derivatives' acceleration steps): where the friction loop does not converge, as on
/// a pose a hair from a singular one.
std::vector<int> check_failures(const Fit& f);

/// The check's Jacobian, residual and score bias (check_jacobian, score_bias) on fit, or on
/// *spare: fit without the samples where the check's changes do not evaluate (check_failures;
/// a heavy mechanism driven a hair from its stretched singular pose: one sample's friction loop
/// did not converge with an encoder's zero moved by 1e-6 rad), noted. The fit the check runs on,
/// or nullptr with verdict->unchecked (and short_log) saying why it cannot run.
/// `an`: fit's data residuals and Jacobian at its parameters (check_jacobian's at_fit; nullptr
/// for a fit other than the solved one).
const Fit* check_inputs(const Fit& fit, const double fl[2], const Analysis* an, Fit* spare,
                        IdentifyResult* out, Eigen::MatrixXd* J, Eigen::VectorXd* r,
                        CauseColumns& idx, Eigen::VectorXd* info, TorqueColumns* tc,
                        Eigen::VectorXd* bias, ModelVerdict* verdict);

// ---- stage_model_check.cc ----

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
/// accelerations are estimated. A model error evidenced on an angles-only log whose window
/// smooths the motion's accelerations beyond kCheckSmoothingCost (check_window) is checked again
/// at the smaller window: evidenced there too, the first check stands (confirmed_note); else the
/// second's verdict, and smoothing_warning names the estimated accelerations. `an`: the fit's
/// data residuals and Jacobian (check_inputs).
ModelVerdict model_check(const Fit& f, const Analysis& an, IdentifyResult* out);

/// One model check on the fit f, its residual whitened by the noise floors fl (an: its own data
/// residuals and Jacobian, check_inputs; nullptr for a fit other than the solved one);
/// *evidenced: a model cause evidenced alone, what the smoothing error of the fit's window could
/// have made (stage_model_check.cc; model_check runs it once or twice).
ModelVerdict check_at(const Fit& fit, const double fl[2], const Analysis* an, IdentifyResult* out,
                      bool* evidenced);

// ---- stage_intervals.cc ----

/// 95 % intervals of the public parameters: Wald, value +- ci_quantile std; profile likelihood
/// where wants_profile (inverse dynamics without a robust loss, converged).
void intervals(const Fit& f, ceres::Problem* problem, const Analysis& an, IdentifyResult* out);

// ---- stage_refits.cc ----

/// IdentifyOptions::check_torque_sign: true (and out->unusable says why) when the log's torques
/// fit far better (fits_far_better) with both negated, or else with one of them negated (a
/// channel wired the other way read as "coulomb at its bound"); the fit with both negated puts
/// its residual in out. Runs when the residual is above kMisfitRatio floors, or when model_check
/// read channels negative (`suspect`, tried first); not when a cause it named decided
/// (ModelVerdict::cause_decided). The refits keep the fit's Savitzky-Golay window
/// (no search of their own) and estimate no delay.
bool torques_fit_negated(const Params<double>& scene, const sim::LoadFunction& loads,
                         const TorqueLog& log, const IdentifyOptions& opt,
                         const ModelVerdict& verdict, IdentifyResult* out);

/// The five-bar's per-joint check (mechanism_stages.h): when the residual is more than
/// kMisfitRatio times its floor and no cause named by model_check decided.
bool friction_differs_by_joint(const Params<double>& scene, const sim::LoadFunction& loads,
                               const TorqueLog& log, const IdentifyOptions& opt,
                               const ModelVerdict& verdict, IdentifyResult* out);

}  // namespace stages
}  // namespace fivebar::identification
