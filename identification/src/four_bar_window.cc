// The four-bar's window stage (four_bar_fit.h): the window chosen by its predicted bias
// (mechanism_stages.h, choose_window_by_bias, with the five-bar's bias prediction) over
// FourBarWindowFit, the four-bar's inputs of the bias prediction and the noise's bias through its
// reactions.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "fivebar/identification/rates.h"
#include "four_bar_fit.h"
#include "mechanism_stages.h"
#include "setup_shared.h"
#include "smoothing_bias.h"

namespace fivebar::identification::four_bar {

bool kinematic_jacobian(const FourBarFit& f, const double* x, const Sample& s,
                        Eigen::Matrix<double, 2, 6>* D, double* M1) {
  mech::Vec<1, double> tau;
  if (!stages::mechanism_drive_torques<FourBar>(f.scene, f.layout, x, s, f.eval, &tau)) {
    return false;
  }
  *M1 = tau[0];
  D->setZero();
  const double step[3] = {1e-6, 1e-6 * std::max(1.0, std::abs(s.v[0])),
                          1e-6 * std::max(1.0, std::abs(s.a[0]))};
  for (int v = 0; v < 3; ++v) {
    double m[2];
    for (int side = 0; side < 2; ++side) {
      Sample d = s;
      double* value = v == 0 ? &d.q[0] : (v == 1 ? &d.v[0] : &d.a[0]);
      *value += side ? step[v] : -step[v];
      if (!stages::mechanism_drive_torques<FourBar>(f.scene, f.layout, x, d, f.eval, &tau)) {
        return false;
      }
      m[side] = tau[0];
    }
    (*D)(0, 2 * v) = (m[1] - m[0]) / (2 * step[v]);
  }
  return true;
}

namespace {

/// The four-bar's fit as choose_window_by_bias reads it (mechanism_stages.h), at the parameters
/// f.x of the preliminary fit: one torque channel, rates from the angles (no residual levels:
/// choose_window is the five-bar's).
class FourBarWindowFit : public stages::WindowFit {
 public:
  explicit FourBarWindowFit(const FourBarFit& f) : f_(f) {}
  const TorqueLog& log() const override { return f_.cond.log; }
  const std::vector<char>& rejected() const override { return f_.cond.rejected; }
  detail::RateSource source() const override { return detail::RateSource::kFromAngles; }
  const std::vector<int>& index() const override { return f_.index; }
  bool spans_reversal(int i, int hw) const override {
    return stages::window_spans_reversal(f_.reversals, i, hw);
  }
  /// the residual's Jacobian (its rows of the second channel zero), the kinematic Jacobians, and
  /// the crank angle's higher terms cut short where they would span a slip reversal; the
  /// Jacobians, which do not depend on the reach, computed once for every window searched
  detail::BiasInputs bias_inputs(int reach, int min_half, int order) const override {
    const TorqueLog& L = f_.cond.log;
    const int n = L.size();
    const double dt = L.duration() / std::max(1, n - 1);
    if (jacobians_.index.empty() && !jacobians()) return {};
    detail::BiasInputs in = jacobians_;
    const std::vector<int>& rev = f_.reversals;
    for (const int i : f_.index) {
      int a = std::max(0, i - reach), b = std::min(n - 1, i + reach);
      while (a < i - min_half && rev[i] - rev[a] > 0) ++a;
      while (b > i + min_half && rev[b] - rev[i] > 0) --b;
      in.terms[0].push_back(detail::high_order_terms(L.t, L.theta1, i, a, b, dt, order));
      in.terms[1].push_back(Eigen::VectorXd::Zero(detail::kReconExtra));
    }
    return in;
  }
  /// At each sample's motion u = (theta1, omega1, alpha1), n the noise of the angle and of its
  /// filtered derivatives (covariance from the filter's taps): detail::noise_bias_at.
  detail::NoiseBias noise_bias(const SgOptions& sg) const override {
    const TorqueLog& L = f_.cond.log;
    const int mid = L.size() / 2, P = f_.layout.size();
    int lo = 0;
    std::vector<double> d1, d2;
    savitzky_golay_taps(L.t, mid, sg, &lo, &d1, &d2);
    const Eigen::Matrix3d C = detail::filtered_noise_covariance(mid, lo, d1, d2, f_.noise.angle[0]);
    detail::NoiseBias nb;
    nb.shift.assign(f_.samples.size(), Eigen::Vector2d::Zero());
    nb.score.assign(f_.samples.size(), Eigen::VectorXd::Zero(P));
    for (size_t u = 0; u < f_.samples.size(); ++u) {
      const Sample& s = f_.samples[u];
      const detail::PerturbedTorques torques = [&](const Eigen::Vector3d& dn, Eigen::Vector2d* m,
                                                   Eigen::MatrixXd* A) {
        Sample p = s;
        p.q[0] += dn(0), p.v[0] += dn(1), p.a[0] += dn(2);
        mech::Vec<1, double> tau;
        Eigen::MatrixXd A1;
        if (!stages::mechanism_drive_torques<FourBar>(f_.scene, f_.layout, f_.x.data(), p, f_.eval,
                                                      &tau, &A1)) {
          return false;
        }
        *m = Eigen::Vector2d(tau[0], 0.0);
        *A = Eigen::MatrixXd::Zero(2, P);
        A->row(0) = A1.row(0);
        return true;
      };
      Eigen::Vector2d shift;
      Eigen::VectorXd score;
      if (!detail::noise_bias_at(C, torques, &shift, &score)) continue;
      nb.shift[u] = shift;
      nb.score[u] = score;
    }
    return nb;
  }

 private:
  /// bias_inputs without the terms into jacobians_; false where the residual fails
  bool jacobians() const {
    const int P = f_.layout.size(), m = static_cast<int>(f_.samples.size());
    detail::BiasInputs& in = jacobians_;
    ceres::Problem problem;
    std::vector<double> x = f_.x, r;
    stages::add_mechanism_terms<FourBar>(f_.scene, f_.layout, f_.samples, f_.eval, x.data(),
                                         &problem);
    ceres::CRSMatrix crs;
    if (!stages::raw_residuals(&problem, &r, &crs)) return false;
    const Eigen::MatrixXd J1 = stages::dense(crs, P);
    in.J = Eigen::MatrixXd::Zero(2 * m, P);
    for (int u = 0; u < m; ++u) in.J.row(2 * u) = J1.row(u);
    for (int u = 0; u < m; ++u) {
      Eigen::Matrix<double, 2, 6> D;
      double M1 = 0;
      if (!kinematic_jacobian(f_, f_.x.data(), f_.samples[u], &D, &M1)) D.setZero();
      in.D.push_back(D);
    }
    const ParameterLayout& lay = f_.layout;
    in.Hp = lay.inertia
                ? detail::prior_information(f_.prior, f_.prior_scale, P, lay.inertia_offset())
                : Eigen::MatrixXd::Zero(P, P);
    in.s2 = f_.prior_scale * f_.prior_scale;
    in.T = stages::to_public(lay);
    in.friction_size = lay.friction_size();
    in.judged = lay.inertia ? P : 0;
    in.source = source();
    in.noise = f_.noise;
    in.index = f_.index;
    return true;
  }
  const FourBarFit& f_;
  mutable detail::BiasInputs jacobians_;  ///< bias_inputs' Jacobians, once
};

}  // namespace

void window_stage(FourBarFit* f, IdentifyResult* out) {
  // with the inertia group the window is chosen on the full layout (the prior on the links, its
  // noise level the residual's floor at the filter before the choice): the freed inertias take
  // up the noise of the estimated accelerations, whose bias the walk weighs in every parameter
  if (f->layout.inertia) {
    bool from_noise = true;
    f->prior_scale = noise_floor(*f, &from_noise);
  }
  const std::vector<double> x_start = f->x;
  std::vector<Sample> some;
  const size_t step = std::max<size_t>(1, f->samples.size() / 1500);
  for (size_t u = 0; u < f->samples.size(); u += step) some.push_back(f->samples[u]);
  ceres::Problem problem;
  std::vector<double> x = f->x;
  stages::add_mechanism_terms<FourBar>(f->scene, f->layout, some, f->eval, x.data(), &problem,
                                       Loss::kNone, 1, f->cost_weight);
  if (f->layout.inertia) {
    problem.AddResidualBlock(
        detail::inertial_prior_cost(f->prior, f->layout.size(), f->layout.inertia_offset(),
                                    &f->prior_scale),
        stages::make_loss(Loss::kNone, 0, f->cost_weight), x.data());
  }
  if (stages::solve_preliminary(f->layout, x.data(), &problem)) f->x = x;
  stages::choose_window_by_bias(FourBarWindowFit(*f), &f->sg, &f->smoothing_bias,
                                &out->window_choice);
  f->x = x_start;
  rates(f, out);
  select_samples(f, out);
}

}  // namespace fivebar::identification::four_bar
