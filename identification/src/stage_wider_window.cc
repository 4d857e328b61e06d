// The data-driven window checked (angles-only logs): the angle noise's bias predicted again from
// the rates of the chosen window, and the friction refitted, linearized, on the log re-filtered
// at kWiderFactor times its half-window; where the bias is beyond kWindowBias of the fit's std
// and the refit moves against it beyond its noise, the wider window is taken (after kWiderSteps
// such moves, the fit is not to be used).
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// The wider window of the check, in the chosen half-window's
constexpr double kWiderFactor = 1.5;

/// The refit at the wider window confirms a predicted bias when it moves the coefficient against
/// it by more than this many std of the move's own noise (the difference of the two linearized
/// refits from the sensor noise)
constexpr double kWindowMoveZ = 1.5;

/// A predicted bias at the chosen window beyond this many std of the fit (the linearized refit's
/// errors-in-variables std) moves the window up when the refit confirms it: a correction's own
/// error grows with it (kUnusableBias). Measured: light, slow five-bars' logs whose fits hold
/// their truths read up to 1.2 (3 s, angle noise 1e-5 and 3e-4 rad), those 3-5 std off 1.7-5.6.
constexpr double kWindowBias = 1.3;

/// The check moves the window up at most this many times; a move still unexplained after them
/// makes the fit unusable
constexpr int kWiderSteps = 3;

/// The largest half-window the check moves to (as --sg-window's limit)
constexpr int kWiderMaxHalf = 200;

/// What the linearized refits of one sample need at both windows.
struct PairedSample {
  int i = 0;
  Eigen::Vector2d ra, rb;
  Eigen::MatrixXd Ja, Jb;
  detail::Sensitivity sa, sb;
};

/// The samples of f (filter f.sg) that the wider filter `wide` keeps too (centred, no slip
/// reversal or glitch in its window, not held by its rest rule; refiltered), each with its
/// residual, Jacobian and noise sensitivities at both windows, at the parameters f.x.
std::vector<PairedSample> paired_samples(const Fit& f, const IdentifyResult& out,
                                         const SgOptions& wide) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  const double dt = log.duration() / std::max(1, n - 1);
  const int h = sg_half_window(wide, dt);
  const Fit g = refiltered(f, out, wide);
  std::vector<int> rejected(n + 1, 0);
  for (int i = 0; i < n; ++i) rejected[i + 1] = rejected[i] + f.cond.rejected[i];
  std::vector<PairedSample> ps;
  SgTapCache taps_a(log.t, f.sg), taps_b(log.t, wide);
  const detail::KinematicJacobians jacobian(f.scene, f.layout, f.x.data());
  size_t v = 0;
  for (size_t u = 0; u < f.samples.size(); ++u) {
    const int i = f.index[u];
    while (v < g.index.size() && g.index[v] < i) ++v;
    if (v == g.index.size() || g.index[v] != i || i - h < 0 || i + h >= n ||
        rejected[i + h + 1] - rejected[i - h] > 0 || spans_reversal(f, i, h)) {
      continue;
    }
    PairedSample p;
    p.i = i;
    Eigen::Matrix<double, 2, 6> D;
    if (!sample_residual(f.scene, f.layout, f.samples[u], f.eval, f.x.data(), &p.ra, &p.Ja) ||
        !sample_residual(f.scene, f.layout, g.samples[v], f.eval, f.x.data(), &p.rb, &p.Jb) ||
        !jacobian(f.samples[u], f.eval, &D)) {
      continue;
    }
    p.sa = detail::sensitivity(&taps_a, i, f.source, f.noise, D);
    p.sb = detail::sensitivity(&taps_b, i, f.source, f.noise, D);
    ps.push_back(std::move(p));
  }
  return ps;
}

/// The move of the public parameters from the linearized refit at f.sg to that at `wide` (one
/// Gauss-Newton step each from f.x, on the samples both keep: paired_samples), and its
/// covariance from the sensor noise: the torque noise enters both refits alike, the angle noise
/// through the two filters' taps (score_covariance over the two refits' rows). False when the
/// samples do not determine the parameters.
bool window_move(const Fit& f, const IdentifyResult& out, const SgOptions& wide,
                 Eigen::VectorXd* move, Eigen::MatrixXd* cov, Eigen::MatrixXd* cov_fit) {
  const std::vector<PairedSample> ps = paired_samples(f, out, wide);
  const int P = f.layout.size(), m = static_cast<int>(ps.size());
  if (m < 2 * P) return false;
  Eigen::MatrixXd Ha = Eigen::MatrixXd::Zero(P, P), Hb = Ha;
  Eigen::VectorXd ga = Eigen::VectorXd::Zero(P), gb = ga;
  for (const PairedSample& p : ps) {
    Ha += p.Ja.transpose() * p.Ja, Hb += p.Jb.transpose() * p.Jb;
    ga += p.Ja.transpose() * p.ra, gb += p.Jb.transpose() * p.rb;
  }
  const Eigen::LDLT<Eigen::MatrixXd> la(Ha), lb(Hb);
  if (la.info() != Eigen::Success || lb.info() != Eigen::Success) return false;
  const Eigen::VectorXd step = la.solve(ga) - lb.solve(gb);  // x_wide - x_fit
  // the refits' responses to each sample's residual, as rows of a Jacobian: the one's with a
  // plus sign, the other's with a minus (score_covariance of the difference)
  Eigen::MatrixXd K(4 * m, P);
  std::vector<detail::Sensitivity> sens(2 * m);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(P, P);
  for (int u = 0; u < m; ++u) {
    const Eigen::MatrixXd ka = la.solve(ps[u].Ja.transpose()), kb = lb.solve(ps[u].Jb.transpose());
    K.middleRows(2 * u, 2) = ka.transpose();
    K.middleRows(2 * (m + u), 2) = -kb.transpose();
    sens[u] = ps[u].sa;
    sens[m + u] = ps[u].sb;
    for (int j = 0; j < kActuators; ++j) {
      const Eigen::VectorXd d = ka.col(j) - kb.col(j);
      C += f.noise.torque[j] * f.noise.torque[j] * d * d.transpose();
    }
  }
  detail::SensorNoise angles = f.noise;
  angles.torque[0] = angles.torque[1] = 0;
  C += detail::score_covariance(K, sens, angles, f.cond.log.size());
  // the refit's own covariance at the fit's window (errors in variables, as the fit's std)
  std::vector<detail::Sensitivity> sa(sens.begin(), sens.begin() + m);
  const Eigen::MatrixXd Ca =
      detail::score_covariance(K.topRows(2 * m), sa, f.noise, f.cond.log.size());
  const Eigen::MatrixXd T = to_public(f.layout);
  *move = T * step;
  *cov = T * C * T.transpose();
  *cov_fit = T * Ca * T.transpose();
  return move->allFinite() && cov->allFinite();
}

}  // namespace

WiderWindow wider_window(const Fit& f, const IdentifyResult& out) {
  WiderWindow w;
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  if (f.source != detail::RateSource::kFromAngles || n < 2) return w;
  const double dt = log.duration() / (n - 1);
  const int h = sg_half_window(f.sg, dt);
  const int wide = static_cast<int>(std::lround(kWiderFactor * h));
  if (wide > kWiderMaxHalf || 2 * wide + 2 >= n) return w;
  w.sg = f.sg;
  w.sg.half_window_s = wide * dt;
  Eigen::VectorXd move;
  Eigen::MatrixXd cov, cov_fit;
  std::vector<Eigen::VectorXd> bias, spread;
  // both predictions read the motion's terms over the wider window's span (one set of inputs)
  if (!window_move(f, out, w.sg, &move, &cov, &cov_fit) ||
      !predicted_biases(FiveBarWindowFit(f, out), f.sg, {h, wide}, wide, &bias, &spread)) {
    return w;
  }
  w.checked = true;
  w.bias = bias[1];
  w.spread = spread[1];
  w.bias_here = bias[0];
  w.spread_here = spread[0];
  const std::vector<std::string> names = f.layout.names();
  std::string predicted, moved;
  const int F = std::min<int>(static_cast<int>(bias[0].size()), f.layout.friction_size());
  for (int p = 0; p < F; ++p) {
    const double ratio = bias[0](p) / std::sqrt(cov_fit(p, p));
    // the refit's move against the predicted bias, in the std of the move from the noise
    const double undoes = -move(p) * (bias[0](p) < 0 ? -1 : 1) / std::sqrt(cov(p, p));
    predicted += (p ? ", " : "") + names[p] + " " + format_significant(ratio, 2);
    moved += (p ? ", " : "") + format_significant(undoes, 2);
    if (std::isfinite(ratio)) w.largest = std::max(w.largest, std::abs(ratio));
    if (std::isfinite(ratio) && std::isfinite(undoes) && std::abs(ratio) > kWindowBias &&
        undoes > kWindowMoveZ && std::abs(ratio) > std::abs(w.z)) {
      w.z = ratio, w.worst = p;
    }
  }
  w.moves = w.worst >= 0;
  w.text = "checked at " + std::to_string(h) + " samples from its own rates: predicted bias " +
           predicted + " std; the friction refitted at " + std::to_string(wide) +
           " samples moves against it by " + moved + " std of the move's noise";
  return w;
}

bool widen_window(Fit* f, IdentifyResult* out, const std::function<bool()>& rates_and_samples) {
  // the law's coefficients enter the torques linearly (but through the reactions), so one
  // Gauss-Newton step is the refit (a Stribeck log at 4 samples: its velocity's step was not)
  // a shared law's: a per-joint fit's window has its own check (unbiased_window_check)
  if (f->layout.inertia || f->layout.actuator || f->layout.per_joint ||
      f->source != detail::RateSource::kFromAngles ||
      f->scene.friction.law != FrictionLaw::kCoulombViscous) {
    return true;
  }
  const TorqueLog& log = f->cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  for (int step = 0;; ++step) {
    const std::vector<double> x_start = f->x;
    preliminary_fit(f);
    const WiderWindow w = wider_window(*f, *out);
    f->x = x_start;
    if (!w.checked) return true;
    const std::string coefficient = w.worst >= 0 ? f->layout.names()[w.worst] : "";
    out->window_choice += "; " + w.text;
    if (!w.moves) {
      // a window the check moved to, or one whose bias the walk's prediction (about the small
      // window's rates) understated beyond kWindowBias: its bias as predicted from its own rates
      // is taken off. Measured on light, slow five-bars' 3 s logs at 3e-4 rad the refit did not
      // confirm (seeds 13-30 of three mechanisms): 6 of 11 fits 2.7-4.3 std off, 0 after.
      if (step > 0 || w.largest > kWindowBias) {
        f->smoothing_bias = w.bias_here;
        f->smoothing_bias_spread = w.spread_here;
        if (step == 0) out->window_choice += " (its predicted bias taken off)";
      }
      return true;
    }
    if (step == kWiderSteps) {
      f->window_unusable =
          "the angle noise biases the friction at every Savitzky-Golay window tried: at a "
          "half-window of " +
          std::to_string(sg_half_window(f->sg, dt)) + " samples, " + std::to_string(kWiderSteps) +
          " above the chosen one, the predicted bias of " + coefficient + " is still " +
          format_significant(std::abs(w.z), 2) + " std, and the friction refitted at " +
          std::to_string(sg_half_window(w.sg, dt)) +
          " samples moves against it: the encoders' noise (" +
          format_significant(std::max(f->noise.angle[0], f->noise.angle[1]), 2) +
          " rad) is too coarse for accelerations estimated from the angles of this motion; log "
          "the rates (omega1, omega2), or give a wide --sg-window";
      return true;
    }
    f->sg = w.sg;
    f->smoothing_bias = w.bias;
    f->smoothing_bias_spread = w.spread;
    out->window_choice += ", so half-window " + std::to_string(sg_half_window(w.sg, dt)) +
                          " samples (its predicted bias taken off instead)";
    if (!rates_and_samples()) return false;
  }
}

void wider_window_check(const Fit& f, IdentifyResult* out) {
  if (!f.window_unusable.empty() && out->unusable.empty()) out->unusable = f.window_unusable;
}

}  // namespace fivebar::identification::stages
