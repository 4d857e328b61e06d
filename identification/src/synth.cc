// Synthetic logs from the simulator with seeded sensor noise.
#include "fivebar/identification/synth.h"

#include <cmath>
#include <random>

#include "fivebar/model/dynamics.h"

namespace fivebar::identification {

sim::LoadFunction multisine_loads(const sim::LoadFunction& scene_loads) {
  return [scene_loads](double t) {
    Loads<double> L = scene_loads(t);
    // four tones per motor, distinct between motors; amplitudes [N m], frequencies [Hz]
    static const double kF1[] = {0.31, 0.83, 1.7, 3.1}, kF2[] = {0.43, 1.1, 2.3, 2.9};
    static const double kA[] = {4.0, 3.0, 2.0, 1.5};
    double m1 = 0, m2 = 0;
    for (int j = 0; j < 4; ++j) {
      // Schroeder phases keep the crest factor low
      const double ph = M_PI * j * (j + 1) / 4.0;
      m1 += kA[j] * std::sin(2 * M_PI * kF1[j] * t + ph);
      m2 += kA[j] * std::sin(2 * M_PI * kF2[j] * t + ph + 1.0);
    }
    L.M1 = 2.0 + m1;
    L.M2 = 3.0 + m2;
    return L;
  };
}

SynthResult synthesize_log(const Params<double>& params, const sim::LoadFunction& loads,
                           const sim::Initial& initial, const SynthOptions& opt) {
  SynthResult out;
  const sim::LoadFunction f = opt.multisine ? multisine_loads(loads) : loads;
  sim::Options so = opt.sim;
  so.duration = opt.duration;
  so.output_step = 1.0 / opt.rate_hz;
  const sim::Result res = sim::simulate(params, f, initial, so);
  out.stats = res.stats;
  if (!res.status.ok()) {
    out.status = res.status;
    return out;
  }
  std::mt19937_64 rng(opt.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  TorqueLog& log = out.log;
  log.has_rates = log.has_accels = opt.with_rates;
  auto quantize = [&](double x) {
    return opt.quantization > 0 ? opt.quantization * std::round(x / opt.quantization) : x;
  };
  std::vector<std::array<double, 5>> rates;
  rates.reserve(res.rows.size());
  for (const sim::Row& row : res.rows) {
    // one fixed order of draws per row keeps logs reproducible across options
    const double n_tau1 = gauss(rng), n_tau2 = gauss(rng), n_th1 = gauss(rng), n_th2 = gauss(rng),
                 n_w1 = gauss(rng), n_w2 = gauss(rng);
    log.t.push_back(row.t);
    log.theta1.push_back(quantize(row.theta[0] + opt.angle_noise * n_th1));
    log.theta2.push_back(quantize(row.theta[1] + opt.angle_noise * n_th2));
    // the sensors read the motor torque plus their offset (ActuatorParams)
    log.tau1.push_back(row.M1 + params.actuators.offset[0] + opt.torque_noise * n_tau1);
    log.tau2.push_back(row.M2 + params.actuators.offset[1] + opt.torque_noise * n_tau2);
    if (opt.with_rates) {
      log.omega1.push_back(row.omega[0] + opt.rate_noise * n_w1);
      log.omega2.push_back(row.omega[1] + opt.rate_noise * n_w2);
      log.alpha1.push_back(row.alpha[0]);
      log.alpha2.push_back(row.alpha[1]);
    }
    log.lines.push_back(log.size() + 1);
    // joint reversals: sign changes of w_k = (w1, w3 - w1, w4 - w3, w2 - w4, w2)
    rates.push_back(relative_rates(row.omega[0], row.omega[1], row.omega[2], row.omega[3]));
  }
  out.reversals = count_reversals(rates);
  return out;
}

std::array<int, 5> count_reversals(const std::vector<std::array<double, 5>>& rates) {
  std::array<int, 5> out{}, prev{};
  for (const auto& w : rates) {
    for (int k = 0; k < 5; ++k) {
      const int s = (w[k] > 0) - (w[k] < 0);
      if (s != 0 && prev[k] != 0 && s != prev[k]) ++out[k];
      if (s != 0) prev[k] = s;
    }
  }
  return out;
}

}  // namespace fivebar::identification
