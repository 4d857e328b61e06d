// Event-driven simulation: the friction-aware right-hand side, root finding on the relative joint
// rates (where sign(w) jumps), restarts at every switch, and output rows on the scene's grid.
#include "fivebar/sim/simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/rest.h"
#include "integrator.h"

namespace fivebar::sim {

const char* method_name(Method m) {
  switch (m) {
    case Method::kCvodeAdams: return "cvode_adams";
    case Method::kCvodeBdf: return "cvode_bdf";
    case Method::kArkodeErk45: return "arkode_erk45";
    case Method::kArkodeErk87: return "arkode_erk87";
    case Method::kArkodeDirk: return "arkode_dirk";
    case Method::kArkodeErk65: return "arkode_erk65";
  }
  return "unknown";
}

bool parse_method(const std::string& name, Method* out) {
  for (Method m : kAllMethods) {
    if (name == method_name(m)) {
      *out = m;
      return true;
    }
  }
  return false;
}

namespace {

constexpr int kStates = 7;   // th1, th2, w1, w2, E_diss, W_in, W_ext
constexpr int kBristle = 7;  // LuGre scenes add z_1..z_5 from here

/// What the C callbacks see.
struct Context {
  const Params<double>* params = nullptr;
  const LoadFunction* loads = nullptr;
  EvalOptions eval;
  bool use_slip = false;                ///< Coulomb sign from the segment's slip directions
  std::array<int, 5> slip{};            ///< slip direction of each joint in this segment
  std::array<int, 5> root_joint{};      ///< root function index -> joint
  int nroots = 0;
  bool lugre = false;                   ///< bristle states follow the 7 base states
  bool full_rows = true;                ///< Options::full_rows
  long rhs_evaluations = 0;
  Status failure;                       ///< last failure inside a callback
  double failure_t = 0;
};

Status at_time(const Status& st, double t, double th1, double th2) {
  std::ostringstream msg;
  msg.precision(6);
  msg << "at t=" << t << " s (theta1=" << th1 << ", theta2=" << th2 << "): " << st.message;
  return Status::Error(st.code, msg.str());
}

int rhs(double t, const double* y, double* ydot, void* user) {
  auto& c = *static_cast<Context*>(user);
  ++c.rhs_evaluations;
  Evaluation<double> ev;
  std::array<double, 5> z{};
  if (c.lugre) std::copy(y + kBristle, y + kBristle + 5, z.begin());
  const Status st = forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3],
                                     c.use_slip ? &c.slip : nullptr, c.eval, &ev, &z);
  if (!st.ok()) {
    c.failure = at_time(st, t, y[0], y[1]);
    c.failure_t = t;
    return 1;  // recoverable: the integrator retries with a smaller step
  }
  if (c.lugre) std::copy(ev.zdot.begin(), ev.zdot.end(), ydot + kBristle);
  ydot[0] = y[2];
  ydot[1] = y[3];
  ydot[2] = ev.thdd[0];
  ydot[3] = ev.thdd[1];
  ydot[4] = ev.P_diss;
  ydot[5] = ev.P_in;
  ydot[6] = ev.P_ext;
  for (int i = 2; i < (c.lugre ? kStates + 5 : kStates); ++i) {
    if (!std::isfinite(ydot[i])) {
      c.failure = at_time(Status::Error(StatusCode::kSolverFailed, "non-finite acceleration"), t,
                          y[0], y[1]);
      return 1;
    }
  }
  return 0;
}

/// Relative joint rates at a state (needs only the first-order kinematics).
bool joint_rates(const Params<double>& p, const double* y, std::array<double, 5>* w) {
  Kinematics<double> k;
  if (!solve_kinematics(p, y[0], y[1], &k, 0.0, false).ok()) return false;
  const Vec2<double> thd(y[2], y[3]);
  *w = fivebar::detail::relative_rates(y[2], y[3], k.G3.dot(thd), k.G4.dot(thd));
  return true;
}

bool any_stuck(const std::array<int, 5>& slip) {
  return std::find(slip.begin(), slip.end(), kStuck) != slip.end();
}

/// Root functions: the relative rate of each slipping joint (zero where sign(w) would jump) and
/// the holding margin mu_s r N - |holding torque| of each stuck joint (zero at breakaway).
int roots(double t, const double* y, double* g, void* user) {
  auto& c = *static_cast<Context*>(user);
  if (any_stuck(c.slip)) {
    Evaluation<double> ev;
    const Status st = forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3], &c.slip,
                                       c.eval, &ev);
    if (!st.ok()) {
      c.failure = at_time(st, t, y[0], y[1]);
      return -1;
    }
    for (int r = 0; r < c.nroots; ++r) {
      const int j = c.root_joint[r];
      g[r] = c.slip[j] == kStuck ? ev.hold_margin[j] : ev.w[j];
    }
    return 0;
  }
  std::array<double, 5> w;
  if (!joint_rates(*c.params, y, &w)) {
    c.failure = at_time(Status::Error(StatusCode::kCannotAssemble, "pose cannot assemble"), t,
                        y[0], y[1]);
    return -1;
  }
  for (int r = 0; r < c.nroots; ++r) g[r] = w[c.root_joint[r]];
  return 0;
}

/// Removes the component of the crank rates that moves the stuck joints (after a stick the
/// located state has |w_k| at the root-finding tolerance; a stuck crank is then exactly at rest).
void project_rates(const Params<double>& p, const std::array<int, 5>& slip, double* y) {
  Kinematics<double> k;
  if (!solve_kinematics(p, y[0], y[1], &k).ok()) return;
  Vec2<double> thd(y[2], y[3]);
  int ns = 0;
  Mat2<double> Js = Mat2<double>::Zero();
  for (int j = 0; j < 5 && ns < 2; ++j) {
    if (slip[j] == kStuck) Js.row(ns++) = fivebar::detail::joint_row(k, j);
  }
  if (ns == 1) {
    const Row2<double> J = Js.row(0);
    thd -= J.transpose() * (J.dot(thd) / J.squaredNorm());
  } else if (ns == 2) {
    thd.setZero();  // two independent constraints lock the mechanism
  }
  y[2] = thd[0];
  y[3] = thd[1];
  if (slip[0] == kStuck) y[2] = 0.0;
  if (slip[4] == kStuck) y[3] = 0.0;
}

/// Tries to stick joint j at (t, y): true if friction can hold it (holding margin >= 0).
/// Otherwise `direction` receives the sign of the holding torque it would need, which is the
/// direction in which the joint slips.
bool can_stick(Context& c, double t, const double* y, int j, int* direction) {
  std::array<int, 5> trial = c.slip;
  trial[j] = kStuck;
  Evaluation<double> ev;
  const Status st =
      forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3], &trial, c.eval, &ev);
  if (!st.ok()) {
    *direction = -c.slip[j];
    return false;
  }
  *direction = sign_of(ev.Mf[j]);
  if (*direction == 0) *direction = -c.slip[j];
  return ev.hold_margin[j] >= 0.0;
}

/// Slip directions for the joints in `undecided` (at rest relative to each other): the direction
/// of the relative acceleration they get with those directions (model.md; reference README).
/// A short fixed-point over the sign vector; returns the last evaluation's status.
Status decide_slip(Context& c, double t, const double* y, const std::array<bool, 5>& undecided) {
  for (int k = 0; k < 5; ++k) {
    if (undecided[k]) c.slip[k] = 0;
  }
  if (std::none_of(undecided.begin(), undecided.end(), [](bool u) { return u; })) {
    return Status::Ok();
  }
  for (int pass = 0; pass < 6; ++pass) {
    Evaluation<double> ev;
    const Status st = forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3], &c.slip,
                                       c.eval, &ev);
    if (!st.ok()) return at_time(st, t, y[0], y[1]);
    const auto wdot = fivebar::detail::relative_accelerations(ev.thdd, ev.alpha3, ev.alpha4);
    bool changed = false;
    for (int k = 0; k < 5; ++k) {
      if (!undecided[k]) continue;
      const int s = sign_of(wdot[k]);
      if (s != c.slip[k]) {
        c.slip[k] = s;
        changed = true;
      }
    }
    if (!changed) break;
  }
  return Status::Ok();
}

/// Root directions: a joint slipping with w > 0 can only cross zero downwards, and vice versa;
/// a stuck joint's holding margin breaks away when it falls through zero.
void root_directions(const Context& c, int* dirs) {
  for (int r = 0; r < c.nroots; ++r) {
    const int s = c.slip[c.root_joint[r]];
    dirs[r] = s == kStuck ? -1 : -s;
  }
}

/// angle continued from the previous row's value (no 2 pi jumps in the output)
double continued(double angle, const Row* previous, int k) {
  if (!previous) return angle;
  return previous->theta[k] + std::remainder(angle - previous->theta[k], 2 * M_PI);
}

/// Angles-only row: the closure, the coupler rates and the energy quadratures.
Row make_angle_row(const Context& c, double t, const double* y, const Row* previous, Status* st) {
  Row row;
  row.t = t;
  Kinematics<double> k;
  *st = solve_kinematics(*c.params, y[0], y[1], &k);
  if (!st->ok()) {
    *st = at_time(*st, t, y[0], y[1]);
    return row;
  }
  const Vec2<double> thd(y[2], y[3]);
  row.theta = {y[0], y[1], continued(k.th3, previous, 2), continued(k.th4, previous, 3)};
  row.omega = {y[2], y[3], k.G3.dot(thd), k.G4.dot(thd)};
  row.E_diss = y[4];
  row.W_in = y[5];
  row.W_ext = y[6];
  row.mode = c.slip;
  if (c.lugre) std::copy(y + kBristle, y + kBristle + 5, row.bristle.begin());
  row.has_bristle = c.lugre;
  return row;
}

Row make_row(const Context& c, double t, const double* y, const Row* previous, Status* st) {
  if (!c.full_rows) return make_angle_row(c, t, y, previous, st);
  Row row;
  row.t = t;
  EvalOptions eval = c.eval;
  eval.want_reactions = true;
  eval.want_angles = true;
  eval.singular_margin = 0.0;
  const Loads<double> L = (*c.loads)(t);
  Evaluation<double> ev;
  std::array<double, 5> z{};
  if (c.lugre) std::copy(y + kBristle, y + kBristle + 5, z.begin());
  *st = forward_dynamics(*c.params, L, y[0], y[1], y[2], y[3], c.use_slip ? &c.slip : nullptr,
                         eval, &ev, &z);
  if (!st->ok()) {
    *st = at_time(*st, t, y[0], y[1]);
    return row;
  }
  row.theta = {y[0], y[1], continued(ev.kin.th3, previous, 2),
               continued(ev.kin.th4, previous, 3)};
  row.omega = {y[2], y[3], ev.bias.w3, ev.bias.w4};
  row.alpha = {ev.thdd[0], ev.thdd[1], ev.alpha3, ev.alpha4};
  row.M1 = L.M1;
  row.M2 = L.M2;
  for (int k = 0; k < 5; ++k) {
    row.N[k] = ev.N[k];
    row.Mf[k] = ev.Mf[k];
  }
  row.P_diss = ev.P_diss;
  row.E_diss = y[4];
  row.W_in = y[5];
  row.W_ext = y[6];
  row.kinetic = kinetic_energy(*c.params, ev.kin, y[2], y[3]);
  row.potential = potential_energy(*c.params, ev.kin);
  row.mode = c.use_slip ? c.slip : ev.slip;
  row.bristle = z;
  row.has_bristle = c.lugre;
  return row;
}

/// Joint modes at a state where the cranks are at rest (all five joints at rest): locked if
/// friction at the two crank joints can hold the mechanism (the holding torques of five joints
/// at rest are statically indeterminate; fivebar carries them at the crank joints O and D0,
/// where the drives act), else one crank stuck, else every joint slips in the direction of its
/// relative acceleration.
Status initial_modes(Context& c, double t, const double* y, bool stick) {
  Kinematics<double> k;
  const Status assembled = solve_kinematics(*c.params, y[0], y[1], &k);
  if (!assembled.ok()) return Status::Error(assembled.code, "initial pose: " + assembled.message);
  const Vec2<double> thd(y[2], y[3]);
  const std::array<double, 5> w =
      fivebar::detail::relative_rates(y[2], y[3], k.G3.dot(thd), k.G4.dot(thd));
  std::array<bool, 5> undecided;
  for (int k = 0; k < 5; ++k) {
    c.slip[k] = sign_of(w[k]);
    undecided[k] = (c.slip[k] == 0);
  }
  const bool at_rest = y[2] == 0.0 && y[3] == 0.0;
  if (stick && at_rest) {
    const bool holds[5] = {c.params->friction.coulomb[0] > 0, false, false, false,
                           c.params->friction.coulomb[4] > 0};
    // both cranks stuck: the mechanism is locked
    if (holds[0] && holds[4]) {
      c.slip = {kStuck, 0, 0, 0, kStuck};
      Evaluation<double> ev;
      const Status st = forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3],
                                         &c.slip, c.eval, &ev);
      if (st.ok() && ev.hold_margin[0] >= 0.0 && ev.hold_margin[4] >= 0.0) return st;
    }
    // one crank stuck, the rest slipping
    for (int j : {0, 4}) {
      if (!holds[j]) continue;
      c.slip = {0, 0, 0, 0, 0};
      c.slip[j] = kStuck;
      std::array<bool, 5> others = undecided;
      others[j] = false;
      if (!decide_slip(c, t, y, others).ok()) continue;
      Evaluation<double> ev;
      const Status st = forward_dynamics(*c.params, (*c.loads)(t), y[0], y[1], y[2], y[3],
                                         &c.slip, c.eval, &ev);
      if (st.ok() && ev.hold_margin[j] >= 0.0) return st;
    }
    c.slip = {0, 0, 0, 0, 0};
  }
  return decide_slip(c, t, y, undecided);
}

}  // namespace

Result simulate(const Params<double>& params, const LoadFunction& loads, const Initial& initial,
                const Options& options) {
  const auto wall_start = std::chrono::steady_clock::now();
  Result result;
  Context c;
  c.params = &params;
  c.loads = &loads;
  c.eval.singular_margin = options.singular_margin;
  c.eval.friction_tol = options.friction_tol;
  c.eval.friction_max_iter = options.friction_max_iter;
  c.eval.want_reactions = false;  // the motion needs reactions only through friction
  c.eval.want_angles = false;     // nor the coupler angles themselves

  // exact Coulomb sign: each joint with a Coulomb part gets a root function on its rate
  const bool exact_sign = params.friction.active() && params.friction.law != FrictionLaw::kLuGre &&
                          params.friction.smoothing_velocity == 0.0;
  c.use_slip = exact_sign && options.locate_switches;
  if (c.use_slip) {
    for (int k = 0; k < 5; ++k) {
      if (params.friction.coulomb[k] != 0.0 && params.friction.pin_radius[k] != 0.0) {
        c.root_joint[c.nroots++] = k;
      }
    }
  }

  c.lugre = params.friction.law == FrictionLaw::kLuGre;
  c.full_rows = options.full_rows;
  double y[kStates + 5] = {initial.theta1, initial.theta2, initial.omega1, initial.omega2,
                           0, 0, 0, 0, 0, 0, 0, 0};  // bristles start relaxed
  double t = 0.0;
  const bool stick = c.use_slip && options.stick;
  if (c.use_slip) {
    result.status = initial_modes(c, t, y, stick);
    if (!result.status.ok()) return result;
  }

  detail::OdeProblem prob{c.lugre ? kStates + 5 : kStates, c.nroots, &rhs, &roots, &c};
  prob.atol_scale.assign(prob.n, 1.0);
  prob.stiff_states = c.lugre;
  for (int i = kStates; i < prob.n; ++i) prob.atol_scale[i] = options.bristle_atol_scale;
  // explicit Runge-Kutta steps grow long (tens of ms at tight tolerances): a rate that touches
  // zero and comes back within one step would go unseen by the root finder, so with located
  // switches their step is capped at the output step (measured: `fivebar stress`)
  const bool explicit_rk = options.method == Method::kArkodeErk45 ||
                           options.method == Method::kArkodeErk65 ||
                           options.method == Method::kArkodeErk87;
  if (c.nroots > 0 && explicit_rk) prob.max_step = options.output_step;
  std::unique_ptr<detail::Integrator> integ = detail::make_integrator(prob, options,
                                                                      options.duration);
  integ->start(t, y);
  int dirs[5] = {0, 0, 0, 0, 0};
  if (c.nroots > 0) {
    root_directions(c, dirs);
    integ->set_root_direction(dirs);
  }

  const long n_out = std::lround(options.duration / options.output_step);
  result.rows.reserve(n_out + 1);
  Status st;
  result.rows.push_back(make_row(c, 0.0, y, nullptr, &st));
  if (!st.ok()) {
    result.status = st;
    return result;
  }
  for (long i = 1; i <= n_out && result.status.ok(); ++i) {
    const double tout = std::min(i * options.output_step, options.duration);
    while (true) {
      c.failure = Status::Ok();  // a recovered failure of an earlier step is not this one's
      const auto outcome = integ->advance(tout, y, &t);
      if (outcome == detail::Integrator::kFailed) {
        if (!c.failure.ok()) {
          result.status = c.failure;
        } else {
          result.status = at_time(Status::Error(StatusCode::kSolverFailed, integ->error()), t,
                                  y[0], y[1]);
        }
        break;
      }
      if (outcome == detail::Integrator::kRoot) {
        // a switch: a slipping joint's rate crossed zero, or a stuck joint's margin ran out
        int fired[5] = {0, 0, 0, 0, 0};
        integ->root_info(fired);
        std::array<bool, 5> unlocked{};
        for (int r = 0; r < c.nroots; ++r) {
          if (fired[r] == 0) continue;
          const int j = c.root_joint[r];
          ++result.stats.friction_events;
          int direction = -c.slip[j];
          if (c.slip[j] == kStuck) {
            // breakaway: slip in the direction of the holding torque that could not be carried
            Evaluation<double> ev;
            if (forward_dynamics(params, loads(t), y[0], y[1], y[2], y[3], &c.slip, c.eval, &ev)
                    .ok()) {
              direction = sign_of(ev.Mf[j]);
            }
            const bool was_locked = std::count(c.slip.begin(), c.slip.end(), kStuck) == 2;
            c.slip[j] = direction != 0 ? direction : 1;
            ++result.stats.breakaway_events;
            if (was_locked) {
              for (int k = 0; k < 5; ++k) unlocked[k] = (c.slip[k] == 0);
            }
          } else if (stick && can_stick(c, t, y, j, &direction)) {
            c.slip[j] = kStuck;
            ++result.stats.stick_events;
            if (std::count(c.slip.begin(), c.slip.end(), kStuck) == 2) {
              for (int k = 0; k < 5; ++k) {
                if (c.slip[k] != kStuck) c.slip[k] = 0;  // locked: every joint at rest
              }
            }
            project_rates(params, c.slip, y);
          } else {
            c.slip[j] = direction;  // reversal: slips the other way from here on
          }
        }
        if (std::any_of(unlocked.begin(), unlocked.end(), [](bool u) { return u; })) {
          result.status = decide_slip(c, t, y, unlocked);
          if (!result.status.ok()) break;
        }
        integ->start(t, y);
        root_directions(c, dirs);
        integ->set_root_direction(dirs);
        continue;
      }
      result.rows.push_back(make_row(c, tout, y, &result.rows.back(), &st));
      if (!st.ok()) result.status = st;
      if (options.max_wall_time_s > 0.0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count() >
              options.max_wall_time_s) {
        result.status = at_time(
            Status::Error(StatusCode::kSolverFailed,
                          "wall-time limit of " + std::to_string(options.max_wall_time_s) +
                              " s reached (simulation.max_wall_time_s)"),
            tout, y[0], y[1]);
      }
      break;
    }
  }
  result.stats.rhs_evaluations = c.rhs_evaluations;
  result.stats.steps = integ->steps();
  result.stats.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return result;
}

Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out) {
  return inverse_rows(params, loads, motion, out, RestThresholds{});
}

Status inverse_rows(const Params<double>& params, const LoadFunction& loads,
                    const std::vector<Row>& motion, std::vector<Row>* out,
                    const RestThresholds& rest) {
  out->clear();
  out->reserve(motion.size());
  const EvalOptions eval = with_rest(EvalOptions{}, rest);
  for (const Row& m : motion) {
    const Loads<double> L = loads(m.t);
    Evaluation<double> ev;
    // LuGre: the run's bristle states (a motion read from a file has none: steady state)
    const bool bristles = params.friction.law == FrictionLaw::kLuGre && m.has_bristle;
    const Status st = inverse_dynamics(params, L, m.theta[0], m.theta[1], m.omega[0], m.omega[1],
                                       m.alpha[0], m.alpha[1], nullptr, eval, &ev,
                                       bristles ? &m.bristle : nullptr);
    if (!st.ok()) return at_time(st, m.t, m.theta[0], m.theta[1]);
    Row r = m;
    const Row* previous = out->empty() ? nullptr : &out->back();
    r.theta[2] = continued(ev.kin.th3, previous, 2);
    r.theta[3] = continued(ev.kin.th4, previous, 3);
    r.omega[2] = ev.bias.w3;
    r.omega[3] = ev.bias.w4;
    r.alpha[2] = ev.alpha3;
    r.alpha[3] = ev.alpha4;
    r.M1 = ev.M1;
    r.M2 = ev.M2;
    for (int k = 0; k < 5; ++k) {
      r.N[k] = ev.N[k];
      r.Mf[k] = ev.Mf[k];
    }
    r.P_diss = ev.P_diss;
    r.mode = ev.slip;
    r.hold_margin = ev.hold_margin;
    r.kinetic = kinetic_energy(params, ev.kin, m.omega[0], m.omega[1]);
    r.potential = potential_energy(params, ev.kin);
    out->push_back(r);
  }
  // dissipated energy along the motion by the trapezoidal rule
  for (size_t i = 0; i < out->size(); ++i) {
    (*out)[i].E_diss = i == 0 ? 0.0
                              : (*out)[i - 1].E_diss + 0.5 * ((*out)[i].P_diss + (*out)[i - 1].P_diss) *
                                                           ((*out)[i].t - (*out)[i - 1].t);
  }
  return Status::Ok();
}

RunChecks check_run(const Params<double>& params, const LoadFunction& loads, const Result& result) {
  RunChecks checks;
  if (result.rows.empty()) return checks;
  const Row& r0 = result.rows.front();
  const double e0 = r0.kinetic + r0.potential;
  double worst = 0.0, scale = 1e-300;
  for (const Row& r : result.rows) {
    const double change = r.kinetic + r.potential - e0;
    worst = std::max(worst, std::abs(change - r.W_in - r.W_ext + r.E_diss));
    scale = std::max({scale, std::abs(r.W_in) + std::abs(r.W_ext), r.E_diss, std::abs(change)});
  }
  checks.energy_balance_relative = worst / scale;
  std::vector<Row> inv;
  if (inverse_rows(params, loads, result.rows, &inv).ok()) {
    for (size_t i = 0; i < inv.size(); ++i) {
      if (any_stuck(result.rows[i].mode)) continue;
      checks.inverse_dynamics_max_abs_error =
          std::max({checks.inverse_dynamics_max_abs_error, std::abs(inv[i].M1 - result.rows[i].M1),
                    std::abs(inv[i].M2 - result.rows[i].M2)});
    }
  } else {
    checks.inverse_dynamics_max_abs_error = INFINITY;
  }
  return checks;
}

}  // namespace fivebar::sim
