// Forward simulation of a scene with SUNDIALS (CVODE, ARKODE behind it, in model/src/).
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/model/evaluation.h"
#include "fivebar/model/four_bar_params.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/params.h"
#include "fivebar/model/rest_rule.h"
#include "fivebar/model/status.h"

namespace fivebar::sim {

/// Integrators offered. Names (method_name / parse_method) are the scene's `simulation.integrator`.
enum class Method : int {
  kCvodeAdams = 0,  ///< "cvode_adams": variable-order Adams-Moulton, fixed-point iteration
  kCvodeBdf,        ///< "cvode_bdf": variable-order BDF, Newton with a dense Jacobian
  kArkodeErk45,     ///< "arkode_erk45": explicit Dormand-Prince 5(4), 7 stages
  kArkodeErk87,     ///< "arkode_erk87": explicit Fehlberg 7(8), 13 stages
  kArkodeDirk,      ///< "arkode_dirk": implicit ARK5(4)8L[2]SA DIRK, Newton, dense Jacobian
  kArkodeErk65,     ///< "arkode_erk65": explicit Verner 6(5), 8 stages
};
/// Every method, in the order the work-precision study reports them.
inline constexpr Method kAllMethods[] = {Method::kCvodeAdams, Method::kCvodeBdf,
                                         Method::kArkodeErk45, Method::kArkodeErk65,
                                         Method::kArkodeErk87, Method::kArkodeDirk};
const char* method_name(Method m);
/// Parses a method name; false if unknown.
bool parse_method(const std::string& name, Method* out);

/// The integrator of a run that does not choose one: BDF when the friction law has internal
/// states (LuGre's bristles are stiff: Adams' fixed-point iteration crawls on them), else Adams
/// (the work-precision study's choice).
inline Method default_method(bool stiff_states) {
  return stiff_states ? Method::kCvodeBdf : Method::kCvodeAdams;
}
inline Method default_method(FrictionLaw law) {
  return default_method(law_descriptor(law).states_per_joint > 0);
}

/// Solver settings (scene key `simulation:`), with the defaults that reach the accuracy figures.
struct Options {
  double duration = 2.0;      ///< [s]
  double output_step = 1e-3;  ///< [s] output grid, from dense output
  /// the integrator (simulation.integrator); unset: default_method of the friction law
  std::optional<Method> method;
  double rtol = 1e-10;
  double atol = 1e-10;
  /// [rad] the global error a run should reach (simulation.target_error); with auto_tolerance
  /// simulate_to_target chooses rtol = atol to meet it
  double target_error = 1e-6;
  /// the scene fixes neither rtol nor atol: simulate_to_target chooses them
  bool auto_tolerance = false;
  bool locate_switches = true;  ///< root-find every zero of a joint's relative rate and restart
  /// exact stick-slip (with located switches): a joint whose rate reaches zero sticks while
  /// |holding torque| <= mu_s r_k N_k, and breaks away when the bound is reached
  bool stick = true;
  long max_steps = 2000000;     ///< steps between two output times (SUNDIALS' mxstep)
  double max_wall_time_s = 0;   ///< stop with kSolverFailed past this wall time (0: no limit)
  /// LuGre: absolute tolerance of the bristle states z [rad] relative to atol (deflections are
  /// ~ mu / sigma0, far below the angles)
  double bristle_atol_scale = 1e-4;
  /// run stops (status kNearSingular) when |sin(th4 - th3)| falls below this; the evaluations
  /// inside the run fail at kEvalMarginFraction of it, so that the stop itself can be located
  double singular_margin = 1e-3;
  double friction_tol = kFrictionTol;  ///< relative stopping test of the reaction/friction loop
  /// false: output rows hold only t, theta, omega and the energy quadratures (no accelerations,
  /// reactions or friction torques): what a work-precision study needs, at a fraction of the cost
  bool full_rows = true;
  int friction_max_iter = kFrictionMaxIter;
  /// called after every accepted step with the time reached (the apps show progress; may be empty)
  std::function<void(double t)> progress;
};

/// The fraction of Options::singular_margin at which a run's evaluations fail (the run itself
/// stops at the margin).
inline constexpr double kEvalMarginFraction = 0.5;

/// The integrator a run with these options uses for friction law `law`.
inline Method method_of(const Options& options, FrictionLaw law) {
  return options.method.value_or(default_method(law));
}

/// Largest number of output rows a run may produce (about 0.6 GB in memory and as much CSV):
/// a duration / output_step beyond it is refused as bad input.
inline constexpr long kMaxOutputRows = 2000000;
/// Output rows of a run: one per output_step from 0, and the last at the duration.
long output_row_count(const Options& options);

/// Load function: the loads at time t.
using LoadFunction = std::function<Loads<double>(double t)>;
/// The four-bar's loads at time t.
using FourBarLoadFunction = std::function<FourBarLoadsT<double>(double t)>;

/// Initial state of the driven links: the five-bar's two cranks; the four-bar's crank (theta1,
/// omega1; theta2 and omega2 are not used).
struct Initial {
  double theta1 = 0, theta2 = 0, omega1 = 0, omega2 = 0;
};

/// One output row: the columns of trajectory.csv (interfaces.md) plus the energy terms. Links in
/// the mechanism's order: the five-bar's cranks 1, 2 and couplers 3, 4; the four-bar's crank,
/// coupler and rocker in slots 0..2 (slot 3 unused, M2 zero, joints O, B, C, D0 in slots 0..3).
struct Row {
  double t = 0;
  std::array<double, kLinks> theta{}, omega{}, alpha{};  ///< links 1..4
  double M1 = 0, M2 = 0;
  std::array<double, kJoints> N{}, Mf{};
  double P_diss = 0, E_diss = 0, W_in = 0, W_ext = 0;
  double kinetic = 0, potential = 0;
  JointModes mode{};  ///< joint modes (written as ints: slip direction +1/-1, 0 at rest, 2 stuck)
  std::array<double, kJoints> bristle{};  ///< LuGre bristle states z_k [rad] (zero for other laws)
  bool has_bristle = false;         ///< bristle holds a simulated state (LuGre runs)
  /// inverse_rows, stuck joints (mode 2): mu_s r_k N_k, the friction torque that could be added
  /// at that joint alone before it slips [N m] (rest.h)
  std::array<double, kJoints> hold_margin{};
  /// inverse_rows: M1_min, M1_max, M2_min, M2_max over which static friction holds the row [N m]:
  /// M itself where the crank moves, M -+ hold_margin where it is stuck alone, and with both
  /// cranks stuck (the pose at rest) each actuator's range with the other at its row value
  /// (friction at all five joints, as the simulator's lock; rest.h)
  std::array<double, 4> hold_range{};
  /// every driven joint stuck (inverse_rows' rest rule): the pose held still. `cranks` 2: the
  /// five-bar's O and D0 (slots 0, 4); 1: the four-bar's O (with one degree of freedom, all)
  bool at_rest(int cranks) const {
    return mode[0] == kStuck && (cranks == 1 || mode[4] == kStuck);
  }
  /// relative rate of the five-bar's joint k (0-based, O, B, C, D, D0) from the link rates [rad/s]
  double omega_rel(int k) const {
    switch (k) {
      case 0: return omega[0];
      case 1: return omega[2] - omega[0];
      case 2: return omega[3] - omega[2];
      case 3: return omega[1] - omega[3];
      default: return omega[1];
    }
  }
};

/// relative rate of the four-bar's joint k (0-based, O, B, C, D0) from a row's link rates
/// (crank, coupler, rocker in slots 0..2) [rad/s]; 0 for k >= 4
inline double four_bar_omega_rel(const Row& r, int k) {
  switch (k) {
    case 0: return r.omega[0];
    case 1: return r.omega[1] - r.omega[0];
    case 2: return r.omega[2] - r.omega[1];
    case 3: return r.omega[2];
    default: return 0.0;
  }
}

struct Stats {
  long rhs_evaluations = 0;
  long steps = 0;
  long friction_events = 0;  ///< located switches: rate zero crossings, sticks, breakaways
  long stick_events = 0;     ///< of which: a joint stuck
  long breakaway_events = 0; ///< of which: a stuck joint slipped again
  /// joint-mode decisions taken (at the start, at every switch and breakaway): each one chooses
  /// the unique consistent combination of slip directions and stuck joints
  long mode_decisions = 0;
  /// slipping joints whose direction disagreed with the sign of their rate (beyond 1e-6 rad/s)
  /// at a decision (a switch missed by the detection); always 0 unless the detection is broken
  long mode_corrections = 0;
  /// decisions (with joints at rest that may move) at which the simpler sign rule (slip the way
  /// the joint accelerates, iterated; never stick) would have chosen inconsistent modes
  long sign_rule_inconsistent = 0;
  double wall_time_s = 0;
};

struct Result {
  Status status;          ///< not ok: rows hold what was computed up to the failure
  std::vector<Row> rows;  ///< on the output grid
  Stats stats;
};

/// Simulates the mechanism from `initial` over [0, options.duration].
Result simulate(const Params<double>& params, const LoadFunction& loads, const Initial& initial,
                const Options& options);
/// The four-bar (four_bar.h): the same events, joint modes, lock and checks. Its joints stick
/// only together (one degree of freedom: one stuck joint holds them all), as the lock.
Result simulate(const FourBarParamsT<double>& params, const FourBarLoadFunction& loads,
                const Initial& initial, const Options& options);

/// The words of a load that is NaN or infinite at t (a load expression that leaves its domain):
/// the simulator's run check and the commands' check before their work say it alike.
std::string non_finite_load(const char* name, double value, double t);

/// Inverse dynamics along a motion: uses t, theta[0..1], omega[0..1], alpha[0..1] of each row and
/// returns rows with the coupler kinematics, reactions, friction torques, and M1, M2 the torques
/// that produce the motion under `loads` (whose M1, M2 are ignored). E_diss by the trapezoidal rule.
Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out);

/// The same with the rest rule of rest.h and these thresholds (the overload above uses the
/// defaults of RestThresholds, meant for computed rates): a joint with |w_k| <= rest.rate is at
/// rest; at rest with |dw_k/dt| <= rest.acceleration it is stuck (mode 2, hold_margin set, no
/// friction torque). A crank stuck this way stands still: the row's torques, reactions and
/// coupler rates are computed with its rate and acceleration at exactly zero (both cranks: the
/// frictionless equilibrium of the pose). mode receives each joint's Coulomb sign or 2.
Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out,
                    const RestThresholds& rest);
/// The four-bar: uses t, theta[0], omega[0], alpha[0] (the crank) and returns the coupler's and
/// the rocker's kinematics in slots 1, 2, the reactions and friction torques of joints O, B, C,
/// D0, and M1. With one degree of freedom the crank at rest stands the whole mechanism still:
/// every joint stuck, hold_range[0..1] the range of M1 over which the locked mechanism holds (as
/// the simulator's lock decides it), hold_range[2..3] zero.
Status inverse_rows(const FourBarParamsT<double>& params, const FourBarLoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out,
                    const RestThresholds& rest = {});

/// Checks of a finished run (summary.json). A run whose checks fail is not ok: `verdict` names
/// the check, the time and the joint.
struct RunChecks {
  /// max_t |d(KE + PE) - W_in - W_ext + E_diss| divided by the largest of |W_in| + |W_ext|,
  /// E_diss, |d(KE + PE)|, KE and |PE - PE(0)| over the run (an energy scale every run has)
  double energy_balance_relative = 0;
  /// max |M_inverse - M_input| over the rows [N m], inverse dynamics with the run's slip
  /// directions; rows with a stuck joint are left out (their holding torque is statically
  /// indeterminate in inverse dynamics). A row where inverse dynamics fails is not counted here:
  /// it fails the checks, and the verdict gives its time and reason
  double inverse_dynamics_max_abs_error = 0;
  /// the time of the first row where inverse dynamics fails [s]; NaN where none does
  double inverse_failed_at = std::numeric_limits<double>::quiet_NaN();
  /// min over rows and joints of Mf_k w_k [W]: friction never supplies power (not checked for
  /// LuGre, whose bristles store and return energy)
  double friction_power_min = 0;
  /// thresholds: energy balance max(1e-6, 1e3 rtol), at most 1e-3, and never below 100 atol [J]
  /// over the run's energy scale (the energy quadratures are integrated to atol); inverse residual
  /// 1e-8 N m per N m of peak input torque (at least 1e-8); friction power -1e-9 W per N m of
  /// peak friction torque
  double energy_tol = 0, inverse_tol = 0, power_tol = 0;
  double energy_scale = 0;  ///< [J] the scale the balance is relative to
  Status verdict;
};
/// `atol` < 0: the same as rtol (the scenes' usual rtol = atol).
RunChecks check_run(const Params<double>& params, const LoadFunction& loads, const Result& result,
                    double rtol = 1e-10, double atol = -1);
RunChecks check_run(const FourBarParamsT<double>& params, const FourBarLoadFunction& loads,
                    const Result& result, double rtol = 1e-10, double atol = -1);

}  // namespace fivebar::sim
