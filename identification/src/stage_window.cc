// Window stage of identify(): the data-driven Savitzky-Golay window, read off the torque
// residual at a preliminary fit, for any mechanism (mechanism_stages.h); the five-bar's residual
// levels.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// the least ratio over the windows beyond which the estimated rates are biased at every window,
/// when the smallest is the best (a frictionless scene's 6-10 s logs read 4.67, a smoothing bias
/// that must not be blamed on the masses, the encoders or the torque sensors; a misfit of the
/// model reads about the same at every window instead)
constexpr double kBiasedRates = 1.5;

}  // namespace

void FiveBarWindowFit::levels(const std::vector<int>& probe, const SgOptions& sg, double rms[2],
                              double floor[2]) const {
  const Fit& f = f_;
  const RestThresholds rest = rest_rule(f.cond.log, out_, *f.opt, sg);
  const TorqueLog& log = f.cond.log;
  Params<double> p = f.scene;
  f.layout.apply(f.x.data(), &p);
  Eigen::Vector2d r2 = Eigen::Vector2d::Zero(), v = Eigen::Vector2d::Zero(), t2 = v;
  int count = 0;
  SgTapCache taps(log.t, sg);
  const detail::KinematicJacobians jacobian(f.scene, f.layout, f.x.data());
  for (int i : probe) {
    Sample s = logged_sample(f, i);
    int lo = 0;
    const std::vector<double>*p1 = nullptr, *p2 = nullptr;
    taps.taps(i, &lo, &p1, &p2);
    const std::vector<double>&d1 = *p1, &d2 = *p2;
    const std::vector<double>& x1 =
        f.source == detail::RateSource::kFromAngles ? log.theta1 : log.omega1;
    const std::vector<double>& x2 =
        f.source == detail::RateSource::kFromAngles ? log.theta2 : log.omega2;
    double e1 = 0, e2 = 0, f1 = 0, f2 = 0;
    for (size_t k = 0; k < d1.size(); ++k) {
      e1 += d1[k] * x1[lo + k];
      e2 += d1[k] * x2[lo + k];
      f1 += d2[k] * x1[lo + k];
      f2 += d2[k] * x2[lo + k];
    }
    if (f.source == detail::RateSource::kFromAngles) {
      s.w1 = e1, s.w2 = e2, s.a1 = f1, s.a2 = f2;
    } else {
      s.w1 = log.omega1[i], s.w2 = log.omega2[i], s.a1 = e1, s.a2 = e2;
    }
    // a held joint's friction is a static torque, not the law: at every window a misfit
    if (held_sample(f.scene, s, rest, std::max(f.noise.angle[0], f.noise.angle[1]))) continue;
    Evaluation<double> ev;
    Eigen::Matrix<double, 2, 6> D;
    if (!inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr, f.eval, &ev)
             .ok() ||
        !jacobian(s, f.eval, &D)) {
      continue;
    }
    const auto& o = p.actuators.offset;  // measured = motor + offset
    r2 += Eigen::Vector2d(std::pow(s.tau1 - o[0] - ev.M1, 2), std::pow(s.tau2 - o[1] - ev.M2, 2));
    t2 += Eigen::Vector2d(s.tau1 * s.tau1, s.tau2 * s.tau2);
    // the filter's taps above, where the rates or accelerations are estimated
    v +=
        detail::propagated_variance(f.source == detail::RateSource::kLogged
                                        ? detail::sensitivity(log.t, i, f.source, sg, f.noise, D)
                                        : detail::sensitivity(i, lo, d1, d2, f.source, f.noise, D));
    ++count;
  }
  for (int j = 0; j < kActuators; ++j) {
    const double c = std::max(1, count);
    rms[j] = std::sqrt(r2(j) / c);
    floor[j] = std::max(std::sqrt(f.noise.torque[j] * f.noise.torque[j] + v(j) / c),
                        kAbsoluteFloor * std::sqrt(t2(j) / c));
  }
}

std::vector<int> window_candidates(int n, double dt, int order) {
  const int min_half = order / 2 + 1;
  const int max_half = std::max(min_half, static_cast<int>(std::lround(0.05 / dt)));
  std::vector<int> cand;
  for (int m = min_half; m <= max_half; m = std::max(m + 1, static_cast<int>(m * 1.25))) {
    if (2 * m + 2 < n) cand.push_back(m);
  }
  if (cand.empty()) cand.push_back(min_half);
  return cand;
}

namespace {

/// The window table of choose_window: the rms residual and noise floor of candidate k, evaluated
/// on demand in increasing order (probes: samples with a centred window for the largest
/// candidate, not glitches).
class WindowTable {
 public:
  WindowTable(const WindowFit& w, const SgOptions& sg) : w_(w), sg_(sg) {
    const TorqueLog& log = w.log();
    const int n = log.size();
    dt_ = n > 1 ? log.duration() / (n - 1) : 1.0;
    cand_ = window_candidates(n, dt_, sg.order);
    const int edge = cand_.back();
    const int step = std::max(1, (n - 2 * edge) / 800);
    for (int i = edge; i < n - edge; i += step) {
      if (!w.rejected()[i]) probe_.push_back(i);
    }
  }
  double dt() const { return dt_; }
  size_t candidates() const { return cand_.size(); }
  const std::vector<detail::WindowLevel>& levels() const { return levels_; }
  /// the next candidate's levels: every probe, those near slip reversals included (the fit
  /// leaves them out): their bias keeps the window small, which the smooth parts' bias, below
  /// what the ratio detects, needs too (measured: judged without them, the per-joint multisine
  /// fits chose 7-8 samples instead of 4-6 and the coverage of their 95 % intervals fell from
  /// 0.97 to 0.90)
  const detail::WindowLevel& evaluate_next() {
    detail::WindowLevel l;
    l.half = cand_[levels_.size()];
    SgOptions sg = sg_;
    sg.half_window_s = l.half * dt_;
    w_.levels(probe_, sg, l.rms, l.floor);
    levels_.push_back(l);
    return levels_.back();
  }

 private:
  const WindowFit& w_;
  const SgOptions sg_;  ///< the filter before the choice (its order)
  double dt_ = 1;
  std::vector<int> cand_, probe_;
  std::vector<detail::WindowLevel> levels_;
};

/// the larger of the two channels' rms residual over its noise level
double level_ratio(const detail::WindowLevel& l) {
  return std::max(l.rms[0] / l.floor[0], l.rms[1] / l.floor[1]);
}

/// the two channels' values of a level, for the choice's text: "a, b"
std::string channels_text(const double v[2]) {
  return format_significant(v[0]) + ", " + format_significant(v[1]);
}

/// choose_window when the window table shows a misfit of the law (window_misfit.h): the largest
/// window up to which the excess over the noise level stays flat (the misfit, not bias), where
/// the fit's residual shows the misfit above a floor near the torque noise.
void misfit_window(const WindowTable& tab, const detail::WindowMisfit& m, SgOptions* sg,
                   std::string* choice) {
  const std::vector<detail::WindowLevel>& lv = tab.levels();
  const detail::WindowLevel &a = lv[m.from], &b = lv[m.to];
  const int j = m.actuator;
  sg->half_window_s = b.half * tab.dt();
  *choice =
      "data-driven, misfit: half-window " + std::to_string(b.half) + " samples (" +
      format_significant(b.half * tab.dt() * 1e3) + " ms): the tau" + std::to_string(j + 1) +
      " residual's excess over the level the measured noise explains is the same from " +
      std::to_string(a.half) + " to " + std::to_string(b.half) + " samples (" +
      format_significant(std::sqrt(std::max(0.0, a.excess(j)))) + ", " +
      format_significant(std::sqrt(std::max(0.0, b.excess(j)))) +
      " N m in quadrature with the noise level " + format_significant(a.floor[j]) + ", " +
      format_significant(b.floor[j]) +
      " N m): not smoothing bias, which grows with the window, but torques the law does not fit; "
      "the largest window where it stays so";
}

}  // namespace

void choose_window(const WindowFit& w, SgOptions* sg, bool* rates_biased, std::string* choice) {
  WindowTable tab(w, *sg);
  std::vector<double> ratio;
  for (size_t k = 0; k < tab.candidates(); ++k) {
    ratio.push_back(level_ratio(tab.evaluate_next()));
    // smoothing bias only grows with the window: stop once it clearly dominates
    if (k >= 2 &&
        ratio[k] > 1.5 * std::max(1.0, *std::min_element(ratio.begin(), ratio.begin() + k))) {
      break;
    }
  }
  // a misfit hidden by the noise of the small windows: its excess is flat in the window
  detail::WindowMisfit m;
  while ((m = detail::window_misfit(tab.levels(), tab.levels().size() < tab.candidates())).state ==
         detail::WindowMisfit::kNeedMore) {
    tab.evaluate_next();
  }
  if (m.state == detail::WindowMisfit::kMisfit) {
    misfit_window(tab, m, sg, choice);
    return;
  }
  // the rule below sees the candidates up to the stop above
  std::vector<int> cand;
  for (size_t k = 0; k < ratio.size(); ++k) cand.push_back(tab.levels()[k].half);
  const double dt = tab.dt();
  // the reference: 1 when the noise explains the residual (a ratio below 1 is a fluctuation of
  // the estimate), the least ratio when a mismatch of the law shows at every window
  const double best = std::max(1.0, *std::min_element(ratio.begin(), ratio.end()));
  // the largest window without detectable excess, then one candidate smaller: the bias just
  // below detection still counts against the std (relative to it, it scales as ~h^3.5)
  size_t chosen = 0;
  for (size_t k = 0; k < cand.size(); ++k) {
    if (ratio[k] <= best * (1 + kWindowExcess)) chosen = k;
  }
  // only the smallest window without detectable bias: the log is sampled too slowly for this
  // order. The back-off never lands on the smallest window: over order/2 + 1 samples each side
  // the polynomial nearly interpolates the noise (one degree of freedom; twice the acceleration
  // noise of the next window at order 5), a cost the margin against bias does not justify.
  // Measured on Stribeck logs at 500 Hz (30 seeds), whose second window was still unbiased:
  // backed off to the smallest, coverage of static_coulomb 0.77; at the second, 0.90.
  const bool undersampled = chosen == 0 && ratio.size() > 1;
  *rates_biased = undersampled && best > kBiasedRates;
  const bool backed_off = chosen > 1;
  if (backed_off) --chosen;
  std::string table;
  for (size_t k = 0; k < cand.size(); ++k) {
    table += (k ? ", " : "") + std::to_string(cand[k]) + ": " + format_significant(ratio[k]);
  }
  sg->half_window_s = cand[chosen] * dt;
  // every window but the smallest of this order shows bias: the log is sampled too slowly for
  // it, and a higher order over the next smallest span bends better at the kinks
  std::string raised;
  if (undersampled) {
    sg->order += 2;
    sg->half_window_s = (sg->order / 2 + 1) * dt;
    raised = "; the smallest window being the choice, order raised to " +
             std::to_string(sg->order) + " over " + std::to_string(sg->order / 2 + 1) +
             " samples each side";
  }
  const detail::WindowLevel& l = tab.levels()[chosen];
  *choice = "data-driven: half-window " + std::to_string(cand[chosen]) + " samples (" +
            format_significant(cand[chosen] * dt * 1e3) + " ms), " +
            (backed_off ? "one below " : "") + "the largest whose torque residual (" +
            channels_text(l.rms) +
            " N m) shows no smoothing bias over the level the measured noise " + "explains (" +
            channels_text(l.floor) + " N m), ratio " + format_significant(ratio[chosen]) +
            " against the reference " + format_significant(best) +
            " (ratio by half-window: " + table + ")" + raised;
}

bool solve_preliminary(const ParameterLayout& layout, double* x, ceres::Problem* problem) {
  for (int i = 0; i < layout.size(); ++i)
    problem->SetParameterLowerBound(x, i, layout.lower_bound(i));
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = 20;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, problem, &summary);
  return summary.IsSolutionUsable();
}

void preliminary_fit(Fit* f) {
  Fit g = *f;
  g.samples.clear();
  const size_t step = std::max<size_t>(1, f->samples.size() / 1500);
  for (size_t u = 0; u < f->samples.size(); u += step) g.samples.push_back(f->samples[u]);
  ceres::Problem problem;
  std::vector<double> x = f->x;
  const bool sized = add_inverse_dynamics_terms(g.scene, g.layout, g.samples, g.eval, Loss::kNone,
                                                1, x.data(), &problem, f->cost_weight);
  if (!sized) return;
  add_inertial_prior(f, x.data(), &problem);
  if (solve_preliminary(f->layout, x.data(), &problem)) f->x = x;
}

}  // namespace fivebar::identification::stages
