// The inverse-dynamics residual: Jet derivatives through the model against central differences,
// a zero residual at the true parameters on exact data, and identify's fallback cost function
// (padded and multi-pass Jet widths) against plain automatic differentiation.
#include <ceres/ceres.h>
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "fallback_cost.h"
#include "fivebar/identification/residual.h"
#include "fivebar/model/dynamics.h"
#include "paper.h"
#include "random_samples.h"

namespace fivebar::identification {
namespace {

// central differences with step h have error ~ h^2 |r'''| + eps |r| / h; h = 1e-5 relative
constexpr double kDerivTol = 1e-6;

using testing::paper_loads;
using testing::random_samples;

/// Every derivative d(i, k) of residual k by parameter i against central differences of f.
template <typename Derivative>
void expect_central_differences(const InverseDynamicsResidual& f, const ParameterLayout& layout,
                                const std::vector<double>& x, Derivative&& d) {
  for (size_t i = 0; i < x.size(); ++i) {
    const double h = 1e-5 * std::max(1.0, std::abs(x[i]));
    std::vector<double> xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    double rp[2], rm[2];
    ASSERT_TRUE(f(xp.data(), rp));
    ASSERT_TRUE(f(xm.data(), rm));
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(d(i, k), (rp[k] - rm[k]) / (2 * h), kDerivTol)
          << "parameter " << layout.names()[i] << ", residual " << k;
    }
  }
}

template <int P>
void check_jet_against_differences(const ParameterLayout& layout, double smoothing) {
  Params<double> scene = paper_params();
  scene.friction.smoothing_velocity = smoothing;
  scene.friction.stribeck_velocity.fill(0.5);
  scene.friction.stribeck_exponent.fill(2.0);
  // distinct per-joint values so that every parameter matters
  std::vector<double> x(P);
  for (int i = 0; i < P; ++i) x[i] = 0.05 + 0.03 * i;
  EvalOptions eval;
  eval.friction_tol = 1e-15;
  for (const Sample& s : random_samples(scene, 5)) {
    InverseDynamicsResidual f(scene, layout, s, eval);
    using J = ceres::Jet<double, P>;
    std::vector<J> xj(P);
    for (int i = 0; i < P; ++i) xj[i] = J(x[i], i);
    J rj[2];
    ASSERT_TRUE(f(xj.data(), rj));
    expect_central_differences(f, layout, x, [&](size_t i, int k) { return rj[k].v[i]; });
    // the value part is the double evaluation
    double r[2];
    ASSERT_TRUE(f(x.data(), r));
    EXPECT_NEAR(rj[0].a, r[0], 1e-12);  // the loop may stop one iteration apart
    EXPECT_NEAR(rj[1].a, r[1], 1e-12);
  }
}

TEST(InverseDynamicsResidual, JetMatchesCentralDifferencesShared) {
  check_jet_against_differences<2>({FrictionLaw::kCoulombViscous, false}, 0.0);
}
TEST(InverseDynamicsResidual, JetMatchesCentralDifferencesPerJoint) {
  check_jet_against_differences<10>({FrictionLaw::kCoulombViscous, true}, 0.0);
}
TEST(InverseDynamicsResidual, JetMatchesCentralDifferencesSmoothSign) {
  check_jet_against_differences<2>({FrictionLaw::kCoulombViscous, false}, 0.05);
}
TEST(InverseDynamicsResidual, JetMatchesCentralDifferencesStribeck) {
  check_jet_against_differences<4>({FrictionLaw::kStribeck, false}, 0.0);
}

TEST(InverseDynamicsResidual, ZeroAtTheTruthOnExactData) {
  const Params<double> truth = paper_params();
  const ParameterLayout layout{FrictionLaw::kCoulombViscous, false};
  const std::vector<double> x = layout.extract(truth.friction);
  for (Sample s : random_samples(truth, 5)) {
    s.tau1 -= 0.3;
    s.tau2 += 0.2;
    double r[2];
    ASSERT_TRUE(InverseDynamicsResidual(truth, layout, s, EvalOptions{})(x.data(), r));
    EXPECT_NEAR(r[0], 0.0, 1e-10);  // same evaluation, round-off of the friction loop
    EXPECT_NEAR(r[1], 0.0, 1e-10);
  }
}

// the Jacobian of cost at x (P parameters, two residuals), row-major
std::vector<double> jacobian(const ceres::CostFunction& cost, const std::vector<double>& x,
                             double r[2]) {
  std::vector<double> jac(2 * x.size());
  const double* params[] = {x.data()};
  double* jacs[] = {jac.data()};
  EXPECT_TRUE(cost.Evaluate(params, r, jacs));
  return jac;
}

// P = 4 runs on the compiled width 5: the Jacobian and residual are Jet<double, 4>'s, bit for bit
TEST(FallbackCost, PaddedWidthGivesTheJacobianOfItsOwnWidth) {
  static_assert(compiled_jet_width(4) == 5);
  const Params<double> scene = paper_params();
  const ParameterLayout layout{FrictionLaw::kStribeck, false};
  std::vector<double> x(4);
  for (int i = 0; i < 4; ++i) x[i] = 0.05 + 0.03 * i;
  for (const Sample& s : random_samples(scene, 5)) {
    const InverseDynamicsResidual f(scene, layout, s, EvalOptions{});
    const ceres::AutoDiffCostFunction<InverseDynamicsResidual, 2, 4> plain(
        new InverseDynamicsResidual(f));
    double r_plain[2] = {}, r_fallback[2] = {};
    const std::vector<double> a = jacobian(plain, x, r_plain);
    const std::vector<double> b = jacobian(FallbackCost<4>(f), x, r_fallback);
    EXPECT_EQ(r_plain[0], r_fallback[0]);
    EXPECT_EQ(r_plain[1], r_fallback[1]);
    for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << "entry " << i;
  }
}

// P = 32 (per-joint Coulomb-viscous, inertia, actuator terms) takes two passes of width 26: every
// column against central differences
TEST(FallbackCost, MultiPassJacobianMatchesCentralDifferences) {
  static_assert(compiled_jet_width(32) == 26);
  Params<double> scene = paper_params();
  scene.actuators.coulomb = {0.02, 0.03};
  scene.actuators.viscous = {0.001, 0.002};
  ParameterLayout layout{FrictionLaw::kCoulombViscous, true};
  layout.inertia = true;
  layout.actuator = true;
  ASSERT_EQ(layout.size(), 32);
  const std::vector<double> x = layout.extract(scene);
  EvalOptions eval;
  eval.friction_tol = 1e-15;
  for (const Sample& s : random_samples(scene, 3)) {
    const InverseDynamicsResidual f(scene, layout, s, eval);
    double r[2] = {};
    const std::vector<double> jac = jacobian(FallbackCost<32>(f), x, r);
    expect_central_differences(f, layout, x, [&](size_t i, int k) { return jac[k * 32 + i]; });
  }
}

}  // namespace
}  // namespace fivebar::identification
