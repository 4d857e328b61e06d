// Sensor noise through rate estimation and inverse dynamics (see noise_model.h).
#include "noise_model.h"

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace fivebar::identification::detail {

KinematicJacobians::KinematicJacobians(const Params<double>& scene, const ParameterLayout& layout,
                                       const double* x)
    : p_(scene.template cast<J6>()) {
  std::vector<J6> xj(layout.size());
  for (int i = 0; i < layout.size(); ++i) xj[i] = J6(x[i]);
  layout.apply(xj.data(), &p_);
}

bool KinematicJacobians::operator()(const Sample& s, const EvalOptions& eval,
                                    Eigen::Matrix<double, 2, 6>* D) const {
  const double v[6] = {s.th1, s.th2, s.w1, s.w2, s.a1, s.a2};
  J6 in[6];
  for (int k = 0; k < 6; ++k) in[k] = J6(v[k], k);
  Evaluation<J6> ev;
  const Status st = inverse_dynamics(p_, s.loads.template cast<J6>(), in[0], in[1], in[2], in[3],
                                     in[4], in[5], nullptr, eval, &ev);
  if (!st.ok()) return false;
  D->row(0) = ev.M1.v.transpose();
  D->row(1) = ev.M2.v.transpose();
  return D->allFinite();
}

bool kinematic_jacobian(const Params<double>& scene, const ParameterLayout& layout, const double* x,
                        const Sample& s, const EvalOptions& eval, Eigen::Matrix<double, 2, 6>* D) {
  return KinematicJacobians(scene, layout, x)(s, eval, D);
}

Sensitivity sensitivity(const std::vector<double>& t, int i, RateSource source, const SgOptions& sg,
                        const SensorNoise& noise, const Eigen::Matrix<double, 2, 6>& D) {
  int lo = i;
  std::vector<double> d1, d2;
  if (source != RateSource::kLogged) savitzky_golay_taps(t, i, sg, &lo, &d1, &d2);
  return sensitivity(i, lo, d1, d2, source, noise, D);
}

Sensitivity sensitivity(SgTapCache* taps, int i, RateSource source, const SensorNoise& noise,
                        const Eigen::Matrix<double, 2, 6>& D) {
  int lo = i;
  static const std::vector<double> none;
  const std::vector<double>*d1 = &none, *d2 = &none;
  if (source != RateSource::kLogged) taps->taps(i, &lo, &d1, &d2);
  return sensitivity(i, lo, *d1, *d2, source, noise, D);
}

Sensitivity sensitivity(int i, int lo, const std::vector<double>& d1, const std::vector<double>& d2,
                        RateSource source, const SensorNoise& noise,
                        const Eigen::Matrix<double, 2, 6>& D) {
  Sensitivity out;
  // r = tau - M: d r / d v = -D[:, v]; v = 0,1 theta, 2,3 omega, 4,5 alpha
  auto col = [&](int v) { return Eigen::Vector2d(-D(0, v), -D(1, v)); };
  for (int c = 0; c < kDof; ++c) {
    if (source == RateSource::kFromAngles) {
      // the angle noise of the window: through omega (d1), alpha (d2) and, at i, theta itself
      out.lo[c] = lo;
      out.sigma[c] = noise.angle[c];
      out.coef[c].reserve(d1.size());
      for (size_t r = 0; r < d1.size(); ++r) {
        Eigen::Vector2d a = col(2 + c) * d1[r] + col(4 + c) * d2[r];
        if (lo + static_cast<int>(r) == i) a += col(c);
        out.coef[c].push_back(a);
      }
    } else {
      // logged rates: their noise directly and through the estimated accelerations (d1)
      out.lo[c] = source == RateSource::kAccelsFromRates ? lo : i;
      out.sigma[c] = noise.rate[c];
      if (source == RateSource::kAccelsFromRates) {
        out.coef[c].reserve(d1.size());
        for (size_t r = 0; r < d1.size(); ++r) {
          Eigen::Vector2d a = col(4 + c) * d1[r];
          if (lo + static_cast<int>(r) == i) a += col(2 + c);
          out.coef[c].push_back(a);
        }
      } else {
        out.coef[c].push_back(col(2 + c));
      }
      // and the angle noise, at i only
      out.lo[2 + c] = i;
      out.sigma[2 + c] = noise.angle[c];
      out.coef[2 + c].push_back(col(c));
    }
  }
  return out;
}

Eigen::Vector2d propagated_variance(const Sensitivity& s) {
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  for (int c = 0; c < 4; ++c) {
    for (const Eigen::Vector2d& a : s.coef[c]) v += s.sigma[c] * s.sigma[c] * a.cwiseAbs2();
  }
  return v;
}

void add_channel_covariance(const Eigen::MatrixXd& G, int first, int last, double sigma,
                            Eigen::MatrixXd* S) {
  if (!(sigma > 0) || last < first) return;
  const auto used = G.middleCols(first, last - first + 1);
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(S->rows(), S->cols());
  C.selfadjointView<Eigen::Lower>().rankUpdate(used, sigma * sigma);
  *S += C.selfadjointView<Eigen::Lower>();
}

namespace {

/// G's column l = sum over the samples u of Jt_u d r_u / d n_{c,l} (Jt: each sample's J_u^T, or a
/// projection Q J_u^T, as a pair of columns): the response to one sample l of the noise channel c,
/// which enters every residual whose window holds it. [first, last]: the columns reached
/// (last < first: none, G untouched).
void channel_response(const Eigen::MatrixXd& Jt, const std::vector<Sensitivity>& sens, int c, int n,
                      Eigen::MatrixXd* G, int* first, int* last) {
  *first = n, *last = -1;
  for (size_t u = 0; u < sens.size(); ++u) {
    const Sensitivity& s = sens[u];
    if (s.coef[c].empty()) continue;
    if (*last < 0) G->setZero(Jt.rows(), n);
    *first = std::min(*first, s.lo[c]);
    *last = std::max(*last, s.lo[c] + static_cast<int>(s.coef[c].size()) - 1);
    const double *j0 = Jt.col(2 * u).data(), *j1 = Jt.col(2 * u + 1).data();
    for (size_t r = 0; r < s.coef[c].size(); ++r) {
      const double a0 = s.coef[c][r](0), a1 = s.coef[c][r](1);
      double* g = G->col(s.lo[c] + r).data();
      for (Eigen::Index p = 0; p < Jt.rows(); ++p) g[p] += a0 * j0[p] + a1 * j1[p];
    }
  }
}

/// the channels' std (the first sample's: every sample's are the same)
double channel_sigma(const std::vector<Sensitivity>& sens, int c) {
  return sens.empty() ? 0.0 : sens.front().sigma[c];
}

}  // namespace

Eigen::MatrixXd score_covariance(const Eigen::MatrixXd& J, const std::vector<Sensitivity>& sens,
                                 const SensorNoise& noise, int n) {
  const int P = static_cast<int>(J.cols()), m = static_cast<int>(sens.size());
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(P, P);
  const Eigen::MatrixXd Jt = J.topRows(2 * m).transpose();
  // the torque noise at every sample: J^T diag(torque noise^2) J
  if (noise.torque[0] != 0 || noise.torque[1] != 0) {
    Eigen::MatrixXd Jw = Jt;
    for (int u = 0; u < m; ++u) {
      for (int j = 0; j < kActuators; ++j) Jw.col(2 * u + j) *= noise.torque[j];
    }
    S.selfadjointView<Eigen::Lower>().rankUpdate(Jw);
    S = S.selfadjointView<Eigen::Lower>();
  }
  Eigen::MatrixXd G;
  for (int c = 0; c < 4; ++c) {
    int first = 0, last = -1;
    channel_response(Jt, sens, c, n, &G, &first, &last);
    add_channel_covariance(G, first, last, channel_sigma(sens, c), &S);
  }
  return S;
}

Eigen::VectorXd projected_score_variance(const Eigen::MatrixXd& Q, const Eigen::MatrixXd& J,
                                         const std::vector<Sensitivity>& sens,
                                         const SensorNoise& noise, int n) {
  const int m = static_cast<int>(sens.size());
  const Eigen::MatrixXd Jq = Q * J.topRows(2 * m).transpose();
  Eigen::VectorXd v = Eigen::VectorXd::Zero(Q.rows());
  for (int u = 0; u < m; ++u) {
    for (int j = 0; j < kActuators; ++j) {
      v += noise.torque[j] * noise.torque[j] * Jq.col(2 * u + j).cwiseAbs2();
    }
  }
  Eigen::MatrixXd G;
  for (int c = 0; c < 4; ++c) {
    int first = 0, last = -1;
    channel_response(Jq, sens, c, n, &G, &first, &last);
    const double sigma = channel_sigma(sens, c);
    if (sigma > 0 && last >= first) {
      v += sigma * sigma * G.middleCols(first, last - first + 1).rowwise().squaredNorm();
    }
  }
  return v;
}

}  // namespace fivebar::identification::detail
