// validate(): the fitted scene simulated against the log, over the whole log and restarted
// every validation window; one procedure for every mechanism (its driven angles compared).
#include "identify_stages.h"

namespace fivebar::identification {

using namespace stages;

namespace {

/// A run of the mechanism from sample i0 under the logged torques, with the given options.
using WindowRun = std::function<sim::Result(int i0, const sim::Options& options)>;

/// Compares the runs' driven angles (the first `dof` of each row) with the log's.
Validation validate_runs(const TorqueLog& log, int dof, const WindowRun& simulate_from,
                         double window_s, double rtol, double budget_s) {
  const auto start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  Validation v;
  v.dof = dof;
  v.window_s = window_s;
  const int n = log.size();
  std::vector<double>* full[2] = {&v.full_theta1, &v.full_theta2};
  std::vector<double>* windowed[2] = {&v.window_theta1, &v.window_theta2};
  for (int j = 0; j < kActuators; ++j) {
    full[j]->assign(n, kNaN);
    windowed[j]->assign(n, kNaN);
  }
  if (n < 2) return v;
  const std::vector<double>* logged[2] = {&log.theta1, &log.theta2};
  auto run = [&](int i0, int i1, bool is_full, double* s2, int* count) {
    sim::Options o = window_sim_options(rtol);
    // a fitted scene far from the log (absurd logs) can make the simulation crawl: bounded
    o.max_wall_time_s = std::max(1e-3, (is_full ? 0.5 : 1.0) * budget_s - elapsed());
    o.max_steps = 50000;  // per output interval (a sample step): normal runs take a few
    o.duration = log.t[i1] - log.t[i0];
    o.output_step = o.duration / (i1 - i0);
    const sim::Result res = simulate_from(i0, o);
    std::vector<double> ts, angle[2];
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      for (int j = 0; j < dof; ++j) angle[j].push_back(row.theta[j]);
    }
    if (is_full) {
      v.status = res.status;
      v.full_duration_s = ts.empty() ? 0.0 : ts.back();
    } else if (!res.status.ok()) {
      if (v.windows_stopped++ == 0) {
        v.window_stop = "the window from t = " + format_significant(log.t[i0], 6) + " s, " +
                        res.status.message + " (t from the window's start)";
      }
    }
    if (ts.size() < 2) return;
    for (int i = i0; i <= i1; ++i) {
      const double tt = log.t[i] - log.t[i0];
      if (tt > ts.back() + 1e-9) break;
      double worst = 0;
      for (int j = 0; j < dof; ++j) {
        const double sim_angle = interp(ts, angle[j], tt);
        const double e = sim_angle - (*logged[j])[i];
        s2[j] += e * e;
        (*(is_full ? full : windowed)[j])[i] = sim_angle;
        if (is_full) v.full_max[j] = std::max(v.full_max[j], std::abs(e));
        worst = std::max(worst, std::abs(e));
      }
      ++*count;
      if (is_full && std::isnan(v.divergence_time_s) && worst > Validation::kDivergedAngle) {
        v.divergence_time_s = tt;
      }
    }
  };
  double s2[2] = {0, 0};
  int count = 0;
  run(0, n - 1, true, s2, &count);
  for (int j = 0; j < dof; ++j) v.full_rms[j] = std::sqrt(s2[j] / std::max(1, count));
  double w2[2] = {0, 0};
  int wc = 0;
  for (auto [i0, i1] : make_windows(log, 0, n - 1, window_s)) {
    if (elapsed() > budget_s) {
      ++v.windows_skipped;
      continue;
    }
    run(i0, i1, false, w2, &wc);
  }
  for (int j = 0; j < dof; ++j) v.window_rms[j] = std::sqrt(w2[j] / std::max(1, wc));
  return v;
}

}  // namespace

Validation validate(const Params<double>& params, const sim::LoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1,
                    const std::vector<double>& omega2, double window_s, double rtol,
                    double budget_s) {
  const WindowRun from = [&](int i0, const sim::Options& o) {
    return sim::simulate(params, logged_loads(log, loads, log.t[i0], params.actuators.offset),
                         {log.theta1[i0], log.theta2[i0], omega1[i0], omega2[i0]}, o);
  };
  return validate_runs(log, 2, from, window_s, rtol, budget_s);
}

Validation validate(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1, double window_s,
                    double rtol, double budget_s) {
  const WindowRun from = [&](int i0, const sim::Options& o) {
    sim::Initial initial;
    initial.theta1 = log.theta1[i0];
    initial.omega1 = omega1[i0];
    return sim::simulate(params, logged_loads(log, loads, log.t[i0], params.actuators.offset[0]),
                         initial, o);
  };
  return validate_runs(log, 1, from, window_s, rtol, budget_s);
}

}  // namespace fivebar::identification
