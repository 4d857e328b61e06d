// Excitation design: the Fisher information that a motion of the two cranks gives on
// the parameters identification estimates, by Jets, and the design problem around it (a periodic
// finite Fourier motion, D-optimal or condition-number objective, torque, singularity, angle and
// reversal constraints). The NLopt driver lives in trajectory/ (nlopt_minimize.h); the command
// in apps/cmd_excite.cc joins the two.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fivebar/identification/parameters.h"
#include "fivebar/identification/rates.h"
#include "fivebar/identification/synth.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"

namespace fivebar::identification {

/// The parameter groups an excitation is designed for (identify --estimate).
struct DesignGroups {
  bool friction = true;   ///< coulomb, viscous (shared, or per joint)
  bool inertia = false;   ///< the 16 standard inertial parameters (model/inertial.h)
  bool actuator = false;  ///< per actuator: torque offset, Coulomb, viscous (load-independent)
  bool per_joint = false;
};

/// Parses "friction,inertia,actuator" (any non-empty subset, any order); false on an unknown
/// or repeated name (with the offending word in *bad).
bool parse_groups(const std::string& list, DesignGroups* groups, std::string* bad);

/// Number of actuator parameters per actuator: offset, coulomb, viscous.
inline constexpr int kActuatorPerMotor = 3;

/// The parameters of a design, in vector order: friction (ParameterLayout order), inertial
/// (m_1, mx_1, ...), actuator (offset_1, coulomb_act_1, viscous_act_1, offset_2, ...).
struct DesignParameters {
  ParameterLayout layout;  ///< the friction layout (coulomb_viscous)
  int friction = 0, inertial = 0, actuator = 0;
  std::vector<std::string> names;
  std::vector<double> nominal;  ///< values at the scene (actuator: 0)
  /// the scale of each parameter in the objective: |nominal|, or for a zero nominal a typical
  /// size (actuator offset and Coulomb 0.1 N m, viscous 0.01 N m s/rad; inertial 1e-3 in SI)
  std::vector<double> scale;
  /// the std of identify's prior on each parameter (its inertial prior on the four-bar's links,
  /// which identify weighs at the residual's noise floor; 0: none), empty where it has none (the
  /// five-bar's design); counted in the Fisher information and in the predicted std
  std::vector<double> prior_std;
  int size() const { return static_cast<int>(names.size()); }
  int jet_size() const { return friction + inertial; }
};
DesignParameters design_parameters(const Params<double>& scene, const DesignGroups& groups);

/// One sample of a motion: pose, rates and accelerations of the two cranks (a mechanism with
/// one crank, the four-bar, uses th1, w1, a1 only).
struct MotionState {
  double th1 = 0, th2 = 0, w1 = 0, w2 = 0, a1 = 0, a2 = 0;
};

/// What one sample gives: the Jacobian of the measured torques (M1, M2) with respect to the
/// design parameters (2 x P; the five-bar's friction and actuator columns in closed form, its
/// inertial ones by Jets; a mechanism with one crank leaves row 2 and M2 at 0), the torques
/// themselves (actuator terms at their nominal 0),
/// the singular measure (the five-bar's coupler sine |sin(th4 - th3)|, the four-bar's
/// |sin(th3 - th2)|) and the relative rates of the joints (slots from the mechanism's joints on:
/// 0).
struct SampleTerms {
  Eigen::MatrixXd J;
  double M1 = 0, M2 = 0, sine = 0;
  std::array<double, kJoints> w{};
  JointModes slip{};
};

/// Evaluates one sample. `slip` (nullptr: sign of each rate) fixes the Coulomb signs, so that
/// derivatives along the motion are those of one slip pattern. Fails where the pose cannot
/// assemble or the friction loop has no solution.
Status sample_terms(const Params<double>& scene, const DesignParameters& dp, const Loads<double>& loads,
                    const MotionState& s, const JointModes* slip, SampleTerms* out);

namespace detail {
/// sample_terms with the friction and inertial columns by Jets through the whole inverse
/// dynamics (the reference of the closed form sample_terms takes where it applies: no inertial
/// parameters, a friction law without internal states).
Status jet_sample_terms(const Params<double>& scene, const DesignParameters& dp,
                        const Loads<double>& loads, const MotionState& s, const JointModes* slip,
                        SampleTerms* out);
}  // namespace detail

/// The Fisher information sum_i J_i^T J_i / sigma^2 of a motion, with its sample terms.
Eigen::MatrixXd fisher_information(const std::vector<Eigen::MatrixXd>& jacobians, double sigma);

struct ExcitationReport;

/// What the design and its prediction need of a mechanism, at the scene's constants and loads:
/// per sample the terms above and the torques' kinematic Jacobian, and identify's rules for the
/// mechanism (its rate filter, its rest rule). The five-bar (five_bar_excitation) and the
/// four-bar (four_bar_excitation) are its instances.
class ExcitationMechanism {
 public:
  virtual ~ExcitationMechanism() = default;
  /// driven cranks (1 or 2) and joints (<= kJoints)
  virtual int dof() const = 0;
  virtual int joints() const = 0;
  virtual std::string joint_name(int k) const = 0;
  /// "five_bar", "four_bar"
  virtual std::string type() const = 0;
  virtual const DesignParameters& parameters() const = 0;
  /// sample_terms at time t (the loads of that time)
  virtual Status terms(double t, const MotionState& s, const JointModes* slip,
                       SampleTerms* out) const = 0;
  /// d (M1, M2) / d (th1, th2, w1, w2, a1, a2) at the scene's parameters (the rows and columns
  /// of a crank the mechanism does not have: 0)
  virtual Status kinematic_jacobian(double t, const MotionState& s,
                                    Eigen::Matrix<double, 2, 6>* D) const = 0;
  /// identify's window rule: true where it walks the windows by their predicted bias from the
  /// filter *sg (the four-bar: choose_window_by_bias, the noise's bias through the reactions
  /// included); false where it takes its residual rule, then the bias limit (the five-bar)
  virtual bool window_by_bias(SgOptions* sg) const = 0;
  /// identify's window stages themselves where its window is not walked by predicted bias (the
  /// five-bar): the filter identify chooses for a log of synth-log's sensors along the motion
  /// `r` (its times, states and torques; torque and angle noise of these std, seed 1) into *sg,
  /// the choice's text into *choice; false where identify stops before its choice (*choice:
  /// why) or the mechanism has no such stages
  virtual bool identify_window(const ExcitationReport& r, double torque_noise, double angle_noise,
                               SgOptions* sg, std::string* choice) const {
    (void)r, (void)torque_noise, (void)angle_noise, (void)sg, (void)choice;
    return false;
  }
  /// identify's rest rule at a sample of the exact motion: true where identify would leave the
  /// sample out as at rest, its rates estimated by a filter whose rate and acceleration noise
  /// gains are g1, g2 from angles of noise std `angle_noise` [rad]
  virtual bool at_rest(double t, const MotionState& s, double g1, double g2,
                       double angle_noise) const = 0;
};

/// The five-bar of `scene` with the loads at each time, for the parameters `dp`.
std::shared_ptr<const ExcitationMechanism> five_bar_excitation(
    const Params<double>& scene, const DesignParameters& dp,
    std::function<Loads<double>(double)> loads);

/// The four-bar's design parameters: its friction, coulomb and viscous shared by its four joints
/// (identify's default on four-bars) or, per_joint, one of each per joint (coulomb_1..4,
/// viscous_1..4), and with `inertia` its three links' 12 standard inertial parameters (m_1 ..
/// J_3) under identify's prior (prior_std), and with `actuator` the crank motor's offset_1,
/// actuator_coulomb_1 and actuator_viscous_1 (columns in closed form).
DesignParameters four_bar_design_parameters(const FourBarParams& scene, bool per_joint = false,
                                            bool inertia = false, bool actuator = false);

/// The four-bar of `scene` for the parameters of four_bar_design_parameters (identify_four_bar.cc's
/// rate filter and rest rule).
std::shared_ptr<const ExcitationMechanism> four_bar_excitation(
    const FourBarParams& scene, std::function<FourBarLoads(double)> loads, bool per_joint = false,
    bool inertia = false, bool actuator = false);

/// The designed motion of each crank: a drift (a steady rotation) plus a finite Fourier series,
/// faded in from rest at the start pose by a ramp r(t) (quintic smoothstep over `ramp` seconds,
/// then 1):
///   th(t) = th0 + r(t) (c t + sum_{l=1..H} a_l sin(l w t) + b_l (cos(l w t) - 1)),
/// w = 2 pi / period. After the ramp the rates and accelerations are periodic; r(0) = r'(0) =
/// r''(0) = 0 makes the motion start at rest at th0 with zero acceleration whatever the
/// coefficients. Free variables per crank: c [rad/s], a_1..a_H, b_1..b_H [rad]; th1's first.
/// With one crank (dof 1) th2 stays at its start.
class FourierMotion {
 public:
  FourierMotion(int harmonics, double period, double ramp, std::array<double, 2> start,
                int dof = kDof);
  int dof() const { return dof_; }
  int harmonics() const { return h_; }
  double period() const { return period_; }
  double ramp() const { return ramp_; }
  int per_joint() const { return 2 * h_ + 1; }
  int num_variables() const { return dof_ * per_joint(); }
  /// Harmonic of variable v of a crank (0 for the drift).
  int harmonic_of(int v) const { return v == 0 ? 0 : (v - 1) % h_ + 1; }
  const std::array<double, 2>& start() const { return start_; }
  /// d th^(k)(t) / d x_v for one crank (k = 0, 1, 2: angle, rate, acceleration), v < per_joint().
  void basis(double t, std::vector<std::array<double, 3>>* d) const;
  MotionState state(const std::vector<double>& x, double t) const;
  /// The variables whose motion is the least-squares fit of the angles th1(t), th2(t) sampled at
  /// `t` (e.g. another excitation, as a start for the design; th2 unused with one crank).
  std::vector<double> fit(const std::vector<double>& t, const std::vector<double>& th1,
                          const std::vector<double>& th2) const;

 private:
  int h_;
  double period_, ramp_;
  std::array<double, 2> start_;
  int dof_;
};

/// The design's objective.
enum class Criterion : int {
  kDOptimal = 0,   ///< maximize log det of the scaled, regularized Fisher information
  kCondition = 1,  ///< minimize log of its condition number
  /// minimize the log of the worst relative std (a p-norm, p = 16, of the scaled variances of
  /// the parameters with a non-zero value; all of them when every value is zero)
  kWorstStd = 2,
};

/// The criterion of a Fisher matrix F (to minimize): scaled by `scale` (S F S), regularized by
/// regularization * trace / P times the identity; with dF, its derivative dPhi/dF. `nominal`
/// chooses the parameters of kWorstStd.
double design_criterion(const Eigen::MatrixXd& F, const std::vector<double>& scale,
                        const std::vector<double>& nominal, double regularization,
                        Criterion criterion, Eigen::MatrixXd* dF);

struct ExcitationOptions {
  double duration = 10;           ///< [s]
  int periods = 4;                ///< periods of the motion in the duration
  int harmonics = 5;              ///< H of FourierMotion
  double ramp = 1.0;              ///< [s] fade-in from rest (FourierMotion)
  int design_samples = 400;       ///< samples of the objective and constraints over the duration
  /// further instants where the constraints (not the objective) are sampled, e.g. where a
  /// previous design's torque peaked between the design samples [s]
  std::vector<double> extra_times;
  double torque_limit = 0;        ///< |M1|, |M2| <= this [N m]
  double torque_margin = 0.01;    ///< the design keeps |M| <= (1 - margin) torque_limit
  int constraint_blocks = 40;     ///< blocks of samples per aggregated constraint
  double aggregation_sharpness = 300;  ///< rho of the KS aggregation (overestimate <= ln(n)/rho)
  double singular_margin = kMotionSingularMargin;  ///< |sin(th4 - th3)| >= this
  double torque_noise = 0.02;     ///< std of the torque noise [N m] (the Fisher's sigma)
  /// std of the angle noise of the log [rad] (synth-log's default): identify estimates the rates
  /// from the angles, and this noise through them enters its std (predict_identified_std)
  double angle_noise = 1e-5;
  double rate_hz = 1000;          ///< the log's sampling rate (the Fisher is scaled to it)
  /// optional angle ranges [rad]: lo < hi, NaN when absent
  std::array<double, 2> theta_lo{NAN, NAN}, theta_hi{NAN, NAN};
  double reversal_rate = 0.2;     ///< every joint's rate reaches +- this [rad/s] (smooth max)
  int min_reversals = 4;          ///< sign changes of every relative rate, checked after design
  double regularization = 1e-6;   ///< times the mean eigenvalue, added to the scaled Fisher
  Criterion criterion = Criterion::kDOptimal;
  DesignGroups groups;
};

/// Value and gradient of the design objective (to minimize) and constraints (<= 0).
struct DesignValue {
  double objective = 0;
  std::vector<double> objective_grad;
  std::vector<double> constraints;       ///< num_constraints()
  std::vector<double> constraints_grad;  ///< row-major m x n
};

/// The design problem over a mechanism. Variables: FourierMotion's (one series per crank).
/// Constraints, scaled to be dimensionless: at every design sample |M_j| / limit - (1 - margin)
/// <= 0 (two per crank), 1 - sine / margin <= 0 (the mechanism's singular measure),
/// the angle ranges when given, each kind aggregated over constraint_blocks blocks of
/// consecutive samples by a Kreisselmeier-Steinhauser upper bound of the block's maximum (few
/// constraints keep the NLopt subproblems cheap); for every joint, a smooth lower bound of the
/// maximum of +-w_k at least reversal_rate.
class ExcitationProblem {
 public:
  ExcitationProblem(std::shared_ptr<const ExcitationMechanism> mechanism,
                    std::array<double, 2> start, const ExcitationOptions& options);
  /// the five-bar of `scene` (options.groups' parameters)
  ExcitationProblem(const Params<double>& scene, std::function<Loads<double>(double)> loads,
                    std::array<double, 2> start, const ExcitationOptions& options);

  const FourierMotion& motion() const { return motion_; }
  const ExcitationMechanism& mechanism() const { return *mech_; }
  const DesignParameters& parameters() const { return mech_->parameters(); }
  const ExcitationOptions& options() const { return opt_; }
  int num_variables() const { return motion_.num_variables(); }
  int num_constraints() const;
  /// the reversal constraints, two per joint, come last
  int reversal_constraints() const { return 2 * mech_->joints(); }
  /// Design sample times (over the duration, midpoints of equal cells), then the extra times.
  const std::vector<double>& times() const { return times_; }

  /// Objective and constraints at x; with `grad`, their gradients: the Jacobian J_i by Jets, its
  /// derivative along the six motion variables by forward differences of that Jet Jacobian (at
  /// fixed slip signs), chained through the linear Fourier basis.
  Status evaluate(const std::vector<double>& x, bool grad, DesignValue* out) const;

  /// The objective of a Fisher matrix (scaled and regularized as in evaluate) and dPhi/dF.
  double criterion_value(const Eigen::MatrixXd& F, Eigen::MatrixXd* dF) const;

 private:
  struct Derivs;
  Status sample(const std::vector<double>& x, int i, bool grad, Derivs* d) const;
  void add_sample_constraints(int i, const Derivs& d, bool grad,
                              const std::vector<std::array<double, 3>>& basis,
                              std::vector<double>* raw, std::vector<double>* raw_grad) const;
  void aggregate(const std::vector<double>& raw, const std::vector<double>& raw_grad, bool grad,
                 DesignValue* out) const;
  int constraint_kinds() const;
  int blocks() const;
  void add_reversal_constraints(const std::vector<Derivs>& all, bool grad,
                                const std::vector<std::vector<std::array<double, 3>>>& basis,
                                DesignValue* out) const;
  int per_sample_constraints() const;

  std::shared_ptr<const ExcitationMechanism> mech_;
  ExcitationOptions opt_;
  FourierMotion motion_;
  std::vector<double> times_;
  int objective_samples_ = 0;  ///< the first ones of times_ (the extra times only constrain)
};

/// The motion on a uniform grid t = i / rate_hz, i = 0 .. duration * rate_hz, with its torques
/// and per-sample terms, and what it gives: predicted covariance, std, reversal counts.
struct ExcitationReport {
  std::vector<double> t;
  std::vector<MotionState> states;
  std::vector<double> M1, M2;
  Eigen::MatrixXd fisher;      ///< unscaled, 1 / sigma^2 sum J^T J
  /// its (pseudo-)inverse; after predict_identified_std, the errors-in-variables covariance
  Eigen::MatrixXd covariance;
  std::vector<double> std_dev, relative_std;  ///< relative: std / |nominal| (NaN for 0)
  /// the std of the torque noise alone (the Fisher's), kept by predict_identified_std
  std::vector<double> torque_only_std;
  /// predict_identified_std: the Savitzky-Golay half-window [samples] identify's rules choose
  /// on this motion (0: not predicted), and how it was chosen
  int sg_half_window = 0;
  std::string window_choice;
  std::array<int, kJoints> reversals{};
  int dof = kDof, joints = kJoints;  ///< the mechanism's cranks and joints (evaluate_motion)
  double peak_torque = 0, peak_time = 0, min_sine = 1, condition_number = 0, log_det_scaled = 0;
  std::array<double, 2> theta_min{}, theta_max{};
};

/// The largest relative std of a report (NaN entries, of zero nominal values, left out).
double worst_relative_std(const ExcitationReport& r);

/// Evaluates a motion given as states on a grid (the design's, or any logged motion). Loads at
/// each time from `loads`. Fails on the first sample that cannot be evaluated.
Status evaluate_motion(const ExcitationMechanism& mechanism, const std::vector<double>& t,
                       const std::vector<MotionState>& states, double torque_noise,
                       ExcitationReport* out);
/// the same for the five-bar of `scene`
Status evaluate_motion(const Params<double>& scene, const DesignParameters& dp,
                       const std::function<Loads<double>(double)>& loads,
                       const std::vector<double>& t, const std::vector<MotionState>& states,
                       double torque_noise, ExcitationReport* out);

/// What identify reports for a log along the motion of `r` (evaluate_motion's, on a uniform
/// grid) whose rates and accelerations it estimates from angles of noise `angle_noise` [rad]
/// (torque noise `torque_noise` [N m]): the errors-in-variables covariance H^-1 S H^-1 of
/// noise_model.h (H = sum J^T J over the samples the fit uses, S the score covariance of the
/// torque noise and of the angle noise through the Savitzky-Golay rates), at the half-window
/// identify's rules choose in expectation: the largest whose smoothing bias on the torques stays
/// within its residual rule's 4 % of the noise level (one candidate below, as identify backs
/// off), then the largest up to it whose bias on the coefficients is within 0.2 of their std.
/// The bias is exact here (the filter applied to the noise-free motion). Samples within the
/// window of a slip reversal, and those identify's rest rule takes as at rest at this noise
/// (ExcitationMechanism::at_rest), are left out as identify leaves them out. Where the samples
/// left do not determine the parameters, fails with NaN std. Replaces covariance,
/// std_dev and relative_std; the Fisher's std goes to torque_only_std. With angle_noise 0 the
/// std are the Fisher's. A mechanism whose identify walks the windows by their predicted bias
/// (ExcitationMechanism::window_by_bias) is predicted at the window of that walk (the same
/// function as identify's, stages::walk_window_by_bias), its bias the smoothing's and the
/// noise's through the reactions, and its std identify's errors-in-variables std.
Status predict_identified_std(const ExcitationMechanism& mechanism, double torque_noise,
                              double angle_noise, ExcitationReport* r);
/// the same for the five-bar of `scene`
Status predict_identified_std(const Params<double>& scene, const DesignParameters& dp,
                              const std::function<Loads<double>(double)>& loads,
                              double torque_noise, double angle_noise, ExcitationReport* r);


}  // namespace fivebar::identification
