// The errors-in-variables score covariance and the smoothing bias's std against their
// definitions, summed noise sample by noise sample.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "fivebar/identification/rates.h"
#include "smoothing_bias.h"

namespace fivebar::identification {
namespace {

constexpr int kSamples = 60, kLog = 120, kParams = 7;

/// A uniform 1 kHz grid of kLog samples
std::vector<double> grid() {
  std::vector<double> t(kLog);
  for (int i = 0; i < kLog; ++i) t[i] = i * 1e-3;
  return t;
}

Eigen::MatrixXd random_matrix(int rows, int cols, std::mt19937_64* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(rows, cols);
  for (int j = 0; j < cols; ++j) {
    for (int i = 0; i < rows; ++i) A(i, j) = g(*rng);
  }
  return A;
}

/// Random sensitivities: channels 0, 1 over windows of 3-9 samples, channel 3 at one sample,
/// channel 2 none
std::vector<detail::Sensitivity> random_sensitivities(std::mt19937_64* rng) {
  std::uniform_int_distribution<int> width(3, 9), start(0, kLog - 10);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<detail::Sensitivity> sens(kSamples);
  for (detail::Sensitivity& s : sens) {
    for (int c : {0, 1, 3}) {
      s.lo[c] = start(*rng);
      const int w = c == 3 ? 1 : width(*rng);
      for (int r = 0; r < w; ++r) s.coef[c].emplace_back(g(*rng), g(*rng));
    }
    s.sigma[0] = 0.3, s.sigma[1] = 0.7, s.sigma[3] = 1.1;
  }
  return sens;
}

/// score_covariance by its definition: each noise sample's response g (the sum over the
/// residuals it enters of J_i^T d r_i / d n) squared, and the torque noise at every residual
Eigen::MatrixXd covariance_by_definition(const Eigen::MatrixXd& J,
                                         const std::vector<detail::Sensitivity>& sens,
                                         const detail::SensorNoise& noise) {
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(J.cols(), J.cols());
  for (size_t u = 0; u < sens.size(); ++u) {
    for (int j = 0; j < 2; ++j) {
      const Eigen::RowVectorXd row = J.row(2 * u + j);
      S += noise.torque[j] * noise.torque[j] * row.transpose() * row;
    }
  }
  for (int c = 0; c < 4; ++c) {
    for (int l = 0; l < kLog; ++l) {
      Eigen::VectorXd g = Eigen::VectorXd::Zero(J.cols());
      for (size_t u = 0; u < sens.size(); ++u) {
        const int r = l - sens[u].lo[c];
        if (r < 0 || r >= static_cast<int>(sens[u].coef[c].size())) continue;
        g += J.middleRows(2 * u, 2).transpose() * sens[u].coef[c][r];
      }
      S += sens.front().sigma[c] * sens.front().sigma[c] * g * g.transpose();
    }
  }
  return S;
}

double relative_error(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / b.norm();
}

TEST(NoiseModel, ScoreCovarianceIsTheSumOfEachNoiseSamplesResponse) {
  std::mt19937_64 rng(7);
  const Eigen::MatrixXd J = random_matrix(2 * kSamples, kParams, &rng);
  const std::vector<detail::Sensitivity> sens = random_sensitivities(&rng);
  detail::SensorNoise noise;
  noise.torque[0] = 0.02, noise.torque[1] = 0.05;
  const Eigen::MatrixXd S = detail::score_covariance(J, sens, noise, kLog);
  EXPECT_LT(relative_error(S, covariance_by_definition(J, sens, noise)), 1e-13);
  EXPECT_EQ(S, S.transpose());
}

TEST(NoiseModel, ProjectedScoreVarianceIsTheDiagonalOfTheProjectedCovariance) {
  std::mt19937_64 rng(8);
  const Eigen::MatrixXd J = random_matrix(2 * kSamples, kParams, &rng);
  const Eigen::MatrixXd Q = random_matrix(3, kParams, &rng);
  const std::vector<detail::Sensitivity> sens = random_sensitivities(&rng);
  detail::SensorNoise noise;
  noise.torque[0] = 0.04, noise.torque[1] = 0.01;
  const Eigen::VectorXd reference =
      (Q * covariance_by_definition(J, sens, noise) * Q.transpose()).diagonal();
  EXPECT_LT(relative_error(detail::projected_score_variance(Q, J, sens, noise, kLog), reference),
            1e-13);
}

TEST(NoiseModel, SensitivitiesFromTheTapCacheAreTheDirectOnesBitForBit) {
  const std::vector<double> t = grid();
  const SgOptions sg{0.006, 5};
  SgTapCache taps(t, sg);
  std::mt19937_64 rng(9);
  const Eigen::Matrix<double, 2, 6> D = random_matrix(2, 6, &rng);
  detail::SensorNoise noise;
  noise.angle[0] = 1e-5, noise.angle[1] = 2e-5, noise.rate[0] = 1e-3, noise.rate[1] = 3e-3;
  for (detail::RateSource source :
       {detail::RateSource::kFromAngles, detail::RateSource::kAccelsFromRates,
        detail::RateSource::kLogged}) {
    for (int i : {0, 3, 40, kLog - 1}) {
      const detail::Sensitivity a = detail::sensitivity(&taps, i, source, noise, D);
      const detail::Sensitivity b = detail::sensitivity(t, i, source, sg, noise, D);
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(a.lo[c], b.lo[c]) << i;
        EXPECT_EQ(a.sigma[c], b.sigma[c]) << i;
        EXPECT_EQ(a.coef[c], b.coef[c]) << i;
      }
    }
  }
}

/// Random bias inputs of kSamples samples at log indices 20, 21, ... (centred windows), with
/// the reconstruction's weights over 15 samples from 7 before each
detail::BiasInputs random_inputs(std::mt19937_64* rng) {
  detail::BiasInputs in;
  in.J = random_matrix(2 * kSamples, kParams, rng);
  for (int u = 0; u < kSamples; ++u) {
    in.index.push_back(20 + u);
    in.D.push_back(random_matrix(2, 6, rng));
    in.recon_lo.push_back(20 + u - 7);
    for (int c = 0; c < 2; ++c) {
      in.terms[c].push_back(1e-6 * random_matrix(1, 1, rng).col(0));
      in.weights[c].push_back(random_matrix(1, 15, rng));
    }
  }
  const Eigen::MatrixXd A = random_matrix(kParams, kParams, rng);
  in.Hp = 0.1 * A.transpose() * A;
  in.s2 = 0.3;
  in.T = Eigen::MatrixXd::Identity(kParams, kParams) + 0.1 * random_matrix(kParams, kParams, rng);
  in.friction_size = 4;
  in.source = detail::RateSource::kFromAngles;
  in.noise.angle[0] = 1e-5, in.noise.angle[1] = 3e-5;
  in.noise.torque[0] = 0.02, in.noise.torque[1] = 0.03;
  return in;
}

TEST(SmoothingBias, StdAndSpreadAreThoseOfTheFullScoreCovariance) {
  std::mt19937_64 rng(10);
  const std::vector<double> t = grid();
  const detail::BiasInputs in = random_inputs(&rng);
  std::vector<char> keep(kSamples, 1);
  keep[3] = keep[17] = 0;
  const SgOptions sg{0.005, 5};
  detail::BiasPrediction p;
  ASSERT_TRUE(detail::predict_smoothing_bias(t, in, keep, sg, true, &p));
  // the covariance T H^-1 (S + s2 Hp) H^-1 T^T in full, S from the sensitivities of the filter
  // (the estimate's std) and of the reconstruction's weights (the prediction's own)
  Eigen::VectorXd r1, r2;
  detail::filter_response(sg, 1e-3, &r1, &r2);
  std::vector<detail::Sensitivity> filtered, weighed;
  for (int u = 0; u < kSamples; ++u) {
    if (!keep[u]) continue;
    filtered.push_back(detail::sensitivity(t, in.index[u], in.source, sg, in.noise, in.D[u]));
    detail::Sensitivity s;
    for (int c = 0; c < 2; ++c) {
      const Eigen::RowVectorXd w1 = r1.transpose() * in.weights[c][u];
      const Eigen::RowVectorXd w2 = r2.transpose() * in.weights[c][u];
      s.lo[c] = in.recon_lo[u], s.sigma[c] = in.noise.angle[c];
      for (int r = 0; r < w1.size(); ++r) {
        s.coef[c].push_back(in.D[u].col(2 + c) * w1(r) + in.D[u].col(4 + c) * w2(r));
      }
    }
    weighed.push_back(s);
  }
  ASSERT_EQ(p.J.rows(), 2 * static_cast<int>(filtered.size()));
  const Eigen::MatrixXd Hinv = (p.J.transpose() * p.J + in.Hp).inverse();
  const Eigen::MatrixXd S = covariance_by_definition(p.J, filtered, in.noise) + in.s2 * in.Hp;
  detail::SensorNoise angles = in.noise;
  angles.torque[0] = angles.torque[1] = 0;
  const Eigen::MatrixXd S2 = covariance_by_definition(p.J, weighed, angles);
  const Eigen::MatrixXd TH = in.T * Hinv;
  const Eigen::VectorXd std = (TH * S * TH.transpose()).diagonal().head(4).cwiseSqrt();
  const Eigen::VectorXd spread = (TH * S2 * TH.transpose()).diagonal().head(4).cwiseSqrt();
  ASSERT_EQ(p.std.size(), 4);
  ASSERT_EQ(p.spread.size(), 4);
  EXPECT_GT(spread.minCoeff(), 0);
  EXPECT_LT(relative_error(p.std, std), 1e-10);
  EXPECT_LT(relative_error(p.spread, spread), 1e-10);
}

}  // namespace
}  // namespace fivebar::identification
