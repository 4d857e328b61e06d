// The inertial group of identification (see inertia.h).
#include "inertia.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "fivebar/model/format.h"

namespace fivebar::identification::detail {

InertialPrior inertial_prior(const Params<double>& scene, double relative) {
  return inertial_prior(scene.links.data(), kLinks, relative);
}

InertialPrior inertial_prior(const Link<double>* links, int n, double relative) {
  InertialPrior p;
  p.links = n;
  standard_inertial_links(links, n, p.centre.data());
  for (int l = 0; l < n; ++l) {
    const double m = links[l].mass, len = links[l].length;
    const double* c = &p.centre[kInertialPerLink * l];
    double* s = &p.sigma[kInertialPerLink * l];
    s[0] = relative * m;
    s[1] = s[2] = relative * m * len;
    s[3] = relative * std::abs(c[3]);
    p.min_com_inertia[l] = 1e-3 * links[l].inertia;
  }
  return p;
}

Eigen::MatrixXd prior_information(const InertialPrior& prior, double s, int P, int offset) {
  Eigen::MatrixXd Hp = Eigen::MatrixXd::Zero(P, P);
  for (int i = 0; i < kInertialPerLink * prior.links; ++i) {
    Hp(offset + i, offset + i) = std::pow(s / prior.sigma[i], 2);
  }
  return Hp;
}

namespace {

/// inertia about the COM of link l from the standard parameters, and its gradient
double com_inertia(const double* pi, double grad[4]) {
  const double m = pi[0], mx = pi[1], my = pi[2], jo = pi[3];
  const double q = mx * mx + my * my;
  grad[0] = q / (m * m);
  grad[1] = -2 * mx / m;
  grad[2] = -2 * my / m;
  grad[3] = 1;
  return jo - q / m;
}

class InertialPriorCost : public ceres::CostFunction {
 public:
  InertialPriorCost(const InertialPrior& prior, int P, int offset, const double* s)
      : prior_(prior), P_(P), offset_(offset), s_(s) {
    set_num_residuals((kInertialPerLink + 1) * prior.links);
    mutable_parameter_block_sizes()->push_back(P);
  }

  bool Evaluate(double const* const* x, double* r, double** jac) const override {
    const double* pi = x[0] + offset_;
    double* J = jac != nullptr ? jac[0] : nullptr;
    if (J != nullptr) std::fill(J, J + num_residuals() * P_, 0.0);
    const int N = kInertialPerLink * prior_.links;
    for (int i = 0; i < N; ++i) {
      const double w = *s_ / prior_.sigma[i];
      r[i] = w * (pi[i] - prior_.centre[i]);
      if (J != nullptr) J[i * P_ + offset_ + i] = w;
    }
    for (int l = 0; l < prior_.links; ++l) {
      const int row = N + l, k = kInertialPerLink * l;
      double grad[4];
      const double gap = prior_.min_com_inertia[l] - com_inertia(pi + k, grad);
      // stiff: a gap of 1 % of the minimum costs as much as 100 prior std of J
      const double w = 1e4 * *s_ / prior_.min_com_inertia[l];
      r[row] = gap > 0 ? w * gap : 0.0;
      if (J != nullptr && gap > 0) {
        for (int a = 0; a < 4; ++a) J[row * P_ + offset_ + k + a] = -w * grad[a];
      }
    }
    return true;
  }

 private:
  InertialPrior prior_;
  int P_, offset_;
  const double* s_;
};

std::string term(double coef, const std::string& name, bool first) {
  std::ostringstream s;
  s.precision(3);
  if (first) {
    if (coef < 0) s << "-";
  } else {
    s << (coef < 0 ? " - " : " + ");
  }
  if (std::abs(std::abs(coef) - 1) > 1e-9) s << std::abs(coef) << " ";
  s << name;
  return s.str();
}

}  // namespace

ceres::CostFunction* inertial_prior_cost(const InertialPrior& prior, int P, int offset,
                                         const double* noise_scale) {
  return new InertialPriorCost(prior, P, offset, noise_scale);
}

void inertial_report(const Eigen::MatrixXd& W, const InertialPrior& prior, double s,
                     const std::vector<double>& pi, const Eigen::MatrixXd& covariance,
                     InertialReport* out) {
  const int N = kInertialPerLink * prior.links;
  Eigen::VectorXd sig(N);
  for (int i = 0; i < N; ++i) sig(i) = prior.sigma[i];
  const Eigen::MatrixXd Ws = W * sig.asDiagonal() / s;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Ws);
  const Eigen::VectorXd sv = svd.singularValues();
  out->information.assign(sv.data(), sv.data() + sv.size());
  int rank = 0;
  for (int k = 0; k < sv.size(); ++k) rank += sv(k) > kDeterminedRatio;
  out->rank = rank;
  // base combinations: the first `rank` pivoted columns are the base parameters; each dependent
  // column is a combination of them, W_d = W_b B (scaled), which regroups into the base ones
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Ws);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(N).triangularView<Eigen::Upper>();
  const Eigen::VectorXi perm = qr.colsPermutation().indices();
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(rank, N - rank);
  if (rank > 0 && rank < N) {
    B = R.topLeftCorner(rank, rank).triangularView<Eigen::Upper>().solve(
        R.topRightCorner(rank, N - rank));
  }
  out->base.clear();
  std::vector<int> order(perm.data(), perm.data() + rank);
  std::sort(order.begin(), order.end());
  for (int b : order) {
    const int i = static_cast<int>(std::find(perm.data(), perm.data() + rank, b) - perm.data());
    InertialReport::Combination c;
    Eigen::VectorXd a = Eigen::VectorXd::Zero(N);
    a(b) = 1;
    c.text = term(1, inertial_name(b), true);
    for (int j = 0; j < N - rank; ++j) {
      const int d = perm(rank + j);
      const double coef = B(i, j) * sig(b) / sig(d);
      if (std::abs(B(i, j)) < 1e-3) continue;
      a(d) = coef;
      c.text += term(coef, inertial_name(d), false);
    }
    c.value = 0;
    for (int k = 0; k < N; ++k) c.value += a(k) * pi[k];
    c.std = std::sqrt(std::max(0.0, a.dot(covariance * a)));
    out->base.push_back(c);
  }
  // parameters the log leaves at their prior: posterior std above half the prior's
  out->at_prior.clear();
  for (int i = 0; i < N; ++i) {
    const double post = std::sqrt(covariance(i, i));
    if (!(post < 0.5 * sig(i))) out->at_prior.push_back(inertial_name(i));
  }
  out->consistent = inertial_consistent(pi.data(), prior.links);
}

void inertial_stage(const Eigen::MatrixXd& W, const InertialPrior& prior, double s,
                    const std::vector<double>& pi, const Eigen::MatrixXd& C, double prior_relative,
                    IdentifyResult* out) {
  InertialReport& rep = out->inertial;
  rep.estimated = true;
  rep.prior_relative = prior_relative;
  if (!C.allFinite()) return;
  inertial_report(W, prior, s, pi, C, &rep);
  if (!rep.at_prior.empty()) {
    std::string list;
    for (const std::string& n : rep.at_prior) list += (list.empty() ? "" : ", ") + n;
    out->warnings.push_back("the log determines " + std::to_string(rep.rank) + " of the " +
                            std::to_string(kInertialPerLink * prior.links) +
                            " inertial directions; " +
                            "left at their prior (the scene's values, relative std " +
                            format_significant(rep.prior_relative) + "): " + list);
  }
  if (!rep.consistent) {
    out->warnings.push_back(
        "the fitted inertial parameters are not physically consistent (some link has m <= 0 or "
        "an inertia about its COM <= 0)");
  }
}

}  // namespace fivebar::identification::detail
