// The four-bar's samples (four_bar_fit.h): the rest rule (a joint whose relative rate is within
// kRestSigmas of its noise std of zero) and, from angles, the samples whose rate filter window
// spans a slip reversal, or that lie between two such windows, left out.
#include <algorithm>
#include <cmath>
#include <string>

#include "fivebar/model/four_bar.h"
#include "four_bar_fit.h"
#include "mechanism_stages.h"
#include "setup_shared.h"

namespace fivebar::identification::four_bar {

/// Slip reversals: prefix counts of the sample steps (i, i + 1) over which some joint's relative
/// rate changes sign (FourBarFit::reversals, the five-bar's form); zeros keep the previous sign.
std::vector<int> reversal_counts(const std::vector<std::array<double, 4>>& rel) {
  std::vector<int> pre(rel.size() + 1, 0);
  std::array<double, kFourBarJoints> last{};
  for (size_t i = 0; i < rel.size(); ++i) {
    bool flip = false;
    for (int k = 0; k < kFourBarJoints; ++k) {
      const double s = rel[i][k] > 0 ? 1.0 : (rel[i][k] < 0 ? -1.0 : 0.0);
      flip = flip || (s != 0 && last[k] != 0 && s != last[k]);
      if (s != 0) last[k] = s;
    }
    pre[i + 1] = pre[i] + (i > 0 && flip ? 1 : 0);
  }
  return pre;
}

bool held(const FourBarFit& f, const std::array<double, 4>& row, double w, double rate_noise) {
  const IdentifyOptions& opt = *f.opt;
  bool held = false;
  for (int j = 0; j < kFourBarJoints; ++j) {
    const double rest = opt.rest_rate_threshold >= 0 ? opt.rest_rate_threshold
                                                     : kRestSigmas * rate_noise * std::abs(row[j]);
    held = held || std::abs(row[j] * w) <= std::max({opt.min_rate, rest, 1e-12});
  }
  return held;
}

/// Per log sample in [first, last]: whether the filter's window of half-width hw centred on it
/// spans a slip reversal, or the sample lies in a run of samples between two such windows that
/// is shorter than the window itself (2 hw + 1): two reversals that close are one fast swing of
/// the acceleration (the crank rocker's 3 s logs: 2000 to -1900 rad/s^2 in 8 ms between reversals
/// 13 ms apart), which no polynomial over the window follows. At half-window 6 those runs held
/// every sample whose estimated acceleration on an exact log was off by more than 2 rad/s^2 (20
/// of 2149, up to 17 rad/s^2, all of one sign: coulomb -4.8 %, -1.5 std of a 3 s log).
std::vector<char> near_reversals(const FourBarFit& f, int hw) {
  const int n = f.cond.log.size();
  std::vector<char> near(n, 0);
  for (int i = f.first; i <= f.last; ++i)
    near[i] = stages::window_spans_reversal(f.reversals, i, hw);
  if (hw <= 0) return near;
  for (int i = f.first; i <= f.last;) {
    if (near[i]) {
      ++i;
      continue;
    }
    int j = i;
    while (j <= f.last && !near[j]) ++j;
    const bool between = i > f.first && j <= f.last;  // near on both sides
    if (between && j - i < 2 * hw + 1) std::fill(near.begin() + i, near.begin() + j, 1);
    i = j;
  }
  return near;
}

void select_samples(FourBarFit* f, IdentifyResult* out) {
  const TorqueLog& L = f->cond.log;
  const IdentifyOptions& opt = *f->opt;
  const int n = L.size();
  std::vector<std::array<double, 4>> rel(n, {0, 0, 0, 0}), row(n, {0, 0, 0, 0});
  for (int i = f->first; i <= f->last; ++i) {
    FourBarKinematics k;
    if (!four_bar_kinematics(f->scene, L.theta1[i], &k).ok()) continue;
    row[i] = four_bar_joint_rows(k);
    for (int j = 0; j < kFourBarJoints; ++j) rel[i][j] = row[i][j] * f->w[i];
  }
  f->reversals = reversal_counts(rel);
  out->used.assign(n, 0);
  out->samples_at_rest = out->samples_near_reversals = 0;
  f->samples.clear();
  f->index.clear();
  const std::vector<char> near = near_reversals(*f, f->hw > 0 && opt.exclude_reversals ? f->hw : 0);
  for (int i = f->first; i <= f->last; ++i) {
    if (f->cond.rejected[i]) continue;
    if (held(*f, row[i], f->w[i], f->rate_noise)) {
      ++out->samples_at_rest;
      continue;
    }
    if (near[i]) {
      ++out->samples_near_reversals;
      continue;
    }
    Sample s;
    s.t = L.t[i];
    s.q[0] = L.theta1[i];
    s.v[0] = f->w[i];
    s.a[0] = f->a[i];
    s.tau[0] = L.tau1[i];
    s.loads = f->loads(L.t[i]);
    f->samples.push_back(s);
    f->index.push_back(i);
    out->used[i] = 1;
  }
  out->slip_reversals = f->reversals.back();
  out->rest_rate_threshold = kRestSigmas * f->rate_noise;
  out->samples_used = static_cast<int>(f->samples.size());
}

}  // namespace fivebar::identification::four_bar
