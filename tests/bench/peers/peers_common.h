// Shared by bench_peers_mujoco and bench_peers_simbody: the frictionless paper scene (model.md,
// section 5) over its first second, the reference it is scored against, the fivebar runs it is
// compared with in the same process, and the markdown table they all end in.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/sim/simulator.h"
#include "paper.h"

namespace fivebar::peers {

inline constexpr double kDuration = 1.0;     ///< [s] first second of the scene
inline constexpr double kOutputStep = 1e-3;  ///< [s] output grid
inline constexpr int kOutputs = 1000;        ///< grid points after t = 0

/// Loads of the canonical scene (model.md, section 5): M1, M2 on the cranks, M3 on link 3,
/// F = 50 N at P perpendicular to link 3 (direction e(th3 + pi/2)).
using testing::paper_loads;

/// The scene's frictionless parameters (friction.law = kNone).
inline Params<double> frictionless_params() {
  Params<double> p = paper_params();
  p.friction.law = FrictionLaw::kNone;
  return p;
}

/// Closed-form assembly at th1 = th2 = pi/2, elbow_up: absolute coupler angles th3, th4.
inline std::array<double, 4> initial_angles() {
  Kinematics<double> k;
  const Status st = solve_kinematics(frictionless_params(), M_PI / 2, M_PI / 2, &k);
  if (!st.ok()) throw std::runtime_error("initial pose: " + st.message);
  return {k.th1, k.th2, k.th3, k.th4};
}

/// theta1..theta4 on the grid t = 0, 1 ms, ..., 1 s (kOutputs + 1 rows).
using Trajectory = std::vector<std::array<double, 4>>;

/// The first second of datasets/reference/paper_frictionless.csv.
inline Trajectory read_reference() {
  const std::string path = std::string(FIVEBAR_REFERENCE_DIR) + "/paper_frictionless.csv";
  auto cols = testing::read_csv(path);
  const std::vector<double>& t = cols["t"];
  if (static_cast<int>(t.size()) < kOutputs + 1) throw std::runtime_error(path + ": too short");
  Trajectory ref;
  for (int i = 0; i <= kOutputs; ++i) {
    if (std::abs(t[i] - kOutputStep * i) > 1e-9) {
      throw std::runtime_error(path + ": grid is not 1 ms");
    }
    ref.push_back({cols["theta1"][i], cols["theta2"][i], cols["theta3"][i], cols["theta4"][i]});
  }
  return ref;
}

/// max over the grid and the four angles of |theta - theta_ref| [rad]; inf if incomplete.
inline double max_error(const Trajectory& run, const Trajectory& ref) {
  if (run.size() != ref.size()) return INFINITY;
  double e = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    for (int j = 0; j < 4; ++j) {
      const double d = std::abs(run[i][j] - ref[i][j]);
      if (!(d == d)) return INFINITY;  // NaN
      e = std::max(e, d);
    }
  }
  return e;
}

/// Minimum wall time [s] of `run` over at least 3 and at most 30 repetitions, stopping once the
/// repetitions have taken 1.5 s: the minimum is the least disturbed by the other jobs on the host.
inline double min_wall(const std::function<void()>& run) {
  using clock = std::chrono::steady_clock;
  double best = INFINITY, total = 0;
  for (int rep = 0; rep < 30 && (rep < 3 || total < 1.5); ++rep) {
    const auto t0 = clock::now();
    run();
    const double s = std::chrono::duration<double>(clock::now() - t0).count();
    best = std::min(best, s);
    total += s;
  }
  return best;
}

/// One configuration of one engine, measured.
struct Measured {
  std::string engine, settings;
  double error = INFINITY;  ///< max |d theta_1..4| [rad]
  double wall = INFINITY;   ///< min wall time [s]
  std::string note;         ///< e.g. the engine's own statistics
};

/// A run on the output grid: `angles()` at t = 0, then after each `advance(i)`, which steps the
/// engine to t = i kOutputStep (kOutputs + 1 rows).
template <typename Advance, typename Angles>
Trajectory on_output_grid(Advance&& advance, Angles&& angles) {
  Trajectory tr;
  tr.reserve(kOutputs + 1);
  tr.push_back(angles());
  for (int i = 1; i <= kOutputs; ++i) {
    advance(i);
    tr.push_back(angles());
  }
  return tr;
}

/// One configuration measured: its error against `ref` and its minimum wall time; `run` returns
/// the trajectory (empty when the engine failed).
inline Measured measure(const std::string& engine, const std::string& settings,
                        const Trajectory& ref, const std::function<Trajectory()>& run) {
  Measured m;
  m.engine = engine;
  m.settings = settings;
  m.error = max_error(run(), ref);
  m.wall = min_wall([&] { run(); });
  return m;
}

/// fivebar on the same scene: sim::simulate over [0, 1] s on the 1 ms grid.
inline Trajectory fivebar_run(sim::Method method, double tol, sim::Result* out = nullptr) {
  sim::Options o;
  o.duration = kDuration;
  o.output_step = kOutputStep;
  o.method = method;
  o.rtol = o.atol = tol;
  sim::Result r = sim::simulate(frictionless_params(), paper_loads,
                                testing::paper_initial(), o);
  Trajectory tr;
  if (!r.status.ok()) return tr;
  for (const sim::Row& row : r.rows) tr.push_back(row.theta);
  if (out) *out = r;
  return tr;
}

/// The fivebar ladder: CVODE Adams (the default integrator), rtol = atol from 1e-6 to 1e-14.
inline std::vector<Measured> measure_fivebar(const Trajectory& ref) {
  std::vector<Measured> out;
  const std::pair<sim::Method, const char*> methods[] = {{sim::Method::kCvodeAdams, "cvode_adams"}};
  for (const auto& [method, name] : methods) {
    for (double tol : {1e-6, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14}) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%s, rtol = atol = %.0e", name, tol);
      sim::Result r;
      Measured m = measure("fivebar", buf, ref, [&] { return fivebar_run(method, tol, &r); });
      std::snprintf(buf, sizeof buf, "%ld steps, %ld rhs", r.stats.steps, r.stats.rhs_evaluations);
      m.note = buf;
      out.push_back(m);
    }
  }
  return out;
}

/// Prints the markdown table: every peer row with the fastest fivebar configuration whose error
/// is at most the peer's (the speed ratio is peer wall / that fivebar wall), then the fivebar rows.
inline void print_table(const std::string& peer, const std::vector<Measured>& peer_rows,
                        const std::vector<Measured>& fivebar_rows) {
  std::printf(
      "| engine | settings | max abs d theta_1..4 [rad] | wall [ms] | "
      "fastest fivebar at <= this error | fivebar wall [ms] | speed ratio |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const Measured& p : peer_rows) {
    const Measured* best = nullptr;
    for (const Measured& f : fivebar_rows) {
      if (f.error <= p.error && (!best || f.wall < best->wall)) best = &f;
    }
    if (best) {
      std::printf("| %s | %s | %.2e | %.3f | %s (%.2e rad) | %.3f | %.1fx |\n", p.engine.c_str(),
                  p.settings.c_str(), p.error, 1e3 * p.wall, best->settings.c_str(), best->error,
                  1e3 * best->wall, p.wall / best->wall);
    } else {
      std::printf("| %s | %s | %.2e | %.3f | none reaches this error | - | - |\n", p.engine.c_str(),
                  p.settings.c_str(), p.error, 1e3 * p.wall);
    }
  }
  for (const Measured& f : fivebar_rows) {
    std::printf("| %s | %s | %.2e | %.3f | (%s) | | |\n", f.engine.c_str(), f.settings.c_str(),
                f.error, 1e3 * f.wall, f.note.c_str());
  }
  // the peer's most accurate row against the fastest fivebar configuration at <= its error
  const Measured* top = nullptr;
  for (const Measured& p : peer_rows) {
    if (!top || p.error < top->error) top = &p;
  }
  const Measured* match = nullptr;
  for (const Measured& f : fivebar_rows) {
    if (top && f.error <= top->error && (!match || f.wall < match->wall)) match = &f;
  }
  if (top && match) {
    std::printf(
        "\nMost accurate %s row: %.2e rad in %.3f ms; fivebar reaches %.2e rad (%s) in "
        "%.3f ms: %.1fx faster at equal or smaller error.\n",
        peer.c_str(), top->error, 1e3 * top->wall, match->error, match->settings.c_str(),
        1e3 * match->wall, top->wall / match->wall);
  } else if (top) {
    std::printf(
        "\nMost accurate %s row: %.2e rad in %.3f ms; no fivebar configuration of the "
        "ladder reaches that error.\n",
        peer.c_str(), top->error, 1e3 * top->wall);
  }
  std::printf(
      "\nScene: the frictionless paper scene (model.md, section 5), t in [0, 1] s; error: "
      "max over the 1 ms grid of |theta_i - theta_i,ref|, i = 1..4, against "
      "datasets/reference/paper_frictionless.csv. Wall: minimum over repeated runs in "
      "this process; %s: the integration only (model built once, outside the timing); "
      "fivebar: a whole sim::simulate call. Speed ratio: peer wall / wall of the fastest "
      "fivebar configuration whose error is at most the peer's.\n",
      peer.c_str());
  std::printf(
      "%s cannot express the paper's joint friction Mf_k = r_k N_k f(w_k): its magnitude "
      "depends on the joint reaction N_k, which the engine only knows after solving the "
      "step, so the scene with friction is fivebar-only.\n",
      peer.c_str());
}

/// The body of a peer benchmark's main(): the peer's rows measured against the reference, then
/// fivebar's, then the table; an exception is reported on stderr with exit 1.
inline int run_peer_bench(
    const char* program, const std::string& peer,
    const std::function<std::vector<Measured>(const Trajectory&)>& peer_rows) {
  try {
    const Trajectory ref = read_reference();
    const std::vector<Measured> rows = peer_rows(ref);
    print_table(peer, rows, measure_fivebar(ref));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", program, e.what());
    return 1;
  }
  return 0;
}

}  // namespace fivebar::peers
