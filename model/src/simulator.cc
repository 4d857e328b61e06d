// Event-driven simulation: the friction-aware right-hand side, root finding on the relative joint
// rates (where sign(w) jumps), restarts at every switch, and output rows on the scene's grid.
#include "fivebar/sim/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/five_bar_mechanism.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/four_bar_rest.h"
#include "fivebar/model/lock.h"
#include "fivebar/model/names.h"
#include "fivebar/model/rest.h"
#include "integrator.h"

namespace fivebar::sim {

namespace {
constexpr Named<Method> kMethodNames[] = {
    {Method::kCvodeAdams, "cvode_adams"},   {Method::kCvodeBdf, "cvode_bdf"},
    {Method::kArkodeErk45, "arkode_erk45"}, {Method::kArkodeErk87, "arkode_erk87"},
    {Method::kArkodeDirk, "arkode_dirk"},   {Method::kArkodeErk65, "arkode_erk65"}};
}  // namespace

const char* method_name(Method m) { return name_in(kMethodNames, m); }

bool parse_method(const std::string& name, Method* out) { return parse_in(kMethodNames, name, out); }

namespace {

/// The state of a mechanism with n degrees of freedom: q (n angles), v (n rates), E_diss, W_in,
/// W_ext; a law with internal states (LawDescriptor::states_per_joint: LuGre's bristles z_k)
/// adds them from base_states(n) on.
constexpr int base_states(int dof) { return 2 * dof + 3; }
/// the longest state: the base states of the largest mechanism and the internal states of the
/// law that has the most
constexpr int kMaxStates = base_states(2) + kJoints * kMaxStatesPerJoint;
static_assert(kMaxStatesPerJoint <= 1, "forward_dynamics carries one internal state per joint");
/// interior points of every step at which the switch functions are sampled (a rate that
/// crosses zero and comes back within one step is seen if it stays across for a quarter step)
constexpr int kSamples = 3;
/// a joint whose |w| is below this at a decision is at rest [rad/s] (a located crossing leaves
/// |w| ~ 1e-13; drift of a stuck coupler joint's rate stays near the integration tolerance)
constexpr double kRestRate = 1e-9;
/// crank rates below this [rad/s] may be set to zero when two constraints say the mechanism is at
/// rest (the drift of a stuck coupler joint's rate leaves ~1e-8)
constexpr double kRestProjection = 1e-6;
/// a switch function that is exactly zero after a decision (a joint that starts to slip from
/// rest) is armed once it is positive; before that it fires only below -kUnarmedSlack
constexpr double kUnarmedSlack = 1e-9;
/// switches closer than this [s, relative to t] count as one instant; more than
/// kMaxSwitchesAtOnce of them means the modes chatter (no consistent motion)
constexpr double kSameInstant = 1e-12;
constexpr int kMaxSwitchesAtOnce = 64;

/// Switch functions: one per joint, and the lock margin 1 - s of a locked mechanism (slot 5).
using Switches = std::array<double, 6>;
constexpr int kLockSlot = 5;
/// relaxed consistency, used only when no combination is strictly consistent (at a located
/// breakaway the accelerations of the joints that start to slip are ~0 and round-off and the
/// location decide their signs): relative accelerations >= -kSlackAccel times the largest
/// relative acceleration of the candidate (at least 1 rad/s^2), margins >= -kSlackTorque times
/// the largest friction torque (at least 1 N m)
constexpr double kSlackAccel = 1e-9;
constexpr double kSlackTorque = 1e-9;

/// angle continued from the previous row's value (no 2 pi jumps in the output)
double continued(double angle, const Row* previous, int k) {
  if (!previous) return angle;
  // remainder(d, 2 pi) is d itself for |d| <= pi (the quotient rounds to 0): the common case,
  // consecutive rows, without the library call
  const double d = angle - previous->theta[k];
  return previous->theta[k] + (std::abs(d) <= M_PI ? d : std::remainder(d, 2 * M_PI));
}

/// What the simulator needs of a mechanism beyond the dynamics (mechanism.h): its types, where
/// its links and drives go in a Row, its energies and its joints' names and static capacity.
/// Row columns: the driven angles q first, then the dependent links.
template <class M>
struct Sim;

template <>
struct Sim<FiveBar> {
  using P = Params<double>;
  using Ld = Loads<double>;
  using K = Kinematics<double>;
  using E = Evaluation<double>;
  static constexpr int kDof = 2;
  /// the joint whose relative rate is driven rate i (the cranks' O and D0)
  static int driven_joint(int i) { return i == 0 ? 0 : 4; }
  static const char* joint(int k) {
    static const char* names[kJoints] = {"O", "B", "C", "D", "D0"};
    return names[k];
  }
  static void set_initial(const Initial& i, double* y) {
    y[0] = i.theta1;
    y[1] = i.theta2;
    y[2] = i.omega1;
    y[3] = i.omega2;
  }
  static std::array<std::pair<const char*, double>, 5> load_values(const Ld& L) {
    return {{{"M1", L.M1}, {"M2", L.M2}, {"M3", L.M3}, {"F", L.F}, {"F_angle", L.F_angle}}};
  }
  /// the couplers' angles and rates from the first-order kinematics
  static void dependent_links(const K& k, const double* y, const Row* previous, Row* row) {
    const Vec2<double> thd(y[2], y[3]);
    row->theta[2] = continued(k.th3, previous, 2);
    row->theta[3] = continued(k.th4, previous, 3);
    row->omega[2] = k.G3.dot(thd);
    row->omega[3] = k.G4.dot(thd);
  }
  static void evaluated_links(const E& ev, const Row* previous, Row* row) {
    row->theta[2] = continued(ev.kin.th3, previous, 2);
    row->theta[3] = continued(ev.kin.th4, previous, 3);
    row->omega[2] = ev.bias.w3;
    row->omega[3] = ev.bias.w4;
    row->alpha[2] = ev.alpha3;
    row->alpha[3] = ev.alpha4;
  }
  static void drives(const Ld& L, Row* row) {
    row->M1 = L.M1;
    row->M2 = L.M2;
  }
  static double drive_error(const E& ev, const Row& r) {
    return std::max(std::abs(ev.M1 - r.M1), std::abs(ev.M2 - r.M2));
  }
  /// inverse dynamics: the drive torques that produce the row's motion
  static void computed_drives(const E& ev, Row* row) {
    row->M1 = ev.M1;
    row->M2 = ev.M2;
  }
  static Status hold_range(const P& p, const Ld& L, const EvalOptions& eval, Row* r);
  static std::array<double, kJoints> joint_accelerations(const E& ev) {
    return fivebar::relative_accelerations(ev.thdd, ev.alpha3, ev.alpha4);
  }
  static double joint_rate(const Row& r, int k) { return r.omega_rel(k); }
  static double kinetic(const P& p, const K& k, const double* v) {
    return kinetic_energy(p, k, v[0], v[1]);
  }
  static double potential(const P& p, const K& k) { return potential_energy(p, k); }
  static bool can_hold(const P& p, int k) { return fivebar::can_hold(p, k); }
};

template <>
struct Sim<FourBar> {
  using P = FourBarParams;
  using Ld = FourBarLoads;
  using K = FourBarKinematics;
  using E = FourBarEvaluation;
  static constexpr int kDof = 1;
  static int driven_joint(int) { return 0; }
  static const char* joint(int k) {
    static const char* names[kJoints] = {"O", "B", "C", "D0", "-"};
    return names[k];
  }
  static void set_initial(const Initial& i, double* y) {
    y[0] = i.theta1;
    y[1] = i.omega1;
  }
  static std::array<std::pair<const char*, double>, 4> load_values(const Ld& L) {
    return {{{"M1", L.M1}, {"M3", L.M3}, {"F", L.F}, {"F_angle", L.F_angle}}};
  }
  /// the coupler's and the rocker's angles and rates from the first-order kinematics
  static void dependent_links(const K& k, const double* y, const Row* previous, Row* row) {
    row->theta[1] = continued(k.th2, previous, 1);
    row->theta[2] = continued(k.th3, previous, 2);
    row->omega[1] = k.G2 * y[1];
    row->omega[2] = k.G3 * y[1];
  }
  static void evaluated_links(const E& ev, const Row* previous, Row* row) {
    row->theta[1] = continued(ev.kin.th2, previous, 1);
    row->theta[2] = continued(ev.kin.th3, previous, 2);
    row->omega[1] = ev.bias.w2;
    row->omega[2] = ev.bias.w3;
    row->alpha[1] = ev.alpha2;
    row->alpha[2] = ev.alpha3;
  }
  static void drives(const Ld& L, Row* row) { row->M1 = L.M1; }
  static double drive_error(const E& ev, const Row& r) { return std::abs(ev.M1 - r.M1); }
  static void computed_drives(const E& ev, Row* row) { row->M1 = ev.M1; }
  static Status hold_range(const P& p, const Ld& L, const EvalOptions& eval, Row* r);
  static std::array<double, kJoints> joint_accelerations(const E& ev) {
    return FourBar::joint_accelerations(ev.kin, ev.bias, ev.thdd);
  }
  static double joint_rate(const Row& r, int k) { return four_bar_omega_rel(r, k); }
  static double kinetic(const P& p, const K& k, const double* v) {
    return four_bar_kinetic(p, k, v[0]);
  }
  static double potential(const P& p, const K& k) { return four_bar_potential(p, k); }
  static bool can_hold(const P& p, int k) {
    return fivebar::can_hold(p.friction, p.actuators, kFourBarActuators, k);
  }
};

template <class M>
using ParamsOf = typename Sim<M>::P;
template <class M>
using LoadsOf = typename Sim<M>::Ld;
template <class M>
using KinOf = typename Sim<M>::K;
template <class M>
using EvalOf = typename Sim<M>::E;
template <class M>
using VecOf = mech::Vec<M::kDof, double>;
template <class M>
using LoadFnOf = std::function<LoadsOf<M>(double)>;

/// q and v of a state y
template <class M>
VecOf<M> q_of(const double* y) {
  return Eigen::Map<const VecOf<M>>(y);
}
template <class M>
VecOf<M> v_of(const double* y) {
  return Eigen::Map<const VecOf<M>>(y + M::kDof);
}

/// The closure at a state's angles: `margin` the singular margin, `angles` whether the dependent
/// angles themselves are needed.
template <class M>
Status close_at(const ParamsOf<M>& p, const double* y, KinOf<M>* k, double margin = 0.0,
                bool angles = true) {
  EvalOptions opt;
  opt.singular_margin = margin;
  opt.want_angles = angles;
  return M::close(p, q_of<M>(y), k, opt);
}

/// Forward dynamics of M at the state y (its angles and rates).
template <class M>
Status forward_at(const ParamsOf<M>& p, const LoadsOf<M>& L, const double* y,
                  const JointModes* slip, const EvalOptions& opt, EvalOf<M>* ev,
                  const std::array<double, kJoints>* bristle = nullptr,
                  FrictionWarmStart* warm = nullptr) {
  return mech::forward<M, double>(p, L, q_of<M>(y), v_of<M>(y), slip, opt, ev, bristle, warm);
}

/// What the C callbacks and the event loop see.
template <class M>
struct Context {
  const ParamsOf<M>* params = nullptr;
  const LoadFnOf<M>* loads = nullptr;
  EvalOptions eval;
  bool use_slip = false;                ///< Coulomb sign from the segment's slip directions
  bool stick = false;                   ///< exact stick-slip (Options::stick, with use_slip)
  JointModes slip{};            ///< mode of each joint in this segment
  bool locked = false;                  ///< all joints stuck, held as lock_analysis finds
  bool decided = false;                 ///< the modes have been decided once (at the start)
  /// switches not located, exact sign: a joint whose rate is exactly zero takes the direction
  /// in which it starts to slip (zero_sign, decided at the start), not sign(0) = 0
  bool zero_signs = false;
  JointModes zero_sign{};
  bool frozen = false;                  ///< signs frozen for a Newton Jacobian (freeze_signs)
  JointModes frozen_sign{};
  std::array<bool, kJoints> watched{};        ///< joints with a Coulomb part: switch functions
  bool law_states = false;  ///< the law's internal states (LuGre bristles) follow the base states
  bool full_rows = true;                ///< Options::full_rows
  int n = base_states(M::kDof);         ///< state size
  long rhs_evaluations = 0;
  Status failure;                       ///< last failure inside a callback
  /// the last right-hand side that failed and the integrator recovered from (a smaller step),
  /// and how many did since the last output row: what a run that stalls is stalled by
  Status recovered;
  long recovered_since_row = 0;
  /// the right-hand side's last friction-loop solution: the next evaluation starts from it
  FrictionWarmStart warm;
  /// the same for the output rows (make_row), one output step apart
  FrictionWarmStart row_warm;
  /// the last right-hand side's point and, from its evaluation, what the switch scan and the
  /// singular-margin check need at a step's end (StepEnd): Dormand-Prince's last stage is the
  /// step's end itself
  struct LastEvaluation {
    bool ok = false;
    double t = 0.0;
    double y[kMaxStates] = {};
    double singular = 0.0;
    std::array<double, kJoints> w{}, wdot{};
  } last;
  /// the loads at the time of the last right-hand side or row (loads_at)
  double loads_time = std::numeric_limits<double>::quiet_NaN();
  LoadsOf<M> loads_then{};
  Status loads_status;
  /// the forward dynamics at one point (t, q, v) in each set of joint modes tried there
  /// (forward_in_modes): a mode decision evaluates the same modes several times (the candidates,
  /// the sign rule, the consistency checks)
  struct PointEvaluations {
    struct InModes {
      JointModes slip;
      Status status;
      EvalOf<M> ev;
    };
    double t = std::numeric_limits<double>::quiet_NaN();
    double qv[2 * M::kDof] = {};
    std::vector<InModes> tried;
  } at_point;
};

/// The status with the time and the driven angles first (theta1 .. theta_dof of `q`).
Status at_time(const Status& st, double t, const double* q, int dof) {
  std::ostringstream msg;
  msg.precision(6);
  msg << "at t=" << t << " s (";
  for (int i = 0; i < dof; ++i) msg << (i ? ", theta" : "theta") << i + 1 << "=" << q[i];
  msg << "): " << st.message;
  return Status::Error(st.code, msg.str());
}
template <class M>
Status at_time(const Status& st, double t, const double* y) {
  return at_time(st, t, y, M::kDof);
}

/// The first load of L whose value `bad` holds for (its name and value), or a null name
template <class Ld, class Bad>
std::pair<const char*, double> first_load(const Ld& L, Bad bad) {
  using M = std::conditional_t<std::is_same_v<Ld, Loads<double>>, FiveBar, FourBar>;
  for (const auto& [name, v] : Sim<M>::load_values(L)) {
    if (bad(v)) return {name, v};
  }
  return {nullptr, 0.0};
}

/// Not ok when a load is NaN or infinite at t: names the load and its value (a load expression
/// that leaves its domain, e.g. sqrt(1.5 - t) after 1.5 s; no smaller step can help)
template <class Ld>
Status finite_loads(const Ld& L, double t) {
  const auto [name, v] = first_load(L, [](double x) { return !std::isfinite(x); });
  if (name != nullptr) return Status::Error(StatusCode::kInvalidInput, non_finite_load(name, v, t));
  return Status::Ok();
}

/// Whether every load of L is finite, as one test: x * 0 is +-0 for a finite x and NaN for an
/// infinite or NaN one, and so is their sum.
template <class M>
bool all_finite(const LoadsOf<M>& L) {
  double zero = 0.0;
  for (const auto& named : Sim<M>::load_values(L)) zero += named.second * 0.0;
  return zero == 0.0;
}

/// The loads at t, from the last evaluation when it was at the same time (a load function is a
/// function of t: Dormand-Prince's last two stages share their time); c.loads_status whether
/// they are finite (finite_loads), checked once per evaluation.
template <class M>
const LoadsOf<M>& loads_at(Context<M>& c, double t) {
  if (!(t == c.loads_time)) {
    c.loads_then = (*c.loads)(t);
    c.loads_time = t;
    // (the status worded only for a load that is not finite: the common case costs no message)
    if (!all_finite<M>(c.loads_then)) {
      c.loads_status = finite_loads(c.loads_then, t);
    } else if (!c.loads_status.ok()) {
      c.loads_status = Status::Ok();
    }
  }
  return c.loads_then;
}

/// Why the acceleration at t overflowed when a load is absurdly large (beyond 1e100: no machine's,
/// a load expression that grows without bound), naming it; else the plain reason.
template <class Ld>
std::string overflow_reason(const Ld& L) {
  const auto [name, v] = first_load(L, [](double x) { return std::abs(x) > 1e100; });
  if (name == nullptr) return "non-finite acceleration";
  std::ostringstream msg;
  msg.precision(6);
  msg << "non-finite acceleration: load " << name << " = " << v
      << " overflows the dynamics: check the scene's load expression (loads." << name << ")";
  return msg.str();
}

/// Forward dynamics at (t, y) in the joint modes `slip` (no warm start, no internal states): a
/// function of t, q, v and the modes alone, so each set of modes is evaluated once at a point
/// (Context::at_point) and read back when tried again there.
template <class M>
Status forward_in_modes(Context<M>& c, double t, const double* y, const JointModes& slip,
                        EvalOf<M>* ev) {
  auto& a = c.at_point;
  constexpr size_t kBytes = sizeof(a.qv);
  if (!(t == a.t) || std::memcmp(y, a.qv, kBytes) != 0) {
    a.t = t;
    std::memcpy(a.qv, y, kBytes);
    a.tried.clear();
  }
  for (const auto& m : a.tried) {
    if (m.slip != slip) continue;
    *ev = m.ev;
    return m.status;
  }
  const Status st = forward_at<M>(*c.params, loads_at(c, t), y, &slip, c.eval, ev);
  a.tried.push_back({slip, st, *ev});
  return st;
}

/// Relative joint rates at a state from its first-order kinematics `k`.
template <class M>
std::array<double, kJoints> joint_rates(const KinOf<M>& k, const double* y) {
  return M::joint_rates_at(k, v_of<M>(y));
}

/// Relative joint rates at a state (needs only the first-order kinematics).
template <class M>
bool joint_rates(const ParamsOf<M>& p, const double* y, std::array<double, kJoints>* w) {
  KinOf<M> k;
  if (!close_at<M>(p, y, &k, 0.0, false).ok()) return false;
  *w = joint_rates<M>(k, y);
  return true;
}

/// Switches not located (Context::zero_signs): the Coulomb sign of each joint from its rate at y,
/// or the direction decided at the start where the rate is exactly zero.
template <class M>
bool state_signs(const Context<M>& c, const double* y, JointModes* signs) {
  std::array<double, kJoints> w;
  if (!joint_rates<M>(*c.params, y, &w)) return false;
  for (int k = 0; k < kJoints; ++k) (*signs)[k] = w[k] != 0.0 ? slip_mode(sign_of(w[k])) : c.zero_sign[k];
  return true;
}

/// OdeProblem::freeze: the signs at y hold for every evaluation until released.
template <class M>
void freeze_signs(const double* y, bool on, void* user) {
  auto& c = *static_cast<Context<M>*>(user);
  c.frozen = on && c.zero_signs && state_signs(c, y, &c.frozen_sign);
}

/// The joint modes the right-hand side uses at y: frozen for a Newton Jacobian; from the rates
/// when switches are not located (with the start's decided direction where a rate is exactly
/// zero); else the segment's (nullptr: sign(w) for laws without located switches).
template <class M>
const JointModes* rhs_modes(const Context<M>& c, const double* y, JointModes* buf) {
  if (c.frozen) return &c.frozen_sign;
  if (c.zero_signs && state_signs(c, y, buf)) return buf;
  return c.use_slip ? &c.slip : nullptr;
}

/// Keeps the point of a right-hand side and, from its evaluation, the joint rates (the
/// evaluation's, the same products and sums as joint_rates from the kinematics), their rates of
/// change and the singular measure.
template <class M>
void remember_evaluation(Context<M>& c, double t, const double* y, const EvalOf<M>& ev) {
  c.last.ok = true;
  c.last.t = t;
  std::copy(y, y + c.n, c.last.y);
  c.last.w = ev.w;
  c.last.wdot = Sim<M>::joint_accelerations(ev);
  c.last.singular = std::abs(M::singular_measure(ev.kin));
}

template <class M>
int rhs(double t, const double* y, double* ydot, void* user) {
  constexpr int n = M::kDof, kBristle = base_states(n);
  auto& c = *static_cast<Context<M>*>(user);
  ++c.rhs_evaluations;
  c.last.ok = false;
  if (c.locked) {  // at rest, held: nothing moves, no power flows
    std::fill(ydot, ydot + c.n, 0.0);
    return 0;
  }
  EvalOf<M> ev;
  std::array<double, kJoints> z{};
  if (c.law_states) std::copy(y + kBristle, y + kBristle + kJoints, z.begin());
  JointModes signs;
  const LoadsOf<M>& loads = loads_at(c, t);
  if (!c.loads_status.ok()) {
    c.failure = c.loads_status;
    return -1;  // fatal: the load is what fails, not the step
  }
  const Status st =
      forward_at<M>(*c.params, loads, y, rhs_modes(c, y, &signs), c.eval, &ev, &z, &c.warm);
  if (!st.ok()) {
    c.failure = at_time<M>(st, t, y);
    c.recovered = c.failure;
    ++c.recovered_since_row;
    return 1;  // recoverable: the integrator retries with a smaller step
  }
  if (c.law_states) std::copy(ev.zdot.begin(), ev.zdot.end(), ydot + kBristle);
  for (int i = 0; i < n; ++i) {
    ydot[i] = y[n + i];
    ydot[n + i] = ev.thdd[i];
  }
  ydot[2 * n] = ev.P_diss;
  ydot[2 * n + 1] = ev.P_in;
  ydot[2 * n + 2] = ev.P_ext;
  for (int i = n; i < c.n; ++i) {
    if (!std::isfinite(ydot[i])) {
      c.failure =
          at_time<M>(Status::Error(StatusCode::kSolverFailed, overflow_reason(loads)), t, y);
      return 1;
    }
  }
  remember_evaluation(c, t, y, ev);
  return 0;
}

bool any_stuck(const JointModes& slip) {
  return std::find(slip.begin(), slip.end(), kStuck) != slip.end();
}

/// Switch functions: s_k w_k of a slipping joint (positive while its rate keeps the slip
/// direction) and the holding margin mu_s r_k N_k - |holding torque| of a stuck one
/// (non-negative while friction holds it); +1 for joints without a Coulomb part. `rates` (may be
/// null): the joint rates at y, when the caller has them.
template <class M>
Status switch_values(Context<M>& c, double t, const double* y, Switches* g,
                     const std::array<double, kJoints>* rates = nullptr) {
  g->fill(1.0);
  if (c.locked) {
    LockAnalysis lock;
    const Status st = lock_analysis<M>(*c.params, loads_at(c, t), q_of<M>(y), c.eval, &lock);
    if (!st.ok()) return at_time<M>(st, t, y);
    (*g)[kLockSlot] = 1.0 - lock.ratio;
    return Status::Ok();
  }
  std::array<double, kJoints> w, hold{};
  if (any_stuck(c.slip)) {  // an evaluation only here: slipping joints need the rates alone
    EvalOf<M> ev;
    const Status st = forward_in_modes(c, t, y, c.slip, &ev);
    if (!st.ok()) return at_time<M>(st, t, y);
    w = ev.w;
    hold = ev.hold_margin;
  } else if (rates) {
    w = *rates;
  } else if (!joint_rates<M>(*c.params, y, &w)) {
    return at_time<M>(Status::Error(StatusCode::kCannotAssemble, "pose cannot assemble"), t, y);
  }
  for (int k = 0; k < kJoints; ++k) {
    if (!c.watched[k]) continue;
    (*g)[k] = c.slip[k] == kStuck ? hold[k] : coulomb_sign(c.slip[k]) * w[k];
  }
  return Status::Ok();
}

/// The switch functions' last values and which of them are armed (have been positive since the
/// last decision: only then does reaching zero mean a switch).
struct Watch {
  Switches g{};
  std::array<bool, 6> armed{};
  /// the switch functions' rates of change at the last step's end, when known (joints slipping)
  Switches gdot{};
  bool has_gdot = false;
};

/// What the switch scan and the singular-margin check need at a step's end: whether the pose
/// closes, its singular measure, the joint rates and, when known, their rates of change.
struct StepEnd {
  bool closes = false;
  double singular = 1.0;
  std::array<double, kJoints> w{}, wdot{};
  bool has_wdot = false;
};
using Fired = std::array<bool, 6>;

/// Switch functions that fired at the values g (joints 0..4, the lock in slot 5).
template <class M>
Fired fired(const Context<M>& c, const Watch& w, const Switches& g) {
  Fired out{};
  for (int k = 0; k < 6; ++k) {
    const bool active = k == kLockSlot ? c.locked : c.watched[k] && !c.locked;
    if (active) out[k] = w.armed[k] ? g[k] <= 0.0 : g[k] < -kUnarmedSlack;
  }
  return out;
}

template <size_t n>
bool any_of(const std::array<bool, n>& a) {
  return std::any_of(a.begin(), a.end(), [](bool b) { return b; });
}

void advance_watch(Watch* w, const Switches& g) {
  for (int k = 0; k < 6; ++k) w->armed[k] = w->armed[k] || g[k] > 0.0;
  w->g = g;
}

/// The rates of change of the slipping joints' switch functions at a step's end (s_k dw_k/dt);
/// false when they are not known there or a joint is stuck or locked.
template <class M>
bool switch_slopes(const Context<M>& c, const StepEnd& end, Switches* gdot) {
  gdot->fill(0.0);
  if (!end.has_wdot || c.locked || any_stuck(c.slip)) return false;
  for (int k = 0; k < kJoints; ++k) {
    if (c.watched[k]) (*gdot)[k] = coulomb_sign(c.slip[k]) * end.wdot[k];
  }
  return true;
}

/// Whether no switch function can reach zero inside the step of length h: each watched one
/// positive at both ends (g0, g1) and g0 + g1 > 2 max(|g0'|, |g1'|) h. A function whose rate of
/// change stays within twice the larger of its ends' cannot fall from g0 and come back to g1
/// through zero in h; the interior samples are then skipped.
template <class M>
bool interior_clear(const Context<M>& c, const Watch& w, const Switches& g1, const Switches& gdot1,
                    double h) {
  if (!w.has_gdot) return false;
  for (int k = 0; k < kJoints; ++k) {
    if (!c.watched[k]) continue;
    const double slope = 2.0 * std::max(std::abs(w.gdot[k]), std::abs(gdot1[k]));
    if (!(w.g[k] > 0.0 && g1[k] > 0.0 && w.g[k] + g1[k] > slope * h)) return false;
  }
  return true;
}

/// Scans the last step (tp, tc] for the first point where a switch function fired: kSamples
/// interior points of the cheap interpolant (confirmed on the dense output; skipped where
/// interior_clear), then the step's end `end`. Found: true with the bracket [*ta, *tb]. Not
/// found: the watch moves to tc.
template <class M>
Status scan_step(Context<M>& c, detail::Integrator& integ, double tp, double tc, const double* yc,
                 const StepEnd& end_values, Watch* watch, bool* found, double* ta, double* tb) {
  *found = false;
  Watch w = *watch;
  double y[kMaxStates];
  double t_prev = tp;
  const std::array<double, kJoints>* end_rates = end_values.closes ? &end_values.w : nullptr;
  Switches gdot_end;
  const bool slopes = switch_slopes(c, end_values, &gdot_end);
  int first = 1;
  Switches g_end;  // the step end's switch values, when computed here (slopes)
  if (slopes) {
    const Status st = switch_values(c, tc, yc, &g_end, end_rates);
    if (!st.ok()) return st;
    if (interior_clear(c, w, g_end, gdot_end, tc - tp)) first = kSamples + 1;
  }
  for (int i = first; i <= kSamples + 1; ++i) {
    const bool end = i == kSamples + 1;
    const double ti = end ? tc : tp + (tc - tp) * i / (kSamples + 1);
    if (end) {
      std::copy(yc, yc + c.n, y);
    } else if (!integ.sample(ti, y)) {  // the right-hand side failed: say why
      return c.failure.ok() ? Status::Error(StatusCode::kSolverFailed, integ.error()) : c.failure;
    }
    Switches g = g_end;
    Status st =
        end && slopes ? Status::Ok() : switch_values(c, ti, y, &g, end ? end_rates : nullptr);
    if (!st.ok()) return st;
    if (!end && any_of(fired(c, w, g))) {  // confirm on the accurate interpolant
      if (!integ.dense(ti, y)) return Status::Error(StatusCode::kSolverFailed, integ.error());
      st = switch_values(c, ti, y, &g);
      if (!st.ok()) return st;
    }
    if (any_of(fired(c, w, g))) {
      *found = true;
      *ta = t_prev;
      *tb = ti;
      return Status::Ok();
    }
    advance_watch(&w, g);
    t_prev = ti;
  }
  w.gdot = gdot_end;
  w.has_gdot = slopes;
  *watch = w;
  return Status::Ok();
}

/// Bisection on the integrator's dense output: `crossed(t, y, &past)` says whether the event
/// has happened at (t, y); false at *ta, true at *tb. Narrows [*ta, *tb] to the time resolution
/// of doubles at *tb; y holds the last state evaluated.
template <typename Crossed>
Status bisect_dense(detail::Integrator& integ, double* ta, double* tb, double* y,
                    Crossed&& crossed) {
  const double tol = 8 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(*tb));
  while (*tb - *ta > tol) {
    const double tm = 0.5 * (*ta + *tb);
    if (!integ.dense(tm, y)) return Status::Error(StatusCode::kSolverFailed, integ.error());
    bool past = false;
    const Status st = crossed(tm, y, &past);
    if (!st.ok()) return st;
    (past ? *tb : *ta) = tm;
  }
  return Status::Ok();
}

/// Bisection on the dense output of [ta, tb] (nothing fired at ta, something at tb) down to
/// the time resolution of doubles at tb; y receives the state at the located tb, `which` the
/// switch functions that fired there.
template <class M>
Status locate_switch(Context<M>& c, detail::Integrator& integ, const Watch& watch, double ta,
                     double tb, double* y, double* te, Fired* which) {
  Switches g;
  Status st = bisect_dense(integ, &ta, &tb, y, [&](double t, const double* yt, bool* past) {
    const Status s = switch_values(c, t, yt, &g);
    *past = s.ok() && any_of(fired(c, watch, g));
    return s;
  });
  if (!st.ok()) return st;
  if (!integ.dense(tb, y)) return Status::Error(StatusCode::kSolverFailed, integ.error());
  st = switch_values(c, tb, y, &g);
  if (!st.ok()) return st;
  *which = fired(c, watch, g);
  *te = tb;
  return Status::Ok();
}

/// Projects the driven rates v so that the joints in `mask` do not move (w_k = 0): fewer
/// independent constraints than degrees of freedom leave the others free, as many bring the
/// mechanism to rest. Returns the number of independent constraints. After a located switch
/// |w_k| is at the location tolerance; projecting makes the decided state exact (a stuck crank
/// exactly at rest). A joint whose rate is zero because its row of J_w is (a kinematic zero, as
/// a four-bar rocker's reversal while the crank turns) is not held: the projection would move
/// v by more than kRestProjection, and nothing is projected.
template <class M>
int project_rates(const ParamsOf<M>& p, const std::array<bool, kJoints>& mask, double* y) {
  constexpr int n = M::kDof;
  KinOf<M> k;
  if (!close_at<M>(p, y, &k).ok()) return 0;
  std::vector<mech::Row<n, double>> rows;
  for (int j = 0; j < kJoints; ++j) {
    if (mask[j]) rows.push_back(M::joint_row(k, j));
  }
  if (rows.empty()) return 0;
  VecOf<M> thd = v_of<M>(y);
  // n independent rows hold the mechanism at rest, if it is (nearly) at rest: rows that are
  // close to dependent (a dead point) can both read zero while the mechanism moves
  const auto independent = [&](size_t a) {
    if constexpr (n == 1) {
      return rows[a](0, 0) != 0.0;
    } else {
      for (size_t b = a + 1; b < rows.size(); ++b) {
        const double det = rows[a][0] * rows[b][1] - rows[a][1] * rows[b][0];
        if (std::abs(det) > 1e-9 * rows[a].norm() * rows[b].norm()) return true;
      }
      return false;
    }
  };
  for (size_t a = 0; a < rows.size() && thd.norm() <= kRestProjection; ++a) {
    if (!independent(a)) continue;
    std::fill(y + n, y + 2 * n, 0.0);
    return n;
  }
  const auto& J = *std::max_element(rows.begin(), rows.end(), [](const auto& a, const auto& b) {
    return a.squaredNorm() < b.squaredNorm();
  });
  if (J.squaredNorm() == 0.0 || std::abs(J.dot(thd)) > kRestProjection * J.norm()) return 0;
  thd -= J.transpose() * (J.dot(thd) / J.squaredNorm());
  for (int i = 0; i < n; ++i) {  // a crank joint's rate is the crank's: exactly zero
    y[n + i] = mask[Sim<M>::driven_joint(i)] ? 0.0 : thd[i];
  }
  return 1;
}

/// A row of J_w this small against the largest is a kinematic zero (kinematic_zero_departures).
constexpr double kKinematicZero = 1e-9;

/// At rest (v = 0) a joint whose row of J_w vanishes (a kinematic zero: a four-bar's joint C with
/// the crank on the ground line) neither moves nor accelerates in any mode, yet its slip
/// direction changes the reactions: w_k(t) = J_k(q(t)) v(t) ~ (t^3 / 2) qdd^T H_k qdd, so it
/// slips the way of qdd^T H_k qdd, the velocity terms of its rate at v = qdd. That value
/// replaces its relative acceleration in `wdot` for the consistency test.
template <class M>
void kinematic_zero_departures(const ParamsOf<M>& p, const EvalOf<M>& ev, const double* y,
                               const std::array<bool, kJoints>& rest,
                               std::array<double, kJoints>* wdot) {
  if (!v_of<M>(y).isZero(0.0)) return;
  std::array<double, kJoints> row{};
  for (int k = 0; k < M::kJoints; ++k) row[k] = M::joint_row(ev.kin, k).norm();
  const double zero = kKinematicZero * *std::max_element(row.begin(), row.end());
  std::array<double, kJoints> third{};  // qdd^T H_k qdd, once a joint needs it
  bool have = false;
  for (int k = 0; k < M::kJoints; ++k) {
    if (!rest[k] || row[k] > zero) continue;
    if (!have) {
      typename M::template Bias<double> b;
      M::bias(p, ev.kin, ev.thdd, &b);  // the velocity terms at v = qdd
      third = M::joint_accelerations(ev.kin, b, VecOf<M>::Zero().eval());
      have = true;
    }
    (*wdot)[k] = third[k];
  }
}

/// Whether the joint modes `slip` are consistent at (t, y) for the joints in `rest`: every
/// slipping one accelerates in its slip direction (beyond -slack_accel), every stuck one is held
/// (margin >= -slack_torque).
template <class M>
bool consistent(Context<M>& c, double t, const double* y, const JointModes& slip,
                const std::array<bool, kJoints>& rest, double slack_accel, double slack_torque,
                VecOf<M>* thdd, Status* failure) {
  EvalOf<M> ev;
  const Status st = forward_in_modes(c, t, y, slip, &ev);
  if (!st.ok()) {
    if (failure->ok()) *failure = st;
    return false;
  }
  auto wdot = Sim<M>::joint_accelerations(ev);
  double accel_scale = 1.0, torque_scale = 1.0;
  for (int k = 0; k < kJoints; ++k) {
    accel_scale = std::max(accel_scale, std::abs(wdot[k]));
    torque_scale = std::max(torque_scale, std::abs(ev.Mf[k]));
  }
  kinematic_zero_departures<M>(*c.params, ev, y, rest, &wdot);
  for (int k = 0; k < kJoints; ++k) {
    if (!rest[k] || slip[k] == JointMode::kRest) continue;
    const bool ok = slip[k] == kStuck ? ev.hold_margin[k] >= -slack_torque * torque_scale
                                      : (slack_accel == 0.0 ? coulomb_sign(slip[k]) * wdot[k] > 0.0
                                                            : coulomb_sign(slip[k]) * wdot[k] >= -slack_accel * accel_scale);
    if (!ok) return false;
  }
  *thdd = ev.thdd;
  return true;
}

/// The candidate modes of the joints at rest while the mechanism may move: each slips either
/// way or is stuck, with fewer stuck joints than degrees of freedom (as many would lock the
/// mechanism: see the lock; a four-bar's joints never stick alone).
template <class M>
std::vector<JointModes> candidate_modes(const Context<M>& c, const std::array<bool, kJoints>& rest,
                                        const std::array<bool, kJoints>& no_stick) {
  auto can_hold = [&](int k) { return c.stick && !no_stick[k] && Sim<M>::can_hold(*c.params, k); };
  std::vector<int> idx;
  for (int k = 0; k < kJoints; ++k) {
    if (rest[k]) idx.push_back(k);
  }
  int combos = 1;
  for (size_t i = 0; i < idx.size(); ++i) combos *= 3;
  std::vector<JointModes> out;
  for (int code = 0; code < combos; ++code) {
    JointModes m = c.slip;
    int stuck = 0, x = code;
    bool allowed = true;
    for (int k : idx) {
      const int option = x % 3;
      x /= 3;
      m[k] = option == 0 ? JointMode::kSlipPositive
             : option == 1 ? JointMode::kSlipNegative
                           : kStuck;
      if (option == 2 && (!can_hold(k) || ++stuck > M::kDof - 1)) allowed = false;
    }
    if (allowed) out.push_back(m);
  }
  return out;
}

/// The consistent candidates (strictly, or within the slacks) and their accelerations.
template <class M>
void consistent_candidates(Context<M>& c, double t, const double* y,
                           const std::vector<JointModes>& candidates,
                           const std::array<bool, kJoints>& rest, bool relaxed,
                           std::vector<JointModes>* found, std::vector<VecOf<M>>* accel,
                           Status* failure) {
  for (const auto& m : candidates) {
    VecOf<M> thdd;
    if (!consistent(c, t, y, m, rest, relaxed ? kSlackAccel : 0.0, relaxed ? kSlackTorque : 0.0,
                    &thdd, failure)) {
      continue;
    }
    found->push_back(m);
    accel->push_back(thdd);
  }
}

template <class M>
std::string rest_list(const std::array<bool, kJoints>& rest) {
  std::string out = " (joints at rest:";
  for (int k = 0; k < kJoints; ++k) {
    if (rest[k]) out += std::string(" ") + Sim<M>::joint(k);
  }
  return out + ")";
}

template <class M>
Status decide_slip_only(Context<M>& c, double t, const double* y,
                        const std::array<bool, kJoints>& rest);

/// Stats::sign_rule_inconsistent: whether the simpler sign rule (the joints at rest slip the way
/// they accelerate, iterated, no stick) gives modes that are not consistent here.
template <class M>
bool sign_rule_inconsistent(Context<M>& c, double t, const double* y,
                            const std::array<bool, kJoints>& rest) {
  const JointModes chosen = c.slip;
  bool inconsistent = true;
  if (decide_slip_only(c, t, y, rest).ok()) {
    VecOf<M> thdd;
    Status failure;
    inconsistent = !consistent(c, t, y, c.slip, rest, 0.0, 0.0, &thdd, &failure);
  }
  c.slip = chosen;
  return inconsistent;
}

/// Chooses the modes of the joints in `rest` (at rest, or stuck) so that the motion is
/// consistent; the other joints slip in the direction of their rate. With every joint at rest
/// the mechanism may stay locked (lock_analysis). No consistent combination, or several with
/// different motions (Painleve-type), is an error.
template <class M>
Status decide_modes(Context<M>& c, double t, const double* y, const std::array<bool, kJoints>& rest,
                    const std::array<bool, kJoints>& no_stick, bool all_rest, bool may_lock,
                    Stats* stats) {
  ++stats->mode_decisions;
  c.locked = false;
  if (!any_of(rest)) return Status::Ok();
  bool lock = false;
  if (all_rest && may_lock && c.stick) {
    LockAnalysis la;
    lock = lock_analysis<M>(*c.params, loads_at(c, t), q_of<M>(y), c.eval, &la).ok() &&
           la.ratio <= 1.0;
  }
  const auto candidates = candidate_modes(c, rest, no_stick);
  std::vector<JointModes> found;
  std::vector<VecOf<M>> accel;
  Status failure;  // the first evaluation that failed (near-singular pose, friction loop)
  consistent_candidates(c, t, y, candidates, rest, false, &found, &accel, &failure);
  if (lock && !found.empty()) {
    return at_time<M>(Status::Error(StatusCode::kIndeterminateModes,
                                    "several consistent joint modes: friction can hold the "
                                    "mechanism at rest, yet it can also start to slip "
                                    "(Painleve-type)" + rest_list<M>(rest)),
                      t, y);
  }
  if (lock) {
    c.locked = true;
    c.slip.fill(kStuck);
    return Status::Ok();
  }
  const bool relaxed = found.empty();
  if (relaxed) consistent_candidates(c, t, y, candidates, rest, true, &found, &accel, &failure);
  if (found.empty() && !failure.ok()) return at_time<M>(failure, t, y);
  if (found.empty()) {
    return at_time<M>(Status::Error(StatusCode::kIndeterminateModes,
                                    "no consistent joint modes: neither slip direction nor stick "
                                    "is consistent with the accelerations" + rest_list<M>(rest)),
                      t, y);
  }
  const double same = relaxed ? 1e-6 : 1e-9;
  for (size_t i = 1; i < found.size(); ++i) {
    if ((accel[i] - accel[0]).norm() > same * (1.0 + accel[0].norm())) {
      return at_time<M>(Status::Error(StatusCode::kIndeterminateModes,
                                      "several consistent joint modes with different motions "
                                      "(Painleve-type indeterminacy)" + rest_list<M>(rest)),
                        t, y);
    }
  }
  c.slip = found.front();
  if (sign_rule_inconsistent(c, t, y, rest)) ++stats->sign_rule_inconsistent;
  return Status::Ok();
}

/// Without stick (Options::stick = false): the joints at rest slip in the direction of the
/// relative acceleration they get with those directions (a short fixed point over the signs).
/// When no slip directions are consistent (friction could hold a joint: only stick can model
/// that), an error with the joints, instead of chattering between the two directions.
template <class M>
Status decide_slip_only(Context<M>& c, double t, const double* y,
                        const std::array<bool, kJoints>& rest) {
  for (int k = 0; k < kJoints; ++k) {
    if (rest[k]) c.slip[k] = JointMode::kRest;
  }
  for (int pass = 0; pass < 6; ++pass) {
    EvalOf<M> ev;
    const Status st = forward_in_modes(c, t, y, c.slip, &ev);
    if (!st.ok()) return at_time<M>(st, t, y);
    const auto wdot = Sim<M>::joint_accelerations(ev);
    bool changed = false;
    for (int k = 0; k < kJoints; ++k) {
      if (!rest[k] || slip_mode(sign_of(wdot[k])) == c.slip[k]) continue;
      c.slip[k] = slip_mode(sign_of(wdot[k]));
      changed = true;
    }
    if (!changed) break;
  }
  VecOf<M> thdd;
  Status failure;
  if (consistent(c, t, y, c.slip, rest, kSlackAccel, kSlackTorque, &thdd, &failure)) {
    return Status::Ok();
  }
  if (!failure.ok()) return at_time<M>(failure, t, y);
  return at_time<M>(Status::Error(StatusCode::kIndeterminateModes,
                                  "no consistent slip directions with simulation.stick = false: "
                                  "friction can hold a joint here, which only stick-slip models "
                                  "(simulation.stick = true)" + rest_list<M>(rest)),
                    t, y);
}

/// The joints that are not at rest slip in the direction of their rate. At a decision after the
/// first, a slipping joint found moving against its slip direction is a switch the detection
/// missed (Stats::mode_corrections); a joint crossing zero within ~1e-12 s of the one that
/// fired reads a few 1e-9 rad/s against its slip, and that is no missed switch.
template <class M>
void slip_moving_joints(Context<M>& c, const std::array<bool, kJoints>& rest,
                        const std::array<double, kJoints>& w, Stats* stats) {
  for (int k = 0; k < kJoints; ++k) {
    if (rest[k]) continue;
    const JointMode s = slip_mode(sign_of(w[k]));
    if (c.decided && c.watched[k] && c.slip[k] != s && c.slip[k] != kStuck &&
        std::abs(w[k]) > kRestProjection) {
      ++stats->mode_corrections;
    }
    c.slip[k] = s;
  }
}

/// Decides the joint modes at (t, y), where the switch functions in `fired_now` just fired
/// (none at the start). The fired and stuck joints are at rest: the rates are projected so that
/// they are exactly (if that takes two independent constraints, the whole mechanism is at rest);
/// any other watched joint whose |w| is then below kRestRate is at rest too.
template <class M>
Status decide_at(Context<M>& c, double t, double* y, const Fired& fired_now, Stats* stats) {
  const bool was_locked = c.locked;
  std::array<bool, kJoints> fixed{};
  for (int k = 0; k < kJoints; ++k) {
    fixed[k] = was_locked || (c.watched[k] && (fired_now[k] || c.slip[k] == kStuck));
  }
  const int rank = project_rates<M>(*c.params, fixed, y);
  std::array<double, kJoints> w{};
  if (!joint_rates<M>(*c.params, y, &w)) {
    return at_time<M>(Status::Error(StatusCode::kCannotAssemble, "pose cannot assemble"), t, y);
  }
  std::array<bool, kJoints> rest{}, no_stick{};
  bool all_rest = rank == M::kDof;
  if (!all_rest) {
    all_rest = std::all_of(w.begin(), w.end(), [](double v) { return std::abs(v) <= kRestRate; });
  }
  for (int k = 0; k < kJoints; ++k) {
    if (!c.watched[k]) continue;
    rest[k] = all_rest || fixed[k] || std::abs(w[k]) <= kRestRate;
    no_stick[k] = fired_now[k] && c.slip[k] == kStuck;  // a breakaway: that joint slips
  }
  const JointModes before = c.slip;
  slip_moving_joints(c, rest, w, stats);
  c.decided = true;
  const Status st =
      c.stick ? decide_modes(c, t, y, rest, no_stick, all_rest, !fired_now[kLockSlot], stats)
              : decide_slip_only(c, t, y, rest);
  if (!st.ok()) return st;
  for (int k = 0; k < 6; ++k) {
    if (!fired_now[k]) continue;
    ++stats->friction_events;
    if (k == kLockSlot) {
      ++stats->breakaway_events;
    } else if (c.slip[k] == kStuck && before[k] != kStuck) {
      ++stats->stick_events;
    } else if (c.slip[k] != kStuck && before[k] == kStuck) {
      ++stats->breakaway_events;
    }
  }
  std::array<bool, kJoints> stuck{};
  for (int k = 0; k < kJoints; ++k) stuck[k] = c.locked || c.slip[k] == kStuck;
  project_rates<M>(*c.params, stuck, y);
  return Status::Ok();
}

/// Angles-only row into `row` (value-initialized): the closure, the dependent links' rates and the
/// energy quadratures.
template <class M>
Status make_angle_row(const Context<M>& c, double t, const double* y, const Row* previous,
                      Row* row) {
  constexpr int n = M::kDof, kBristle = base_states(n);
  row->t = t;
  KinOf<M> k;
  if (Status st = close_at<M>(*c.params, y, &k); !st.ok()) return at_time<M>(st, t, y);
  for (int i = 0; i < n; ++i) {
    row->theta[i] = y[i];
    row->omega[i] = y[n + i];
  }
  Sim<M>::dependent_links(k, y, previous, row);
  row->E_diss = y[2 * n];
  row->W_in = y[2 * n + 1];
  row->W_ext = y[2 * n + 2];
  row->mode = c.slip;
  if (c.law_states) std::copy(y + kBristle, y + kBristle + kJoints, row->bristle.begin());
  row->has_bristle = c.law_states;
  return Status::Ok();
}

/// Row of a locked mechanism: at rest, its friction torques the holding torques of lock_analysis.
template <class M>
Status make_locked_row(const Context<M>& c, double t, const double* y, const Row* previous,
                       Row* row) {
  Status st = make_angle_row(c, t, y, previous, row);
  if (!st.ok()) return st;
  const LoadsOf<M> L = (*c.loads)(t);
  LockAnalysis lock;
  KinOf<M> k;
  st = lock_analysis<M>(*c.params, L, q_of<M>(y), c.eval, &lock);
  if (st.ok()) st = close_at<M>(*c.params, y, &k);
  if (!st.ok()) return at_time<M>(st, t, y);
  Sim<M>::drives(L, row);
  row->N = lock.N;
  row->Mf = lock.hold;
  row->potential = Sim<M>::potential(*c.params, k);
  return Status::Ok();
}

/// The dependent links' angles (continued from the previous row), rates and accelerations, the
/// reactions, friction torques and dissipated power of an evaluation, into a row.
template <class M>
void set_evaluated(const EvalOf<M>& ev, const Row* previous, Row* row) {
  Sim<M>::evaluated_links(ev, previous, row);
  for (int k = 0; k < kJoints; ++k) {
    row->N[k] = ev.N[k];
    row->Mf[k] = ev.Mf[k];
  }
  row->P_diss = ev.P_diss;
}

/// The output row at (t, y) into `row` (value-initialized, written in place: a row is large).
template <class M>
Status make_row(Context<M>& c, double t, const double* y, const Row* previous, Row* row) {
  constexpr int n = M::kDof, kBristle = base_states(n);
  if (!c.full_rows) return make_angle_row(c, t, y, previous, row);
  if (c.locked) return make_locked_row(c, t, y, previous, row);
  row->t = t;
  EvalOptions eval = c.eval;
  eval.want_reactions = true;
  eval.want_angles = true;
  eval.singular_margin = 0.0;
  const LoadsOf<M>& L = loads_at(c, t);
  EvalOf<M> ev;
  std::array<double, kJoints> z{};
  if (c.law_states) std::copy(y + kBristle, y + kBristle + kJoints, z.begin());
  JointModes signs;  // the modes the right-hand side uses
  if (Status st =
          forward_at<M>(*c.params, L, y, rhs_modes(c, y, &signs), eval, &ev, &z, &c.row_warm);
      !st.ok()) {
    return at_time<M>(st, t, y);
  }
  for (int i = 0; i < n; ++i) {
    row->theta[i] = y[i];
    row->omega[i] = y[n + i];
    row->alpha[i] = ev.thdd[i];
  }
  set_evaluated<M>(ev, previous, row);
  Sim<M>::drives(L, row);
  row->E_diss = y[2 * n];
  row->W_in = y[2 * n + 1];
  row->W_ext = y[2 * n + 2];
  row->kinetic = Sim<M>::kinetic(*c.params, ev.kin, y + n);
  row->potential = Sim<M>::potential(*c.params, ev.kin);
  row->mode = c.use_slip ? c.slip : ev.slip;
  row->bristle = z;
  row->has_bristle = c.law_states;
  return Status::Ok();
}

/// Appends the output row at (t, y), continued from the last row (if any). A row that fails is
/// kept, partly written: the caller stops at its status.
template <class M>
Status append_row(Context<M>& c, double t, const double* y, std::vector<Row>* rows) {
  rows->emplace_back();
  const size_t i = rows->size() - 1;
  return make_row(c, t, y, i > 0 ? &(*rows)[i - 1] : nullptr, &(*rows)[i]);
}

/// The event loop's state: integrator, switch watch, output grid and counters.
template <class M>
struct Loop {
  Context<M> c;
  std::unique_ptr<detail::Integrator> integ;
  Watch watch;
  std::vector<double> grid;  ///< output times
  size_t next = 1;           ///< next output time to write
  double t = 0.0;
  double y[kMaxStates] = {};
  double last_switch = -1.0;
  int burst = 0;             ///< switches at the same instant in a row
  long steps_since_row = 0;
};

/// (Re)starts the integration at the loop's (t, y) with fresh switch functions.
template <class M>
Status restart(Loop<M>& L, const Options& options) {
  // locked, nothing moves and the integrator's steps grow without bound, while the lock margin
  // still follows the loads: steps no longer than the output step keep its zero in sight
  if (!L.integ->start(L.t, L.y) || !L.integ->set_max_step(L.c.locked ? options.output_step : 0.0)) {
    return at_time<M>(Status::Error(StatusCode::kSolverFailed, L.integ->error()), L.t, L.y);
  }
  L.watch = Watch{};
  if (!L.c.use_slip) return Status::Ok();
  Switches g;
  const Status st = switch_values(L.c, L.t, L.y, &g);
  if (!st.ok()) return st;
  advance_watch(&L.watch, g);
  return Status::Ok();
}

/// Writes the rows of the output times in (.., t_end] from the dense output (the state `y_end`
/// at t_end itself).
template <class M>
Status emit_rows(Loop<M>& L, Result* result, double t_end, const double* y_end) {
  double y[kMaxStates];
  while (L.next < L.grid.size() && L.grid[L.next] <= t_end) {
    const double tout = L.grid[L.next];
    if (tout == t_end) {
      std::copy(y_end, y_end + L.c.n, y);
    } else if (!L.integ->dense(tout, y)) {
      return at_time<M>(Status::Error(StatusCode::kSolverFailed, L.integ->error()), tout, y);
    }
    if (Status st = append_row(L.c, tout, y, &result->rows); !st.ok()) return st;
    ++L.next;
    L.steps_since_row = 0;
    L.c.recovered_since_row = 0;
  }
  return Status::Ok();
}

/// |singular measure| at a state (1 where the pose cannot close: the closure reports that itself).
template <class M>
double singular_measure_at(const ParamsOf<M>& p, const double* y) {
  KinOf<M> k;
  if (!close_at<M>(p, y, &k, 0.0, false).ok()) return 1.0;
  return std::abs(M::singular_measure(k));
}

/// The values at the end (tc, yc) of a step that the singular-margin check and the switch scan
/// share: from the last right-hand side when it was evaluated there (Dormand-Prince's last
/// stage), else from the first-order kinematics.
template <class M>
StepEnd step_end(const Context<M>& c, double tc, const double* yc) {
  StepEnd end;
  if (c.last.ok && c.last.t == tc && std::memcmp(c.last.y, yc, sizeof(double) * c.n) == 0) {
    end.closes = true;
    end.singular = c.last.singular;
    end.w = c.last.w;
    end.wdot = c.last.wdot;
    end.has_wdot = true;
    return end;
  }
  KinOf<M> k;
  end.closes = close_at<M>(*c.params, yc, &k, 0.0, false).ok();
  if (end.closes) {
    end.singular = std::abs(M::singular_measure(k));
    end.w = joint_rates<M>(k, yc);
  }
  return end;
}

/// A run stops where the singular measure (|sin(th4 - th3)| of the five-bar) reaches
/// simulation.singular_margin: located on the dense output, the rows up to it written, then
/// kNearSingular (the right-hand side itself only fails at half the margin, so that steps do not
/// shrink without end next to the singular pose). `end`: the values at the step's end yc.
template <class M>
Status stop_at_singular_margin(Loop<M>& L, Result* result, const Options& options, double tp,
                               double tc, const double* yc, const StepEnd& end) {
  const double margin = options.singular_margin;
  if (!(margin > 0.0) || (end.closes ? end.singular : 1.0) >= margin) {
    return Status::Ok();
  }
  double ta = tp, tb = tc, y[kMaxStates];
  std::copy(yc, yc + L.c.n, y);
  // (a failed dense output keeps the bracket reached: the run stops here either way)
  static_cast<void>(bisect_dense(*L.integ, &ta, &tb, y, [&](double, const double* yt, bool* past) {
    *past = singular_measure_at<M>(*L.c.params, yt) < margin;
    return Status::Ok();
  }));
  if (tb != tc && !L.integ->dense(tb, y)) std::copy(yc, yc + L.c.n, y);
  const Status rows = emit_rows(L, result, ta, y);
  if (!rows.ok()) return rows;
  KinOf<M> k;
  Status st = close_at<M>(*L.c.params, y, &k, margin, false);
  if (st.ok()) st = Status::Error(StatusCode::kNearSingular, "near-singular pose");
  return at_time<M>(st, tb, y);
}

/// Steps within one output interval after which a run is taken to stall: the loads ahead are
/// probed (loads_ahead), and right-hand sides that failed meanwhile are named (stalled_by)
constexpr long kStallProbe = 10000;

/// A run whose steps shrink while its right-hand sides keep failing (say, a friction loop with
/// several consistent solutions in the states the integrator tries) creeps on to
/// simulation.max_steps: at the stall probe, the last of those failures names the cause.
template <class M>
Status stalled_by(const Loop<M>& L) {
  if (L.c.recovered_since_row == 0) return Status::Ok();
  return Status::Error(L.c.recovered.code,
                       "the run stalls (" + std::to_string(kStallProbe) + " steps within one " +
                           "output interval, " + std::to_string(L.c.recovered_since_row) +
                           " failed evaluations retried with smaller steps); the last: " +
                           L.c.recovered.message);
}

/// Loads that leave their domain stall a run long before a non-finite value is evaluated: the
/// steps shrink toward the point (sqrt(1.5 - t) at 1.5 s, 1 / (t - 0.5) at 0.5 s) and the run
/// would end at simulation.max_steps. The loads over the next two output intervals, on a fine
/// grid and at the output times themselves, name the first that is not finite.
template <class M>
Status loads_ahead(const Loop<M>& L, double step) {
  constexpr int kProbes = 200;
  std::vector<double> times;
  for (int i = 0; i <= kProbes; ++i) times.push_back(L.t + 2 * step * i / kProbes);
  for (size_t g = L.next; g < std::min(L.grid.size(), L.next + 2); ++g) times.push_back(L.grid[g]);
  for (double ti : times) {
    const Status bad = finite_loads((*L.c.loads)(ti), ti);
    if (!bad.ok()) return bad;
  }
  return Status::Ok();
}

/// One integrator step, its switch (located and decided) if any, and the rows it covers.
template <class M>
Status advance(Loop<M>& L, Result* result, const Options& options) {
  const double tp = L.t;
  double yc[kMaxStates], tc = tp;
  L.c.failure = Status::Ok();  // a recovered failure of an earlier step is not this one's
  if (!L.integ->step(yc, &tc)) {
    if (!L.c.failure.ok()) return L.c.failure;
    return at_time<M>(Status::Error(StatusCode::kSolverFailed, L.integ->error()), tc, yc);
  }
  if (++L.steps_since_row == kStallProbe) {
    const Status bad = loads_ahead(L, options.output_step);
    if (!bad.ok()) return at_time<M>(bad, tc, yc);
    const Status stalled = stalled_by(L);
    if (!stalled.ok()) return stalled;
  }
  if (L.steps_since_row > options.max_steps) {
    // steps shrink without end next to a singular pose: say so when that is the cause
    KinOf<M> k;
    const Status near = close_at<M>(*L.c.params, yc, &k, 10 * options.singular_margin, false);
    const std::string why =
        near.ok() ? "" : near.message + " (within 10x simulation.singular_margin); ";
    return at_time<M>(Status::Error(near.ok() ? StatusCode::kSolverFailed : near.code,
                                    why + "more than simulation.max_steps = " +
                                        std::to_string(options.max_steps) +
                                        " steps between two output times"),
                      tc, yc);
  }
  const StepEnd end = step_end(L.c, tc, yc);
  const Status singular = stop_at_singular_margin(L, result, options, tp, tc, yc, end);
  if (!singular.ok()) return singular;
  bool found = false;
  double ta = tp, tb = tc;
  if (L.c.use_slip) {
    const Status st = scan_step(L.c, *L.integ, tp, tc, yc, end, &L.watch, &found, &ta, &tb);
    if (!st.ok()) return st;
  }
  if (!found) {
    L.t = tc;
    std::copy(yc, yc + L.c.n, L.y);
    return emit_rows(L, result, tc, yc);
  }
  double ye[kMaxStates], te = tb;
  Fired which{};
  Status st = locate_switch(L.c, *L.integ, L.watch, ta, tb, ye, &te, &which);
  if (!st.ok()) return st;
  st = emit_rows(L, result, te, ye);
  if (!st.ok()) return st;
  L.burst = te - L.last_switch <= kSameInstant * std::max(1.0, te) ? L.burst + 1 : 0;
  if (L.burst > kMaxSwitchesAtOnce) {
    return at_time<M>(Status::Error(StatusCode::kSolverFailed,
                                    "the joint modes chatter: more than " +
                                        std::to_string(kMaxSwitchesAtOnce) +
                                        " switches at one instant (no consistent motion)"),
                      te, ye);
  }
  L.last_switch = te;
  L.t = te;
  std::copy(ye, ye + L.c.n, L.y);
  st = decide_at(L.c, L.t, L.y, which, &result->stats);
  return st.ok() ? restart(L, options) : st;
}

/// The output times: every output_step from 0, and the duration itself.
std::vector<double> output_grid(const Options& o) {
  std::vector<double> grid;
  const long n = output_row_count(o);
  grid.reserve(n);
  // i / rate when the rate is a whole number of rows per second: t = 0.476 prints as 0.476,
  // where i * 0.001 is the double 0.47600000000000003
  const double rate = 1.0 / o.output_step;
  const bool whole = std::abs(rate - std::round(rate)) <= 1e-9 * rate;
  for (long i = 0; i + 1 < n; ++i) {
    grid.push_back(whole ? i / std::round(rate) : i * o.output_step);
  }
  grid.push_back(o.duration);
  return grid;
}

/// The context of a run: which joints have switch functions, state size, evaluation settings.
template <class M>
void setup_context(Context<M>& c, const ParamsOf<M>& params, const LoadFnOf<M>& loads,
                   const Options& options) {
  c.params = &params;
  c.loads = &loads;
  // the run stops at the margin itself (stop_at_singular_margin); evaluations fail at half of it
  c.eval.singular_margin = kEvalMarginFraction * options.singular_margin;
  c.eval.friction_tol = options.friction_tol;
  c.eval.friction_max_iter = options.friction_max_iter;
  c.eval.want_reactions = false;  // the motion needs reactions only through friction
  c.eval.want_angles = false;     // nor the coupler angles themselves
  // exact Coulomb sign: each joint with a Coulomb part gets a switch function on its rate
  c.use_slip = exact_sign(params.friction) && options.locate_switches;
  c.stick = c.use_slip && options.stick;
  for (int k = 0; k < M::kJoints; ++k) {  // the slots beyond the mechanism's joints stay off
    c.watched[k] = c.use_slip && params.friction.coulomb[k] != 0.0 &&
                   params.friction.pin_radius[k] != 0.0;
  }
  const int law_states = law_descriptor(params.friction.law).states_per_joint;
  c.law_states = law_states > 0;
  c.full_rows = options.full_rows;
  c.n = base_states(M::kDof) + kJoints * law_states;
}

/// The run of mechanism M: simulate's body.
template <class M>
Result run(const ParamsOf<M>& params, const LoadFnOf<M>& loads, const Initial& initial,
           const Options& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  Result result;
  if (output_row_count(options) > kMaxOutputRows) {
    result.status = Status::Error(StatusCode::kInvalidInput,
                                  "simulation.duration / simulation.output_step needs " +
                                      std::to_string(output_row_count(options)) +
                                      " output rows, more than the limit of " +
                                      std::to_string(kMaxOutputRows));
    return result;
  }
  Loop<M> L;
  setup_context(L.c, params, loads, options);
  Sim<M>::set_initial(initial, L.y);  // energies and bristles start at zero
  L.grid = output_grid(options);
  if (L.c.use_slip) {
    // at the start every watched joint at rest is undecided
    result.status = decide_at(L.c, 0.0, L.y, {}, &result.stats);
    if (!result.status.ok()) return result;
  } else if (exact_sign(params.friction)) {
    // switches not located: joints at rest at the start slip the way they accelerate
    std::array<double, kJoints> w{};
    std::array<bool, kJoints> rest{};
    if (joint_rates<M>(params, L.y, &w)) {
      for (int k = 0; k < kJoints; ++k) rest[k] = w[k] == 0.0;
      if (decide_slip_only(L.c, 0.0, L.y, rest).ok()) {
        L.c.zero_sign = L.c.slip;
        L.c.zero_signs = true;
      }
    }
  }
  detail::OdeProblem prob{L.c.n, &rhs<M>, &L.c, std::vector<double>(L.c.n, 1.0),
                          L.c.law_states};
  if (L.c.zero_signs) prob.freeze = &freeze_signs<M>;
  for (int i = base_states(M::kDof); i < prob.n; ++i) {
    prob.atol_scale[i] = options.bristle_atol_scale;
  }
  L.integ = detail::make_integrator(prob, options, options.duration);
  result.rows.reserve(L.grid.size());
  Status st = append_row(L.c, 0.0, L.y, &result.rows);
  if (st.ok()) st = restart(L, options);
  while (st.ok() && L.next < L.grid.size()) {
    st = advance(L, &result, options);
    if (options.progress) options.progress(L.t);
    if (st.ok() && options.max_wall_time_s > 0.0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count() >
            options.max_wall_time_s) {
      st = at_time<M>(Status::Error(StatusCode::kSolverFailed,
                                    "wall-time limit of " +
                                        std::to_string(options.max_wall_time_s) +
                                        " s reached (simulation.max_wall_time_s)"),
                      L.t, L.y);
    }
  }
  if (!L.integ->steps(&result.stats.steps) && st.ok()) {
    st = Status::Error(StatusCode::kSolverFailed, L.integ->error());
  }
  result.status = st;
  result.stats.rhs_evaluations = L.c.rhs_evaluations;
  result.stats.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

}  // namespace

long output_row_count(const Options& o) {
  if (!(o.output_step > 0.0) || !(o.duration > 0.0)) return 1;
  const double steps = o.duration / o.output_step;
  if (!(steps < 1e15)) return std::numeric_limits<long>::max();
  // the last grid point is the duration: one more row when it is not on the grid
  const long full = static_cast<long>(std::floor(steps * (1 + 1e-12)));
  // (within the product's rounding too: 1e7 steps of 1e-5 s make 100.00000000000001 s)
  const bool on_grid =
      std::abs(full * o.output_step - o.duration) <= 1e-9 * o.output_step + 1e-12 * o.duration;
  return full + (on_grid ? 1 : 2);
}

Result simulate(const Params<double>& params, const LoadFunction& loads, const Initial& initial,
                const Options& options) {
  return run<FiveBar>(params, loads, initial, options);
}

Result simulate(const FourBarParams& params, const FourBarLoadFunction& loads,
                const Initial& initial, const Options& options) {
  return run<FourBar>(params, loads, initial, options);
}

namespace {

/// The drive torques' half-widths added by the passive joints (B, C, D) stuck where a crank
/// moves. Such a joint holds with any friction torque within its capacity C_j (hold_margin_j),
/// which the motion does not fix: the row (Mf_j = 0) is one of the torques that produce it. Each
/// joint's torque moves M1, M2 by dM/dMf_j C_j; dM/dMf_j is read from the row evaluated again
/// with joint j slipping forward (its friction torque Mf_j^+ = phi_j N_j, the reactions and the
/// other joints' friction following it), as (M^+ - M) / Mf_j^+.
Status passive_hold_widths(const Params<double>& p, const Loads<double>& L, const EvalOptions& eval,
                           const Row& r, double width[2]) {
  width[0] = width[1] = 0.0;
  for (int j = 1; j <= 3; ++j) {
    if (r.mode[j] != kStuck || !(r.hold_margin[j] > 0.0)) continue;
    JointModes slip = r.mode;
    slip[j] = JointMode::kSlipPositive;
    Evaluation<double> ev;
    const Status st = mech::inverse<FiveBar, double>(
        p, L, Vec2<double>(r.theta[0], r.theta[1]), Vec2<double>(r.omega[0], r.omega[1]),
        Vec2<double>(r.alpha[0], r.alpha[1]), &slip, eval, &ev);
    if (!st.ok()) return st;
    if (!(std::abs(ev.Mf[j]) > 0.0)) continue;
    const double scale = r.hold_margin[j] / std::abs(ev.Mf[j]);
    width[0] += std::abs(ev.M1 - r.M1) * scale;
    width[1] += std::abs(ev.M2 - r.M2) * scale;
  }
  return Status::Ok();
}

/// Row::hold_range of an inverse-dynamics row: the torque itself where the cranks move and every
/// joint slips, M +- mu_s r N where a crank is stuck alone, widened by the passive joints stuck
/// (passive_hold_widths), and where both cranks are stuck (the pose at rest) the range of each
/// over which the mechanism stays locked, the other at its row value (rest.h).
Status Sim<FiveBar>::hold_range(const P& p, const Ld& L, const EvalOptions& eval, Row* r) {
  const bool o = r->mode[0] == kStuck, d0 = r->mode[4] == kStuck;
  double m1 = o ? r->hold_margin[0] : 0.0, m2 = d0 ? r->hold_margin[4] : 0.0;
  if (!(o && d0) && p.friction.active()) {
    double width[2];
    const Status st = passive_hold_widths(p, L, eval, *r, width);
    if (!st.ok()) return st;
    m1 += width[0];
    m2 += width[1];
  }
  r->hold_range = {r->M1 - m1, r->M1 + m1, r->M2 - m2, r->M2 + m2};
  if (!(o && d0 && p.friction.active())) return Status::Ok();
  Holding<double> h;
  const Status st = holding_torques(p, L, r->theta[0], r->theta[1], eval, &h);
  if (!st.ok()) return st;
  r->hold_range = {r->M1 - (h.M1 - h.M1_min), r->M1 + (h.M1_max - h.M1),
                   r->M2 - (h.M2 - h.M2_min), r->M2 + (h.M2_max - h.M2)};
  return Status::Ok();
}

/// The four-bar's Row::hold_range: M1 itself where the crank moves. With the crank stuck every
/// joint is (one degree of freedom), and the row's M1 is the frictionless equilibrium M1_eq;
/// the range is that over which the locked mechanism holds, as the simulator's lock decides it.
/// lock_analysis at M1 = M1_eq + d has the ratio |d| / sum_k w_k(N) |a_k|, so each end is the
/// fixed point d = d / ratio (the reactions change little with the holding torques: a few
/// iterations). M2's slots are zero.
Status Sim<FourBar>::hold_range(const P& p, const Ld& L, const EvalOptions& eval, Row* r) {
  r->hold_range = {r->M1, r->M1, 0.0, 0.0};
  if (r->mode[0] != kStuck || !p.friction.active()) return Status::Ok();
  const double start = r->hold_margin[0] > 0.0 ? r->hold_margin[0] : 1.0;
  for (int end = 0; end < 2; ++end) {
    const double sign = end == 0 ? -1.0 : 1.0;
    double d = 0.0;
    const Status st = lock_extent<FourBar>(
        p, L, VecOf<FourBar>(r->theta[0]), eval, r->M1, sign, start,
        [](Ld* l, double v) { l->M1 = v; }, &d);
    if (!st.ok()) return st;
    r->hold_range[end] = r->M1 + sign * d;
  }
  return Status::Ok();
}

/// inverse_rows for mechanism M.
template <class M>
Status inverse_rows_of(const ParamsOf<M>& params, const LoadFnOf<M>& loads,
                       const std::vector<Row>& motion, std::vector<Row>* out,
                       const RestThresholds& rest) {
  out->clear();
  out->reserve(motion.size());
  std::vector<double> power_in, power_ext;  // the drives' power and that of the other loads [W]
  const EvalOptions eval = with_rest(EvalOptions{}, rest);
  for (const Row& m : motion) {
    const LoadsOf<M> L = loads(m.t);
    if (const Status bad = finite_loads(L, m.t); !bad.ok()) return bad;
    EvalOf<M> ev;
    // LuGre: the run's bristle states (a motion read from a file has none: steady state)
    const bool bristles = law_descriptor(params.friction.law).states_per_joint > 0 && m.has_bristle;
    const VecOf<M> v = Eigen::Map<const VecOf<M>>(m.omega.data());
    const Status st = mech::inverse<M, double>(
        params, L, Eigen::Map<const VecOf<M>>(m.theta.data()), v,
        Eigen::Map<const VecOf<M>>(m.alpha.data()), nullptr, eval, &ev,
        bristles ? &m.bristle : nullptr);
    if (!st.ok()) {
      return at_time(st, m.t, m.theta.data(), M::kDof);
    }
    Row r = m;
    const Row* previous = out->empty() ? nullptr : &out->back();
    set_evaluated<M>(ev, previous, &r);
    Sim<M>::computed_drives(ev, &r);
    r.mode = ev.slip;
    r.hold_margin = ev.hold_margin;
    const Status held = Sim<M>::hold_range(params, L, eval, &r);
    if (!held.ok()) return at_time(held, m.t, m.theta.data(), M::kDof);
    r.kinetic = Sim<M>::kinetic(params, ev.kin, v.data());
    r.potential = Sim<M>::potential(params, ev.kin);
    out->push_back(r);
    power_in.push_back(ev.P_in);
    power_ext.push_back(ev.P_ext);
  }
  // dissipated energy and the works along the motion by the trapezoidal rule
  for (size_t i = 1; i < out->size(); ++i) {
    Row& r = (*out)[i];
    const Row& q = (*out)[i - 1];
    const double half_dt = 0.5 * (r.t - q.t);
    r.E_diss = q.E_diss + half_dt * (r.P_diss + q.P_diss);
    r.W_in = q.W_in + half_dt * (power_in[i] + power_in[i - 1]);
    r.W_ext = q.W_ext + half_dt * (power_ext[i] + power_ext[i - 1]);
  }
  if (!out->empty()) out->front().E_diss = out->front().W_in = out->front().W_ext = 0.0;
  return Status::Ok();
}

}  // namespace

Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out) {
  return inverse_rows(params, loads, motion, out, RestThresholds{});
}

Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out,
                    const RestThresholds& rest) {
  return inverse_rows_of<FiveBar>(params, loads, motion, out, rest);
}

Status inverse_rows(const FourBarParams& params, const FourBarLoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out,
                    const RestThresholds& rest) {
  return inverse_rows_of<FourBar>(params, loads, motion, out, rest);
}

namespace {

/// Energy balance: max |d(KE + PE) - W_in - W_ext + E_diss| over an energy scale every run has,
/// at least 1e-9 of the mechanism's own (sum of masses x max(g, 1 m/s^2) x sum of lengths), so
/// that a mechanism at rest does not divide round-off by round-off.
template <class P>
double energy_balance(const P& p, const std::vector<Row>& rows, double* scale_out) {
  const Row& r0 = rows.front();
  const double e0 = r0.kinetic + r0.potential;
  double mass = 0.0, length = p.ground_length;
  for (const auto& link : p.links) {
    mass += link.mass;
    length += link.length;
  }
  double worst = 0.0, scale = 1e-9 * mass * std::max(p.gravity, 1.0) * length;
  for (const Row& r : rows) {
    const double change = r.kinetic + r.potential - e0;
    worst = std::max(worst, std::abs(change - r.W_in - r.W_ext + r.E_diss));
    scale = std::max({scale, std::abs(r.W_in) + std::abs(r.W_ext), std::abs(r.E_diss),
                      std::abs(change), r.kinetic, std::abs(r.potential - r0.potential)});
  }
  *scale_out = scale;
  return worst / scale;
}

template <class M>
std::string check_failure(const char* what, double value, double tol, double t, int joint) {
  std::ostringstream msg;
  msg.precision(3);
  msg << what << " " << value << " beyond its threshold " << tol << " at t=" << t << " s";
  if (joint >= 0) msg << ", joint " << Sim<M>::joint(joint) << " (k=" << joint + 1 << ")";
  return msg.str();
}

/// check_run's body for mechanism M.
template <class M>
RunChecks checks_of(const ParamsOf<M>& params, const LoadFnOf<M>& loads, const Result& result,
                    double rtol, double atol) {
  RunChecks checks;
  if (result.rows.empty()) return checks;
  checks.energy_balance_relative = energy_balance(params, result.rows, &checks.energy_scale);
  double peak_M = 0.0, peak_Mf = 0.0;
  for (const Row& r : result.rows) {
    peak_M = std::max({peak_M, std::abs(r.M1), std::abs(r.M2)});
    for (double mf : r.Mf) peak_Mf = std::max(peak_Mf, std::abs(mf));
  }
  checks.energy_tol = std::max(std::min(1e-3, std::max(1e-6, 1e3 * rtol)),
                               100.0 * (atol < 0 ? rtol : atol) / checks.energy_scale);
  checks.inverse_tol = 1e-8 * std::max(1.0, peak_M);
  checks.power_tol = 1e-9 * std::max(1.0, peak_Mf);
  // not with internal states (LuGre's bristles store and return energy)
  const bool check_power = law_descriptor(params.friction.law).states_per_joint == 0;
  double t_inv = 0, t_pow = 0;
  Status inverse_failure;
  int j_pow = -1;
  EvalOptions eval;
  for (const Row& r : result.rows) {
    for (int k = 0; k < kJoints && check_power; ++k) {
      if (r.mode[k] == kStuck) continue;  // a holding torque times the drift of a held rate
      const double p = r.Mf[k] * Sim<M>::joint_rate(r, k);
      if (p < checks.friction_power_min) {
        checks.friction_power_min = p;
        t_pow = r.t;
        j_pow = k;
      }
    }
    if (any_stuck(r.mode)) continue;
    // inverse dynamics with the run's slip directions (a wrong direction shows in the power)
    EvalOf<M> ev;
    const bool bristles = law_descriptor(params.friction.law).states_per_joint > 0 && r.has_bristle;
    const Status st = mech::inverse<M, double>(
        params, loads(r.t), Eigen::Map<const VecOf<M>>(r.theta.data()),
        Eigen::Map<const VecOf<M>>(r.omega.data()), Eigen::Map<const VecOf<M>>(r.alpha.data()),
        params.friction.active() ? &r.mode : nullptr, eval, &ev, bristles ? &r.bristle : nullptr);
    if (!st.ok()) {  // the first row where inverse dynamics fails, with its own reason
      if (inverse_failure.ok()) {
        inverse_failure = at_time(st, r.t, r.theta.data(), M::kDof);
        checks.inverse_failed_at = r.t;
      }
      continue;
    }
    const double e = Sim<M>::drive_error(ev, r);
    if (!(e <= checks.inverse_dynamics_max_abs_error)) {
      checks.inverse_dynamics_max_abs_error = e;
      t_inv = r.t;
    }
  }
  if (!(checks.energy_balance_relative <= checks.energy_tol)) {
    checks.verdict = Status::Error(StatusCode::kSolverFailed,
                                   check_failure<M>("energy balance residual (relative)",
                                                 checks.energy_balance_relative, checks.energy_tol,
                                                 result.rows.back().t, -1));
  } else if (!inverse_failure.ok()) {
    checks.verdict = Status::Error(StatusCode::kSolverFailed,
                                   "inverse dynamics of the run failed " + inverse_failure.message);
  } else if (!(checks.inverse_dynamics_max_abs_error <= checks.inverse_tol)) {
    checks.verdict = Status::Error(
        StatusCode::kSolverFailed,
        check_failure<M>("inverse-dynamics residual [N m]", checks.inverse_dynamics_max_abs_error,
                      checks.inverse_tol, t_inv, -1));
  } else if (!(checks.friction_power_min >= -checks.power_tol)) {
    checks.verdict = Status::Error(
        StatusCode::kSolverFailed,
        check_failure<M>("friction supplies power: Mf w [W] =", checks.friction_power_min,
                      -checks.power_tol, t_pow, j_pow));
  }
  return checks;
}

}  // namespace

RunChecks check_run(const Params<double>& params, const LoadFunction& loads, const Result& result,
                    double rtol, double atol) {
  return checks_of<FiveBar>(params, loads, result, rtol, atol);
}

RunChecks check_run(const FourBarParams& params, const FourBarLoadFunction& loads,
                    const Result& result, double rtol, double atol) {
  return checks_of<FourBar>(params, loads, result, rtol, atol);
}

std::string non_finite_load(const char* name, double value, double t) {
  std::ostringstream msg;
  msg.precision(6);
  msg << "load " << name << " = " << (std::isnan(value) ? "nan" : value > 0 ? "inf" : "-inf")
      << " at t=" << t << " s is not finite: check the scene's load expression (loads." << name
      << ")";
  return msg.str();
}

}  // namespace fivebar::sim

// Holding a four-bar at rest (four_bar_rest.h): here, where the four-bar's inverse dynamics and
// lock are compiled for the simulator already.
namespace fivebar {

Status four_bar_holding(const FourBarParams& p, FourBarLoads L, double th1, const EvalOptions& opt,
                        FourBarHolding* h) {
  FourBarParams frictionless = p;
  frictionless.friction.law = FrictionLaw::kNone;
  FourBarEvaluation ev;
  const Status st = four_bar_inverse(frictionless, L, th1, 0.0, 0.0, opt, &ev);
  if (!st.ok()) return st;
  h->M1 = ev.M1;
  for (int k = 0; k < kFourBarJoints; ++k) {
    h->N[k] = ev.N[k];
    h->bound[k] = p.friction.active() ? FourBar::holding_capacity(p, k, ev.N[k]) : 0.0;
  }
  double ext[2] = {0.0, 0.0};  // below, above the equilibrium
  if (p.friction.active()) {
    L.M1 = h->M1;
    const double start = std::max(h->bound[0], 1e-12 * (1.0 + std::abs(h->M1)));
    for (int e = 0; e < 2; ++e) {
      const Status s = lock_extent<FourBar>(
          p, L, FourBar::Q<double>(th1), opt, h->M1, e == 0 ? -1.0 : 1.0, start,
          [](FourBarLoads* l, double v) { l->M1 = v; }, &ext[e]);
      if (!s.ok()) return s;
    }
  }
  h->M1_min = h->M1 - ext[0];
  h->M1_max = h->M1 + ext[1];
  return Status::Ok();
}

}  // namespace fivebar

// The four-bar's double passes (four_bar.h declares them `extern template` for the code that
// links fivebar::sim), compiled here with the simulator that runs them.
namespace fivebar::mech::detail {
template Status inverse_pass<FourBar, double>(const FourBar::Params<double>&,
                                              const FourBar::Loads<double>&,
                                              const FourBar::Q<double>&, const FourBar::Q<double>&,
                                              const FourBar::Q<double>&, const JointModes*,
                                              const EvalOptions&, FourBar::Evaluation<double>*,
                                              const std::array<double, kJoints>*, LoopSolution*);
template Status forward_pass<FourBar, double>(
    const FourBar::Params<double>&, const FourBar::Loads<double>&, const FourBar::Q<double>&,
    const FourBar::Q<double>&, const JointModes*, const EvalOptions&, FourBar::Evaluation<double>*,
    const std::array<double, kJoints>*, LoopSolution*, FrictionWarmStart*);
}  // namespace fivebar::mech::detail
