// validate(): the fitted scene simulated against the log, over the whole log and restarted
// every validation window.
#include "identify_stages.h"

namespace fivebar::identification {

using namespace stages;

Validation validate(const Params<double>& params, const sim::LoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1,
                    const std::vector<double>& omega2, double window_s, double rtol,
                    double budget_s) {
  const auto start = Clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  Validation v;
  v.window_s = window_s;
  const int n = log.size();
  v.full_theta1.assign(n, kNaN);
  v.full_theta2.assign(n, kNaN);
  v.window_theta1.assign(n, kNaN);
  v.window_theta2.assign(n, kNaN);
  if (n < 2) return v;
  auto run = [&](int i0, int i1, bool full, double* s2, int* count) {
    sim::Options o = window_sim_options(rtol);
    // a fitted scene far from the log (absurd logs) can make the simulation crawl: bounded
    o.max_wall_time_s = std::max(1e-3, (full ? 0.5 : 1.0) * budget_s - elapsed());
    o.max_steps = 50000;  // per output interval (a sample step): normal runs take a few
    o.duration = log.t[i1] - log.t[i0];
    o.output_step = o.duration / (i1 - i0);
    const sim::Result res =
        sim::simulate(params, logged_loads(log, loads, log.t[i0], params.actuators.offset),
                      {log.theta1[i0], log.theta2[i0], omega1[i0], omega2[i0]}, o);
    std::vector<double> ts, a, b;
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      a.push_back(row.theta[0]);
      b.push_back(row.theta[1]);
    }
    if (full) {
      v.status = res.status;
      v.full_duration_s = ts.empty() ? 0.0 : ts.back();
    }
    if (ts.size() < 2) return;
    for (int i = i0; i <= i1; ++i) {
      const double tt = log.t[i] - log.t[i0];
      if (tt > ts.back() + 1e-9) break;
      const double e1 = interp(ts, a, tt) - log.theta1[i];
      const double e2 = interp(ts, b, tt) - log.theta2[i];
      s2[0] += e1 * e1;
      s2[1] += e2 * e2;
      ++*count;
      (full ? v.full_theta1 : v.window_theta1)[i] = interp(ts, a, tt);
      (full ? v.full_theta2 : v.window_theta2)[i] = interp(ts, b, tt);
      if (full) {
        if (std::isnan(v.divergence_time_s) &&
            std::max(std::abs(e1), std::abs(e2)) > Validation::kDivergedAngle) {
          v.divergence_time_s = tt;
        }
        v.full_max[0] = std::max(v.full_max[0], std::abs(e1));
        v.full_max[1] = std::max(v.full_max[1], std::abs(e2));
      }
    }
  };
  double s2[2] = {0, 0};
  int count = 0;
  run(0, n - 1, true, s2, &count);
  for (int j = 0; j < kActuators; ++j) v.full_rms[j] = std::sqrt(s2[j] / std::max(1, count));
  double w2[2] = {0, 0};
  int wc = 0;
  for (auto [i0, i1] : make_windows(log, 0, n - 1, window_s)) {
    if (elapsed() > budget_s) {
      ++v.windows_skipped;
      continue;
    }
    run(i0, i1, false, w2, &wc);
  }
  for (int j = 0; j < kActuators; ++j) v.window_rms[j] = std::sqrt(w2[j] / std::max(1, wc));
  return v;
}

}  // namespace fivebar::identification
