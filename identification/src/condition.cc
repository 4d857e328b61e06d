// Log conditioning: unwrapping, isolated-glitch rejection, noise levels, degrees from the motion.
#include "fivebar/identification/condition.h"

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

namespace fivebar::identification {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double median_abs(std::vector<double> v) {
  if (v.empty()) return 0;
  for (double& x : v) x = std::isfinite(x) ? std::abs(x) : kInf;
  return median_of(std::move(v));
}

double noise_std(const std::vector<double>& z);

/// Units of logged angles other than radians that the motion can reveal, with their factor to
/// radians: degrees, turns, gradians, and the counts of common encoder resolutions.
struct AngleUnit {
  const char* name;
  double to_rad;
};
constexpr AngleUnit kAngleUnits[] = {
    {"degrees", M_PI / 180},
    {"turns", 2 * M_PI},
    {"gradians", M_PI / 200},
    {"encoder counts (1000 per turn)", 2 * M_PI / 1000},
    {"encoder counts (1024 per turn)", 2 * M_PI / 1024},
    {"encoder counts (2000 per turn)", 2 * M_PI / 2000},
    {"encoder counts (2048 per turn)", 2 * M_PI / 2048},
    {"encoder counts (4000 per turn)", 2 * M_PI / 4000},
    {"encoder counts (4096 per turn)", 2 * M_PI / 4096},
    {"encoder counts (8192 per turn)", 2 * M_PI / 8192},
    {"encoder counts (10000 per turn)", 2 * M_PI / 10000},
    {"encoder counts (16384 per turn)", 2 * M_PI / 16384},
    {"encoder counts (65536 per turn)", 2 * M_PI / 65536},
};

/// Indices of the four neighbours the leave-one-out cubic of sample i uses.
std::array<int, 4> neighbours(int i, int n) {
  if (i < 2) return i == 0 ? std::array<int, 4>{1, 2, 3, 4} : std::array<int, 4>{0, 2, 3, 4};
  if (i > n - 3) {
    return i == n - 1 ? std::array<int, 4>{n - 5, n - 4, n - 3, n - 2}
                      : std::array<int, 4>{n - 5, n - 4, n - 3, n - 1};
  }
  return {i - 2, i - 1, i + 1, i + 2};
}

/// Glitch signature at an interior sample: the deviations of both neighbours have the other sign
/// and about 2/3 of its size (the cubic gives them weight 4/6); a step between two samples does
/// not have it (its neighbours deviate by 1/6 and 1/2 of the step).
bool glitch_signature(const std::vector<double>& z, int i) {
  const int n = static_cast<int>(z.size());
  if (i < 3 || i > n - 4) return true;  // at the ends the one-sided fit has no signature
  if (!std::isfinite(z[i])) return true;
  for (int j : {i - 1, i + 1}) {
    if (!std::isfinite(z[j])) return true;  // an absurd value drowns its neighbours
    const double ratio = -z[j] / z[i];
    if (!(ratio > 0.45 && ratio < 0.9)) return false;
  }
  return true;
}

/// One column beyond the cubic of a local fit: its value at sample k, u the sample's scaled time.
using FitColumn = std::function<double(int k, double u)>;

/// A local least-squares cubic (fit_cubic): its coefficients, residuals and frame.
struct LocalCubic {
  Eigen::VectorXd coef;      ///< of 1, u, u^2, u^3, then the extra column if any
  Eigen::VectorXd residual;  ///< fit minus sample, one per fitted sample in order of index
  double t0 = 0, step = 1, x0 = 0;
  /// the cubic (extra column left out) at sample k of `t`, in the column's units
  double at(const std::vector<double>& t, int k) const {
    const double u = (t[k] - t0) / step;
    return Eigen::RowVector4d(1, u, u * u, u * u * u).dot(coef.head<4>()) + x0;
  }
};

/// The least-squares fit of samples lo..hi of `x`, less those in `out`, by a cubic in
/// u = (t - t[centre]) / (mean sample step over lo..hi), plus `column` when given. Fitted to
/// x - x[ref]: the offset keeps multi-turn angles exact.
LocalCubic fit_cubic(const std::vector<double>& t, const std::vector<double>& x, int lo, int hi,
                     const std::vector<int>& out, int centre, int ref,
                     const FitColumn& column = {}) {
  LocalCubic fit;
  fit.t0 = t[centre];
  fit.step = (t[hi] - t[lo]) / (hi - lo);
  fit.x0 = x[ref];
  const int cols = column ? 5 : 4;
  std::vector<int> rows;
  for (int k = lo; k <= hi; ++k) {
    if (std::find(out.begin(), out.end(), k) == out.end()) rows.push_back(k);
  }
  Eigen::MatrixXd V(rows.size(), cols);
  Eigen::VectorXd y(rows.size());
  for (size_t r = 0; r < rows.size(); ++r) {
    const int k = rows[r];
    const double u = (t[k] - fit.t0) / fit.step;
    V.row(r).head(4) << 1, u, u * u, u * u * u;
    if (column) V(r, 4) = column(k, u);
    y(r) = x[k] - fit.x0;
  }
  fit.coef = V.colPivHouseholderQr().solve(y);
  fit.residual = V * fit.coef - y;
  return fit;
}

/// Whether a kink at interior sample i (the slope changing there: a joint breaking away from
/// rest, seen in its logged rate) explains the samples around i at least half as well as a
/// glitch of i does. A kink's leave-one-out deviations have the glitch signature's shape (its
/// neighbours deviate by -1/2 of it, against -2/3 for a glitch), so only a fit tells them apart.
bool kink_explains(const std::vector<double>& t, const std::vector<double>& x, int i) {
  const int n = static_cast<int>(x.size());
  if (i < 4 || i + 4 >= n) return false;
  // residual sum of squares of samples i - 4 .. i + 4 about a cubic plus `column`
  auto rss = [&](const FitColumn& column) {
    return fit_cubic(t, x, i - 4, i + 4, {}, i, i - 4, column).residual.squaredNorm();
  };
  const double glitch = rss([i](int k, double) { return k == i ? 1.0 : 0.0; });
  const double kink = rss([](int, double u) { return std::max(0.0, u); });
  return !(glitch < 0.5 * kink);
}

/// Which sample near an end is the glitch. There the leave-one-out cubic extrapolates, and one
/// bad sample among the first four makes its neighbours deviate about as much as itself (a
/// glitch on sample 1 gives sample 0 the same deviation): the culprit is the sample whose
/// removal lets a cubic fit the other seven of the eight end samples best. `hit` is the sample
/// flagged; returns the culprit and its value from that fit.
int end_culprit(const std::vector<double>& t, const std::vector<double>& x, int hit,
                double* expected) {
  const int n = static_cast<int>(x.size());
  const bool start = hit < n / 2;
  const int base = start ? 0 : n - 8;
  double best = std::numeric_limits<double>::infinity();
  int culprit = hit;
  *expected = x[hit];
  for (int c = 0; c < 4; ++c) {
    const int j = start ? c : n - 1 - c;
    const LocalCubic fit = fit_cubic(t, x, base, base + 7, {j}, j, j == base ? base + 1 : base);
    const double rms = fit.residual.norm();
    if (rms < best) {
      best = rms;
      culprit = j;
      *expected = fit.coef(0) + fit.x0;  // the cubic at t_j (u = 0)
    }
  }
  return culprit;
}

/// The end samples a cubic fits once the samples of `out` (one or two of the kEndCandidates
/// nearest the end) are left out.
constexpr int kEndWindow = 10, kEndCandidates = 6;

struct EndFit {
  std::vector<int> bad;           ///< the samples left out
  std::vector<double> expected;   ///< the cubic at each of them
  double rss = std::numeric_limits<double>::infinity();
};

/// The cubic through the kEndWindow end samples other than `bad`: whether it fits them within
/// `tolerance` while every left-out sample leaves it by more than `threshold`.
bool fit_end(const std::vector<double>& t, const std::vector<double>& x, bool start,
             const std::vector<int>& bad, double threshold, double tolerance, EndFit* fit) {
  const int n = static_cast<int>(x.size());
  const int base = start ? 0 : n - kEndWindow;
  const int ref = start ? base + kEndWindow - 1 : base;  // farthest from the end: never bad
  const LocalCubic cubic = fit_cubic(t, x, base, base + kEndWindow - 1, bad, ref, ref);
  const Eigen::VectorXd& r = cubic.residual;
  if (!r.allFinite() || !(r.cwiseAbs().maxCoeff() <= tolerance)) return false;
  fit->bad = bad;
  fit->expected.clear();
  for (int k : bad) {
    const double e = cubic.at(t, k);
    if (!(std::abs(x[k] - e) > threshold)) return false;
    fit->expected.push_back(e);
  }
  fit->rss = r.squaredNorm();
  return true;
}

/// Which samples near an end are bad, when a leave-one-out hit falls there: the fewest (one,
/// else two) of the kEndCandidates samples nearest the end whose removal lets a cubic fit the
/// other end samples within half the glitch threshold while each removed one leaves it by more
/// than the threshold; the best fit among those. A pair of bad samples there (e.g. lines
/// 1997-1998 of 2001, which taken one at a time give viscous -4.7 std, five good samples
/// "rejected" and one replaced by a value 0.2 rad off) has no single culprit. False when no such
/// set exists.
bool end_repair(const std::vector<double>& t, const std::vector<double>& x, bool start,
                double threshold, EndFit* best) {
  const int n = static_cast<int>(x.size());
  if (n < 2 * kEndWindow) return false;
  auto sample = [&](int c) { return start ? c : n - 1 - c; };
  EndFit all;
  if (fit_end(t, x, start, {}, threshold, 0.5 * threshold, &all)) return false;  // none bad
  for (int size = 1; size <= 2; ++size) {
    for (int a = 0; a < kEndCandidates; ++a) {
      for (int b = size == 1 ? a : a + 1; b < (size == 1 ? a + 1 : kEndCandidates); ++b) {
        std::vector<int> bad = {sample(a)};
        if (size == 2) bad.push_back(sample(b));
        EndFit fit;
        if (fit_end(t, x, start, bad, threshold, 0.5 * threshold, &fit) && fit.rss < best->rss) {
          *best = fit;
        }
      }
    }
    if (!best->bad.empty()) return true;
  }
  return false;
}

/// Whether the run (i .. i + len - 1) is the two sides of a step or a kink rather than bad
/// samples: its first samples continue the line through the left neighbours (i - 2, i - 1) and
/// the others the line through the right ones (i + len, i + len + 1), each to within half its
/// deviation from the cubic across the run (all on one side: the run is one side of a step).
/// A step or a kink inside or beside the run (a breakaway's jump of the logged acceleration,
/// the kink of its logged rate, a torque flipping with the friction) leaves the cubic with one
/// sign, as a glitch run does; but a glitch run leaves both sides' lines.
bool continues_one_side(const std::vector<double>& t, const std::vector<double>& x, int i,
                        int len, const double* cubic) {
  const auto along = [&](int q, int a) {
    const double line = x[a] + (x[a + 1] - x[a]) * (t[i + q] - t[a]) / (t[a + 1] - t[a]);
    return std::abs(x[i + q] - line) < 0.5 * std::abs(x[i + q] - cubic[q]);
  };
  for (int split = 0; split <= len; ++split) {  // samples before `split` on the left line
    bool sides = true;
    for (int q = 0; q < len && sides; ++q) sides = along(q, q < split ? i - 2 : i + len);
    if (sides) return true;
  }
  return false;
}

/// Runs of `len` adjacent bad samples (2: two adjacent +0.1 rad samples must not give Coulomb at
/// its bound 0; 3: a 3-sample torque burst of 1.5 N m must not give Coulomb +3 std with the noise
/// floor doubled). Each sample of a run is in the others'
/// leave-one-out stencils, which hides them all. The run (i .. i + len - 1) is predicted by the
/// cubic through i - 2, i - 1, i + len, i + len + 1; it is a glitch when every deviation (over
/// its noise gain) passes `threshold` with the same sign, the run is the largest among its
/// overlapping neighbours, and it does not continue one side (continues_one_side: the runs
/// beside a step). A step straddled by the run deviates with opposite signs. Returns the first
/// sample of each run, and the run's predictions in `expected`.
std::vector<int> run_hits(const std::vector<double>& t, const std::vector<double>& x, int len,
                          double threshold, std::vector<std::vector<double>>* expected) {
  const int n = static_cast<int>(x.size());
  std::vector<double> score(n, 0.0);
  std::vector<double> pred(static_cast<size_t>(n) * len, 0.0);  // run i: pred[i * len + q]
  for (int i = 2; i + len + 1 < n; ++i) {
    const int nb[4] = {i - 2, i - 1, i + len, i + len + 1};
    double lo = kInf;
    int sign = 0;
    for (int q = 0; q < len; ++q) {
      double gain2 = 1, p = 0;
      for (int a = 0; a < 4; ++a) {
        double w = 1;
        for (int b = 0; b < 4; ++b) {
          if (b != a) w *= (t[i + q] - t[nb[b]]) / (t[nb[a]] - t[nb[b]]);
        }
        gain2 += w * w;
        p += w * (x[nb[a]] - x[i]);  // offset: keeps multi-turn angles exact
      }
      double& at = pred[static_cast<size_t>(i) * len + q];
      at = p + x[i];
      const double e = (x[i + q] - at) / std::sqrt(gain2);
      const int sq = e > 0 ? 1 : e < 0 ? -1 : 0;
      if (!std::isfinite(e) || sq == 0 || (q > 0 && sq != sign)) lo = -1;
      sign = sq;
      lo = std::min(lo, std::abs(e));
    }
    if (lo > 0 && !continues_one_side(t, x, i, len, &pred[static_cast<size_t>(i) * len])) {
      score[i] = lo;
    }
  }
  std::vector<int> hits;
  for (int i = 2; i + len + 1 < n; ++i) {
    if (!(score[i] > threshold) || threshold <= 0) continue;
    bool peak = true;
    for (int j = std::max(0, i - len); j <= std::min(n - 1, i + len); ++j) {
      if (j != i && (score[j] > score[i] || (j < i && score[j] == score[i]))) peak = false;
    }
    if (!peak) continue;
    hits.push_back(i);
    const auto first = pred.begin() + static_cast<std::ptrdiff_t>(i) * len;
    expected->emplace_back(first, first + len);
  }
  return hits;
}

/// The glitch of sample i of column `name` (values `x`, before repair), with its expected value.
Glitch make_glitch(const TorqueLog& log, const char* name, const std::vector<double>& x, int i,
                   double expected, double noise) {
  Glitch g;
  g.index = i;
  g.expected = expected;
  g.line = log.lines.empty() ? i + 1 : log.lines[i];
  g.column = name;
  g.value = x[i];
  g.sigmas = noise > 0 ? std::abs(g.value - g.expected) / noise : kInf;
  return g;
}

/// Noise gain of an interior leave-one-out deviation (weights -1/6, 4/6, 4/6, -1/6): the floor
/// of a column is compared with the deviation over it everywhere, so that the ends (gain ~8.4)
/// are judged like the inside (a +100 spike of alpha1 on the last line is found too).
const double kInteriorGain = std::sqrt(70.0 / 36.0);

/// A burst of up to this many samples that leaves the trend and returns is a glitch run (a step
/// of an angle, glitch_run; adjacent glitches of any column, run_hits).
constexpr int kMaxRun = 3;

/// Leave-one-out hits of one pass: beyond `noise_threshold` (in noise std, `z`) and, by its
/// deviation from `expected` over kInteriorGain, beyond `floor`; the largest within two samples,
/// with the glitch signature, and not a kink.
std::vector<int> single_hits(const std::vector<double>& t, const std::vector<double>& x,
                             const std::vector<double>& z, const std::vector<double>& expected,
                             double noise_threshold, double floor) {
  const int n = static_cast<int>(x.size());
  std::vector<int> hits;
  for (int i = 0; i < n; ++i) {
    const double a = std::abs(z[i]);
    const bool beyond = a > noise_threshold &&
                        (std::isinf(a) || std::abs(x[i] - expected[i]) / kInteriorGain > floor);
    if (!beyond || std::max(noise_threshold, floor) <= 0) continue;
    bool peak = true;
    for (int j = std::max(0, i - 2); j <= std::min(n - 1, i + 2); ++j) {
      if (j != i && std::abs(z[j]) > a) peak = false;
      if (j < i && std::abs(z[j]) == a) peak = false;  // ties: the first one
    }
    if (peak && glitch_signature(z, i) && !kink_explains(t, x, i)) hits.push_back(i);
  }
  return hits;
}

/// The bad samples at one end (end_repair), repaired in place and appended to `found`; false
/// when the end fit finds none.
bool repair_end(const TorqueLog& log, const char* name, bool start, double threshold,
                double noise, std::vector<double>* x, std::vector<Glitch>* found) {
  EndFit fit;
  if (!end_repair(log.t, *x, start, threshold, &fit)) return false;
  for (size_t k = 0; k < fit.bad.size(); ++k) {
    found->push_back(make_glitch(log, name, *x, fit.bad[k], fit.expected[k], noise));
  }
  for (size_t k = 0; k < fit.bad.size(); ++k) (*x)[fit.bad[k]] = fit.expected[k];
  return true;
}

/// Repairs the hits of one pass in place, appending them to `found`: hits near an end by the
/// end fit (end_repair: one or two bad samples there), the others (and those near an end that
/// no end fit explains) one by one, the culprit of a hit on the first or last three samples by
/// end_culprit.
void repair_hits(const TorqueLog& log, const char* name, const std::vector<int>& hits,
                 const std::vector<double>& z, const std::vector<double>& expected,
                 double threshold, double noise, std::vector<double>* x,
                 std::vector<Glitch>* found) {
  const int n = static_cast<int>(x->size());
  auto near = [n](int i, bool start) { return start ? i < kEndWindow - 1 : i > n - kEndWindow; };
  bool explained[2] = {false, false};
  for (int e = 0; e < 2; ++e) {
    const bool start = e == 0;
    if (std::none_of(hits.begin(), hits.end(), [&](int i) { return near(i, start); })) continue;
    explained[e] = repair_end(log, name, start, threshold, noise, x, found);
  }
  for (int i : hits) {
    if ((explained[0] && near(i, true)) || (explained[1] && near(i, false))) continue;
    int index = i;
    double value = expected[i];
    if ((i < 3 || i > n - 4) && std::isfinite(z[i])) index = end_culprit(log.t, *x, i, &value);
    found->push_back(make_glitch(log, name, *x, index, value, noise));
    (*x)[index] = value;
  }
}

/// One glitch per sample: a sample flagged again in a later pass (its first repair left it off
/// the trend) keeps the value in the file and takes its last repair (so the glitch list neither
/// repeats lines nor counts them twice).
void merge_repeats(std::vector<Glitch>* found, double noise) {
  std::vector<Glitch> merged;
  for (const Glitch& g : *found) {
    auto same = std::find_if(merged.begin(), merged.end(),
                             [&](const Glitch& m) { return m.index == g.index; });
    if (same == merged.end()) {
      merged.push_back(g);
      continue;
    }
    same->expected = g.expected;
    same->sigmas = noise > 0 ? std::abs(same->value - same->expected) / noise : kInf;
  }
  *found = std::move(merged);
}

/// Repairs in place the shortest runs of adjacent glitches (run_hits) of lengths shortest to
/// longest that are found, appending them to `found`; returns their length (0: none found).
int repair_runs(const TorqueLog& log, const char* name, int shortest, int longest,
                double threshold, double noise, std::vector<double>* x,
                std::vector<Glitch>* found) {
  for (int len = shortest; len <= longest; ++len) {
    std::vector<std::vector<double>> expected;
    const std::vector<int> runs = run_hits(log.t, *x, len, threshold, &expected);
    for (size_t k = 0; k < runs.size(); ++k) {
      for (int q = 0; q < len; ++q) {
        found->push_back(make_glitch(log, name, *x, runs[k] + q, expected[k][q], noise));
      }
      for (int q = 0; q < len; ++q) (*x)[runs[k] + q] = expected[k][q];
    }
    if (!runs.empty()) return len;
  }
  return 0;
}

/// Rejects isolated glitches of one column in place; returns the glitches found.
std::vector<Glitch> reject_column(const TorqueLog& log, const char* name, double sigmas,
                                  std::vector<double>* x, double* noise, double min_threshold) {
  std::vector<Glitch> found;
  const int n = static_cast<int>(x->size());
  if (n < 8) return found;
  // the motion's own curvature: second differences, robustly; a noise-free log has kinks
  // (acceleration jumps at slip reversals) that leave the cubic by ~0.1 of them
  std::vector<double> d2;
  for (int i = 1; i + 1 < n; ++i) d2.push_back((*x)[i + 1] - 2 * (*x)[i] + (*x)[i - 1]);
  const double curvature_floor = std::max(10.0 * median_abs(d2), min_threshold);
  for (int pass = 0; pass < 4; ++pass) {
    std::vector<double> expected;
    const std::vector<double> z = loo_deviation(log.t, *x, &expected);
    *noise = robust_std(z);
    const double threshold = std::max(sigmas * *noise, curvature_floor);
    const std::vector<int> hits =
        single_hits(log.t, *x, z, expected, sigmas * *noise, curvature_floor);
    if (hits.empty()) {
      // no single glitch left: adjacent pairs, each hiding the other from the leave-one-out
      int len = repair_runs(log, name, 2, 2, threshold, *noise, x, &found);
      // and a pair at an end, where neither has a two-sided stencil
      bool ends = false;
      for (bool start : {true, false}) {
        ends = repair_end(log, name, start, threshold, *noise, x, &found) || ends;
      }
      // then, with neither, longer runs (a pair at an end would pass for one)
      if (len == 0 && !ends) len = repair_runs(log, name, 3, kMaxRun, threshold, *noise, x, &found);
      if (len > 0 || ends) continue;
      *noise = noise_std(z);
      break;
    }
    repair_hits(log, name, hits, z, expected, threshold, *noise, x, &found);
  }
  merge_repeats(&found, *noise);
  return found;
}

/// Absurd values: samples farther from the column's median than 1000 times its interquartile
/// range (at least 1 in the column's unit), or jumping away and back by more than 1000 median
/// steps. No cubic can judge them (a 1e300 spike overflows every
/// leave-one-out fit that uses it, and near the ends it drowns the sample that is really wrong),
/// so they are replaced first, by linear interpolation between the nearest sane samples.
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

/// Frozen encoder: three or more equal samples of a moving angle, then a catch-up jump of more
/// than twice the steps around the run. A real mechanism cannot stop dead and resume, and a
/// quantized encoder's runs end with a one-count step, not a jump. The run is interpolated
/// linearly and its samples are rejected, named.
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

std::string line_list(const std::vector<Glitch>& g, size_t max_shown = 5) {
  std::string s;
  for (size_t i = 0; i < g.size() && i < max_shown; ++i) {
    s += (i ? ", " : "") + std::to_string(g[i].line);
  }
  if (g.size() > max_shown) s += ", ...";
  return s;
}

/// Median |tau - M| (frictionless inverse dynamics of `scene`) over up to 400 samples of the
/// angles `th1, th2` (rates by Savitzky-Golay); failed poses count as infinite.
double torque_mismatch(const Params<double>& scene, const sim::LoadFunction& loads,
                       const TorqueLog& log, const std::vector<double>& th1,
                       const std::vector<double>& th2, double* median_rate) {
  std::vector<double> w1, w2, a1, a2;
  savitzky_golay(log.t, th1, SgOptions{}, &w1, &a1);
  savitzky_golay(log.t, th2, SgOptions{}, &w2, &a2);
  Params<double> p = scene;
  p.friction.law = FrictionLaw::kNone;
  const int n = log.size();
  const int step = std::max(1, n / 400);
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

/// White-noise std of leave-one-out deviations: the rms of those within 4 robust std (efficient
/// like the rms, robust like the median), corrected for the truncation of a Gaussian at 4 std.
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

/// Steps of the angle column `x` (find_steps): a short run that leaves the trend and returns
/// (glitch_run) is rejected like a glitch, in place; any other step throws LogError naming its
/// line (which side is right cannot be told, and either side fitted with the other gives the
/// rates a spike and the poses an offset).
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

}  // namespace

double robust_std(std::vector<double> v) { return 1.4826 * median_abs(std::move(v)); }

int unwrap_angles(std::vector<double>* theta) {
  std::vector<double>& th = *theta;
  const int n = static_cast<int>(th.size());
  int count = 0;
  double offset = 0, prev_raw = n ? th[0] : 0, prev_step = 0;
  for (int i = 1; i < n; ++i) {
    const double raw = th[i];
    const double step = raw - prev_raw;
    prev_raw = raw;
    // a wrap: this step is the previous one plus or minus one turn (within a quarter turn)
    double turns = 0;
    for (double k : {-1.0, 1.0}) {
      if (std::abs(step - prev_step - 2 * M_PI * k) < M_PI / 2) turns = k;
    }
    if (turns != 0) {
      offset -= 2 * M_PI * turns;
      ++count;
    }
    const double unwrapped_step = step - 2 * M_PI * turns;
    // the predictor follows the motion, not absurd steps (those are glitches, handled later)
    prev_step = std::abs(unwrapped_step) < M_PI / 2 ? unwrapped_step : prev_step;
    th[i] = raw + offset;
  }
  return count;
}

std::vector<double> loo_deviation(const std::vector<double>& t, const std::vector<double>& x,
                                  std::vector<double>* expected) {
  const int n = static_cast<int>(x.size());
  std::vector<double> z(n, 0.0);
  if (expected) *expected = x;
  if (n < 5) return z;
  for (int i = 0; i < n; ++i) {
    const std::array<int, 4> nb = neighbours(i, n);
    // Lagrange weights of the cubic through the four neighbours, evaluated at t_i
    double w[4], gain2 = 1, pred = 0;
    for (int a = 0; a < 4; ++a) {
      w[a] = 1;
      for (int b = 0; b < 4; ++b) {
        if (b != a) w[a] *= (t[i] - t[nb[b]]) / (t[nb[a]] - t[nb[b]]);
      }
      gain2 += w[a] * w[a];
      pred += w[a] * x[nb[a]];
    }
    const double e = (x[i] - pred) / std::sqrt(gain2);
    z[i] = std::isfinite(e) ? e : kInf;
    if (expected) (*expected)[i] = std::isfinite(pred) ? pred : x[i];
  }
  return z;
}

namespace {

/// One column of the log that is checked for glitches, with where its noise estimate goes.
struct NoisyColumn {
  const char* name;
  std::vector<double>* x;
  double* noise;
};

/// The columns checked for glitches: angles and torques, and the logged rates and
/// accelerations when the log has them.
std::vector<NoisyColumn> noisy_columns(ConditionedLog* out) {
  TorqueLog& L = out->log;
  std::vector<NoisyColumn> cols = {{"theta1", &L.theta1, &out->angle_noise[0]},
                                   {"theta2", &L.theta2, &out->angle_noise[1]},
                                   {"tau1", &L.tau1, &out->torque_noise[0]},
                                   {"tau2", &L.tau2, &out->torque_noise[1]}};
  if (L.has_rates) {
    cols.push_back({"omega1", &L.omega1, &out->rate_noise[0]});
    cols.push_back({"omega2", &L.omega2, &out->rate_noise[1]});
  }
  if (L.has_accels) {  // one alpha spike left in could put Coulomb at its bound 0
    cols.push_back({"alpha1", &L.alpha1, &out->accel_noise[0]});
    cols.push_back({"alpha2", &L.alpha2, &out->accel_noise[1]});
  }
  return cols;
}

/// The glitches of one column (absurd values, frozen angles, spikes), repaired in place; a step
/// in an angle is refused. Sets the column's noise estimate.
std::vector<Glitch> column_glitches(const TorqueLog& L, const NoisyColumn& c,
                                    const ConditionOptions& opt) {
  std::vector<Glitch> g = reject_absurd(L, c.name, c.x);
  if (c.name[0] == 't' && c.name[1] == 'h') {
    std::vector<Glitch> frozen = reject_frozen(L, c.name, c.x);
    g.insert(g.end(), frozen.begin(), frozen.end());
    // before the spikes: a step's two sides would read as a bad pair there
    std::vector<Glitch> runs = runs_or_steps(L, c.name, c.x, opt.glitch_sigmas);
    g.insert(g.end(), runs.begin(), runs.end());
  }
  // logged accelerations are often exact or nearly (computed, not measured): their real fast
  // changes (a Stribeck peak crossed in a few samples) would read as glitches, so a glitch must
  // also leave the cubic by a quarter of the column's interquartile range
  double floor = 0;
  if (c.name[0] == 'a') {
    std::vector<double> v = *c.x;
    std::sort(v.begin(), v.end());
    floor = v.empty() ? 0.0 : 0.25 * (v[(3 * v.size()) / 4] - v[v.size() / 4]);
  }
  std::vector<Glitch> spikes = reject_column(L, c.name, opt.glitch_sigmas, c.x, c.noise, floor);
  g.insert(g.end(), spikes.begin(), spikes.end());
  return g;
}

bool by_line(const Glitch& a, const Glitch& b) { return a.line < b.line; }

/// The note that lists the rejected glitches (the first five).
std::string glitch_note(const std::vector<Glitch>& glitches) {
  std::string what;
  for (size_t i = 0; i < glitches.size() && i < 5; ++i) {
    const Glitch& g = glitches[i];
    what += std::string(i ? "; " : "") + "line " + std::to_string(g.line) + " " + g.column +
            " = " + format_significant(g.value, 6) + " where its neighbours give " +
            format_significant(g.expected, 6) + " (" + format_significant(g.sigmas, 2) +
            " noise std)";
  }
  if (glitches.size() > 5) what += "; ...";
  return "rejected " + std::to_string(glitches.size()) +
         " isolated glitch(es), left out of the fit and interpolated for the rates: " + what;
}

}  // namespace

ConditionedLog condition_log(const TorqueLog& log, const ConditionOptions& opt) {
  ConditionedLog out;
  out.log = log;
  TorqueLog& L = out.log;
  const int n = L.size();
  out.rejected.assign(n, 0);
  for (int i : opt.rejected_before) {
    if (i >= 0 && i < n) out.rejected[i] = 1;
  }
  if (opt.unwrap) {
    out.unwrapped[0] = unwrap_angles(&L.theta1);
    out.unwrapped[1] = unwrap_angles(&L.theta2);
    if (out.unwrapped[0] + out.unwrapped[1] > 0) {
      out.notes.push_back("unwrapped " + std::to_string(out.unwrapped[0]) + " + " +
                          std::to_string(out.unwrapped[1]) +
                          " one-turn (2 pi) jumps of theta1, theta2 (angles wrapped by the "
                          "encoder or logger)");
    }
  }
  const int allowed = std::max(2, static_cast<int>(opt.max_glitch_fraction * n));
  for (const NoisyColumn& c : noisy_columns(&out)) {
    std::vector<Glitch> g;
    if (opt.reject_glitches) {
      g = column_glitches(L, c, opt);
    } else {
      *c.noise = noise_std(loo_deviation(L.t, *c.x));
    }
    if (static_cast<int>(g.size()) > allowed) {
      std::sort(g.begin(), g.end(), by_line);
      throw LogError(L.path, std::string("column ") + c.name,
                     std::to_string(g.size()) + " samples leave their neighbours' trend (lines " +
                         line_list(g) + "): more than the " + std::to_string(allowed) +
                         " isolated glitches that are rejected; the column is not a smooth "
                         "measurement");
    }
    for (Glitch& x : g) {
      out.rejected[x.index] = 1;
      if (c.x == &L.theta1 || c.x == &L.theta2) {
        // quoted as in the file: the turn the unwrapping added is taken off both values
        const double in_file = (c.x == &L.theta1 ? log.theta1 : log.theta2)[x.index];
        x.expected += in_file - x.value;
        x.value = in_file;
      }
    }
    out.glitches.insert(out.glitches.end(), g.begin(), g.end());
  }
  for (int j = 0; j < kActuators; ++j) {
    if (opt.torque_noise[j] > 0) out.torque_noise[j] = opt.torque_noise[j];
  }
  out.torque_variance_factor = opt.torque_variance_factor;
  if (!out.glitches.empty()) {
    std::sort(out.glitches.begin(), out.glitches.end(), by_line);
    out.notes.push_back(glitch_note(out.glitches));
  }
  return out;
}

std::string angle_units_from_motion(const Params<double>& scene, const sim::LoadFunction& loads,
                                    const TorqueLog& log, std::string* unit) {
  // too little motion says nothing about the units (25-30 samples of a radian log, 1.5
  // Savitzky-Golay windows, can read as "encoder counts"): at least four windows and 40 samples
  const int n = log.size();
  const int window = 2 * sg_half_window(SgOptions{}, log.duration() / std::max(1, n - 1)) + 1;
  if (n < std::max(40, 4 * window)) return "";
  std::vector<double> r1 = log.theta1, r2 = log.theta2;
  unwrap_angles(&r1);
  unwrap_angles(&r2);
  double rate_rad = 0;
  const double as_rad = torque_mismatch(scene, loads, log, r1, r2, &rate_rad);
  // the reading that explains the torques best
  double best = kInf, best_rate = 0;
  std::string best_unit;
  for (const AngleUnit& u : kAngleUnits) {
    std::vector<double> a1 = log.theta1, a2 = log.theta2;
    for (std::vector<double>* v : {&a1, &a2}) {
      for (double& x : *v) x *= u.to_rad;
    }
    unwrap_angles(&a1);
    unwrap_angles(&a2);
    double rate = 0;
    const double m = torque_mismatch(scene, loads, log, a1, a2, &rate);
    if (m < best) {
      best = m;
      best_rate = rate;
      best_unit = u.name;
    }
  }
  // another unit only when that reading explains the torques several times better than
  // radians, and well in absolute terms (within half the logged torques' median size): a log
  // that no reading explains (wrong scene, absurd values) is not called another unit
  std::vector<double> tau;
  for (int i = 0; i < n; ++i) tau.push_back(std::max(std::abs(log.tau1[i]), std::abs(log.tau2[i])));
  if (!(best < 0.25 * as_rad) || !(best < 0.5 * median_abs(tau))) return "";
  *unit = best_unit;
  return "read as radians, the motion (median crank rate " + format_significant(rate_rad, 3) +
         " rad/s) needs torques a median " + format_significant(as_rad, 3) +
         " N m away from the logged ones; read as " + best_unit + " (median rate " +
         format_significant(best_rate, 3) + " rad/s), " + format_significant(best, 3) + " N m";
}

}  // namespace fivebar::identification
