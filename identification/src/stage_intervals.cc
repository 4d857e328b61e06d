// Intervals stage of identify(): Wald intervals, and profile-likelihood intervals where a Wald
// interval does not fit.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

// ---- 95 % intervals ----

/// Whether public parameter i gets a profile-likelihood interval: a nonlinear coefficient of the
/// Stribeck law (static_coulomb, stribeck_velocity: a peak's height and width trade off, and
/// the cost is far from quadratic in them), or a friction or actuator term whose Wald interval
/// reaches below its lower bound (values the law cannot take, where the curvature at the fit
/// says little). Only with a std, off its bounds; not the inertial parameters.
bool wants_profile(const ParameterLayout& layout, int i, const ParameterEstimate& e) {
  if (e.at_bound || !std::isfinite(e.std) || layout.is_inertial(i)) return false;
  if (i < layout.friction_size()) {
    const LawCoefficient* c =
        law_coefficient(law_descriptor(layout.law), layout.group(i / layout.per_group()));
    if (c && c->profiled) return true;
  }
  return e.ci_low < layout.lower_bound(i);
}

/// The re-fits of a profile: every residual block of the fit's problem (no robust loss, the
/// fit's cost weight, taken off the rises), on the coordinates y other than y_i, y_i held at
/// theta. x = M y: for static_coulomb (internally coulomb + excess) y are the public parameters
/// and each joint's coulomb is bounded above by the static value (static >= kinetic); otherwise
/// y are the internal parameters.
class ProfileFits {
 public:
  ProfileFits(const ProfileProblem& pp, int i) : so_(pp.solver), weight_(pp.cost_weight) {
    const ParameterLayout& layout = pp.layout;
    const int P = layout.size();
    const Eigen::MatrixXd T = to_public(layout);
    const bool stat = layout.static_as_excess && i < layout.friction_size() &&
                      layout.group(i / layout.per_group()) == Coefficient::kStaticCoulomb;
    const Eigen::MatrixXd M = stat ? Eigen::MatrixXd(T.inverse()) : Eigen::MatrixXd::Identity(P, P);
    const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(pp.x.data(), P);
    const Eigen::VectorXd y = stat ? Eigen::VectorXd(T * x) : x;
    theta_ = y(i);
    Eigen::MatrixXd B(P, P - 1);
    for (int k = 0, c = 0; k < P; ++k) {
      if (k != i) B.col(c) = M.col(k), z_hat_.push_back(y(k)), ++c;
    }
    std::vector<ceres::ResidualBlockId> blocks;
    pp.problem->GetResidualBlocks(&blocks);
    z_ = z_hat_;
    for (ceres::ResidualBlockId id : blocks) {
      reduced_.AddResidualBlock(
          new detail::AffineCost(pp.problem->GetCostFunctionForResidualBlock(id), M.col(i), B,
                                 &theta_),
          make_loss(Loss::kNone, 0, weight_), z_.data());
    }
    for (int k = 0; k < P; ++k) {
      if (k != i)
        reduced_.SetParameterLowerBound(z_.data(), k < i ? k : k - 1, layout.lower_bound(k));
    }
    if (stat)
      coulomb_ =
          layout.group_of(Coefficient::kCoulomb) * layout.per_group() + i % layout.per_group();
    double cost = 0;
    reduced_.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
    cost_hat_ = cost;
    start_[0] = start_[1] = z_hat_;
  }

  /// The least cost with y_i = theta, warm-started from the last re-fit on `side`, minus the
  /// fit's; NaN when the re-fit fails.
  double rise(double theta, int side) {
    std::vector<double>& start = start_[side > 0];
    theta_ = theta;
    std::copy(start.begin(), start.end(), z_.begin());
    if (coulomb_ >= 0) {  // static >= kinetic: the coulomb of the joint below the static value
      z_[coulomb_] = std::min(z_[coulomb_], theta);
      reduced_.SetParameterUpperBound(z_.data(), coulomb_, theta);
    }
    ceres::Solver::Options so = so_;
    so.max_num_iterations = 50;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &reduced_, &summary);
    if (!summary.IsSolutionUsable() || !std::isfinite(summary.final_cost)) return kNaN;
    start = z_;
    return (summary.final_cost - cost_hat_) / weight_;
  }

 private:
  ceres::Solver::Options so_;
  double weight_;     ///< of every block's cost
  int coulomb_ = -1;  ///< static profile: index (in z) of the same joint's coulomb
  double theta_ = 0, cost_hat_ = 0;
  std::vector<double> z_hat_, z_;
  std::vector<double> start_[2];
  ceres::Problem reduced_;
};

/// The profile-likelihood interval of public parameter i: the values whose re-fit raises the
/// cost by at most q^2 / 2 times its noise scale V_ii / Hinv_ii (V the reported covariance, Hinv
/// that of J^T J: for a quadratic cost this is exactly value +- q std, so the interval agrees
/// with the covariance model wherever the Wald interval is right). Warnings for an open side.
void profile_parameter(const ProfileProblem& pp, int i, IdentifyResult* out) {
  ParameterEstimate& e = out->parameters[i];
  const Eigen::VectorXd t = to_public(pp.layout).row(i).transpose();
  const Eigen::MatrixXd Hinv =
      pp.Hinv.unaryExpr([](double v) { return std::isfinite(v) ? v : 0.0; });
  const double h = t.dot(Hinv * t), q = out->ci_quantile;
  if (!(h > 0)) return;
  const double threshold = 0.5 * q * q * e.std * e.std / h;
  ProfileFits fits(pp, i);
  const auto rise = [&](double theta, int side) { return fits.rise(theta, side); };
  const detail::ProfileInterval pi =
      detail::profile_interval(rise, e.value, q * e.std, threshold, pp.layout.lower_bound(i),
                               std::numeric_limits<double>::infinity(), 0.02 * e.std);
  out->profile_refits += pi.refits;
  if (pi.low.failed || pi.high.failed) {
    out->warnings.push_back("the profile-likelihood interval of " + e.name +
                            " failed (a re-fit did not converge): the Wald interval is reported");
    return;
  }
  e.ci_low = pi.low.value;
  e.ci_high = pi.high.value;
  e.ci_method = "profile-likelihood";
  for (const detail::ProfileEnd* end : {&pi.low, &pi.high}) {
    if (!end->unbounded) continue;
    out->warnings.push_back(
        "the log does not bound " + e.name + (end == &pi.low ? " from below" : " from above") +
        ": its profile-likelihood 95 % interval is open on that side (the cost stays within the "
        "95 % threshold up to 32 times the Wald half-width)");
  }
}

}  // namespace

void intervals(const Fit& f, ceres::Problem* problem, const Analysis& an, IdentifyResult* out) {
  for (ParameterEstimate& e : out->parameters) {
    if (!std::isfinite(e.std)) continue;
    e.ci_low = e.value - out->ci_quantile * e.std;
    e.ci_high = e.value + out->ci_quantile * e.std;
    e.ci_method = "wald";
  }
  if (!f.method->profiles_intervals() || f.opt->loss != Loss::kNone) return;
  profile_intervals({f.layout, f.x, problem, an.Hinv, solver_options(f), f.cost_weight}, out);
}

void profile_intervals(const ProfileProblem& pp, IdentifyResult* out) {
  if (!out->converged) return;
  for (int i = 0; i < static_cast<int>(out->parameters.size()); ++i) {
    if (wants_profile(pp.layout, i, out->parameters[i])) profile_parameter(pp, i, out);
  }
}

}  // namespace fivebar::identification::stages
