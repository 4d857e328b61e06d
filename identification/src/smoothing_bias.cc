// Predicted Savitzky-Golay smoothing bias of the fitted coefficients (see smoothing_bias.h).
#include "smoothing_bias.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstring>

namespace fivebar::identification::detail {

/// The least-squares basis of high_order_terms: the powers of the offsets (t - t_i) / reach of
/// the samples [a, b] up to degree deg (V empty where deg <= order: no term is read)
struct ReconBasis {
  int deg = 0;
  double reach = 1;
  Eigen::MatrixXd V;
};

namespace {

ReconBasis recon_basis(const std::vector<double>& t, int i, int a, int b, double dt, int order,
                       int extra) {
  ReconBasis B;
  B.deg = std::min(order + extra, b - a);
  // the offsets scaled by the window's reach keep the powers near 1 (conditioning)
  B.reach = std::max({i - a, b - i, 1}) * dt;
  if (B.deg <= order) return B;
  B.V.resize(b - a + 1, B.deg + 1);
  for (int r = 0; r <= b - a; ++r) {
    const double u = (t[a + r] - t[i]) / B.reach;
    double p = 1.0;
    for (int c = 0; c <= B.deg; ++c, p *= u) B.V(r, c) = p;
  }
  return B;
}

/// The terms from the factorized basis and the samples y
Eigen::VectorXd terms_of(const ReconBasis& B, const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr,
                         const Eigen::VectorXd& y, double dt, int order, int extra) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(extra);
  if (B.deg <= order) return out;
  const Eigen::VectorXd coef = qr.solve(y);
  for (int k = order + 1; k <= B.deg; ++k) {
    out(k - order - 1) = coef(k) * std::pow(dt / B.reach, k);  // per ((t - t_i) / dt)^k
  }
  return out;
}

/// high_order_weights from the basis
Eigen::MatrixXd weights_of(const ReconBasis& B, int a, int b, double dt, int order, int extra) {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(extra, b - a + 1);
  if (B.deg <= order) return W;
  // as high_order_terms: the rows of the least-squares pseudo-inverse of its terms
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(B.V.transpose() * B.V);
  for (int k = order + 1; k <= B.deg; ++k) {
    const Eigen::VectorXd z = ldlt.solve(Eigen::VectorXd::Unit(B.deg + 1, k));
    W.row(k - order - 1) = (B.V * z).transpose() * std::pow(dt / B.reach, k);
  }
  return W;
}

Eigen::VectorXd window_samples(const std::vector<double>& x, int a, int b) {
  Eigen::VectorXd y(b - a + 1);
  for (int r = 0; r <= b - a; ++r) y(r) = x[a + r];
  return y;
}

}  // namespace

Eigen::VectorXd high_order_terms(const std::vector<double>& t, const std::vector<double>& x, int i,
                                 int a, int b, double dt, int order, int extra) {
  const ReconBasis B = recon_basis(t, i, a, b, dt, order, extra);
  if (B.deg <= order) return Eigen::VectorXd::Zero(extra);
  return terms_of(B, B.V.colPivHouseholderQr(), window_samples(x, a, b), dt, order, extra);
}

Eigen::MatrixXd high_order_weights(const std::vector<double>& t, int i, int a, int b, double dt,
                                   int order, int extra) {
  return weights_of(recon_basis(t, i, a, b, dt, order, extra), a, b, dt, order, extra);
}

struct HighOrderCache::Window {
  ReconBasis basis;
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr;
  Eigen::MatrixXd W;
  bool weighed = false;
};

HighOrderCache::HighOrderCache(const std::vector<double>& t, double dt, int order, int extra)
    : t_(t), dt_(dt), order_(order), extra_(extra) {}

HighOrderCache::~HighOrderCache() = default;

HighOrderCache::Window& HighOrderCache::window(int i, int a, int b) {
  // the basis is a function of these offsets and of the reach each side alone
  const double reach = std::max({i - a, b - i, 1}) * dt_;
  key_.assign({static_cast<std::uint64_t>(i - a), static_cast<std::uint64_t>(b - i)});
  for (int r = 0; r <= b - a; ++r) {
    const double u = (t_[a + r] - t_[i]) / reach;
    std::uint64_t bits = 0;
    std::memcpy(&bits, &u, sizeof bits);
    key_.push_back(bits);
  }
  std::unique_ptr<Window>& w = memo_[key_];
  if (!w) {
    w = std::make_unique<Window>();
    w->basis = recon_basis(t_, i, a, b, dt_, order_, extra_);
    if (w->basis.deg > order_) w->qr.compute(w->basis.V);
  }
  return *w;
}

Eigen::VectorXd HighOrderCache::terms(const std::vector<double>& x, int i, int a, int b) {
  const Window& w = window(i, a, b);
  if (w.basis.deg <= order_) return Eigen::VectorXd::Zero(extra_);
  return terms_of(w.basis, w.qr, window_samples(x, a, b), dt_, order_, extra_);
}

const Eigen::MatrixXd& HighOrderCache::weights(int i, int a, int b) {
  Window& w = window(i, a, b);
  if (!w.weighed) w.W = weights_of(w.basis, a, b, dt_, order_, extra_), w.weighed = true;
  return w.W;
}

void filter_response(const SgOptions& sg, double dt, Eigen::VectorXd* r1, Eigen::VectorXd* r2,
                     int extra) {
  const int m = sg_half_window(sg, dt);
  std::vector<double> tu(2 * m + 1);
  for (int r = 0; r <= 2 * m; ++r) tu[r] = (r - m) * dt;
  int lo = 0;
  std::vector<double> d1, d2;
  savitzky_golay_taps(tu, m, sg, &lo, &d1, &d2);
  r1->setZero(extra);
  r2->setZero(extra);
  for (int e = 0; e < extra; ++e) {
    const int k = sg.order + 1 + e;
    for (size_t r = 0; r < d1.size(); ++r) {
      const double p = std::pow(static_cast<double>(lo + static_cast<int>(r) - m), k);
      (*r1)(e) += d1[r] * p;
      (*r2)(e) += d2[r] * p;
    }
  }
}

namespace {

/// the public parameters the prediction gives (BiasInputs::judged)
int judged_size(const BiasInputs& in) { return in.judged > 0 ? in.judged : in.friction_size; }

/// The std of the smoothing's prediction (public friction coefficients) from the angle noise
/// through the reconstruction: the prediction is linear in the angles (weights W of each sample's
/// terms, through the filter's response r1, r2 and the kinematic Jacobian), so its score's
/// covariance is that of the errors in variables (score_covariance) with these sensitivities;
/// the std of the public parameters judged: Q = (T (J^T J + Hp)^-1)'s first rows, diag(Q S Q^T).
Eigen::VectorXd prediction_spread(const std::vector<double>& t, const BiasInputs& in,
                                  const std::vector<char>& keep, const Eigen::MatrixXd& J,
                                  const Eigen::MatrixXd& Q, const Eigen::VectorXd& r1,
                                  const Eigen::VectorXd& r2) {
  const int k_out = static_cast<int>(Q.rows()), n = static_cast<int>(t.size());
  const Eigen::MatrixXd QJt = Q * J.transpose();  // the kept samples' Q J_u^T as column pairs
  Eigen::VectorXd var = Eigen::VectorXd::Zero(k_out);
  Eigen::MatrixXd G, V(k_out, r1.size());
  for (int c = 0; c < kDof; ++c) {
    // G's column l: the prediction's response to the angle sample l through every kept sample's
    // terms: the torque error d dM_u / d theta_l = sum over the terms e of W_u(e, l - lo_u)
    // (D_omega r1(e) + D_alpha r2(e)), through Q J_u^T: sum over e of W_u(e, l - lo_u) V(:, e)
    G.setZero(k_out, n);
    int first = n, last = -1;
    for (size_t u = 0, k = 0; u < keep.size(); ++u) {
      if (!keep[u]) continue;
      const Eigen::MatrixXd& W = in.weights[c][u];
      for (int e = 0; e < W.rows(); ++e) {
        const Eigen::Vector2d d = in.D[u].col(2 + c) * r1(e) + in.D[u].col(4 + c) * r2(e);
        V.col(e) = QJt.col(2 * k) * d(0) + QJt.col(2 * k + 1) * d(1);
      }
      const int lo = in.recon_lo[u];
      for (int r = 0; r < W.cols(); ++r) {
        double* g = G.col(lo + r).data();
        for (int e = 0; e < W.rows(); ++e) {
          const double w = W(e, r), *v = V.col(e).data();
          for (int p = 0; p < k_out; ++p) g[p] += w * v[p];
        }
      }
      if (W.cols() > 0) first = std::min(first, lo), last = std::max(last, lo + int(W.cols()) - 1);
      ++k;
    }
    const double sigma = in.noise.angle[c];
    if (sigma > 0 && last >= first) {
      var += sigma * sigma * G.middleCols(first, last - first + 1).rowwise().squaredNorm();
    }
  }
  return var.cwiseMax(0.0).cwiseSqrt();
}

/// The 3-point Gauss-Hermite points along the principal axes of the covariance C:
/// sqrt(3 lambda_k) v_k for each eigenpair (weights 1/6 at +-, 2/3 at 0)
std::array<Eigen::Vector3d, 3> gauss_hermite_axes(const Eigen::Matrix3d& C) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  std::array<Eigen::Vector3d, 3> axes;
  for (int k = 0; k < 3; ++k) {
    axes[k] = std::sqrt(3.0 * std::max(0.0, eig.eigenvalues()(k))) * eig.eigenvectors().col(k);
  }
  return axes;
}

}  // namespace

Eigen::Matrix3d filtered_noise_covariance(int at, int lo, const std::vector<double>& d1,
                                          const std::vector<double>& d2, double sigma) {
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (size_t r = 0; r < d1.size(); ++r) {
    const Eigen::Vector3d g(lo + static_cast<int>(r) == at ? 1.0 : 0.0, d1[r], d2[r]);
    C += g * g.transpose();
  }
  return C * (sigma * sigma);
}

bool noise_bias_at(const Eigen::Matrix3d& C, const PerturbedTorques& torques,
                   Eigen::Vector2d* shift, Eigen::VectorXd* score) {
  Eigen::Vector2d m0, m1;
  Eigen::MatrixXd A0, A1;
  if (!torques(Eigen::Vector3d::Zero(), &m0, &A0)) return false;
  shift->setZero();
  *score = Eigen::VectorXd::Zero(A0.cols());
  for (const Eigen::Vector3d& e : gauss_hermite_axes(C)) {
    for (double side : {1.0, -1.0}) {
      if (!torques(side * e, &m1, &A1)) return false;
      for (int j = 0; j < 2; ++j) {
        (*shift)(j) += (m1(j) - m0(j)) / 6;
        *score += (A1.row(j) - A0.row(j)).transpose() * (m1(j) - m0(j)) / 6;
      }
    }
  }
  return true;
}

std::array<Eigen::Vector3d, 3> noise_axes(const std::vector<double>& t, const SgOptions& sg) {
  const int mid = static_cast<int>(t.size()) / 2;
  int lo = 0;
  std::vector<double> d1, d2;
  savitzky_golay_taps(t, mid, sg, &lo, &d1, &d2);
  return gauss_hermite_axes(filtered_noise_covariance(mid, lo, d1, d2, 1.0));
}

bool predict_smoothing_bias(const std::vector<double>& t, const BiasInputs& in,
                            const std::vector<char>& keep, const SgOptions& sg, bool with_spread,
                            BiasPrediction* out) {
  if (in.source != RateSource::kFromAngles || t.size() < 2) return false;
  const int P = static_cast<int>(in.J.cols());
  const int kept = static_cast<int>(std::count(keep.begin(), keep.end(), 1));
  if (kept < P + 1) return false;
  const double dt = (t.back() - t.front()) / (static_cast<double>(t.size()) - 1);
  Eigen::VectorXd r1, r2;
  filter_response(sg, dt, &r1, &r2);
  Eigen::MatrixXd& J = out->J;
  J.resize(2 * kept, P);
  out->dM.resize(2 * kept);
  std::vector<Sensitivity> sens;
  sens.reserve(kept);
  SgTapCache taps(t, sg);
  for (size_t u = 0, k = 0; u < keep.size(); ++u) {
    if (!keep[u]) continue;
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    for (int c = 0; c < kDof; ++c) {
      m += in.D[u].col(2 + c) * in.terms[c][u].dot(r1) + in.D[u].col(4 + c) * in.terms[c][u].dot(r2);
    }
    out->dM.segment<2>(2 * k) = m;
    J.middleRows(2 * k, 2) = in.J.middleRows(2 * u, 2);
    int lo = 0;
    const std::vector<double>*d1 = nullptr, *d2 = nullptr;
    taps.taps(in.index[u], &lo, &d1, &d2);
    sens.push_back(sensitivity(in.index[u], lo, *d1, *d2, in.source, in.noise, in.D[u]));
    ++k;
  }
  const Eigen::MatrixXd H = J.transpose() * J + in.Hp;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  // a log that does not determine some parameter (a Stribeck law fitted to a Coulomb-viscous
  // log) makes H singular to rounding: its solve would be a bias of millions, not a prediction
  const Eigen::VectorXd d = ldlt.vectorD().cwiseAbs();
  if (!(d.minCoeff() > 1e-12 * d.maxCoeff())) return false;
  out->Hinv = ldlt.solve(Eigen::MatrixXd::Identity(P, P));
  const Eigen::MatrixXd& Hinv = out->Hinv;
  // the model's torque M is off by dM where the residual r = tau - M is evaluated with biased
  // rates; the Gauss-Newton step from the truth moves x by (J^T J)^-1 J^T dM (J = d r / d x)
  const Eigen::VectorXd score = J.transpose() * out->dM;
  const Eigen::VectorXd b = in.T * (Hinv * score);
  // the std's covariance T Hinv (S + s2 Hp) Hinv T^T is needed on its diagonal alone, for the
  // public parameters judged: the rows Q of T Hinv (Hinv symmetric) through the score's
  const Eigen::MatrixXd Q = (in.T * Hinv).topRows(judged_size(in));
  const Eigen::VectorXd var =
      projected_score_variance(Q, J, sens, in.noise, static_cast<int>(t.size())) +
      in.s2 * (Q * in.Hp).cwiseProduct(Q).rowwise().sum();
  out->bias = b.head(judged_size(in));
  out->std = var.cwiseMax(0.0).cwiseSqrt();
  if (with_spread) {
    const size_t n = keep.size();
    const bool weighed = in.recon_lo.size() == n && in.weights[0].size() == n &&
                         in.weights[1].size() == n && in.D.size() == n;
    out->spread = weighed ? prediction_spread(t, in, keep, J, Q, r1, r2)
                          : Eigen::VectorXd::Zero(judged_size(in));
  }
  return out->bias.allFinite() && out->std.allFinite();
}

bool noisy_bias(const BiasInputs& in, const std::vector<char>& keep, const NoiseBias& noise,
                const BiasPrediction& p, Eigen::VectorXd* bias) {
  Eigen::VectorXd dM = p.dM;
  for (size_t u = 0, k = 0; u < keep.size(); ++u) {
    if (!keep[u]) continue;
    dM.segment<2>(2 * k) += noise.shift[u];
    ++k;
  }
  Eigen::VectorXd score = p.J.transpose() * dM;
  for (size_t u = 0; u < keep.size(); ++u) {
    if (keep[u]) score -= noise.score[u];
  }
  const Eigen::VectorXd b = in.T * (p.Hinv * score);
  *bias = b.head(judged_size(in));
  return bias->allFinite() && p.std.allFinite();
}

bool smoothing_bias(const std::vector<double>& t, const BiasInputs& in,
                    const std::vector<char>& keep, const SgOptions& sg, Eigen::VectorXd* bias,
                    Eigen::VectorXd* std, const NoiseBias* noise, Eigen::VectorXd* spread) {
  BiasPrediction p;
  if (!predict_smoothing_bias(t, in, keep, sg, spread != nullptr, &p)) return false;
  *std = p.std;
  if (spread) *spread = p.spread;
  if (!noise) {
    *bias = p.bias;
    return true;
  }
  return noisy_bias(in, keep, *noise, p, bias);
}

}  // namespace fivebar::identification::detail
