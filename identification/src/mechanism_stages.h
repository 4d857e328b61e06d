// The data-driven Savitzky-Golay window and its smoothing bias, written once for every
// mechanism: the window choice (stage_window.cc) and the smoothing-bias stages
// (stage_smoothing_bias.cc) read a fit through WindowFit, which each mechanism's identify
// implements over its own residual (the five-bar: identify_stages.h, FiveBarWindowFit; the
// four-bar: identify_four_bar.cc). A mechanism of one driven joint fills channel 0 of the
// two-channel noise model (noise_model.h) and leaves channel 1 at zero. The profile-likelihood
// intervals (stage_intervals.cc) read a fit through ProfileProblem.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/rates.h"
#include "fivebar/sim/simulator.h"
#include "smoothing_bias.h"
#include "window_misfit.h"

namespace fivebar::identification::stages {

/// Whether the Savitzky-Golay window of half-width hw centred on log sample i spans a slip
/// reversal, from the reversals' prefix counts over the sample steps (reversals[i + 1] -
/// reversals[i]: whether the step into sample i reverses; empty: none known).
inline bool window_spans_reversal(const std::vector<int>& reversals, int i, int hw) {
  const int n = static_cast<int>(reversals.size()) - 1;
  if (hw <= 0 || n <= 0) return false;
  const int a = std::clamp(i - hw, 0, n - 1), b = std::clamp(i + hw, 0, n - 1);
  return reversals[b] - reversals[a] > 0;
}

/// Whether a fit leaves out the samples whose filter window spans a slip reversal, `near` of its
/// `total` centred samples: not where that would leave out more than half of them (the
/// accelerations near the reversals are then smoothed across them, and a warning says so)
inline bool leaves_out_reversals(int near, int total) { return 2 * near <= total; }

/// What a mechanism's model check leaves for the refits after it (the sign and per-joint checks,
/// the delay)
struct ModelVerdict {
  /// torque channels read negative (torque_signs; bit 0: tau1, bit 1: tau2): the sign check
  /// fits them negated whatever the residual
  unsigned negative_readings = 0;
  /// a named cause (the encoders' zeros, the torque readings' offsets or positive gains, a
  /// common scale) made the fit unusable: the sign and per-joint refits have nothing left to
  /// decide (they tripled the time of such rejected runs)
  bool cause_decided = false;
  /// the reason the check gave for a model error no cause explains (out->unusable then; ""
  /// otherwise): a window whose accelerations cannot be unbiased names the real cause instead
  /// (unbiased_window_check)
  std::string unattributed;
  /// the torque-to-angle delay as one more candidate cause (model_check; docs 9): kUnchecked
  /// when the check did not run, else whether its fall is evidenced (kCauseZ) and clearly
  /// beyond every other cause's; delay_falls: the falls of each cause, for the delay's warning;
  /// delay_tied: kNotMost for a delay whose fall is the largest but not clearly (a delay or a
  /// model error, the log cannot tell which)
  enum class Delay { kUnchecked, kNotEvidenced, kNotMost, kExplainsMost } delay = Delay::kUnchecked;
  std::string delay_falls;
  bool delay_tied = false;
  /// why the check did not run ("" when it ran); `short_log`: only because the log has too few
  /// samples for its columns (kCheckRowsPerColumn), the one case a delay may still be judged
  /// without it (delay_stage)
  std::string unchecked;
  bool short_log = false;
};

/// What the window stages read of a mechanism's fit, at the parameters of its preliminary fit.
class WindowFit {
 public:
  virtual ~WindowFit() = default;
  /// the conditioned log
  virtual const TorqueLog& log() const = 0;
  /// per log sample: 1 for a glitch (never probed)
  virtual const std::vector<char>& rejected() const = 0;
  /// where the rates and accelerations come from
  virtual detail::RateSource source() const = 0;
  /// log index of each sample of the fit
  virtual const std::vector<int>& index() const = 0;
  /// whether the filter's window of half-width hw centred on log sample i spans a slip reversal
  virtual bool spans_reversal(int i, int hw) const = 0;
  /// per channel (two: choose_window is the five-bar's): the rms torque residual and the level
  /// the sensor noise explains over the log samples `probe` (joints at rest left out), with the
  /// rates of the filter `sg` (read by choose_window; a mechanism whose window
  /// choose_window_by_bias chooses leaves them NaN)
  virtual void levels(const std::vector<int>& probe, const SgOptions& sg, double rms[2],
                      double floor[2]) const {
    (void)probe, (void)sg;
    rms[0] = rms[1] = floor[0] = floor[1] = std::numeric_limits<double>::quiet_NaN();
  }
  /// the inputs of the bias prediction (smoothing_bias.h) over the samples of the fit: the
  /// motion's higher terms above `order` from local polynomials over +-reach samples, cut short
  /// (not below +-min_half) at slip reversals
  virtual detail::BiasInputs bias_inputs(int reach, int min_half, int order) const = 0;
  /// what the noise of the rates and accelerations estimated with `sg` does to the fit at each
  /// of its samples (smoothing_bias.h); empty when not predicted (choose_window_by_bias reads it)
  virtual detail::NoiseBias noise_bias(const SgOptions& sg) const {
    (void)sg;
    return {};
  }
};

/// The data-driven Savitzky-Golay half-window (stage_window.cc). Smoothing bias shows in the
/// torque residual as an excess over the level the sensor noise explains: the window chosen is
/// the largest whose residual/noise ratio stays within kWindowExcess of the reference (1, or the
/// least ratio over the candidates when that is above 1: a mismatch of the law that no window
/// removes), then one candidate smaller; a flat excess (a misfit the small windows' noise hides,
/// window_misfit.h) is chosen by its own rule. Sets sg's half-window (and its order when the
/// smallest window is the choice), *rates_biased, and *choice (the text of the choice). It reads
/// both torque channels' levels (WindowFit::levels): the five-bar's rule. A mechanism of one
/// driven joint (the four-bar) chooses by choose_window_by_bias, which reads no levels: the
/// misfit of a law shows in its residual at the window chosen, whose noise floor is mostly the
/// torque noise (the crank rocker's 3 s logs: floor 0.024 N m for torque noise 0.02 N m), and
/// its model check names it.
void choose_window(const WindowFit& w, SgOptions* sg, bool* rates_biased, std::string* choice);

/// After choose_window: the largest window up to its choice whose predicted bias (smoothing_bias.h:
/// the smoothing's, and the noise's through the reactions where the mechanism predicts it,
/// WindowFit::noise_bias) is within kBiasFraction of the std for every friction coefficient, from
/// the rule's choice down to the second smallest window; when none is (the noise's bias grows as
/// the window shrinks: a heavy mechanism's reactions), the one of least predicted bias up to the
/// rule's choice and up from it while the bias falls. A filter whose order choose_window raised
/// (`given_order`: the order before) is kept when its own predicted bias is within
/// kBiasFraction, or when `rates_biased`; else the windows of the given order are searched as
/// above, from the second smallest up. Angles only. *bias: the prediction at the window kept
/// (left empty when not predicted); *choice gets its text appended; *left: the largest predicted
/// |bias| / std at the window kept when no window searched is within kBiasFraction (0 otherwise);
/// *spread: the std of the prediction kept from the angle noise (smoothing_bias.h), which the
/// search counts with the bias.
void limit_smoothing_bias(const WindowFit& w, int given_order, bool rates_biased, SgOptions* sg,
                          Eigen::VectorXd* bias, std::string* choice, double* left,
                          Eigen::VectorXd* spread);

/// The predicted bias of the public friction coefficients, the smoothing's and the noise's
/// through the reactions (as limit_smoothing_bias predicts it), at each half-window of `halves`
/// [samples] of sg's order, the motion's higher terms over +-kReconSpan times the larger of the
/// half-window and `reach_half`; *spread: each prediction's own std from the angle noise. False
/// when a prediction cannot be formed (or the rates are not estimated from the angles).
bool predicted_biases(const WindowFit& w, const SgOptions& sg, const std::vector<int>& halves,
                      int reach_half, std::vector<Eigen::VectorXd>* bias,
                      std::vector<Eigen::VectorXd>* spread);

/// The window of a mechanism that predicts the noise's bias (WindowFit::noise_bias), in place of
/// choose_window and limit_smoothing_bias: the noise's bias through the reactions falls as the
/// window grows while the smoothing bias grows, and the search runs up from the second smallest
/// candidate with the bias of both: the smallest window within kBiasFraction of the std of every
/// friction coefficient (the bias left is then mostly the noise's, which correct_smoothing_bias
/// takes off, while a larger window adds smoothing bias and leaves out more samples near slip
/// reversals), else the one of least predicted bias. Angles only, at sg's order; sg as given
/// when no bias can be predicted. *bias: the prediction at the window kept (left empty when not
/// predicted); *choice: its text, with the predictions by half-window.
void choose_window_by_bias(const WindowFit& w, SgOptions* sg, Eigen::VectorXd* bias,
                           std::string* choice);

/// The predicted smoothing bias at the chosen window (`bias`, public friction coefficients)
/// taken off the estimates, their intervals and the fitted parameters x (internal layout).
/// Coefficients at a bound, or whose std the log does not determine, are left as fitted, and no
/// correction takes a coefficient past its bound (a Stribeck static_coulomb stays >= coulomb):
/// the correction is limited there, and says so. Its own error, from the angle noise through
/// the reconstruction (`spread`, the std of each coefficient's prediction; empty: none), is added
/// to the std in quadrature and widens the interval as much: a few hundredths of the std on the
/// paper scene's logs, up to several std where the angle noise dominates the residual (a light
/// mechanism's clean logs).
void correct_smoothing_bias(const ParameterLayout& layout, const Eigen::VectorXd& bias,
                            std::vector<double>* x, IdentifyResult* out,
                            const Eigen::VectorXd& spread = Eigen::VectorXd());

/// A refit of the sign check: the fit of `log` with `opt` into *fit (its residual levels at
/// least); false or a LogError when the log cannot be fitted (no evidence either way).
using Refit =
    std::function<bool(const TorqueLog& log, const IdentifyOptions& opt, IdentifyResult* fit)>;

/// The sign check (IdentifyOptions::check_torque_sign) of a mechanism of `drives` torque
/// channels, once the caller has decided it runs (stage_refits.cc): true (and out->unusable says
/// why, with the --flip-torque-sign advice) when the log's torques fit far better negated: all
/// channels, or else one of them (a channel wired the other way read as "coulomb at its bound");
/// `suspect` (bit c - 1: tau c, read negative by the model check) is tried first. The refits
/// (`refit`) keep the fit's Savitzky-Golay window (no search of their own), estimate no delay and
/// run no sign check; the one with every channel negated puts its residual in out.
bool torques_fit_negated(const TorqueLog& log, const IdentifyOptions& opt, int drives,
                         unsigned suspect, const Refit& refit, IdentifyResult* out);

/// The fit redone by `refit` (stage_delay.cc) on the conditioned log with its torques (every
/// channel the log has) shifted by the delay `first` found (first.delay_s: the torques at
/// t + d match the angles at t), carrying over what the first pass reported about the log: its
/// glitches left out again, its torque noise, the samples whose shifted torques fall beyond the
/// log left out and noted. The refit estimates the delay left after the shift (and refits again,
/// at most opt.delay_refits - 1 times); the result's delay is the total, delay_corrected, and its
/// first warning says it. A refit that fails gives a result with `unusable` set.
IdentifyResult refit_with_delay(const TorqueLog& conditioned, const IdentifyOptions& opt,
                                const IdentifyResult& first, const Refit& refit);

/// The per-joint check (IdentifyOptions::check_per_joint) of a shared-law fit, once the caller
/// has decided it runs (stage_refits.cc): true (and out->unusable says why, replacing the reason
/// the model check gave) when the fit with one coefficient per joint (`refit`, the same log)
/// fits far better (fits_far_better, as the sign check's refits; offset_friction.yaml, whose
/// five joints' coefficients differ by up to 2.5 times, multi-sine log with rates: 18.3 floors
/// shared, 1.00 per joint). The refit keeps the fit's Savitzky-Golay window and estimates no
/// delay.
bool friction_differs_by_joint(const TorqueLog& log, const IdentifyOptions& opt, const Refit& refit,
                               IdentifyResult* out);

/// Raw (unweighted) residuals of the problem at its parameters, and its Jacobian with `jac`;
/// false where an evaluation fails (stage_solve.cc).
bool raw_residuals(ceres::Problem* problem, std::vector<double>* r,
                   ceres::CRSMatrix* jac = nullptr);

/// The CRS Jacobian as a dense matrix of P columns.
Eigen::MatrixXd dense(const ceres::CRSMatrix& crs, int P);

/// The preliminary fit before the window choice: plain least squares of the residual blocks
/// already in `problem` on the parameter block x (its lower bounds set here), at most 20
/// iterations; whether the solution is usable.
bool solve_preliminary(const ParameterLayout& layout, double* x, ceres::Problem* problem);

// ---- residual_blocks.cc ----

/// The loss of a residual block: the robust `loss` at `scale` (in the residual's units), its
/// cost times `weight` (torque_cost_weight); nullptr for Loss::kNone at weight 1. The problem
/// owns it.
ceres::LossFunction* make_loss(Loss loss, double scale, double weight = 1);

/// Linear interpolation of y(t) on the sorted grid ts (clamped at the ends).
double interp(const std::vector<double>& ts, const std::vector<double>& y, double t);

/// Consecutive windows [i0, i1] of about window_s over the samples [first, last].
std::vector<std::pair<int, int>> make_windows(const TorqueLog& log, int first, int last,
                                              double window_s);

/// The simulator options of an output-error window and of validate(): CVODE Adams at rtol.
sim::Options window_sim_options(double rtol);

/// The robust loss's default scale under output error [rad]: the residuals are angles, of the
/// same order at any scale of the mechanism.
inline constexpr double kOutputErrorLossScale = 0.1;

/// The text of a window no data-driven stage chose (rate_source.window_choice): "given" with
/// --sg-window, else "default".
inline std::string fixed_window_choice(const IdentifyOptions& opt, int half_window) {
  return std::string(opt.auto_window ? "default" : "given") + ": half-window " +
         std::to_string(half_window) + " samples";
}

/// Output error's warning under --classical-std (the residual variance's std).
inline constexpr const char* kIndependentWindowResiduals =
    "output-error standard deviations treat the angle residuals as independent; within a window "
    "they are correlated (they integrate the torque noise), so the reported std understate the "
    "uncertainty";

/// An output-error window's run: the mechanism at the parameters x (internal, ParameterLayout)
/// from the logged state at the window's start under the logged torques, over `options`.
using WindowSimulation = std::function<sim::Result(const double* x, const sim::Options& options)>;

/// Output error: the window [i0, i1] of the log as one residual block on the parameter block x
/// (the `dof` driven angles of `run` minus the logged ones at samples i0+1..i1, differentiated
/// by central differences of `relative_step`), under `loss` (the problem owns it); returns its
/// residual count.
int add_window_block(const TorqueLog& log, int dof, WindowSimulation run, int i0, int i1,
                     const sim::Options& so, double relative_step, ceres::LossFunction* loss,
                     std::vector<double>* x, ceres::Problem* problem);

// ---- stage_analysis.cc ----

/// Output error: the block sandwich over the windows (covariance.h) of `sizes` residuals each,
/// correlated within a window (they integrate the torque noise from the logged start) and
/// independent between windows; sets the std method, its detail and the intervals' Student t.
/// Empty when too few windows carry residuals (a warning).
Eigen::MatrixXd window_covariance(const std::vector<int>& sizes, const Eigen::MatrixXd& Jf,
                                  const std::vector<double>& r, IdentifyResult* out);

// ---- stage_predictions.cc ----

/// Output error: the torque residual of the fitted scene (out->predicted_tau1, and tau2 when it
/// has one) over the log samples [first, last], and its white-noise level.
void output_error_levels(const TorqueLog& log, int first, int last, IdentifyResult* out);

/// Output error's residual rule (it has no model check): a torque residual (output_error_levels)
/// more than kOutputErrorMisfitRatio times its noise floor makes the fit unusable, with a
/// warning saying why. The residual carries the rates' smoothing at the fixed window, which the
/// white-noise floor does not count: clean logs read 1.0-2.5, and a heavy five-bar with good
/// sensors (angle noise 1e-6 rad, torque noise 0.001 N m) 7.2 with exact estimates; a drag
/// link's offset of 0.1 N m, a coupler 15 % light and negated torques read 13-97 (caught), its
/// gain 1.1 and encoder zero 4.4-6.7 (not).
inline constexpr double kOutputErrorMisfitRatio = 10.0;
void output_error_misfit(IdentifyResult* out);

// ---- stage_solve.cc ----

/// The robust loss's default scale: kLossScaleHuber or kLossScaleCauchy times `level`, a
/// sample's expected residual level [N m] (0.1 where it is not positive and finite); the note
/// saying so is added to out.
double loss_scale_from_level(Loss loss, double level, IdentifyResult* out);

/// The weight of every residual block of a torque residual's cost (make_loss): the power of 4
/// nearest 1 / (the finite logged torques' mean square), 1 where that mean square is not
/// positive and finite. The solver works on a cost of order one per sample at any scale of the
/// mechanism: its tolerances are absolute, its Jacobi scaling 1 / (1 + column norm) and its
/// projected gradient x - P(x - g) rounds to 0 beside a coefficient of 0.1 where |g| < eps |x|
/// (a MEMS four-bar's 1e-16 N m torques, a cost of 1e-31, stopped the fit at its start values).
/// A power of 4 scales the residuals by a power of 2, so the weight and its undoing (the costs
/// reported and compared) are exact.
double torque_cost_weight(const TorqueLog& log);

/// The solver's brief report with its costs divided by the problem's cost `weight`.
std::string unweighted_report(const ceres::Solver::Summary& summary, double weight);

// ---- stage_analysis.cc ----

/// Warnings of a strong correlation (|r| > 0.98) between two public parameters (not two
/// inertial ones: the base combinations say which the log separates).
void correlation_warnings(const ParameterLayout& layout, const Eigen::MatrixXd& correlation,
                          std::vector<std::string>* warnings);

/// The warning of public parameter i's estimate *e (at_bound, value and std set): at its bound
/// or its std not determined (e->std then NaN: not reported), or poorly determined (std above
/// its value; not for inertial parameters).
void judge_estimate(const ParameterLayout& layout, int i, bool converged, ParameterEstimate* e,
                    std::vector<std::string>* warnings);

// ---- stage_intervals.cc ----

/// What a profile-likelihood interval re-fits: the fit's problem (its residual blocks on the
/// internal parameters x, without a robust loss), (J^T J + Hp)^-1 of its free parameters (NaN
/// or 0 elsewhere), the fit's solver options and the weight of its blocks' costs (make_loss).
/// Any mechanism's fit provides one.
struct ProfileProblem {
  const ParameterLayout& layout;
  const std::vector<double>& x;
  ceres::Problem* problem;
  const Eigen::MatrixXd& Hinv;
  ceres::Solver::Options solver;
  double cost_weight;
};

/// The profile-likelihood intervals where wants_profile, on a converged fit whose Wald
/// intervals are in out->parameters.
void profile_intervals(const ProfileProblem& pp, IdentifyResult* out);

}  // namespace fivebar::identification::stages
