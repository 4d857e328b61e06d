// Internal to identification: the model check's candidate causes and their comparison, over a
// whitened Jacobian J of the residual r and the index sets of its columns (fitted, inertial,
// angle offsets, torque readings, delay). The five-bar's model_check (stage_model_check.cc) and
// the four-bar's (four_bar_model_check.cc) build their J and decide with these.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/parameters.h"
#include "fivebar/model/evaluation.h"
#include "fivebar/model/params.h"
#include "misfit.h"

namespace fivebar::identification::stages {

/// The columns of a drive's residual r = tau - M on its motor's friction coefficients (Coulomb,
/// viscous: d r / d c, d r / d v) at its crank's rate w and acceleration a: the motor's friction
/// torque c s + v w (s the joint law's Coulomb direction, actuator.h) acts between the ground and
/// the crank, so that at given accelerations it adds to that drive's torque alone (the reactions
/// do not see it): -(s, w), and 0 where the crank is held (the rest rule of inverse dynamics,
/// EvalOptions::rest_rate and rest_acceleration).
Eigen::Vector2d motor_friction_columns(const FrictionParams<double>& fp, const EvalOptions& eval,
                                       double w, double a);

/// Whether a column of the check varies over the samples by at least kOffsetSpread of its mean
/// (rms about the mean): else it is nearly an offset, which the torque readings' cause frees
/// (with both free, constant drive torques of 40 N m read back an offset of -170 N m and a gain
/// of 424 %; a crank that never reverses makes its motor's Coulomb column an offset exactly)
constexpr double kOffsetSpread = 0.1;
bool unlike_an_offset(const Eigen::Ref<const Eigen::VectorXd>& v);

/// The motors' friction columns of a check that has `actuators` drives: from D, one candidate
/// column per drive's Coulomb then viscous coefficient (actuator_coulomb_1, .., actuator_viscous_1,
/// .., as motor_friction_columns gives them per sample), those unlike an offset. `terms`: each
/// kept column's actuator term (actuator_term_name).
std::vector<int> motor_terms(const Eigen::MatrixXd& D, int actuators);

/// What a freed step of the motors' cause reads: "actuator_coulomb_1 0.05 +- 0.01 N m, ..." of
/// its extras, the actuator terms `terms` (motor_terms)
std::string motor_reading(const detail::FreedStep& fs, const std::vector<int>& terms,
                          int actuators);

/// model_check: a friction move beyond this many std (its own, or the move's) is a warning
constexpr double kFreedMove = 3.0;

/// The candidate causes of model_check, in the order of check_jacobian's idx[1..4] (the motors'
/// friction only where the fit leaves it out: motor_columns), then the torque-to-angle delay
/// (idx[5]: one column, the logged torques' rates). The delay competes in
/// the falls of one cost (most_explaining_cause, cause_explaining_most, delay_verdict) but not in
/// the model causes' evidence beyond each other (detail::model_causes), which a delay does not
/// explain: a cause of the model stays named as it was without the delay's column.
enum CauseId { kCauseInertia, kCauseAngles, kCauseTorque, kCauseMotors, kCauseDelay, kCauseCount };

/// The index sets of a check's columns: the fitted parameters', then each cause's (CauseId + 1)
using CauseColumns = std::array<std::vector<int>, kCauseCount + 1>;

/// Every cause's bit
constexpr unsigned kAllCauses = (1u << kCauseCount) - 1;

/// model_check runs only with at least this many residuals per column of its Jacobian (25
/// samples of a 0.05 s log against 22 freed columns read offsets of 43 N m)
constexpr int kCheckRowsPerColumn = 10;

/// model_check's freed steps: each candidate cause whose columns the check has (the inertias
/// only when they are not fitted) freed alone, all of them together, and the causes the log
/// evidences (detail::model_causes: each beyond what the others' parameters explain, and
/// explaining kExplainedExcess of the whitened residual's excess over its length).
struct CauseSteps {
  std::array<detail::FreedStep, kCauseCount> alone;  ///< not ok: no candidate
  detail::FreedStep all;
  std::vector<IdentifyResult::MisfitCause> report;    ///< IdentifyResult::model_check ("any" last)
  std::array<int, kCauseCount> slot{-1, -1, -1, -1, -1};  ///< each cause's entry in `report`
  bool named(int id) const { return slot[id] >= 0 && report[slot[id]].evidenced; }
  /// evidence alone [std of noise's]
  double z(int id) const { return slot[id] >= 0 ? report[slot[id]].z : 0.0; }
  /// a model cause (any but the delay) named
  bool any() const {
    for (int id = 0; id < kCauseDelay; ++id) {
      if (named(id)) return true;
    }
    return false;
  }
};

/// model_check's candidate causes by CauseId: the name in identification.json, the words, and
/// the words of a reason that names the cause (the torque readings' reasons say which reading)
struct CauseText {
  const char* name;
  const char* what;
  const char* off;
};

constexpr CauseText kCauseText[kCauseCount] = {
    {"inertia", "the links' inertial parameters",
     "the scene's masses or inertias do not match the log (or its lengths, gravity or loads: "
     "the links' inertial parameters absorb those too)"},
    {"angle_offsets", "the encoders' zeros",
     "the logged angles' zeros are off (subtract the offsets the warning reads from the logged "
     "angles)"},
    {"torque_readings", "the torque sensors' offsets and gains",
     "the logged torques' zeros or gains are off"},
    {"motor_friction", "the motors' friction coefficients",
     "the motors' (gearboxes') friction is not the scene's (fit it: --estimate friction,actuator)"},
    {"delay", "the torque readings' times (a delay)", "the logged torques are delayed"}};

/// The friction coefficients a freed step moves beyond kFreedMove std, as "name from a to b
/// (k std)": the std of the estimate (or `judged`, one per friction coefficient, when given), or
/// with `own` the larger of it and the move's own std (the test of Hausman); empty if none moves
/// so, or one is at its bound (which has its own warning). *largest: the largest such move [std].
std::string friction_moves(const ParameterLayout& layout, const IdentifyResult& out,
                           const detail::FreedStep& fs, bool own, double* largest = nullptr,
                           const Eigen::VectorXd* judged = nullptr);

/// The freed steps of the causes whose columns idx[1..5] holds (idx[0]: the fitted parameters;
/// info: the inertial columns' prior information; bias: the score's expectation, empty: none):
/// the model causes (inertia, angle offsets, torque readings) alone, together and beyond each
/// other; the motors' friction and the delay alone and beyond the model causes, whose evidence
/// they do not enter (the motors' friction named by motors_named in model_check_causes.cc);
/// `attributable`: a cause may be named below kExplainsAll of the excess.
CauseSteps cause_steps(const Eigen::MatrixXd& J, const Eigen::VectorXd& r, const CauseColumns& idx,
                       const Eigen::VectorXd& info, const Eigen::VectorXd& bias, bool attributable);

/// "the residual falls by D (noise alone: m +- s)" of a freed step
std::string drop_clause(const detail::FreedStep& fs);

/// "B with <other>, C with <other>": the falls of the other candidates checked than `best`
std::string other_falls(const CauseSteps& cs, int best);

/// Whether cause id competes in the comparisons of falls (most_explaining_cause,
/// cause_explaining_most, the delay's verdict, decisive_model_error): checked, its step ok and
/// evidenced alone (z above kCauseZ); the motors' friction (judged alone and beyond the model
/// causes, as the delay: cause_steps) only where also evidenced beyond them and read as a
/// friction (no coefficient below 0 beyond kFreedMove std)
bool competes(const CauseSteps& cs, int id);

/// Whether an entry of a check's report (IdentifyResult::model_check) is a model cause that
/// counts by its evidence alone: not the delay, not "any", and the motors' friction only where
/// named
bool counts_alone(const IdentifyResult::MisfitCause& c);

/// Whether candidate k, evidenced alone (z above kCauseZ), lowers the cost clearly more than
/// candidate id (cause_explaining_most's "clearly")
bool clearly_more(const CauseSteps& cs, int k, int id);

/// The cause whose refit alone explains most of the misfit among those evidenced alone
/// (kCauseCount: none)
int most_explaining_cause(const CauseSteps& cs);

/// "the residual falls by A with <best> free, against B with <other>, ..."
std::string falls_clause(const CauseSteps& cs, int best);

/// The cause a reason names: `what`, or another candidate among `others` that explains clearly
/// more (or as much: both named)
std::string cause_explaining_most(const CauseSteps& cs, int id, unsigned others,
                                  const std::string& what);

/// Evidence of a cause beyond the other causes' parameters (or alone, with none named) this many
/// times kCauseZ makes the fit unusable even with the residual at its floor (the light
/// mechanism's multi-sine log with tau1 x 0.9: 69 std, coulomb 0.048 for 0.12, and no warning;
/// clean logs read -2 to 2)
constexpr double kDecisiveCauseZ = 4 * detail::kCauseZ;

/// The cause a reason names for the model error: of the causes the check names (inertia,
/// encoders' zeros, torque readings), the one with the largest fall (attributed_what names
/// another that explains clearly more instead); kCauseCount: none.
int named_cause(const CauseSteps& cs);

/// The words of a reason for the named cause `id` (cause_explaining_most)
std::string attributed_what(const CauseSteps& cs, int id);

/// A model error the log evidences decisively that the checks before leave usable makes the fit
/// unusable (the first reason stays):
/// - the cause named (named_cause), evidenced beyond the other causes by more than
///   kDecisiveCauseZ, would move a friction coefficient beyond kFreedMove std (`moves`, its
///   largest move `largest` [std], 0: from a bound): an encoder 0.005 rad off a heavy five-bar,
///   read at 1877 std beyond the others, coulomb 3.6 std, viscous 5.2 std;
/// - a cause alone beyond kDecisiveCauseZ while no cause stands out beyond the others (the
///   masses and inertias scaled alike read as both torque gains off alike), or while the cause
///   named explains clearly less than another: whatever the linearized move of the friction,
///   which the small windows' noise, chosen by such an error, understates (a heavy five-bar's
///   links 3 % lighter than the scene: viscous 36 std off, the inertias' refit moving it less
///   than 3 std; evidence alone 52 std for the inertias, 95 for the torque readings, where clean
///   logs of three mechanisms read at most 16). The reason names the cause that explains most,
///   the inertias where they explain as much (a common scale of the torques is the masses').
void decisive_model_error(const CauseSteps& cs, bool moves, double largest, IdentifyResult* out);

/// A model error (what: its cause, or that none is named) that would move a friction
/// coefficient by `largest` std makes the fit unusable beyond kUnusableMove; largest 0: a
/// friction coefficient is at its bound, so the move cannot be given. The first reason stays.
void unusable_move(double largest, const std::string& what, IdentifyResult* out);

}  // namespace fivebar::identification::stages
