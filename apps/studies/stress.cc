// Stress catalogue and runner. Every run is classified as
//   ok:       the run finished, every output value is finite, the energy balance closes to
//             StressOptions::max_energy_balance and the trajectory agrees with the case's
//             reference (rtol = atol = 1e-12) to StressCase::max_error;
//   rejected: the run stopped with a non-ok status and a message (a user gets exit 2 when the
//             start pose is bad input, as the scene loader rejects it, else exit 3);
//   failed:   anything else: a crash, a run killed at the wall-time budget (a hang), NaN in the
//             rows, an ok status with garbage, a rejection without a message.
// Runs are isolated in child processes (fork) so that a crash or hang of one run is a `failed`
// row, not the end of the study.
#include "fivebar/studies/stress.h"

#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"
#include "fivebar/model/names.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/sim/bytes.h"
#include "fivebar/studies/accuracy.h"

namespace fivebar::studies {

const char* stress_outcome_name(StressOutcome outcome) {
  static constexpr Named<StressOutcome> kNames[] = {{StressOutcome::kOk, "ok"},
                                                    {StressOutcome::kRejected, "rejected"},
                                                    {StressOutcome::kFailed, "failed"}};
  return name_in(kNames, outcome);
}

int StressReport::count(StressOutcome outcome) const {
  return static_cast<int>(std::count_if(rows.begin(), rows.end(),
                                        [&](const StressRow& r) { return r.outcome == outcome; }));
}

namespace {

// ---------------------------------------------------------------------------------------------
// The catalogue
// ---------------------------------------------------------------------------------------------

/// Steps an integrator may take to reach the next output time (SUNDIALS' mxstep, which is what
/// Options::max_steps sets). With the 1 ms output grid, 500 steps per interval is 5e5 steps per
/// second of motion: far above what any non-stiff case needs (<= 50 per interval at 1e-8), and
/// low enough that an explicit method on the stiff LuGre case is rejected within seconds.
constexpr long kStepsPerOutput = 500;
/// rtol = atol of the catalogue's runs.
constexpr double kRunTolerance = 1e-8;

Options run_options(double duration) {
  Options o;
  o.duration = duration;
  o.output_step = 1e-3;
  o.rtol = o.atol = kRunTolerance;
  o.max_steps = kStepsPerOutput;
  return o;
}

StressCase paper_case(const std::string& name, const std::string& description, double duration) {
  StressCase c;
  c.name = name;
  c.description = description;
  c.params = paper_params();
  c.loads = paper_loads;
  c.initial = {M_PI / 2, M_PI / 2, 0.0, 0.0};
  c.options = run_options(duration);
  return c;
}

/// The paper mechanism with couplers shortened to 0.2 m: |BD| reaches l3 + l4 = 0.4 m (the
/// paper's couplers, 0.5 m, never align since |BD| <= l0 + l1 + l2 = 0.42 m), so the stretched
/// singularity and unassemblable poses exist.
Params<double> stretchable_params() {
  Params<double> p = paper_params();
  p.links[2] = {0.20, 1.0, 0.1, 0.16, 0.0};
  p.links[3] = {0.20, 1.0, 0.1, 0.12, 0.0};
  p.point_p = 0.16;
  return p;
}

/// |sin(th4 - th3)| at a pose, or -1 where the mechanism cannot assemble.
double coupler_sine(const Params<double>& p, double th1, double th2) {
  Kinematics<double> k;
  if (!solve_kinematics(p, th1, th2, &k, 0.0).ok()) return -1.0;
  return std::abs(value_of(k.sin43));
}

/// th2 in [0, pi/2] at which the stretchable mechanism with th1 = pi has |sin(th4 - th3)| =
/// target (bisection: at th2 = 0 it cannot assemble, at pi/2 it is far from alignment).
double theta2_at_sine(const Params<double>& p, double target) {
  double lo = 0.0, hi = M_PI / 2;  // sine(lo) < target <= sine(hi)
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (coupler_sine(p, M_PI, mid) < target ? lo : hi) = mid;
  }
  return hi;
}

/// Crank torques that hold the frictionless mechanism at rest at (th1, th2) under `L`'s other
/// loads: minus the generalized force A thdd of the unheld mechanism.
Vec2<double> holding_torques(Params<double> p, Loads<double> L, double th1, double th2) {
  p.friction.law = FrictionLaw::kNone;
  L.M1 = L.M2 = 0.0;
  Evaluation<double> ev;
  if (!forward_dynamics(p, L, th1, th2, 0.0, 0.0, nullptr, EvalOptions{}, &ev).ok()) {
    return Vec2<double>::Zero();
  }
  return -(ev.A * ev.thdd);
}

}  // namespace

namespace {

/// Every joint with pin radius `radius` [m], mu_c = `coulomb` and mu_s = `static_coulomb`.
void set_pin_friction(FrictionParams<double>* f, double radius, double coulomb,
                      double static_coulomb) {
  f->pin_radius.fill(radius);
  f->coulomb.fill(coulomb);
  f->static_coulomb.fill(static_coulomb);
}

/// Couplers within 1e-3 rad of alignment at the start.
void near_singular_start_cases(double d_short, std::vector<StressCase>* cases) {
  StressCase c = paper_case("near_singular_start", "", d_short);
  c.params = stretchable_params();
  const double sine = 5e-4;  // couplers 5e-4 rad from alignment
  c.initial = {M_PI, theta2_at_sine(c.params, sine), 0.0, 0.0};
  c.description = "couplers " + format_significant(sine, 4) +
                  " rad from alignment at the start (l3 = l4 = 0.2 m)"
                  "; must be rejected by singular_margin = 1e-3 (exit 2)";
  cases->push_back(c);
  c.name = "near_singular_start_margin_1e-5";
  c.options.singular_margin = 1e-5;
  c.description = "the same start with singular_margin lowered to 1e-5: runs, or stops cleanly "
                  "at the margin";
  c.max_error = 1e-3;  // the motion starts next to a singularity: sensitive to the start
  cases->push_back(c);
}

/// Constant torques stretch the couplers straight.
StressCase driven_through_singularity_case(double d_short) {
  StressCase c = paper_case("driven_through_singularity", "", d_short);
  c.params = stretchable_params();
  c.loads = [](double) { return Loads<double>{10.0, -10.0, 0.0, 0.0, 0.0}; };
  c.description = "M1 = +10, M2 = -10 N m pull B and D apart until the couplers are straight "
                  "(l3 = l4 = 0.2 m): must stop with time and pose (exit 3)";
  return c;
}

/// r_k * mu so large that the fixed-point friction loop stops contracting.
void friction_loop_cases(double d_short, std::vector<StressCase>* cases) {
  StressCase c = paper_case("friction_newton", "", d_short);
  auto& f = c.params.friction;
  set_pin_friction(&f, 0.15, 0.6, 0.6);
  // started in motion: at rest, friction this large holds the mechanism (lock_analysis)
  c.initial = {M_PI / 2, M_PI / 2, 5.0, -3.0};
  c.description = "pin radius 0.15 m, mu_c = mu_s = 0.6, started at rates (5, -3) rad/s: the "
                  "fixed-point friction loop stops contracting on much of the motion, Newton "
                  "finds the unique reaction forces";
  cases->push_back(c);
  c.name = "friction_no_solution";
  set_pin_friction(&f, 0.15, 1.0, 1.0);
  c.description = "pin radius 0.15 m, mu_c = 1, started at rates (5, -3) rad/s: no consistent "
                  "reaction forces at the start: must be rejected saying so (exit 3)";
  cases->push_back(c);
  c.name = "friction_several_solutions";
  set_pin_friction(&f, 1.0, 0.12, 0.12);
  c.initial = {M_PI / 2, M_PI / 2, -3.0, 4.0};
  c.description = "pin radius 1 m, mu_c = 0.12, started at rates (-3, 4) rad/s: several "
                  "consistent reaction forces at the start: must be rejected saying so (exit 3)";
  cases->push_back(c);
}

/// A link with a tiny inertia.
void tiny_inertia_cases(double d_short, std::vector<StressCase>* cases) {
  StressCase c = paper_case("tiny_inertia", "", d_short);
  c.params.links[0].inertia = 1e-6;
  c.description = "paper scene with J1 = 1e-6 kg m^2 on crank 1";
  c.max_error = 1e-4;
  cases->push_back(c);
  c.name = "tiny_inertia_light_links";
  for (auto& link : c.params.links) {
    link.inertia = 1e-6;
    link.mass = 1e-2;
  }
  c.loads = [](double t) {
    Loads<double> L = paper_loads(t);
    L.M1 *= 1e-2;
    L.M2 *= 1e-2;
    L.M3 *= 1e-2;
    L.F *= 1e-2;
    return L;
  };
  c.description = "every link J = 1e-6 kg m^2 and m = 10 g, loads scaled by 1e-2 (gravity "
                  "dominated)";
  // measured: the error shrinks in proportion to the tolerance (arkode_erk87 4e-4 rad at
  // 1e-8, 5e-6 at 1e-10) while the 1e-12 and 1e-13 references agree to 1e-7: a sensitive
  // motion, not garbage
  c.max_error = 1e-3;
  cases->push_back(c);
}

/// LuGre with a stiff bristle.
StressCase lugre_stiff_case(double d_short) {
  StressCase c = paper_case("lugre_stiff", "", d_short);
  auto& f = c.params.friction;
  f.law = FrictionLaw::kLuGre;
  f.sigma0.fill(1e5);
  f.sigma1.fill(std::sqrt(1e5) * 1e-2);
  f.sigma2.fill(0.02);
  f.stribeck_velocity.fill(0.1);
  f.static_coulomb.fill(0.15);
  c.reference_method = Method::kCvodeBdf;
  // atol = 1e-8 against bristle deflections z ~ mu / sigma0 ~ 1e-6 rad: the runs resolve z to
  // about 1 %, so their angles are tolerance-limited well above 1e-8
  c.max_error = 1e-3;
  c.description = "LuGre, sigma0 = 1e5, sigma1 = 3.16, sigma2 = 0.02, w_st = 0.1, mu_s = 0.15: "
                  "stiff; implicit methods must run it, explicit ones may be rejected";
  return c;
}

/// A 200 Hz drive.
StressCase drive_200hz_case(double d_short) {
  StressCase c = paper_case("drive_200hz", "", d_short);
  c.loads = [](double t) {
    Loads<double> L = paper_loads(t);
    L.M1 = 2.0 + 5.0 * std::sin(2.0 * M_PI * 200.0 * t);
    return L;
  };
  c.description = "paper scene with M1 = 2 + 5 sin(2 pi 200 t)";
  return c;
}

/// A long run.
void long_run_cases(double d_short, double d_long, std::vector<StressCase>* cases) {
  StressCase c = paper_case("long_run_60s", "", d_long);
  c.description = "the paper scene over " + format_significant(d_long, 4) +
                  " s: energy balance drift over the "
                  "whole run; error over the first 2 s";
  // the forced motion is chaotic: cvode_adams at 1e-12 and 1e-13 and cvode_bdf at 1e-12
  // separate by more than 1e-6 rad after 5-7 s and by tens of radians at 60 s, so the error
  // is measured where the reference is meaningful
  c.error_horizon = 2.0;
  cases->push_back(c);
  // a hard constant drive: dozens of slip reversals at every joint (a missed one makes
  // friction supply power, which the run's checks catch)
  c = paper_case("hard_drive_40", "", d_short);
  c.loads = [](double t) {
    Loads<double> L = paper_loads(t);
    L.M1 = 40.0;
    L.M2 = -40.0;
    return L;
  };
  c.description = "the paper scene driven by M1 = 40, M2 = -40 N m: fast motion, many reversals";
  c.error_horizon = 1.0;
  cases->push_back(c);
}

/// A start that cannot assemble.
StressCase unassemblable_start_case(double d_short) {
  StressCase c = paper_case("unassemblable_start", "", d_short);
  c.params = stretchable_params();
  c.initial = {M_PI, 0.0, 0.0, 0.0};
  c.description = "|BD| = 0.42 m > l3 + l4 = 0.4 m at the start: must be rejected (exit 2)";
  return c;
}

/// A drive below breakaway: exact stick holds the mechanism still.
StressCase stick_below_breakaway_case(double d_short) {
  StressCase c = paper_case("stick_below_breakaway", "", d_short);
  c.params.gravity = 0.0;  // the 50 N force at P loads the joints: hold bound ~0.06 N m
  const Loads<double> force{0.0, 0.0, 0.0, 50.0, M_PI / 2};
  const Vec2<double> eq = holding_torques(c.params, force, M_PI / 2, M_PI / 2);
  c.loads = [eq](double t) {
    // equilibrium torques plus an excess below the holding bound, oscillating
    return Loads<double>{eq[0] + 0.02 * std::sin(5.0 * t), eq[1] - 0.02 * std::sin(5.0 * t),
                         0.0, 50.0, M_PI / 2};
  };
  c.max_displacement = 1e-12;
  c.description = "weightless paper scene held by torques 0.02 N m off equilibrium (below "
                  "breakaway): must not move (< 1e-12 rad)";
  return c;
}

/// Huge friction with stick-slip.
StressCase huge_friction_stick_case(double d_short) {
  StressCase c = paper_case("huge_friction_stick",
                            "pin radius 0.05 m, mu_c = 0.5, mu_s = 0.6: repeated stick and "
                            "breakaway (5 sticks, 4 breakaways in 1 s)",
                            d_short);
  set_pin_friction(&c.params.friction, 0.05, 0.5, 0.6);
  return c;
}

}  // namespace

std::vector<StressCase> stress_catalogue(bool reduced) {
  // durations: the full catalogue, and the reduced one for tests
  const double d_short = reduced ? 0.3 : 1.0;
  const double d_long = reduced ? 2.0 : 60.0;
  std::vector<StressCase> cases;
  near_singular_start_cases(d_short, &cases);
  cases.push_back(driven_through_singularity_case(d_short));
  friction_loop_cases(d_short, &cases);
  tiny_inertia_cases(d_short, &cases);
  cases.push_back(lugre_stiff_case(d_short));
  cases.push_back(drive_200hz_case(d_short));
  long_run_cases(d_short, d_long, &cases);
  cases.push_back(unassemblable_start_case(d_short));
  cases.push_back(stick_below_breakaway_case(d_short));
  cases.push_back(huge_friction_stick_case(d_short));
  return cases;
}

namespace {

// ---------------------------------------------------------------------------------------------
// One run and its classification
// ---------------------------------------------------------------------------------------------

bool row_finite(const Row& r) {
  bool ok = std::isfinite(r.t) && std::isfinite(r.M1) && std::isfinite(r.M2) &&
            std::isfinite(r.P_diss) && std::isfinite(r.E_diss) && std::isfinite(r.W_in) &&
            std::isfinite(r.W_ext) && std::isfinite(r.kinetic) && std::isfinite(r.potential);
  for (int i = 0; i < kLinks; ++i) {
    ok = ok && std::isfinite(r.theta[i]) && std::isfinite(r.omega[i]) && std::isfinite(r.alpha[i]);
  }
  for (int k = 0; k < kJoints; ++k) ok = ok && std::isfinite(r.N[k]) && std::isfinite(r.Mf[k]);
  return ok;
}

/// Exit status of `fivebar simulate` for a failed run: the scene loader rejects a start pose
/// that cannot assemble or lies within the singular margin as bad input (2); everything else is
/// a numerical failure (3).
int exit_code_for(const StressCase& c) {
  Kinematics<double> k;
  const Status st =
      solve_kinematics(c.params, c.initial.theta1, c.initial.theta2, &k, c.options.singular_margin);
  return st.ok() ? 3 : 2;
}

/// max |d theta_1..4| between two runs on the same grid over t <= horizon (all rows if horizon
/// is negative); infinity if the grids differ.
double theta_difference(const std::vector<Row>& a, const std::vector<Row>& b, double horizon) {
  if (a.size() != b.size()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (horizon >= 0.0 && a[i].t > horizon + 1e-12) break;
    for (int k = 0; k < kLinks; ++k) {
      worst = std::max(worst, std::abs(a[i].theta[k] - b[i].theta[k]));
    }
  }
  return worst;
}

/// Simulates `c` with `method` and classifies the result against `ref` (empty: no reference).
StressRow evaluate_run(const StressCase& c, Method method, const std::vector<Row>& ref,
                       const std::string& ref_message, const StressOptions& opt) {
  StressRow row;
  row.case_name = c.name;
  row.method = method;
  Options o = c.options;
  o.method = method;
  const Result r = simulate(c.params, c.loads, c.initial, o);
  row.wall_time_s = r.stats.wall_time_s;
  row.steps = r.stats.steps;
  row.rhs_evaluations = r.stats.rhs_evaluations;
  row.final_time = r.rows.empty() ? 0.0 : r.rows.back().t;
  const bool finite = std::all_of(r.rows.begin(), r.rows.end(), row_finite);
  auto fail = [&](const std::string& why) {
    row.outcome = StressOutcome::kFailed;
    row.exit_code = 0;
    row.message = why;
    return row;
  };

  if (!r.status.ok()) {
    row.exit_code = exit_code_for(c);
    if (r.status.message.empty()) return fail("stopped without a message");
    if (!finite) return fail("stopped (" + r.status.message + ") with non-finite output rows");
    row.outcome = StressOutcome::kRejected;
    row.message = r.status.message;
    return row;
  }

  // finished: check that the result is what it claims to be
  const long expected = std::lround(o.duration / o.output_step) + 1;
  if (static_cast<long>(r.rows.size()) != expected) {
    return fail("status ok with " + std::to_string(r.rows.size()) + " output rows, expected " +
                std::to_string(expected));
  }
  if (!finite) return fail("status ok with non-finite values in the output rows");
  const sim::RunChecks checks = sim::check_run(c.params, c.loads, r, o.rtol, o.atol);
  row.energy_balance = checks.energy_balance_relative;
  if (!(row.energy_balance <= opt.max_energy_balance)) {
    return fail("energy balance residual " + format_significant(row.energy_balance, 4) + " above " +
                format_significant(opt.max_energy_balance, 4));
  }
  // the run's own checks: friction never supplies power, inverse dynamics returns the input
  // (`simulate` exits 3 with that message: a rejection that names its reason)
  if (!checks.verdict.ok()) {
    row.outcome = StressOutcome::kRejected;
    row.exit_code = 3;
    row.message = "run check failed: " + checks.verdict.message;
    return row;
  }
  if (c.max_displacement >= 0.0) {
    row.displacement = 0.0;
    for (const Row& x : r.rows) {
      for (int i = 0; i < kLinks; ++i) {
        row.displacement =
            std::max(row.displacement, std::abs(x.theta[i] - r.rows.front().theta[i]));
      }
    }
    if (!(row.displacement <= c.max_displacement)) {
      return fail("moved " + format_significant(row.displacement, 4) +
                  " rad below breakaway (bound " + format_significant(c.max_displacement, 4) + ")");
    }
  }
  if (ref.empty()) {
    return fail("finished, but the reference run did not (" + ref_message +
                "): the result cannot be trusted");
  }
  row.error = theta_difference(r.rows, ref, c.error_horizon);
  if (!(row.error <= c.max_error)) {
    return fail("max |d theta| " + format_significant(row.error, 4) +
                " rad from the reference, above the case's "
                "bound " +
                format_significant(c.max_error, 4) + " (silent garbage)");
  }
  row.outcome = StressOutcome::kOk;
  row.exit_code = 0;
  return row;
}

// ---------------------------------------------------------------------------------------------
// Child processes: the result of a run comes back through a pipe as a flat byte string
// ---------------------------------------------------------------------------------------------

using Writer = sim::ByteWriter;
using Reader = sim::ByteReader;

void write_row(Writer* w, const StressRow& r) {
  w->put(static_cast<int>(r.outcome));
  w->put(r.exit_code);
  w->put(r.error);
  w->put(r.energy_balance);
  w->put(r.displacement);
  w->put(r.wall_time_s);
  w->put(r.steps);
  w->put(r.rhs_evaluations);
  w->put(r.final_time);
  w->put_string(r.message);
}

bool read_row(Reader* rd, StressRow* r) {
  int outcome = 0;
  const bool ok = rd->get(&outcome) && rd->get(&r->exit_code) && rd->get(&r->error) &&
                  rd->get(&r->energy_balance) && rd->get(&r->displacement) &&
                  rd->get(&r->wall_time_s) && rd->get(&r->steps) && rd->get(&r->rhs_evaluations) &&
                  rd->get(&r->final_time) && rd->get_string(&r->message);
  r->outcome = static_cast<StressOutcome>(outcome);
  return ok;
}

/// How a child ended.
struct ChildOutcome {
  bool finished = false;  ///< exited with status 0 and delivered its bytes
  std::string bytes;
  std::string problem;  ///< otherwise: killed at the budget, a signal, a bad exit status
};

/// Runs `work` in a child process and collects the bytes it returns, killing it after
/// `budget_s` seconds. The parent reads while the child writes (a full pipe never blocks it).
ChildOutcome run_child(const std::function<std::string()>& work, double budget_s) {
  ChildOutcome out;
  int fds[2];
  if (pipe(fds) != 0) {
    out.problem = std::string("pipe: ") + std::strerror(errno);
    return out;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    out.problem = std::string("fork: ") + std::strerror(errno);
    close(fds[0]);
    close(fds[1]);
    return out;
  }
  if (pid == 0) {
    // child: compute, write everything, leave without running the parent's atexit handlers
    close(fds[0]);
    const std::string bytes = work();
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = write(fds[1], bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) _exit(4);
      done += n;
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(budget_s);
  bool eof = false, timed_out = false;
  char buf[1 << 16];
  while (!eof) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    if (left <= 0.0) {
      timed_out = true;
      break;
    }
    pollfd p{fds[0], POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>(std::ceil(left * 1e3)));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) continue;  // timeout: the loop head ends it
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      eof = true;
    } else {
      out.bytes.append(buf, n);
    }
  }
  close(fds[0]);
  if (timed_out) kill(pid, SIGKILL);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    out.problem = "no result within the wall-time budget of " + format_significant(budget_s, 4) +
                  " s (killed)";
  } else if (WIFSIGNALED(status)) {
    out.problem = "crashed with signal " + std::to_string(WTERMSIG(status)) + " (" +
                  strsignal(WTERMSIG(status)) + ")";
  } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    out.problem = "child process exited with status " + std::to_string(WEXITSTATUS(status));
  } else {
    out.finished = true;
  }
  return out;
}

/// The reference of a case: its trajectory at the tightest tolerance (t and theta only).
struct ReferenceRun {
  StressReference info;
  std::vector<Row> rows;  ///< empty when the reference run did not finish
};

std::string encode_reference(const Result& r) {
  Writer w;
  w.put(static_cast<int>(r.status.code));
  w.put_string(r.status.message);
  w.put(r.stats.wall_time_s);
  w.put(r.stats.steps);
  w.put(static_cast<long>(r.rows.size()));
  for (const Row& x : r.rows) {
    w.put(x.t);
    for (double th : x.theta) w.put(th);
  }
  return w.bytes();
}

bool decode_reference(const std::string& bytes, ReferenceRun* ref) {
  Reader rd(bytes);
  int code = 0;
  long n = 0;
  if (!rd.get(&code) || !rd.get_string(&ref->info.message) || !rd.get(&ref->info.wall_time_s) ||
      !rd.get(&ref->info.steps) || !rd.get(&n) || n < 0) {
    return false;
  }
  ref->info.ok = code == static_cast<int>(StatusCode::kOk);
  ref->rows.resize(n);
  for (Row& x : ref->rows) {
    if (!rd.get(&x.t)) return false;
    for (double& th : x.theta) {
      if (!rd.get(&th)) return false;
    }
  }
  return true;
}

ReferenceRun reference_run(const StressCase& c, const StressOptions& opt) {
  ReferenceRun ref;
  ref.info.case_name = c.name;
  ref.info.method = c.reference_method;
  ref.info.tolerance = opt.reference_tolerance;
  Options o = c.options;
  o.method = c.reference_method;
  o.rtol = o.atol = opt.reference_tolerance;
  o.max_steps = 100 * c.options.max_steps;  // the reference may need many more steps
  auto work = [&] { return encode_reference(simulate(c.params, c.loads, c.initial, o)); };
  std::string bytes;
  if (opt.isolate) {
    // the reference gets three run budgets: it runs at a much tighter tolerance
    const ChildOutcome child = run_child(work, 3.0 * opt.run_budget_s);
    if (!child.finished) {
      ref.info.message = "reference run: " + child.problem;
      return ref;
    }
    bytes = child.bytes;
  } else {
    bytes = work();
  }
  if (!decode_reference(bytes, &ref)) {
    ref.info.ok = false;
    ref.info.message = "reference run: garbled result from the child process";
  }
  if (!ref.info.ok) ref.rows.clear();
  // the reference must itself be sound: finite and on the full grid
  const long expected = std::lround(o.duration / o.output_step) + 1;
  if (ref.info.ok && static_cast<long>(ref.rows.size()) != expected) {
    ref.info.ok = false;
    ref.info.message = "reference run finished with " + std::to_string(ref.rows.size()) +
                       " rows, expected " + std::to_string(expected);
    ref.rows.clear();
  }
  return ref;
}

}  // namespace

StressReport run_stress(const std::vector<StressCase>& cases, const StressOptions& opt) {
  StressReport report;
  for (const StressCase& c : cases) {
    const ReferenceRun ref = reference_run(c, opt);
    report.references.push_back(ref.info);
    for (Method m : opt.methods) {
      StressRow row;
      if (opt.isolate) {
        const ChildOutcome child = run_child(
            [&] {
              Writer w;
              write_row(&w, evaluate_run(c, m, ref.rows, ref.info.message, opt));
              return w.bytes();
            },
            opt.run_budget_s);
        Reader rd(child.bytes);
        if (!child.finished) {
          row.outcome = StressOutcome::kFailed;
          row.message = child.problem;
          row.wall_time_s = opt.run_budget_s;
        } else if (!read_row(&rd, &row)) {
          row.outcome = StressOutcome::kFailed;
          row.message = "garbled result from the child process";
        }
      } else {
        row = evaluate_run(c, m, ref.rows, ref.info.message, opt);
      }
      row.case_name = c.name;
      row.method = m;
      report.rows.push_back(row);
      if (opt.on_row) opt.on_row(report.rows.back());
    }
  }
  return report;
}

}  // namespace fivebar::studies
