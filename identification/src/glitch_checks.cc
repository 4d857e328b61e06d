// Glitch checks of one log column before the repair: absurd values, a frozen encoder, steps of
// an angle; the noise level of the leave-one-out deviations.
#include "fivebar/identification/condition.h"
#include "glitches.h"
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include "fivebar/identification/rates.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"

namespace fivebar::identification::glitches {

std::vector<Glitch> reject_absurd(const TorqueLog& log, const char* name, std::vector<double>* x) {
  std::vector<Glitch> found;
  std::vector<double>& v = *x;
  const int n = static_cast<int>(v.size());
  if (n < 8) return found;
  std::vector<double> sorted = v;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[n / 2];
  const double spread = std::max(sorted[(3 * n) / 4] - sorted[n / 4], 1.0);
  // and isolated jumps: steps to and from the sample (one step at the ends, where no cubic can
  // tell which side is wrong) beyond 1000 times the median step
  std::vector<double> steps;
  for (int i = 1; i < n; ++i) steps.push_back(std::abs(v[i] - v[i - 1]));
  const double jump = 1e3 * std::max(median_of(std::move(steps)), 1e-12);
  auto step_ok = [&](int a, int b) { return std::abs(v[b] - v[a]) <= jump; };
  auto jumps = [&](int i) {
    // at an end: the jump to the neighbour, whose own next step is sane (else the neighbour is
    // the spike)
    if (i == 0) return !step_ok(0, 1) && step_ok(1, 2);
    if (i == n - 1) return !step_ok(n - 2, n - 1) && step_ok(n - 3, n - 2);
    return !step_ok(i - 1, i) && !step_ok(i, i + 1) && (v[i] - v[i - 1]) * (v[i + 1] - v[i]) < 0;
  };
  std::vector<char> bad(n, 0);
  for (int i = 0; i < n; ++i) bad[i] = !(std::abs(v[i] - median) <= 1e3 * spread) || jumps(i);
  for (int i = 0; i < n; ++i) {
    if (!bad[i]) continue;
    int a = i - 1, b = i + 1;
    while (a >= 0 && bad[a]) --a;
    while (b < n && bad[b]) ++b;
    double expected = median;
    if (a >= 0 && b < n) {
      expected = v[a] + (v[b] - v[a]) * (log.t[i] - log.t[a]) / (log.t[b] - log.t[a]);
    } else if (a >= 0 || b < n) {
      // at an end: the line through the two nearest sane samples on the one side
      const int p = a >= 0 ? a : b, dir = a >= 0 ? -1 : 1;
      int q = p + dir;
      while (q >= 0 && q < n && bad[q]) q += dir;
      expected = q >= 0 && q < n ? v[p] + (v[p] - v[q]) * (log.t[i] - log.t[p]) / (log.t[p] - log.t[q])
                                 : v[p];
    }
    Glitch g;
    g.index = i;
    g.line = log.lines.empty() ? i + 1 : log.lines[i];
    g.column = name;
    g.value = v[i];
    g.expected = expected;
    g.sigmas = kInf;
    found.push_back(g);
  }
  for (const Glitch& g : found) v[g.index] = g.expected;
  return found;
}

std::vector<Glitch> reject_frozen(const TorqueLog& log, const char* name, std::vector<double>* x) {
  std::vector<Glitch> found;
  std::vector<double>& v = *x;
  const int n = static_cast<int>(v.size());
  for (int s = 1; s + 3 < n;) {
    int e = s;
    while (e + 1 < n && v[e + 1] == v[s]) ++e;
    const bool run = e - s >= 2 && e + 2 < n;
    if (run) {
      const double before = std::abs(v[s] - v[s - 1]), after = std::abs(v[e + 2] - v[e + 1]);
      const double jump = std::abs(v[e + 1] - v[e]);
      if (before > 0 && jump > 2 * std::max(before, after)) {
        for (int i = s + 1; i <= e; ++i) {  // v[s] is the last good sample of the run
          Glitch g;
          g.index = i;
          g.line = log.lines.empty() ? i + 1 : log.lines[i];
          g.column = name;
          g.value = v[i];
          g.expected = v[s] + (v[e + 1] - v[s]) * (log.t[i] - log.t[s]) / (log.t[e + 1] - log.t[s]);
          g.sigmas = kInf;
          found.push_back(g);
        }
        for (const Glitch& g : found) v[g.index] = g.expected;
      }
    }
    s = e + 1;
  }
  return found;
}

namespace {

/// Steps of an angle between two samples (an encoder slip or reset): an isolated spike of the
/// first differences d_k = x_(k+1) - x_k, found like a glitch of d (leave-one-out cubic, the
/// glitch signature on both neighbours, beyond `sigmas` robust std and the floor of the motion's
/// own third differences). A glitch of x gives d a +g, -g doublet and an adjacent pair +g, 0,
/// -g: neither has the signature. Returns the index of the first sample after each step.
std::vector<int> find_steps(const std::vector<double>& t, const std::vector<double>& x,
                            double sigmas, std::vector<double>* sizes) {
  std::vector<int> found;
  const int n = static_cast<int>(x.size());
  if (n < 12) return found;
  std::vector<double> d, tm, d2;
  for (int k = 0; k + 1 < n; ++k) {
    d.push_back(x[k + 1] - x[k]);
    tm.push_back(0.5 * (t[k] + t[k + 1]));
  }
  for (size_t k = 1; k + 1 < d.size(); ++k) d2.push_back(d[k + 1] - 2 * d[k] + d[k - 1]);
  std::vector<double> expected;
  const std::vector<double> z = loo_deviation(tm, d, &expected);
  const double threshold = std::max(sigmas * robust_std(z), 10.0 * median_abs(d2));
  const int m = static_cast<int>(d.size());
  for (int k = 3; k + 4 < m; ++k) {
    const double a = std::abs(z[k]);
    if (!(a > threshold) || threshold <= 0 || !std::isfinite(a)) continue;
    if (std::abs(z[k - 1]) >= a || std::abs(z[k + 1]) > a) continue;
    if (!glitch_signature(z, k)) continue;
    found.push_back(k + 1);
    sizes->push_back(d[k] - expected[k]);
  }
  return found;
}

}  // namespace

std::string line_list(const std::vector<Glitch>& g, size_t max_shown) {
  std::string s;
  for (size_t i = 0; i < g.size() && i < max_shown; ++i) {
    s += (i ? ", " : "") + std::to_string(g[i].line);
  }
  if (g.size() > max_shown) s += ", ...";
  return s;
}

double torque_mismatch(const Params<double>& scene, const sim::LoadFunction& loads,
                       const TorqueLog& log, const std::vector<double>& th1,
                       const std::vector<double>& th2, double* median_rate) {
  const int n = log.size();
  const int step = std::max(1, n / 400);
  std::vector<double> w1, w2, a1, a2;  // at the samples read below only
  savitzky_golay(log.t, th1, SgOptions{}, &w1, &a1, step);
  savitzky_golay(log.t, th2, SgOptions{}, &w2, &a2, step);
  Params<double> p = scene;
  p.friction.law = FrictionLaw::kNone;
  std::vector<double> mismatch, rate;
  EvalOptions eval;
  for (int i = 0; i < n; i += step) {
    Evaluation<double> ev;
    const Status st = inverse_dynamics(p, loads(log.t[i]), th1[i], th2[i], w1[i], w2[i], a1[i],
                                       a2[i], nullptr, eval, &ev);
    mismatch.push_back(
        st.ok() ? std::max(std::abs(log.tau1[i] - ev.M1), std::abs(log.tau2[i] - ev.M2)) : kInf);
    rate.push_back(std::max(std::abs(w1[i]), std::abs(w2[i])));
  }
  *median_rate = median_abs(rate);
  return median_abs(mismatch);
}

double noise_std(const std::vector<double>& z) {
  const double s0 = robust_std(z);
  if (!(s0 > 0)) return 0;
  double s2 = 0;
  int c = 0;
  for (double v : z) {
    if (std::abs(v) <= 4 * s0) {
      s2 += v * v;
      ++c;
    }
  }
  return c ? std::sqrt(s2 / c / 0.99893) : s0;
}

namespace {

/// Samples on each side of a run that judge it.
constexpr int kRunSide = 6;

/// The fit of the kRunSide samples on each side of the run [a, b] by a cubic (plus, with
/// `offset`, a step from sample a on, its size in *offset): its largest residual; with
/// `expected`, the cubic at the run's samples.
double run_fit(const std::vector<double>& t, const std::vector<double>& x, int a, int b,
               double* offset, std::vector<double>* expected) {
  std::vector<int> run;
  for (int k = a; k <= b; ++k) run.push_back(k);
  const FitColumn step = [b](int k, double) { return k > b ? 1.0 : 0.0; };
  const LocalCubic fit =
      fit_cubic(t, x, a - kRunSide, b + kRunSide, run, a, a - 1, offset ? step : FitColumn());
  if (offset) *offset = fit.coef(4);
  if (expected) {
    expected->clear();
    for (int k = a; k <= b; ++k) expected->push_back(fit.at(t, k));
  }
  const Eigen::VectorXd& r = fit.residual;
  return r.allFinite() ? r.cwiseAbs().maxCoeff() : kInf;
}

/// A glitch run at the step find_steps flagged before sample k (a +0.1 rad burst of three
/// samples, a +0.1/-0.1 doublet or two swapped rows, none of them a step that "stays there"):
/// the run [a, b] of up to kMaxRun samples, containing k - 1 or k, whose leaving out lets
/// one cubic fit the kRunSide samples on each side within `tolerance`, with no step between
/// those sides (a cubic plus a step finds one under `tolerance`), while every sample of the run
/// leaves that cubic by more than `threshold`. The best fit among those; false when none.
bool glitch_run(const std::vector<double>& t, const std::vector<double>& x, int k,
                double threshold, double tolerance, int* first, std::vector<double>* expected) {
  const int n = static_cast<int>(x.size());
  double best = kInf;
  for (int a = k - kMaxRun; a <= k; ++a) {
    for (int b = std::max(a, k - 1); b < a + kMaxRun; ++b) {
      if (a < kRunSide || b + kRunSide >= n) continue;
      std::vector<double> e;
      double step = 0;
      const double misfit = run_fit(t, x, a, b, nullptr, &e);
      if (!(misfit <= tolerance) || !(misfit < best)) continue;
      run_fit(t, x, a, b, &step, nullptr);
      if (!(std::abs(step) <= tolerance)) continue;
      bool all_bad = true;
      for (int q = a; q <= b; ++q) all_bad = all_bad && std::abs(x[q] - e[q - a]) > threshold;
      if (!all_bad) continue;
      best = misfit;
      *first = a;
      *expected = e;
    }
  }
  return best < kInf;
}

/// The message for a step before sample i of size `size` that no glitch run explains: when a
/// step back of about the same size follows within 50 samples, the samples between are named
/// (the angle does not stay there); otherwise an encoder slip or reset.
std::string step_message(const TorqueLog& log, const std::vector<int>& steps,
                         const std::vector<double>& sizes) {
  auto line = [&](int i) { return log.lines.empty() ? i + 1 : log.lines[i]; };
  const int i = steps.front();
  const double s = sizes.front();
  for (size_t j = 1; j < steps.size() && steps[j] <= i + 50; ++j) {
    if (sizes[j] * s < 0 && std::abs(sizes[j] + s) < 0.5 * std::abs(s)) {
      return "the angle jumps by " + format_significant(s, 3) + " rad after line " +
             std::to_string(line(i - 1)) + " and back by " + format_significant(sizes[j], 3) +
             " rad after line " + std::to_string(line(steps[j] - 1)) + ": " +
             std::to_string(steps[j] - i) + " samples off their neighbours' trend, more than the " +
             std::to_string(kMaxRun) +
             " of a glitch run that is rejected; correct those lines or cut them out of the log";
    }
  }
  return "the angle steps by " + format_significant(s, 3) + " rad from line " +
         std::to_string(line(i - 1)) + " and stays there (" + std::to_string(steps.size()) +
         " such step(s)): an encoder slip or reset, not a motion; correct the offset or cut the "
         "log at the step";
}

}  // namespace

std::vector<Glitch> runs_or_steps(const TorqueLog& log, const char* name, std::vector<double>* x,
                                  double sigmas) {
  std::vector<Glitch> found;
  std::vector<double> d2;
  for (size_t i = 1; i + 1 < x->size(); ++i) d2.push_back((*x)[i + 1] - 2 * (*x)[i] + (*x)[i - 1]);
  const double noise = robust_std(loo_deviation(log.t, *x));
  const double threshold = std::max(sigmas * noise, 10.0 * median_abs(d2));
  for (int round = 0;; ++round) {
    std::vector<double> sizes;
    const std::vector<int> steps = find_steps(log.t, *x, sigmas, &sizes);
    if (steps.empty()) return found;
    int first = 0;
    std::vector<double> expected;
    if (round == 20 ||
        !glitch_run(log.t, *x, steps.front(), threshold, 0.5 * threshold, &first, &expected)) {
      const int i = steps.front();
      throw LogError(log.path,
                     "line " + std::to_string(log.lines.empty() ? i + 1 : log.lines[i]) +
                         ", column " + name,
                     step_message(log, steps, sizes));
    }
    for (size_t q = 0; q < expected.size(); ++q) {
      found.push_back(make_glitch(log, name, *x, first + static_cast<int>(q), expected[q], noise));
    }
    for (size_t q = 0; q < expected.size(); ++q) (*x)[first + q] = expected[q];
  }
}

}  // namespace fivebar::identification::glitches

namespace fivebar::identification {

int first_angle_step(const std::vector<double>& t, const std::vector<double>& x, double* size,
                     double sigmas) {
  std::vector<double> sizes;
  const std::vector<int> steps = glitches::find_steps(t, x, sigmas, &sizes);
  if (steps.empty()) return -1;
  *size = sizes.front();
  return steps.front();
}

}  // namespace fivebar::identification
