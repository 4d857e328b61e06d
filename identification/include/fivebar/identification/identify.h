// Friction identification from a torque log with Ceres: inverse-dynamics (equation-error) and
// output-error methods, covariance, identifiability, validation against the log.
//
// Coulomb sign. The inverse-dynamics residual uses the exact sign(w_k) by default (the scene's
// smoothing_velocity, normally 0; --smooth-sign overrides). With measured or estimated rates the
// sign of each joint at each sample is a datum, not a function of the coefficients, so the
// residual is smooth in them: they enter through Mf_k = r_k N_k f_k(w_k), with N_k itself
// depending on them through the reaction/friction loop, which ceres::Jet differentiates exactly.
// tanh(w / w_s) would instead bias the Coulomb coefficient low wherever |w| ~ w_s. Samples whose
// rate is within the noise of zero can carry the wrong sign: --min-rate drops them and a robust
// loss (Huber/Cauchy) bounds their weight.
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "fivebar/identification/condition.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/identification/rates.h"
#include "fivebar/identification/torque_log.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"
#include "fivebar/sim/simulator.h"

namespace fivebar::identification {

enum class Method : int {
  /// residual = measured - predicted actuator torques (inverse dynamics), Jacobian by ceres::Jet
  kInverseDynamics = 0,
  /// residual = measured - simulated crank angles over short windows restarted from the measured
  /// state and driven by the measured torques; Jacobian by central differences (the simulator is
  /// not templated on the scalar), so it is slower and its derivatives are approximate
  kOutputError,
};
bool parse_method(const std::string& name, Method* out);
const char* method_name(Method m);

enum class Loss : int { kNone = 0, kHuber, kCauchy };
bool parse_loss(const std::string& name, Loss* out);
const char* loss_name(Loss l);

/// Default robust-loss scales in units of the residual's noise level: the tuning constants of
/// 95 % efficiency under Gaussian noise (Huber 1.345, Cauchy 2.385).
inline constexpr double kLossScaleHuber = 1.345, kLossScaleCauchy = 2.385;

struct IdentifyOptions {
  /// the parameter groups (friction; with layout.inertia the 16 standard inertial parameters)
  ParameterLayout layout;
  /// group inertia: relative std of the Gaussian prior that holds the inertial parameters the
  /// log cannot determine at the scene's values (m: relative * m; m c_x, m c_y: relative * m *
  /// link length; J_O: relative * J_O). Must be > 0.
  double inertia_prior = 0.2;
  Method method = Method::kInverseDynamics;
  Loss loss = Loss::kNone;
  /// [N m] (inverse dynamics) or [rad] (output error): Huber/Cauchy a. 0: chosen from the noise,
  /// kLossScaleHuber or kLossScaleCauchy times the expected noise level of a sample's residual
  /// (the two actuators' noise floors in quadrature, at the start values; inverse dynamics),
  /// 0.1 rad (output error). A fixed scale below the noise floor biased a clean fit (Cauchy at
  /// 0.1 N m against a floor of 0.14 N m: Coulomb +1.7 %, 3.3 std)
  double loss_scale = 0;
  /// Coulomb sign: < 0 takes the scene's friction.smoothing_velocity; 0 exact sign(w) (a fixed
  /// datum per sample with measured rates); > 0 tanh(w / w_s) [rad/s]
  double smoothing_velocity = -1;
  SgOptions sg;  ///< rate/acceleration estimation when the log lacks them
  /// choose the Savitzky-Golay half-window from the data (sg.half_window_s is then ignored):
  /// after a preliminary fit, one candidate below the largest window whose torque residual shows
  /// no excess over the level the measured sensor noise explains (docs/identification.md)
  bool auto_window = true;
  ConditionOptions condition;  ///< unwrapping and glitch rejection
  bool check_degrees = true;   ///< tell radians from other units by the motion (condition.h)
  /// standard deviations by the sandwich (J^T J)^-1 J^T Sigma J (J^T J)^-1, Sigma from the
  /// torque noise plus the angle (or rate) noise propagated through the rate estimation
  /// (errors in variables); false: the residual variance times (J^T J)^-1
  bool errors_in_variables = true;
  bool estimate_rates = false;  ///< estimate rates even when the log has them
  /// drop samples where some joint's |w_k| is below this [rad/s] (their sign is uncertain)
  double min_rate = 0;
  /// Rest rule (fivebar/model/rest.h, docs/hold.md): a sample where some joint is stuck
  /// (|w_k| <= rate threshold and |dw_k/dt| <= acceleration threshold) holds a static friction
  /// torque anywhere in [-mu_s r_k N_k, mu_s r_k N_k], not the kinetic law: it is left out of the
  /// fit. A joint within the rate threshold that accelerates takes the sign of its acceleration.
  /// < 0: derived, kRestSigmas deviations of the noise of the rates and accelerations used
  /// (series_noise of the logged series, or of the angles through the Savitzky-Golay gains).
  double rest_rate_threshold = -1, rest_acceleration_threshold = -1;
  int max_iterations = 100;
  int num_threads = 1;
  /// start values of the friction coefficients, in layout order (or of every parameter);
  /// empty: neutral values (0.1 / 0.01 / ...). The inertial parameters start at the scene's.
  std::vector<double> initial;
  // output error
  /// length of each simulated window [s]; 0: 0.2 s, shortened so that the log has at least 20
  /// windows (the output-error std come from the spread between windows: with 10 of them their
  /// coverage was 0.89, with 20 0.93; output_error_window)
  double window_s = 0;
  double sim_rtol = 1e-8;  ///< integrator tolerances inside the windows (rtol = atol)
  /// central-difference step relative to |x|: large against the integrator noise (~rtol), the
  /// residual being nearly linear in the coefficients
  double relative_step = 1e-2;
  /// accelerations estimated by Savitzky-Golay (inverse dynamics): leave out the samples whose
  /// filter window spans a slip reversal of some joint (a sign change of its relative rate),
  /// where the accelerations jump and the filter smears the jump (a bias of the Coulomb
  /// coefficients that no window is small enough to remove; docs/identification.md)
  bool exclude_reversals = true;
  /// inverse dynamics: estimate the delay of the torques behind the angles (separate
  /// acquisition channels) by one Gauss-Newton step on tau(t + d) - M, with its std; when it is
  /// significant (over 3 std and over a tenth of a sample) the torques are shifted by it and the
  /// fit is redone, which estimates the remaining delay again (Gauss-Newton iterations on d)
  bool estimate_delay = true;
  /// refits at most for the delay: each one shifts the torques by the total delay found so far
  int delay_refits = 4;
  /// inverse dynamics: when the residual is far above its noise floor, fit the log once more
  /// with its torques negated; torques that fit far better so are a sign-convention error, which
  /// makes the fit unusable (IdentifyResult::unusable) and no delay is estimated
  bool check_torque_sign = true;
  /// inverse dynamics, shared law: when the residual is still far above its noise floor (the
  /// sign check found nothing), fit the log once more with one coefficient per joint; a misfit
  /// that goes away so names the joints' differing friction, makes the fit unusable and no
  /// delay is estimated
  bool check_per_joint = true;
  /// the torques the caller already negated before the fit (--flip-torque-sign; bit 0: tau1,
  /// bit 1: tau2): the sign check's advice names the flip relative to the torques as logged
  unsigned torques_negated = 0;
};

struct ParameterEstimate {
  std::string name;
  double value = 0;
  double std = 0;  ///< NaN when not determined (never a silent 0)
  double initial = 0;
  /// at a bound (lower bound, or static_coulomb = coulomb): the std, from the unconstrained
  /// curvature, is not meaningful
  bool at_bound = false;
  /// 95 % interval [ci_low, ci_high]: NaN when no std; -inf / +inf on a side where the profile
  /// found no end (the cost never rose enough: the log does not bound the parameter there)
  double ci_low = std::numeric_limits<double>::quiet_NaN(), ci_high = ci_low;
  /// "wald" (value +- IdentifyResult::ci_quantile std) or "profile-likelihood" (the re-fits with
  /// the parameter fixed whose cost rises by at most the quantile's square over 2 times the
  /// parameter's noise scale, docs/identification.md "Intervals"); empty when no interval
  std::string ci_method;
};

/// Group inertia: what the log determines of the 16 standard inertial parameters.
struct InertialReport {
  bool estimated = false;
  double prior_relative = 0;
  /// singular values of the regressor d r / d pi scaled by the prior std and the noise level
  /// (largest first): above 3, the log determines that direction to better than a third of its
  /// prior std; below 1, the prior holds it
  std::vector<double> information;
  int rank = 0;  ///< directions the log determines (information > 3)
  /// the base (identifiable) combinations, e.g. "J_1 + 0.0064 m_3", with value and std
  struct Combination {
    std::string text;
    double value = 0, std = 0;
  };
  std::vector<Combination> base;
  std::vector<std::string> at_prior;  ///< parameters left at their prior (posterior std > prior/2)
  bool consistent = true;             ///< every link m > 0 and inertia about the COM > 0
};

/// A model error the log cannot attribute makes the fit unusable when it would move a friction
/// coefficient by more than this many std (model_check; below, it is a warning)
inline constexpr double kUnusableMove = 10.0;

/// Identification outcome. `status` not ok: the numerics failed (values may be partial).
struct IdentifyResult {
  Status status;
  /// The fit's own verdict on a converged fit (docs/identification.md, "Status"): empty when it
  /// may be used; otherwise why not: a friction coefficient at its bound with the residual far
  /// above its floor, a model error the log cannot attribute that moves the friction by more
  /// than kUnusableMove std, or torques that fit far better negated
  std::string unusable;
  ParameterLayout layout;
  Method method = Method::kInverseDynamics;
  double window_s = 0;  ///< [s] the output-error and validation window used (output_error_window)
  std::vector<ParameterEstimate> parameters;
  Eigen::MatrixXd covariance;   ///< s^2 (J^T J)^-1 [units of the parameters squared]
  /// per parameter (internal layout = public except Stribeck's static_coulomb): the Cramer-Rao
  /// bound for white torque noise at the logged level, the angle noise ignored; NaN when unknown
  std::vector<double> cramer_rao_std;
  Eigen::MatrixXd correlation;  ///< covariance normalised by the standard deviations
  /// singular values of the Jacobian with columns scaled to unit norm (largest first): a ratio
  /// near 0 means a combination of parameters the log cannot determine
  std::vector<double> singular_values;
  std::vector<std::string> warnings;
  /// The model check's candidate causes of a misfit the friction law cannot absorb, each tried
  /// by one linearized refit with its parameters freed: "inertia" (the links' 16 inertial
  /// parameters, when not estimated), "angle_offsets" (the encoders' zeros), "torque_readings"
  /// (the torque sensors' offsets, when not estimated, and gains); and "any", all of them
  /// together. Empty when the check did not run (the fit did not converge, the output-error
  /// method, or fewer than 10 residuals per parameter of the check).
  struct MisfitCause {
    std::string name;
    bool checked = false;  ///< false: the refit is singular, the log cannot separate these
                           ///< parameters from the friction (drop and z mean nothing)
    double drop = 0;       ///< fall of the whitened cost, net of what noise alone gives
    double z = 0;          ///< that fall in std of noise's
    double z_given = 0;    ///< the same beyond the other causes' parameters ("any": z)
    /// the fraction of the residual's excess over its noise floor that the fall removes (NaN:
    /// no excess)
    double explained = 0;
    bool evidenced = false;  ///< z and z_given above 8, and half the excess explained when there
                             ///< is one: a warning names it when the friction would move
  };
  std::vector<MisfitCause> model_check;
  /// rms torque residual of the fit with the logged torques negated, when the sign check ran
  /// (IdentifyOptions::check_torque_sign) [N m]; NaN otherwise
  double negated_rms_torque_residual[2] = {std::numeric_limits<double>::quiet_NaN(),
                                           std::numeric_limits<double>::quiet_NaN()};
  int samples = 0;       ///< samples in the log
  int samples_used = 0;  ///< samples that entered the fit
  int samples_at_rest = 0;  ///< samples left out by the rest rule (some joint stuck)
  /// IdentifyOptions::exclude_reversals: sign changes of the joints' relative rates found, and
  /// the samples left out because their Savitzky-Golay window spans one
  int slip_reversals = 0, samples_near_reversals = 0;
  double rest_rate_threshold = 0, rest_acceleration_threshold = 0;  ///< as applied
  int residuals = 0;
  /// rms of the unweighted residual per actuator [N m] (inverse dynamics: tau - M at the fit)
  double rms_torque_residual[2] = {0, 0};
  double rms_torque_residual_initial[2] = {0, 0};  ///< same at the start values
  /// the torque residual's expected rms from the sensor noise alone [N m]: the logged torque
  /// noise plus the angle (or rate) noise propagated through the rate estimation and the
  /// dynamics, floored at 0.1 % of the rms logged torque (noise-free logs); rms_torque_residual
  /// well above it means structure the fitted law misses. Output error: the torque residual's
  /// white-noise level, 1.4826 median |r_i - r_(i-1)| / sqrt 2.
  double residual_noise_floor[2] = {0, 0};
  double rms_angle_residual[2] = {0, 0};  ///< output error: theta - simulated [rad]
  double residual_sigma = 0;              ///< sqrt(2 cost / (m - p)) in residual units
  double wall_time_s = 0;                 ///< solve + covariance
  int iterations = 0;
  bool converged = false;
  double loss_scale = 0;  ///< the robust loss's scale as applied (0: no robust loss)
  std::string solver_message;
  std::vector<double> iteration_costs;  ///< Ceres cost at each iteration (iteration 0 first)
  bool rates_estimated = false, accels_estimated = false;
  int sg_half_window = 0;     ///< samples, when estimated
  int sg_order = 0;           ///< Savitzky-Golay polynomial order used, when estimated
  std::string window_choice;  ///< how the half-window was chosen (data-driven or given)
  /// the log's conditioning: one sentence per thing done (unwrapping, glitches rejected)
  std::vector<std::string> notes;
  std::vector<Glitch> glitches;  ///< samples rejected as isolated glitches
  TorqueLog conditioned_log;     ///< the log as fitted: unwrapped, glitches interpolated
  int unwrapped[2] = {0, 0};     ///< one-turn jumps undone in theta1, theta2
  /// robust white-noise std of the logged columns (condition.h) [rad], [N m], [rad/s]
  double angle_noise[2] = {0, 0}, torque_noise[2] = {0, 0}, rate_noise[2] = {0, 0};
  /// "errors-in-variables" (inverse dynamics), "window-sandwich" (output error) or
  /// "residual-variance" (--classical-std)
  std::string std_method;
  std::string std_detail;  ///< one sentence on how the std were formed, when there is more to say
  /// half-width of the Wald 95 % intervals in std: the normal 1.96, or Student's t with
  /// ci_dof = G - 1 degrees of freedom for the window sandwich over G windows (0: normal)
  double ci_quantile = 1.959963984540054;
  int ci_dof = 0;
  int profile_refits = 0;  ///< re-fits spent on profile-likelihood intervals
  /// torque-to-angle delay d [s]: the logged torques at t + d match the angles at t (positive:
  /// the torques lag); NaN when not estimated. delay_corrected: the fit used torques shifted by d
  double delay_s = std::numeric_limits<double>::quiet_NaN(), delay_std_s = delay_s;
  bool delay_corrected = false;
  /// a significant delay that the fit with the torques shifted by it did not explain (a model
  /// error, not a delay: not corrected, named in the warnings)
  bool delay_unexplained = false;
  /// per sample (log order): rates and accelerations used, predicted torques at the fit (inverse
  /// dynamics of the fitted scene at every sample; NaN where it failed), and whether used
  std::vector<double> omega1, omega2, alpha1, alpha2, predicted_tau1, predicted_tau2;
  std::vector<char> used;
  Params<double> fitted;  ///< the scene's parameters with the identified friction (and links)
  /// a four-bar's fit (identify's four-bar overload): the scene's four-bar with the identified
  /// friction; `fitted` is then left at its defaults
  FourBarParams fitted_four_bar;
  InertialReport inertial;  ///< group inertia
};

/// Identifies the friction coefficients of `scene` from `log`. `loads` gives the scene's
/// non-actuator loads (M3, F, F_angle; its M1, M2 are ignored). The log is first conditioned
/// (condition.h: unwrapped, isolated glitches rejected). Throws LogError for a log that cannot
/// be used (fewer samples than parameters, poses that do not fit the scene, angles in degrees,
/// more than isolated glitches). A numerical failure (an evaluation that fails at the start
/// values or the solution, a solver that gives up) is a status naming the sample and the reason;
/// the covariance is computed only on a converged solution.
IdentifyResult identify(const Params<double>& scene, const sim::LoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& options);

/// The Savitzky-Golay filter identify's five-bar chooses for `log` (conditioning, rates and, with
/// options.auto_window, its data-driven window stages: the steps of identify before its fit)
/// into *sg, and the text of the choice into *choice; false where the log stops identify before
/// its choice (*choice then says why). Throws as identify.
bool identify_window(const Params<double>& scene, const sim::LoadFunction& loads,
                     const TorqueLog& log, const IdentifyOptions& options, SgOptions* sg,
                     std::string* choice);

/// Identifies the joint friction of a four-bar (one crank: a log of dof 1, t, theta1, tau1 and
/// optionally omega1, alpha1) by inverse dynamics over the mechanism (four_bar.h): the same
/// conditioning, rate estimation, fit, covariance, model check and Wald intervals as the
/// five-bar's, with the checks that need the five-bar's two cranks or its inertial and
/// actuator models left out (docs/identification.md, "Four-bar"). `loads` gives M3, F and
/// F_angle (its M1 is ignored). A layout or method the four-bar does not support is a status
/// kInvalidInput naming it (four_bar_unsupported). Throws LogError as identify.
IdentifyResult identify(const FourBarParams& scene, const sim::FourBarLoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& options);

/// Empty if identify's four-bar overload supports `options`, else the option it does not
/// support, in one line ("--method output-error runs five-bars only (...)").
std::string four_bar_unsupported(const IdentifyOptions& options);

/// Angles of a simulation of `params` driven by the logged torques (linear between samples)
/// against the logged angles.
struct Validation {
  int dof = 2;                    ///< driven angles compared (channels 0..dof-1 below)
  Status status;                  ///< of the full run (not ok: the run stopped early)
  double full_rms[2] = {0, 0};    ///< [rad] one run from the first sample over the whole log
  double full_max[2] = {0, 0};    ///< [rad]
  double full_duration_s = 0;     ///< how far the full run got
  double window_s = 0;            ///< restart period of the windowed check
  double window_rms[2] = {0, 0};  ///< [rad] runs restarted from the logged state every window
  std::vector<double> full_theta1,
      full_theta2;          ///< simulated at the log's times (NaN after a stop)
  /// the windowed runs at the log's times (each window restarted from the logged state; NaN
  /// where no window ran)
  std::vector<double> window_theta1, window_theta2;
  /// when the full run first departs from the log by more than kDivergedAngle (NaN: never):
  /// on chaotic motion any model or noise error grows until the run leaves the log
  double divergence_time_s = std::numeric_limits<double>::quiet_NaN();
  static constexpr double kDivergedAngle = 0.1;  ///< [rad]
  int windows_skipped = 0;  ///< windows not run: the time budget was spent
  /// windows whose run stopped before their end (their samples from there NaN), and the first's
  /// start and reason
  int windows_stopped = 0;
  std::string window_stop;
};

/// The output-error and validation window for a log of `duration` seconds: window_s when > 0,
/// else 0.2 s or duration / 20 if shorter.
double output_error_window(double window_s, double duration);

/// The validation runs' tolerance (CVODE rtol = atol): their integration error (~3e-8 rad on the
/// windowed rms of the paper scene's per-joint log, against 1.2e-4 rad of model and noise
/// error and 1e-5 rad of angle noise) is far below what they measure; 1e-9 took 2.4 times as long
/// for a windowed rms within 3e-4 of it.
inline constexpr double kValidationRtol = 1e-7;

/// Simulates `params` with the log's torques from the log's state (rates: `omega1/2`), once over
/// the whole log and in windows of `window_s` restarted from the logged state, within a wall-time
/// budget (the full run gets half; windows past the budget are skipped and counted).
Validation validate(const Params<double>& params, const sim::LoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1,
                    const std::vector<double>& omega2, double window_s,
                    double rtol = kValidationRtol, double budget_s = 10.0);
/// The four-bar's: its crank driven by the logged tau1 from the logged theta1, omega1; its
/// crank angle compared (channel 0 of the Validation; channel 1 stays empty).
Validation validate(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1, double window_s,
                    double rtol = kValidationRtol, double budget_s = 10.0);

/// Loads for the simulator: logged tau1, tau2 (linear in t) less the sensors' `offset` as M1, M2
/// and the scene's M3, F, F_angle, shifted by t0 (the simulator starts at t = 0).
sim::LoadFunction logged_loads(const TorqueLog& log, const sim::LoadFunction& scene_loads,
                               double t0, std::array<double, kActuators> offset = {0.0, 0.0});
/// The four-bar's: logged tau1 less its sensor's `offset` as M1, the scene's M3, F, F_angle.
sim::FourBarLoadFunction logged_loads(const TorqueLog& log,
                                      const sim::FourBarLoadFunction& scene_loads, double t0,
                                      double offset = 0.0);

}  // namespace fivebar::identification
