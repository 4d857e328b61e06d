// Glitch repair of one log column: leave-one-out cubics, single samples, short runs and the
// log's ends.
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

std::array<int, 4> neighbours(int i, int n) {
  if (i < 2) return i == 0 ? std::array<int, 4>{1, 2, 3, 4} : std::array<int, 4>{0, 2, 3, 4};
  if (i > n - 3) {
    return i == n - 1 ? std::array<int, 4>{n - 5, n - 4, n - 3, n - 2}
                      : std::array<int, 4>{n - 5, n - 4, n - 3, n - 1};
  }
  return {i - 2, i - 1, i + 1, i + 2};
}

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

LocalCubic fit_cubic(const std::vector<double>& t, const std::vector<double>& x, int lo, int hi,
                     const std::vector<int>& out, int centre, int ref,
                     const FitColumn& column) {
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

namespace {

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

}  // namespace

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

namespace {

/// Noise gain of an interior leave-one-out deviation (weights -1/6, 4/6, 4/6, -1/6): the floor
/// of a column is compared with the deviation over it everywhere, so that the ends (gain ~8.4)
/// are judged like the inside (a +100 spike of alpha1 on the last line is found too).
const double kInteriorGain = std::sqrt(70.0 / 36.0);

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

}  // namespace

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

}  // namespace fivebar::identification::glitches
