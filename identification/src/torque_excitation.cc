// Torque-driven excitation design: tone torques, their free motion, a seeded evolution strategy.
#include "fivebar/identification/torque_excitation.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <thread>

#include "fivebar/model/rest.h"

namespace fivebar::identification {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// synth-log's multi-sine: four tones per motor [Hz], amplitudes [N m], Schroeder-like phases
// (motor 2's shifted by 1 rad), biases 2 and 3 N m
constexpr double kMultisineF1[] = {0.31, 0.83, 1.7, 3.1}, kMultisineF2[] = {0.43, 1.1, 2.3, 2.9};
constexpr double kMultisineA[] = {4.0, 3.0, 2.0, 1.5};
constexpr double kMultisineBias[] = {2.0, 3.0};

// how far a candidate misses the constraints (0: feasible; infinity: the run failed)
double violation(const TorqueCandidate& c, const ExcitationOptions& o) {
  if (!c.status.ok() || !std::isfinite(c.objective)) return kInf;
  double v = 0;
  const ExcitationReport& r = c.report;
  for (int k : r.reversals) v += std::max(0, o.min_reversals - k);
  if (r.min_sine < o.singular_margin) v += 1 + o.singular_margin - r.min_sine;
  // the tones are clipped at the limit, but the torques that hold a stuck joint (the motion's
  // inverse dynamics, which a log along the design reads) may exceed it
  if (o.torque_limit > 0 && r.peak_torque > o.torque_limit * (1 + 1e-9)) {
    v += r.peak_torque / o.torque_limit - 1;
  }
  for (int j = 0; j < kDof; ++j) {
    if (!std::isfinite(o.theta_lo[j])) continue;
    v += std::max(0.0, o.theta_lo[j] - r.theta_min[j]) + std::max(0.0, r.theta_max[j] - o.theta_hi[j]);
  }
  return v;
}

// (objective a, miss va) beats (b, vb): feasible first, then the lower objective; among
// infeasible ones the smaller miss
bool better(double a, double va, double b, double vb) {
  if ((va == 0) != (vb == 0)) return va == 0;
  if (va > 0) return va < vb;
  return a < b;
}
bool better(const TorqueCandidate& a, double va, const TorqueCandidate& b, double vb) {
  return better(a.objective, va, b.objective, vb);
}

// the best `size` candidates of a search, ranked as `better` (the earlier first among equals)
class Finalists {
 public:
  explicit Finalists(int size) : size_(static_cast<size_t>(std::max(1, size))) {}
  void offer(const TorqueCandidate& c, double v) {
    if (!c.status.ok()) return;
    size_t i = 0;
    while (i < kept_.size() && !better(c.objective, v, kept_[i].objective, kept_[i].miss)) ++i;
    if (i >= size_) return;
    kept_.insert(kept_.begin() + static_cast<std::ptrdiff_t>(i), {c.x, c.objective, v});
    if (kept_.size() > size_) kept_.pop_back();
  }
  void write(TorqueDesignResult* out) const {
    for (const Kept& k : kept_) {
      out->finalists.push_back(k.x);
      out->finalist_objectives.push_back(k.objective);
    }
  }

 private:
  struct Kept {
    std::vector<double> x;
    double objective, miss;
  };
  size_t size_;
  std::vector<Kept> kept_;
};

}  // namespace

double ToneTorques::raw(const std::vector<double>& x, int j, double t) const {
  const double* v = x.data() + j * per_motor();
  double m = 0;
  for (int k = 0; k < k_; ++k) m += v[1 + k] * std::sin(2 * M_PI * v[1 + k_ + k] * t + v[1 + 2 * k_ + k]);
  return v[0] + m;
}

double ToneTorques::torque(const std::vector<double>& x, int j, double t) const {
  return std::clamp(raw(x, j, t), -limit_, limit_);
}

sim::LoadFunction ToneTorques::loads(const std::vector<double>& x, const sim::LoadFunction& scene) const {
  // the sounding tones of each motor with their angular frequencies formed once: the same sums
  // as raw (a silent tone adds an exact zero)
  struct Tone {
    double a, w, phi;
  };
  struct Motor {
    double bias = 0;
    std::vector<Tone> tones;
    double raw(double t) const {
      double m = 0;
      for (const Tone& k : tones) m += k.a * std::sin(k.w * t + k.phi);
      return bias + m;
    }
  };
  std::array<Motor, kActuators> motors;
  for (int j = 0; j < kActuators; ++j) {
    const double* v = x.data() + j * per_motor();
    motors[j].bias = v[0];
    for (int k = 0; k < k_; ++k) {
      if (v[1 + k] != 0)
        motors[j].tones.push_back({v[1 + k], 2 * M_PI * v[1 + k_ + k], v[1 + 2 * k_ + k]});
    }
  }
  return [motors, limit = limit_, scene](double t) {
    Loads<double> L = scene(t);
    L.M1 = std::clamp(motors[0].raw(t), -limit, limit);
    L.M2 = std::clamp(motors[1].raw(t), -limit, limit);
    return L;
  };
}

std::vector<double> ToneTorques::steps() const {
  std::vector<double> s;
  for (int j = 0; j < kActuators; ++j) {
    s.push_back(limit_ / 4);
    for (int k = 0; k < k_; ++k) s.push_back(limit_ / 4);
    for (int k = 0; k < k_; ++k) s.push_back(0.3);
    for (int k = 0; k < k_; ++k) s.push_back(1.0);
  }
  return s;
}

void ToneTorques::bound(std::vector<double>* x) const {
  for (int j = 0; j < kActuators; ++j) {
    double* v = x->data() + j * per_motor();
    v[0] = std::clamp(v[0], -limit_, limit_);
    for (int k = 0; k < k_; ++k) {
      v[1 + k] = std::clamp(v[1 + k], 0.0, 4 * limit_);
      v[1 + k_ + k] = std::clamp(v[1 + k_ + k], 0.02, 8.0);
    }
  }
}

std::vector<double> multisine_tones() {
  std::vector<double> x;
  for (int j = 0; j < kActuators; ++j) {
    const double* f = j == 0 ? kMultisineF1 : kMultisineF2;
    x.push_back(kMultisineBias[j]);
    for (int k = 0; k < 4; ++k) x.push_back(kMultisineA[k]);
    for (int k = 0; k < 4; ++k) x.push_back(f[k]);
    for (int k = 0; k < 4; ++k) x.push_back(M_PI * k * (k + 1) / 4.0 + (j == 0 ? 0.0 : 1.0));
  }
  return x;
}

FittedMultisine fit_multisine(const Params<double>& scene, const sim::LoadFunction& loads,
                              const sim::Initial& initial, const MultisineFitOptions& o) {
  const std::vector<double> x0 = multisine_tones();
  const ToneTorques raw(4, kInf);
  // the tones' peak over the duration, sampled at 1 kHz
  double peak = 0;
  const long n = std::max(1L, std::lround(o.duration * 1000));
  for (long i = 0; i <= n; ++i) {
    const double t = o.duration * static_cast<double>(i) / static_cast<double>(n);
    peak = std::max({peak, std::abs(raw.raw(x0, 0, t)), std::abs(raw.raw(x0, 1, t))});
  }
  std::array<double, 2> hold{};
  Holding<double> h;
  if (holding_torques(scene, loads(0.0), initial.theta1, initial.theta2, EvalOptions{}, &h).ok()) {
    hold = {h.M1, h.M2};
  }
  sim::Options so = o.sim;
  so.duration = o.duration;
  so.output_step = o.duration / 100;  // only whether it runs matters here
  so.singular_margin = std::max(so.singular_margin, o.singular_margin);
  so.full_rows = false;
  so.progress = nullptr;
  const ToneTorques clipped(4, o.torque_limit);
  FittedMultisine out;
  double factor = std::min(1.0, o.torque_limit / peak);
  for (int halving = 0; halving <= kMultisineHalvings; ++halving, factor /= 2) {
    for (bool holding : {false, true}) {
      std::vector<double> x = x0;
      for (int j = 0; j < kActuators; ++j) {
        double* v = x.data() + j * raw.per_motor();
        v[0] = holding ? hold[j] : factor * v[0];
        for (int k = 0; k < 4; ++k) v[1 + k] *= factor;
      }
      const sim::Result r = sim::simulate(scene, clipped.loads(x, loads), initial, so);
      out = {x, factor, holding, r.status};
      if (r.status.ok()) return out;
    }
  }
  return out;
}

std::vector<double> resize_tones(const std::vector<double>& x, int from, int tones) {
  std::vector<double> y;
  for (int j = 0; j < kActuators; ++j) {
    const double* v = x.data() + j * (1 + 3 * from);
    y.push_back(v[0]);
    for (int part = 0; part < 3; ++part) {
      for (int k = 0; k < tones; ++k) {
        if (k < from) {
          y.push_back(v[1 + part * from + k]);
        } else {
          // a silent tone (amplitude 0) at a frequency above the given ones, phase 0
          const double top = from > 0 ? v[1 + from + from - 1] : 1.0;
          y.push_back(part == 0 ? 0.0 : part == 1 ? top * (1.0 + 0.37 * (k - from + 1)) : 0.0);
        }
      }
    }
  }
  return y;
}

TorqueCandidate evaluate_tones(const Params<double>& scene, const sim::LoadFunction& scene_loads,
                               std::array<double, 2> start, const TorqueDesignOptions& options,
                               const std::vector<double>& x, double step) {
  const ExcitationOptions& o = options.excitation;
  const ToneTorques tones(options.tones, o.torque_limit);
  TorqueCandidate c;
  c.x = x;
  c.objective = std::numeric_limits<double>::quiet_NaN();
  sim::Options so = options.sim;
  so.duration = o.duration;
  so.output_step = step;
  so.singular_margin = std::max(so.singular_margin, o.singular_margin);
  sim::Initial init;
  init.theta1 = start[0];
  init.theta2 = start[1];
  const sim::Result res = sim::simulate(scene, tones.loads(x, scene_loads), init, so);
  c.status = res.status;
  if (!res.status.ok()) return c;
  std::vector<double> t;
  std::vector<MotionState> states;
  for (const sim::Row& r : res.rows) {
    t.push_back(r.t);
    states.push_back({r.theta[0], r.theta[1], r.omega[0], r.omega[1], r.alpha[0], r.alpha[1]});
    c.tau1.push_back(r.M1);
    c.tau2.push_back(r.M2);
    c.peak_applied = std::max({c.peak_applied, std::abs(r.M1), std::abs(r.M2)});
  }
  const DesignParameters dp = design_parameters(scene, o.groups);
  c.status = evaluate_motion(scene, dp, scene_loads, t,
                             states, o.torque_noise, &c.report);
  if (!c.status.ok()) return c;
  // each grid sample stands for rate * duration / samples samples of the log
  const double weight = o.rate_hz * o.duration / static_cast<double>(t.size());
  c.objective = design_criterion(weight * c.report.fisher, dp.scale, dp.nominal, o.regularization,
                                 o.criterion, nullptr);
  c.feasible = violation(c, o) == 0;
  return c;
}

std::vector<std::vector<double>> tone_starts(const ToneTorques& tones, const std::vector<double>& x0) {
  std::vector<std::vector<double>> starts;
  const int K = tones.tones(), pm = tones.per_motor();
  for (double amplitude : {1.0, 3.0, 10.0}) {
    for (double frequency : {1.0, 0.7, 0.5}) {
      std::vector<double> x = x0;
      for (int j = 0; j < kActuators; ++j) {
        for (int k = 0; k < K; ++k) {
          x[j * pm + 1 + k] *= amplitude;
          x[j * pm + 1 + K + k] *= frequency;
        }
      }
      tones.bound(&x);
      starts.push_back(x);
    }
  }
  return starts;
}

namespace {

// evaluates every point, two at a time: each thread takes the next point not yet taken, so a
// long simulation does not hold the other thread up (results in order, whatever the threads)
template <class Result>
std::vector<Result> evaluate_all(const std::vector<std::vector<double>>& xs,
                                 const std::function<Result(const std::vector<double>&)>& eval) {
  std::vector<Result> cs(xs.size());
  std::atomic<size_t> next{0};
  const auto work = [&] {
    for (size_t i = next++; i < xs.size(); i = next++) cs[i] = eval(xs[i]);
  };
  std::thread other(work);
  work();
  other.join();
  return cs;
}

}  // namespace

sim::Options search_settings(const sim::Options& scene, double tolerance, FrictionLaw law) {
  sim::Options s = scene;
  if (tolerance <= 0) return s;
  s.rtol = std::max(s.rtol, tolerance);
  s.atol = std::max(s.atol, tolerance);
  if (law_descriptor(law).states_per_joint == 0) s.method = sim::Method::kArkodeErk45;
  return s;
}

TorqueDesignResult design_torque_excitation(const Params<double>& scene,
                                            const sim::LoadFunction& scene_loads,
                                            std::array<double, 2> start,
                                            const TorqueDesignOptions& options,
                                            const std::vector<std::vector<double>>& starts) {
  const ExcitationOptions& o = options.excitation;
  const ToneTorques tones(options.tones, o.torque_limit);
  const double step = o.duration / std::max(16, o.design_samples);
  TorqueDesignOptions search = options;
  search.sim = search_settings(options.sim, options.search_tolerance, scene.friction.law);
  const std::function<TorqueCandidate(const std::vector<double>&)> eval =
      [&](const std::vector<double>& x) {
        return evaluate_tones(scene, scene_loads, start, search, x, step);
      };
  TorqueDesignResult out;
  Finalists finalists(kFinalistSpares * std::max(1, options.finalists));
  std::vector<TorqueCandidate> first = evaluate_all(starts, eval);
  out.evaluations = static_cast<int>(first.size());
  double vbest = kInf;
  out.best_unconstrained.objective = kInf;
  auto track = [&](const TorqueCandidate& c) {
    if (c.status.ok() && c.objective < out.best_unconstrained.objective) out.best_unconstrained = c;
  };
  for (size_t i = 0; i < first.size(); ++i) {
    track(first[i]);
    const double v = violation(first[i], o);
    finalists.offer(first[i], v);
    out.start_objectives.push_back(first[i].objective);
    out.start_feasible.push_back(v == 0);
    if (i == 0 || better(first[i], v, out.best, vbest)) {
      out.best = std::move(first[i]);
      out.best_start = static_cast<int>(i);
      vbest = v;
    }
  }
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::vector<double> s = tones.steps();
  double sigma = options.step;
  const int lambda = std::max(1, options.offspring);
  while (out.evaluations + lambda <= options.max_evaluations) {
    std::vector<std::vector<double>> ys(lambda, out.best.x);
    for (std::vector<double>& y : ys) {
      for (size_t v = 0; v < y.size(); ++v) y[v] += sigma * s[v] * gauss(rng);
      tones.bound(&y);
    }
    std::vector<TorqueCandidate> cs = evaluate_all(ys, eval);
    out.evaluations += lambda;
    bool improved = false;
    for (TorqueCandidate& c : cs) {
      track(c);
      const double vc = violation(c, o);
      finalists.offer(c, vc);
      if (better(c, vc, out.best, vbest)) {
        out.best = std::move(c);
        vbest = vc;
        improved = true;
      }
    }
    out.improvements += improved ? 1 : 0;
    sigma = std::clamp(sigma * (improved ? 1.5 : 0.8), 0.01, 2.0);
  }
  finalists.write(&out);
  return out;
}

namespace {

// a finalist at the scene's settings and its prediction
struct Final {
  TorqueCandidate c;
  Status predicted = Status::Error(StatusCode::kSolverFailed, "not evaluated");
  double miss = kInf;
};

// a beats b as finish_torque_design says
bool better_final(const Final& a, const Final& b, bool worst_std) {
  if (a.c.status.ok() != b.c.status.ok()) return a.c.status.ok();
  if ((a.miss == 0) != (b.miss == 0)) return a.miss == 0;
  if (a.miss > 0 && a.miss != b.miss) return a.miss < b.miss;
  if (a.predicted.ok() != b.predicted.ok()) return a.predicted.ok();
  if (worst_std && a.predicted.ok()) {
    return worst_relative_std(a.c.report) < worst_relative_std(b.c.report);
  }
  return a.c.objective < b.c.objective;
}

}  // namespace

FinishedTorqueDesign finish_torque_design(const Params<double>& scene,
                                          const sim::LoadFunction& scene_loads,
                                          std::array<double, 2> start,
                                          const TorqueDesignOptions& options,
                                          const std::vector<std::vector<double>>& finalists) {
  const ExcitationOptions& o = options.excitation;
  const DesignParameters dp = design_parameters(scene, o.groups);
  const std::function<Final(const std::vector<double>&)> eval = [&](const std::vector<double>& x) {
    Final f;
    f.c = evaluate_tones(scene, scene_loads, start, options, x, 1.0 / o.rate_hz);
    if (!f.c.status.ok()) return f;
    f.miss = violation(f.c, o);
    f.predicted =
        predict_identified_std(scene, dp, scene_loads, o.torque_noise, o.angle_noise, &f.c.report);
    return f;
  };
  const size_t group = static_cast<size_t>(std::max(1, options.finalists));
  std::vector<Final> fs;
  FinishedTorqueDesign out;
  for (size_t begin = 0; begin < finalists.size(); begin += group) {
    const size_t end = std::min(finalists.size(), begin + group);
    for (Final& f : evaluate_all(
             std::vector<std::vector<double>>(finalists.begin() + begin, finalists.begin() + end),
             eval)) {
      fs.push_back(std::move(f));
      if (fs.size() > 1 && better_final(fs.back(), fs[static_cast<size_t>(out.finalist)],
                                        o.criterion == Criterion::kWorstStd)) {
        out.finalist = static_cast<int>(fs.size() - 1);
      }
    }
    const Final& best = fs[static_cast<size_t>(out.finalist)];
    if (best.c.status.ok() && best.miss == 0 && best.predicted.ok()) break;
  }
  out.evaluated = static_cast<int>(fs.size());
  if (fs.empty()) {
    out.design.status =
        Status::Error(StatusCode::kSolverFailed, "no finalist: no candidate of the search ran");
    return out;
  }
  Final& best = fs[static_cast<size_t>(out.finalist)];
  out.design = std::move(best.c);
  out.predicted = best.predicted;
  return out;
}

}  // namespace fivebar::identification
