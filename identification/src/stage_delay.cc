// Delay stage of identify(): the torque-to-angle delay, and the fit redone with the torques
// shifted by it.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// Torque-to-angle delay d: one Gauss-Newton step of the fit with d as an extra parameter
/// (d r_i / d d = tau'(t_i), tau' by Savitzky-Golay on the logged torques), its std from the
/// errors-in-variables covariance of that augmented step.
/// The delay's regressor, the logged torques' rates, carries their noise: it attenuates the
/// estimate by the share of the rates' variance that is noise (errors in variables). The window
/// of the rates doubles from the fit's (at least 3 samples) until that share is at most this on
/// both channels, or the window reaches kDelayWindowMax (a light mechanism's torques of 0.08 N m
/// with 0.02 N m of noise: at 3 samples the rates' noise was 14 times their signal, and a lag of
/// 20 ms read 1.4 ms)
constexpr double kDelayRateNoise = 0.05;

/// ... [s], and at most a twentieth of the log
constexpr double kDelayWindowMax = 0.1;

}  // namespace

void delay_regressor(const std::vector<double>& t,
                     const std::vector<const std::vector<double>*>& tau, const double* torque_noise,
                     const std::vector<int>& index, double half_window_s,
                     std::vector<std::vector<double>>* rates) {
  const double duration = t.back() - t.front(), dt = duration / std::max<size_t>(1, t.size() - 1);
  const double widest = std::min(kDelayWindowMax, duration / 20);
  SgOptions sg;
  sg.order = 3;
  sg.half_window_s = std::max(half_window_s, 3 * dt);
  rates->assign(tau.size(), {});
  std::vector<double> unused;
  for (;;) {
    double gain = 0, acc_gain = 0;
    sg_noise_gains(t, sg, &gain, &acc_gain);
    bool quiet = true;
    for (size_t c = 0; c < tau.size(); ++c) {
      std::vector<double>& g = (*rates)[c];
      savitzky_golay(t, *tau[c], sg, &g, &unused);
      double power = 0;
      for (int i : index) power += g[i] * g[i];
      power /= std::max<size_t>(1, index.size());
      quiet = quiet && std::pow(torque_noise[c] * gain, 2) <= kDelayRateNoise * power;
    }
    if (quiet || 2 * sg.half_window_s > widest) return;
    sg.half_window_s *= 2;
  }
}

/// The five-bar's: both channels, from the fit's window
void delay_regressor(const Fit& f, std::vector<double>* g1, std::vector<double>* g2) {
  const TorqueLog& log = f.cond.log;
  std::vector<std::vector<double>> g;
  delay_regressor(log.t, {&log.tau1, &log.tau2}, f.noise.torque, f.index, f.sg.half_window_s, &g);
  *g1 = std::move(g[0]);
  *g2 = std::move(g[1]);
}

void estimate_delay(const Fit& f, const Eigen::MatrixXd& J, const std::vector<double>& r,
                    const std::vector<detail::Sensitivity>& sens, IdentifyResult* out) {
  const TorqueLog& log = f.cond.log;
  const int P = static_cast<int>(J.cols()), m = static_cast<int>(J.rows());
  std::vector<double> g1, g2;
  delay_regressor(f, &g1, &g2);
  Eigen::MatrixXd Ja(m, P + 1);
  Ja.leftCols(P) = J;
  for (size_t u = 0; u < f.index.size(); ++u) {
    Ja(2 * u, P) = g1[f.index[u]];
    Ja(2 * u + 1, P) = g2[f.index[u]];
  }
  const Eigen::MatrixXd H = Ja.transpose() * Ja;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  const double emax = es.eigenvalues().maxCoeff(), emin = es.eigenvalues().minCoeff();
  if (!H.allFinite() || !(emax > 0) || !(emin > 1e-14 * emax)) return;
  const Eigen::MatrixXd Hinv = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                               es.eigenvectors().transpose();
  const Eigen::VectorXd step =
      -Hinv * (Ja.transpose() * Eigen::Map<const Eigen::VectorXd>(r.data(), m));
  Eigen::MatrixXd S = detail::score_covariance(Ja, sens, f.noise, log.size());
  for (int j = 0; j < kActuators; ++j) {
    const double excess = std::max(
        0.0, std::pow(out->rms_torque_residual[j], 2) - std::pow(out->residual_noise_floor[j], 2));
    for (int row = j; row < m; row += 2) S += excess * Ja.row(row).transpose() * Ja.row(row);
  }
  const Eigen::MatrixXd C = Hinv * S * Hinv;
  out->delay_s = step(P);
  out->delay_std_s = std::sqrt(C(P, P));
}

namespace {

/// `log` with its torques (tau1, and tau2 where the log has it) read at t + d (cubic through the
/// four nearest samples, clamped at the ends): torques that lag the angles by d brought in line.
/// The interpolation smooths their noise: *variance_factor is the sum of the squared weights at
/// the middle sample (0.64 for half a sample), the per-sample variance left of white noise; its
/// low-frequency level, which the std of the coefficients see, is unchanged (the weights sum to
/// 1).
TorqueLog shift_torques(const TorqueLog& log, double d, double* variance_factor) {
  TorqueLog out = log;
  const int n = log.size();
  const bool second = log.tau2.size() == log.tau1.size();
  *variance_factor = 1;
  for (int i = 0; i < n; ++i) {
    const double t = log.t[i] + d;
    const int k = static_cast<int>(std::upper_bound(log.t.begin(), log.t.end(), t) - log.t.begin());
    const int lo = std::clamp(k - 2, 0, std::max(0, n - 4));
    const int hi = std::min(n, lo + 4);
    const double tc = std::clamp(t, log.t.front(), log.t.back());
    double v1 = 0, v2 = 0, g = 0;
    for (int a = lo; a < hi; ++a) {
      double w = 1;
      for (int b = lo; b < hi; ++b) {
        if (b != a) w *= (tc - log.t[b]) / (log.t[a] - log.t[b]);
      }
      v1 += w * log.tau1[a];
      if (second) v2 += w * log.tau2[a];
      g += w * w;
    }
    if (i == n / 2) *variance_factor = g;
    out.tau1[i] = v1;
    if (second) out.tau2[i] = v2;
  }
  return out;
}

/// Samples whose shifted torque (by `delay`) would lie beyond the samples that have torques have
/// none: left out (again->condition.rejected_before). In a chain of refits those are the log's
/// ends less the end blocks an earlier refit left out (its shifted torques there were clamped),
/// and only the samples not left out before are counted (else a chain of refits reports more
/// samples left out than the log has: `before`, the samples left out before this refit). Returns
/// that count.
int leave_out_beyond(const TorqueLog& conditioned, double delay, const std::vector<int>& before,
                     IdentifyOptions* again) {
  const int n = conditioned.size();
  auto left_out = [&](int i) { return std::find(before.begin(), before.end(), i) != before.end(); };
  int lo = 0, hi = n - 1;
  while (lo < hi && left_out(lo)) ++lo;
  while (hi > lo && left_out(hi)) --hi;
  const double tol = 1e-9 * std::max(1.0, conditioned.duration());
  int beyond = 0;
  for (int i = 0; i < n; ++i) {
    const double t = conditioned.t[i] + delay;
    if (t > conditioned.t[hi] + tol || t < conditioned.t[lo] - tol) {
      again->condition.rejected_before.push_back(i);
      beyond += !left_out(i);
    }
  }
  return beyond;
}

/// One note for the whole chain of refits: `beyond` samples left out by this refit plus those a
/// deeper refit's note counted (its note replaced)
void note_beyond(int beyond, std::vector<std::string>* notes) {
  const char* const kBeyond =
      " samples at an end of the log left out: their torques, shifted by "
      "the delay, fall beyond the log";
  int total = beyond;
  for (auto it = notes->begin(); it != notes->end();) {
    if (it->find(kBeyond) == std::string::npos) {
      ++it;
      continue;
    }
    total += std::stoi(*it);
    it = notes->erase(it);
  }
  if (total > 0) notes->push_back(std::to_string(total) + kBeyond);
}

}  // namespace

IdentifyResult refit_with_delay(const TorqueLog& conditioned, const IdentifyOptions& opt,
                                const IdentifyResult& first, const Refit& refit) {
  IdentifyOptions again = opt;
  again.delay_refits = opt.delay_refits - 1;
  again.estimate_delay = again.delay_refits > 0;
  // the sign was checked on the log as logged (a shift does not change it), and so was the
  // friction per joint: no refit repeats them
  again.check_torque_sign = false;
  again.check_per_joint = false;
  for (const Glitch& g : first.glitches) again.condition.rejected_before.push_back(g.index);
  const int beyond =
      leave_out_beyond(conditioned, first.delay_s, opt.condition.rejected_before, &again);
  // the shift smooths the torques' noise, which the refit would then measure too small (a 0.5 ms
  // lag would give std 22 % small and a false structure warning): it keeps the noise measured
  // before (the level the coefficients' std see) and scales the per-sample level by the
  // interpolation's sum of squared weights (a product over a chain of refits, approximately)
  double factor = 1;
  const TorqueLog shifted = shift_torques(conditioned, first.delay_s, &factor);
  for (int j = 0; j < kActuators; ++j) again.condition.torque_noise[j] = first.torque_noise[j];
  again.condition.torque_variance_factor = opt.condition.torque_variance_factor * factor;
  IdentifyResult res;
  if (!refit(shifted, again, &res)) {
    res = IdentifyResult();
    res.unusable = "the fit of the shifted log failed";
    return res;
  }
  // the refit estimated the delay left after the shift (and corrected it when significant): the
  // total is their sum, with the std of the last estimate
  if (res.delay_corrected) res.warnings.erase(res.warnings.begin());
  res.samples = first.samples;
  // (a refit whose estimate is not finite keeps the first, so no "lag by nan +- nan ms")
  const bool refit_estimate =
      again.estimate_delay && std::isfinite(res.delay_s) && std::isfinite(res.delay_std_s);
  res.delay_s = first.delay_s + (refit_estimate ? res.delay_s : 0.0);
  res.delay_std_s = refit_estimate ? res.delay_std_s : first.delay_std_s;
  res.delay_corrected = true;
  res.notes.insert(res.notes.begin(), first.notes.begin(), first.notes.end());
  note_beyond(beyond, &res.notes);
  res.glitches.insert(res.glitches.begin(), first.glitches.begin(), first.glitches.end());
  for (int j = 0; j < kDof; ++j) res.unwrapped[j] += first.unwrapped[j];
  // the significance that decided the correction is the first estimate's (the refit's std is
  // that of the delay left after the shift)
  std::vector<std::string> w = {std::string("the torques ") + (res.delay_s < 0 ? "lead" : "lag") +
                                " the angles by " +
                                format_significant(std::abs(res.delay_s) * 1e3) + " +- " +
                                format_significant(res.delay_std_s * 1e3) + " ms (first estimate " +
                                format_significant(std::abs(first.delay_s) / first.delay_std_s) +
                                " std): refitted with the torques shifted by it"};
  // the glitches' warning, where the mechanism's fit gives one (the first, one of its notes)
  if (!first.glitches.empty() && !first.warnings.empty() &&
      std::find(first.notes.begin(), first.notes.end(), first.warnings.front()) !=
          first.notes.end()) {
    w.push_back(first.warnings.front());
  }
  res.warnings.insert(res.warnings.begin(), w.begin(), w.end());
  return res;
}

IdentifyResult refit_with_delay(const Params<double>& scene_in, const sim::LoadFunction& loads,
                                const TorqueLog& conditioned, const IdentifyOptions& opt,
                                const IdentifyResult& first) {
  const Refit refit = [&](const TorqueLog& shifted, const IdentifyOptions& again,
                          IdentifyResult* fit) {
    *fit = identify(scene_in, loads, shifted, again);
    return true;
  };
  return refit_with_delay(conditioned, opt, first, refit);
}

}  // namespace fivebar::identification::stages
