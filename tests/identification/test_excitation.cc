// Excitation design: the Jet Jacobian and Fisher matrix against finite differences,
// the design gradient against finite differences, the Fourier motion's consistency, the
// predicted std (the four-bar's: test_four_bar_identify.cc).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "design_gradients.h"
#include "fivebar/identification/excitation.h"
#include "fivebar/identification/identify.h"
#include "fivebar/identification/synth.h"
#include "fivebar/identification/torque_excitation.h"
#include "fivebar/model/inertial.h"
#include "light_scene.h"
#include "paper.h"

namespace fivebar::identification {
namespace {

using fivebar::testing::paper_static_load_function;
using fivebar::testing::paper_static_loads;

Params<double> per_joint_scene() {
  Params<double> p = paper_params();
  p.friction.coulomb = {0.08, 0.10, 0.12, 0.14, 0.16};
  p.friction.viscous = {0.010, 0.015, 0.020, 0.025, 0.030};
  return p;
}

// M1, M2 at a parameter vector x (friction, then inertial), by plain double inverse dynamics
std::array<double, 2> torques(const Params<double>& scene, const DesignParameters& dp,
                              const std::vector<double>& x, const MotionState& s,
                              const JointModes& slip) {
  Params<double> p = scene;
  if (dp.friction > 0) dp.layout.apply(x.data(), &p.friction);
  if (dp.inertial > 0) set_standard_inertial(x.data() + dp.friction, &p);
  Evaluation<double> ev;
  EXPECT_TRUE(inverse_dynamics(p, paper_static_loads(), s.th1, s.th2, s.w1, s.w2, s.a1, s.a2,
                               &slip, EvalOptions{}, &ev)
                  .ok());
  return {ev.M1, ev.M2};
}

// The actuator group's values are the scene's (`actuators:`), so that their relative std is
// defined and enters the design's worst; a scale of their kind where the scene has none.
TEST(Excitation, ActuatorParametersTakeTheScenesValues) {
  Params<double> scene = per_joint_scene();
  scene.actuators.offset = {0.05, -0.02};
  scene.actuators.coulomb = {0.04, 0.0};
  scene.actuators.viscous = {0.01, 0.003};
  DesignGroups g;
  g.actuator = true;
  const DesignParameters dp = design_parameters(scene, g);
  const int a = dp.friction;
  ASSERT_EQ(dp.size(), a + 6);
  const std::vector<double> want = {0.05, 0.04, 0.01, -0.02, 0.0, 0.003};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(dp.nominal[a + i], want[i]) << dp.names[a + i];
  EXPECT_EQ(dp.scale[a + 4], 0.1);  // no value: the typical Coulomb scale
  EXPECT_EQ(dp.scale[a + 3], 0.02);
}

TEST(Excitation, JetJacobianMatchesFiniteDifferences) {
  const Params<double> scene = per_joint_scene();
  DesignGroups g;
  g.per_joint = true;
  g.inertia = true;
  g.actuator = true;
  const DesignParameters dp = design_parameters(scene, g);
  ASSERT_EQ(dp.size(), 10 + 16 + 6);
  const MotionState s{1.4, 1.9, 2.5, -3.0, 20.0, 15.0};
  SampleTerms t;
  ASSERT_TRUE(sample_terms(scene, dp, paper_static_loads(), s, nullptr, &t).ok());
  for (int c = 0; c < dp.jet_size(); ++c) {
    std::vector<double> xp = dp.nominal, xm = dp.nominal;
    const double h = 1e-6 * std::max(1e-3, std::abs(dp.nominal[c]));
    xp[c] += h;
    xm[c] -= h;
    const auto mp = torques(scene, dp, xp, s, t.slip), mm = torques(scene, dp, xm, s, t.slip);
    for (int r = 0; r < kDof; ++r) {
      const double fd = (mp[r] - mm[r]) / (2 * h);
      EXPECT_NEAR(t.J(r, c), fd, 1e-6 * (1 + std::abs(fd))) << dp.names[c] << " row " << r;
    }
  }
  // actuator columns: offset 1, Coulomb sign(w), viscous w, on their own motor only
  const int a = dp.friction + dp.inertial;
  EXPECT_EQ(t.J(0, a), 1.0);
  EXPECT_EQ(t.J(0, a + 1), 1.0);
  EXPECT_EQ(t.J(0, a + 2), 2.5);
  EXPECT_EQ(t.J(1, a + 4), -1.0);
  EXPECT_EQ(t.J(1, a + 5), -3.0);
  EXPECT_EQ(t.J(1, a), 0.0);
  // the Fisher matrix is J^T J / sigma^2 summed
  const Eigen::MatrixXd F = fisher_information({t.J, t.J}, 0.5);
  EXPECT_NEAR(F(3, 7), 2 * 4 * t.J.col(3).dot(t.J.col(7)), 1e-12 * (1 + std::abs(F(3, 7))));
}

// fisher_information sums J^T J entry by entry: the same sums as Eigen's product bit for bit, for
// two torque rows (the five-bar) and one (the four-bar), at the sizes of every layout, skipping
// a sample whose Jacobian is not finite; symmetric.
TEST(Excitation, FisherInformationIsTheProductBitForBit) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-3, 3);
  for (int rows : {1, 2}) {
    for (int P : {2, 4, 8, 10, 16, 20, 36}) {
      std::vector<Eigen::MatrixXd> Js;
      Eigen::MatrixXd want = Eigen::MatrixXd::Zero(P, P);
      for (int i = 0; i < 50; ++i) {
        Eigen::MatrixXd J(rows, P);
        for (int r = 0; r < rows; ++r) {
          for (int c = 0; c < P; ++c) J(r, c) = u(rng) * std::pow(10.0, u(rng));
        }
        if (i == 7) J(0, P - 1) = std::numeric_limits<double>::quiet_NaN();
        if (J.allFinite()) want.noalias() += J.transpose() * J;
        Js.push_back(J);
      }
      want /= 0.3 * 0.3;
      const Eigen::MatrixXd F = fisher_information(Js, 0.3);
      ASSERT_EQ(F.rows(), P);
      for (int a = 0; a < P; ++a) {
        for (int b = 0; b < P; ++b) {
          EXPECT_EQ(F(a, b), want(a, b)) << rows << " rows, P " << P << " at " << a << ", " << b;
          EXPECT_EQ(F(a, b), F(b, a));
        }
      }
    }
  }
}

// The friction columns in closed form (implicit function theorem through the friction loop)
// against the Jets through the whole inverse dynamics, on the paper scene and on seeded random
// states of scenes with other laws, actuator friction and given slip modes.
TEST(Excitation, ClosedFormColumnsMatchTheJets) {
  Params<double> actuated = per_joint_scene();
  actuated.actuators.coulomb = {0.05, 0.03};
  actuated.actuators.viscous = {0.01, 0.004};
  const Params<double> scenes[] = {
      paper_params(), per_joint_scene(), actuated,
      fivebar::testing::with_law(
          per_joint_scene(), FrictionLaw::kStribeck,
          {{Coefficient::kStaticCoulomb, 0.2}, {Coefficient::kStribeckVelocity, 0.5}})};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> acc(-60, 60);
  int compared = 0;
  for (const Params<double>& scene : scenes) {
    for (bool per_joint : {false, true}) {
      for (bool actuator : {false, true}) {
        DesignGroups g;
        g.per_joint = per_joint;
        g.actuator = actuator;
        const DesignParameters dp = design_parameters(scene, g);
        for (const auto& r : fivebar::testing::random_states(scene, 40, 5 + compared)) {
          const MotionState s{r.th1, r.th2, r.w1, r.w2, acc(rng), acc(rng)};
          for (int given = 0; given < 2; ++given) {
            SampleTerms want, got;
            const Status ref = detail::jet_sample_terms(scene, dp, r.loads, s, nullptr, &want);
            const JointModes* slip = given ? &want.slip : nullptr;
            if (given) {
              ASSERT_TRUE(detail::jet_sample_terms(scene, dp, r.loads, s, slip, &want).ok());
            }
            const Status st = sample_terms(scene, dp, r.loads, s, slip, &got);
            ASSERT_EQ(st.ok(), ref.ok()) << st.message << " / " << ref.message;
            if (!ref.ok()) continue;
            ++compared;
            const double m = std::max({1.0, std::abs(want.M1), std::abs(want.M2)});
            EXPECT_NEAR(got.M1, want.M1, 1e-12 * m);
            EXPECT_NEAR(got.M2, want.M2, 1e-12 * m);
            EXPECT_NEAR(got.sine, want.sine, 1e-14);
            EXPECT_EQ(got.slip, want.slip);
            for (int k = 0; k < kJoints; ++k)
              EXPECT_NEAR(got.w[k], want.w[k], 1e-12 * (1 + std::abs(want.w[k])));
            ASSERT_EQ(got.J.cols(), want.J.cols());
            for (int c = 0; c < dp.size(); ++c) {
              const double scale = want.J.col(c).cwiseAbs().maxCoeff();
              for (int row = 0; row < kDof; ++row) {
                EXPECT_NEAR(got.J(row, c), want.J(row, c), 1e-9 * scale + 1e-300)
                    << dp.names[c] << " row " << row << " law "
                    << static_cast<int>(scene.friction.law) << " given " << given << " state "
                    << s.th1 << " " << s.th2 << " " << s.w1 << " " << s.w2 << " " << s.a1 << " "
                    << s.a2 << " slip " << static_cast<int>(want.slip[0])
                    << static_cast<int>(want.slip[1]) << static_cast<int>(want.slip[2])
                    << static_cast<int>(want.slip[3]) << static_cast<int>(want.slip[4]);
              }
            }
          }
        }
      }
    }
  }
  EXPECT_GT(compared, 500);
}

TEST(Excitation, FourierMotionIsConsistentAndStartsAtRest) {
  const FourierMotion m(5, 2.5, 0.7, {1.5, 1.7});
  std::vector<double> x(m.num_variables());
  for (size_t i = 0; i < x.size(); ++i) x[i] = 0.05 * std::sin(1.0 + 3.0 * i);
  const MotionState s0 = m.state(x, 0.0);
  EXPECT_DOUBLE_EQ(s0.th1, 1.5);
  EXPECT_DOUBLE_EQ(s0.th2, 1.7);
  EXPECT_NEAR(s0.w1, 0, 1e-12);
  EXPECT_NEAR(s0.w2, 0, 1e-12);
  EXPECT_NEAR(s0.a1, 0, 1e-10);
  EXPECT_NEAR(s0.a2, 0, 1e-10);
  // after the ramp, rates and accelerations repeat every period
  const MotionState s1 = m.state(x, 1.3), s2 = m.state(x, 3.8);
  EXPECT_NEAR(s1.w1, s2.w1, 1e-10);
  EXPECT_NEAR(s1.a2, s2.a2, 1e-9);
  for (double t : {0.3, 0.69, 0.71, 1.1, 2.2}) {
    const double h = 1e-5;
    const MotionState a = m.state(x, t - h), b = m.state(x, t + h), c = m.state(x, t);
    EXPECT_NEAR(c.w1, (b.th1 - a.th1) / (2 * h), 1e-7);
    EXPECT_NEAR(c.w2, (b.th2 - a.th2) / (2 * h), 1e-7);
    EXPECT_NEAR(c.a1, (b.w1 - a.w1) / (2 * h), 1e-6);
    EXPECT_NEAR(c.a2, (b.w2 - a.w2) / (2 * h), 1e-6);
  }
}

TEST(Excitation, DesignGradientMatchesFiniteDifferences) {
  ExcitationOptions o = testing::small_design(20);
  o.groups.per_joint = true;
  for (Criterion c : {Criterion::kDOptimal, Criterion::kCondition, Criterion::kWorstStd}) {
    o.criterion = c;
    const ExcitationProblem problem(per_joint_scene(), paper_static_load_function(),
                                    {M_PI / 2, M_PI / 2}, o);
    std::vector<double> x = {0.5, 0.10, -0.05, 0.04, 0.02, -0.08, 0.06,
                             -0.7, 0.03, -0.02, 0.05, 0.01, 0.02, -0.04};
    ASSERT_EQ(problem.num_variables(), static_cast<int>(x.size()));
    testing::expect_design_gradients(problem, x);
  }
}

TEST(Excitation, ReversalsAreCounted) {
  std::vector<std::array<double, kJoints>> w = {
      {1, 1, 0, -1, 1}, {0, -1, 0, 1, 1}, {-1, 1, 0, -1, 1}, {2, 1, 0, 1, 1}};
  const std::array<int, kJoints> r = count_reversals(w);
  EXPECT_EQ(r[0], 2);  // 1, 0, -1, 2: a zero between is not a reversal of its own
  EXPECT_EQ(r[1], 2);
  EXPECT_EQ(r[2], 0);
  EXPECT_EQ(r[3], 3);
  EXPECT_EQ(r[4], 0);
}

TEST(Excitation, GroupsParse) {
  DesignGroups g;
  std::string bad;
  EXPECT_TRUE(parse_groups("friction,inertia", &g, &bad));
  EXPECT_TRUE(g.friction && g.inertia && !g.actuator);
  EXPECT_FALSE(parse_groups("friction,friction", &g, &bad));
  EXPECT_EQ(bad, "friction");
  EXPECT_FALSE(parse_groups("mass", &g, &bad));
  EXPECT_EQ(bad, "mass");
}

TEST(Excitation, WorstStdCriterionIsTheWorstRelativeStd) {
  // a diagonal Fisher: the scaled variances are 1 / (s_i^2 F_ii); the criterion is about the
  // log of the largest std (a p-norm, p = 16, over the parameters with a non-zero value)
  const std::vector<double> scale = {0.1, 0.02, 1.0}, nominal = {0.1, 0.02, 0.0};
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(3, 3);
  F.diagonal() << 1e6, 1e8, 1.0;  // rel. std 1e-2, 5e-3; the third (value 0) is left out
  const double v = design_criterion(F, scale, nominal, 0.0, Criterion::kWorstStd, nullptr);
  EXPECT_GT(v, std::log(1e-2));
  EXPECT_LT(v, std::log(1e-2) + std::log(2.0) / 32 + 1e-12);
}

TEST(Excitation, ToneTorquesAreClippedAndContainTheMultisine) {
  const ToneTorques tones(4, 5.0);
  const std::vector<double> x = multisine_tones();
  ASSERT_EQ(static_cast<int>(x.size()), tones.num_variables());
  const sim::LoadFunction scene = paper_static_load_function();
  const sim::LoadFunction ms = multisine_loads(scene), clipped = tones.loads(x, scene);
  const ToneTorques free(4, std::numeric_limits<double>::infinity());
  int clips = 0;
  for (double t = 0; t < 3; t += 0.01) {
    EXPECT_EQ(ms(t).M1, free.torque(x, 0, t));
    EXPECT_EQ(ms(t).M2, free.torque(x, 1, t));
    EXPECT_EQ(clipped(t).M3, 6.0);
    EXPECT_LE(std::abs(clipped(t).M1), 5.0);
    EXPECT_LE(std::abs(clipped(t).M2), 5.0);
    clips += std::abs(tones.raw(x, 0, t)) > 5.0 ? 1 : 0;
  }
  EXPECT_GT(clips, 0);
  // more tones: the extra ones silent, the motion the same
  const std::vector<double> y = resize_tones(x, 4, 6);
  const ToneTorques six(6, 5.0);
  for (double t : {0.1, 1.3, 2.7}) EXPECT_DOUBLE_EQ(six.raw(y, 1, t), tones.raw(x, 1, t));
}

TEST(Excitation, TorqueDesignIsSeededAndNeverWorseThanItsFirstStart) {
  TorqueDesignOptions o;
  o.excitation.duration = 1.5;
  o.excitation.design_samples = 150;
  o.excitation.torque_limit = 13.4;
  o.excitation.min_reversals = 0;  // the crank O does not reverse within 1.5 s
  o.excitation.groups.per_joint = true;
  o.excitation.criterion = Criterion::kWorstStd;
  o.max_evaluations = 13;
  o.seed = 3;
  const sim::LoadFunction scene = paper_static_load_function();
  const ToneTorques tones(4, 13.4);
  const std::vector<std::vector<double>> starts = tone_starts(tones, multisine_tones());
  ASSERT_EQ(starts.size(), 9u);
  EXPECT_EQ(starts[0], multisine_tones());
  const std::array<double, 2> start = {M_PI / 2, M_PI / 2};
  const TorqueDesignResult a = design_torque_excitation(per_joint_scene(), scene, start, o, starts);
  const TorqueDesignResult b = design_torque_excitation(per_joint_scene(), scene, start, o, starts);
  ASSERT_TRUE(a.best.status.ok()) << a.best.status.message;
  EXPECT_EQ(a.evaluations, 13);
  EXPECT_EQ(a.best.x, b.best.x);
  EXPECT_EQ(a.best.objective, b.best.objective);
  for (size_t i = 0; i < starts.size(); ++i) {
    if (a.start_feasible[i]) {
      EXPECT_LE(a.best.objective, a.start_objectives[i]);
    }
  }
  EXPECT_TRUE(a.best.feasible);
  // asking more reversals than 1.5 s can give: no candidate is feasible, the search says so
  o.excitation.min_reversals = 1000;
  o.max_evaluations = 9;
  EXPECT_FALSE(design_torque_excitation(per_joint_scene(), scene, start, o, starts).best.feasible);
  EXPECT_LE(a.best.peak_applied, 13.4);
  // the report's torques (inverse dynamics along the simulated motion) are the applied ones
  const ExcitationReport& r = a.best.report;
  for (size_t i = 0; i < r.t.size(); ++i) {
    EXPECT_NEAR(r.M1[i], a.best.tau1[i], 1e-6) << "t = " << r.t[i];
    EXPECT_NEAR(r.M2[i], a.best.tau2[i], 1e-6) << "t = " << r.t[i];
  }
}

// the search's simulations: looser and explicit where the scene's are tighter, the scene's
// settings otherwise; LuGre's stiff bristles keep the scene's method
TEST(Excitation, TorqueSearchSettingsLoosenTheScenesOnly) {
  const sim::Options scene;  // rtol = atol = 1e-10, the law's default method
  const sim::Options s = search_settings(scene, 1e-6, FrictionLaw::kCoulombViscous);
  EXPECT_EQ(s.rtol, 1e-6);
  EXPECT_EQ(s.atol, 1e-6);
  EXPECT_EQ(s.method, sim::Method::kArkodeErk45);
  EXPECT_EQ(s.duration, scene.duration);
  EXPECT_EQ(search_settings(scene, 1e-6, FrictionLaw::kLuGre).method, std::nullopt);
  const sim::Options unchanged = search_settings(scene, 0, FrictionLaw::kCoulombViscous);
  EXPECT_EQ(unchanged.rtol, 1e-10);
  EXPECT_EQ(unchanged.method, std::nullopt);
  sim::Options loose = scene;
  loose.rtol = loose.atol = 1e-4;
  EXPECT_EQ(search_settings(loose, 1e-6, FrictionLaw::kCoulombViscous).rtol, 1e-4);
}

// the search ranks its candidates at search_settings; its finalists are its best, best first;
// finish_torque_design simulates them again at the scene's settings on the log's grid and keeps
// the one of the lowest worst relative std identify would report
TEST(Excitation, TorqueDesignIsFinishedAtTheScenesSettings) {
  TorqueDesignOptions o;
  o.excitation.duration = 1.5;
  o.excitation.design_samples = 150;
  o.excitation.torque_limit = 13.4;
  o.excitation.min_reversals = 0;
  o.excitation.groups.per_joint = true;
  o.excitation.criterion = Criterion::kWorstStd;
  o.max_evaluations = 13;
  o.seed = 3;
  o.finalists = 3;
  const Params<double> p = per_joint_scene();
  const sim::LoadFunction scene = paper_static_load_function();
  const std::array<double, 2> start = {M_PI / 2, M_PI / 2};
  const TorqueDesignResult a = design_torque_excitation(
      p, scene, start, o, tone_starts(ToneTorques(4, 13.4), multisine_tones()));
  ASSERT_TRUE(a.best.status.ok()) << a.best.status.message;
  // 13 candidates ran: kFinalistSpares * 3 = 9 kept, ranked
  ASSERT_EQ(a.finalists.size(), 9u);
  EXPECT_EQ(a.finalists[0], a.best.x);
  EXPECT_EQ(a.finalist_objectives[0], a.best.objective);
  for (size_t i = 1; i < a.finalists.size(); ++i) {
    EXPECT_LE(a.finalist_objectives[i - 1], a.finalist_objectives[i]);
  }
  // the search's objective is that of its own settings, not the scene's
  const double step = o.excitation.duration / o.excitation.design_samples;
  TorqueDesignOptions search = o;
  search.sim = search_settings(o.sim, o.search_tolerance, p.friction.law);
  EXPECT_EQ(evaluate_tones(p, scene, start, search, a.best.x, step).objective, a.best.objective);
  EXPECT_NE(evaluate_tones(p, scene, start, o, a.best.x, step).objective, a.best.objective);

  const FinishedTorqueDesign f = finish_torque_design(p, scene, start, o, a.finalists);
  ASSERT_TRUE(f.design.status.ok()) << f.design.status.message;
  ASSERT_TRUE(f.predicted.ok()) << f.predicted.message;
  EXPECT_EQ(f.design.x, a.finalists[static_cast<size_t>(f.finalist)]);
  EXPECT_EQ(f.design.report.t.size(), 1501u);  // the log's grid, 1 kHz
  EXPECT_EQ(f.evaluated, 3);  // the first three ran and met the constraints: no spare evaluated
  const DesignParameters dp = design_parameters(p, o.excitation.groups);
  for (size_t i = 0; i < 3; ++i) {
    const std::vector<double>& x = a.finalists[i];
    TorqueCandidate c = evaluate_tones(p, scene, start, o, x, 1e-3);
    ASSERT_TRUE(c.status.ok());
    ASSERT_TRUE(predict_identified_std(p, dp, scene, o.excitation.torque_noise,
                                       o.excitation.angle_noise, &c.report)
                    .ok());
    if (x == f.design.x) {
      EXPECT_EQ(worst_relative_std(c.report), worst_relative_std(f.design.report));
    } else if (c.feasible) {
      EXPECT_GE(worst_relative_std(c.report), worst_relative_std(f.design.report));
    }
  }
  // a finalist that misses the constraints at the scene's settings (full torque one way: crank
  // O turns past the range allowed) is passed over for the next one
  std::vector<double> spin(a.best.x.size(), 0.0);
  spin[0] = 13.4;
  spin[spin.size() / 2] = -13.4;
  o.excitation.theta_lo = {-10, NAN};
  o.excitation.theta_hi = {55, NAN};
  ASSERT_FALSE(evaluate_tones(p, scene, start, o, spin, 1e-3).feasible);
  o.finalists = 1;
  const FinishedTorqueDesign g = finish_torque_design(p, scene, start, o, {spin, a.finalists[0]});
  ASSERT_TRUE(g.design.status.ok()) << g.design.status.message;
  EXPECT_EQ(g.finalist, 1);
  EXPECT_EQ(g.evaluated, 2);
  EXPECT_EQ(g.design.x, a.finalists[0]);
}

}  // namespace
}  // namespace fivebar::identification

namespace fivebar::identification {
namespace {

using fivebar::testing::paper_initial;

using fivebar::testing::light_loads;
using fivebar::testing::light_params;

// the paper scene's multi-sine is the fit on the paper scene (within its 13.36 N m peak): same
// tones, factor 1, so its logs and the excite baseline are unchanged
TEST(Excitation, MultisineFitKeepsThePaperScenesTones) {
  MultisineFitOptions o;
  o.duration = 10;
  for (double limit : {std::numeric_limits<double>::infinity(), 13.4}) {
    o.torque_limit = limit;
    const FittedMultisine fit =
        fit_multisine(paper_params(), paper_static_load_function(), paper_initial(), o);
    ASSERT_TRUE(fit.status.ok()) << fit.status.message;
    EXPECT_EQ(fit.factor, 1.0);
    EXPECT_FALSE(fit.holding_bias);
    EXPECT_EQ(fit.tones, multisine_tones());
  }
}

// on a light mechanism the unscaled multi-sine spins the cranks into a singular pose; fitted to a
// 0.2 N m limit it runs the duration within the limit and away from the singularity margin, and
// synth-log's multi-sine is that fit
TEST(Excitation, MultisineFitRunsOnALightMechanismWithinTheLimit) {
  const Params<double> light = light_params();
  const sim::Result unscaled = sim::simulate(light, multisine_loads(light_loads()), paper_initial(),
                                             [] {
                                               sim::Options so;
                                               so.duration = 10;
                                               so.output_step = 0.1;
                                               so.singular_margin = 0.1;
                                               return so;
                                             }());
  EXPECT_FALSE(unscaled.status.ok());
  MultisineFitOptions o;
  o.duration = 10;
  o.torque_limit = 0.2;
  const FittedMultisine fit = fit_multisine(light, light_loads(), paper_initial(), o);
  ASSERT_TRUE(fit.status.ok()) << fit.status.message;
  EXPECT_LT(fit.factor, 0.2 / 13.3);
  EXPECT_GT(fit.factor, 0.0);
  SynthOptions so;
  so.duration = 10;
  so.multisine = true;
  so.torque_limit = 0.2;
  so.with_rates = true;
  const SynthResult log = synthesize_log(light, light_loads(), paper_initial(), so);
  ASSERT_TRUE(log.status.ok()) << log.status.message;
  EXPECT_EQ(log.multisine_factor, fit.factor);
  double peak = 0;
  for (int i = 0; i < log.log.size(); ++i) {
    peak = std::max({peak, std::abs(log.log.tau1[i]), std::abs(log.log.tau2[i])});
  }
  EXPECT_LE(peak, 0.2);
  EXPECT_GT(peak, 0.1);  // scaled to the limit, not far below it
}

/// The light mechanism's multi-sine log (limit 0.2 N m, rates logged) of `duration` seconds and
/// its samples' states.
struct LightMotion {
  SynthResult log;
  std::vector<MotionState> states;
};

LightMotion light_multisine(double duration) {
  SynthOptions so;
  so.duration = duration;
  so.multisine = true;
  so.torque_limit = 0.2;
  so.with_rates = true;
  LightMotion m{synthesize_log(light_params(), light_loads(), paper_initial(), so), {}};
  const TorqueLog& l = m.log.log;
  for (int i = 0; i < l.size(); ++i) {
    m.states.push_back(
        {l.theta1[i], l.theta2[i], l.omega1[i], l.omega2[i], l.alpha1[i], l.alpha2[i]});
  }
  return m;
}

// The std identify reports for a log along a motion (predict_identified_std): the torque noise's
// alone without angle noise; with it, never less, growing with the angle noise, and back near
// the torque noise's where that noise dominates. Motion: the light mechanism's multi-sine.
TEST(Excitation, PredictedStdAddsTheAngleNoiseThroughTheRates) {
  const Params<double> light = light_params();
  const LightMotion motion = light_multisine(4);
  ASSERT_TRUE(motion.log.status.ok()) << motion.log.status.message;
  const SynthResult& log = motion.log;
  const std::vector<MotionState>& states = motion.states;
  const DesignParameters dp = design_parameters(light, DesignGroups{});
  auto predicted = [&](double torque_noise, double angle_noise) {
    ExcitationReport r;
    EXPECT_TRUE(evaluate_motion(light, dp, light_loads(), log.log.t, states, torque_noise, &r).ok());
    const Status st = predict_identified_std(light, dp, light_loads(), torque_noise, angle_noise, &r);
    EXPECT_TRUE(st.ok()) << st.message;
    return r;
  };
  const ExcitationReport exact = predicted(0.02, 0);
  EXPECT_EQ(exact.sg_half_window, 0);
  const ExcitationReport noisy = predicted(0.02, 1e-5), noisier = predicted(0.02, 4e-5);
  const ExcitationReport loud = predicted(1.0, 1e-5);
  EXPECT_GT(noisy.sg_half_window, 0);
  EXPECT_FALSE(noisy.window_choice.empty());
  for (int i = 0; i < dp.size(); ++i) {
    EXPECT_EQ(exact.std_dev[i], exact.torque_only_std[i]);
    EXPECT_EQ(noisy.torque_only_std[i], exact.std_dev[i]);
    EXPECT_TRUE(std::isfinite(noisy.std_dev[i]));
    EXPECT_GE(noisy.std_dev[i], noisy.torque_only_std[i]) << dp.names[i];
    EXPECT_GT(noisier.std_dev[i], noisy.std_dev[i]) << dp.names[i];
    // torque noise of 1 N m: the angle noise's share is small (the samples the fit leaves out
    // near the slip reversals and at the ends cost a little)
    EXPECT_NEAR(loud.std_dev[i] / loud.torque_only_std[i], 1.0, 0.15) << dp.names[i];
    EXPECT_NEAR(noisy.relative_std[i], noisy.std_dev[i] / std::abs(dp.nominal[i]), 1e-15);
  }
}

// identify's rest rule in the prediction: a sample whose joint rates are within the noise of the
// filtered rates is at rest (identify leaves it out), one that turns well above it is not, and
// without angle noise none is (the five-bar's held_sample).
TEST(Excitation, RestRuleOfThePredictionIsIdentifys) {
  const auto five =
      five_bar_excitation(light_params(), design_parameters(light_params(), {}), light_loads());
  const MotionState still{1.4, 1.9, 1e-4, -1e-4, 0, 0}, turning{1.4, 1.9, 2.0, -1.5, 0, 0};
  const double g1 = 30, g2 = 3000;  // a filter's noise gains [1/s], [1/s^2]
  EXPECT_TRUE(five->at_rest(0, still, g1, g2, 1e-5));
  EXPECT_FALSE(five->at_rest(0, turning, g1, g2, 1e-5));
  EXPECT_FALSE(five->at_rest(0, still, g1, g2, 0));
  EXPECT_TRUE(five->at_rest(0, turning, g1, g2, 1e-1));
}

// Where the angle noise puts every sample of a motion at rest for identify (it then refuses the
// log: too few samples usable), the prediction has no std either, not an optimistic one.
TEST(Excitation, NoPredictionWhereIdentifyKeepsNoSample) {
  const Params<double> light = light_params();
  const LightMotion motion = light_multisine(2);
  ASSERT_TRUE(motion.log.status.ok()) << motion.log.status.message;
  const std::vector<MotionState>& states = motion.states;
  const TorqueLog& l = motion.log.log;
  const DesignParameters dp = design_parameters(light, DesignGroups{});
  ExcitationReport r;
  ASSERT_TRUE(evaluate_motion(light, dp, light_loads(), l.t, states, 0.02, &r).ok());
  const Status st = predict_identified_std(light, dp, light_loads(), 0.02, 0.1, &r);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message.find("not at rest"), std::string::npos) << st.message;
  for (int i = 0; i < dp.size(); ++i) EXPECT_TRUE(std::isnan(r.std_dev[i])) << dp.names[i];
}

/// A heavy five-bar: cranks of 2.5-3 kg on a 0.4 m ground, pins of 0.015 m, coulomb 0.2,
/// viscous 0.05, M3 0.5 N m and F 20 N at 1 rad (its motor torques of about 8 N m); its angle
/// noise through the rates and the reactions sets most of its std.
/// (testing::slow_light_params' geometry and friction, its inertias doubled, full gravity)
Params<double> heavy_params() {
  Params<double> p = testing::slow_light_params();
  for (Link<double>& l : p.links) l.inertia *= 2;
  p.gravity = 9.81;
  return p;
}

sim::LoadFunction heavy_loads() {
  return [](double) { return Loads<double>{0.0, 0.0, 0.5, 20.0, 1.0}; };
}

// The predicted window and std are identify's on a heavy five-bar, whose window identify's stages
// choose far below the largest without smoothing bias on the exact motion (10 samples against
// 33: its preliminary fit's error shows in the larger windows' residual): its per-joint design
// (`excite --per-joint --torque-limit 8 --duration 10 --family fourier`: 5 harmonics, 4 periods,
// a 1 s ramp), two seeded logs of synth-log's sensors along it other than the prediction's own
// (seed 1). Predicted at 33 samples over the samples identify keeps there, the std were 0.29-0.57
// of identify's; identify's over seeds 1-3 read 1.005-1.07 of the prediction.
TEST(Excitation, PredictedWindowAndStdAreIdentifysOnAHeavyDesign) {
  const Params<double> p = heavy_params();
  const std::vector<double> x = {
      -0.0487866, 0.193429,   0.0231193,  -0.00581921, -0.0449203, -0.0549707, 0.495189, 0.163332,
      0.0608077,  -0.0741435, -0.0735834, 0.144947,    -0.794372,  -0.172706,  0.185495, -0.0931461,
      -0.0970744, -0.447261,  0.384231,   -0.14066,    -0.175664,  -0.0883463};
  const FourierMotion motion(5, 2.5, 1.0, {1.6, 1.4});
  std::vector<double> t;
  std::vector<MotionState> states;
  std::vector<sim::Row> path, rows;
  for (int i = 0; i <= static_cast<int>(10000); ++i) {
    t.push_back(i * 1e-3);
    states.push_back(motion.state(x, t.back()));
    const MotionState& q = states.back();
    sim::Row row;
    row.t = t.back();
    row.theta = {q.th1, q.th2};
    row.omega = {q.w1, q.w2};
    row.alpha = {q.a1, q.a2};
    path.push_back(row);
  }
  ASSERT_TRUE(sim::inverse_rows(p, heavy_loads(), path, &rows).ok());
  DesignGroups groups;
  groups.per_joint = true;
  const DesignParameters dp = design_parameters(p, groups);
  ExcitationReport r;
  ASSERT_TRUE(evaluate_motion(p, dp, heavy_loads(), t, states, 0.02, &r).ok());
  const Status st = predict_identified_std(p, dp, heavy_loads(), 0.02, 1e-5, &r);
  ASSERT_TRUE(st.ok()) << st.message;
  IdentifyOptions opt;
  opt.layout.per_joint = true;
  for (const std::uint64_t seed : {2, 3}) {
    SynthOptions so;
    so.torque_noise = 0.02;
    so.angle_noise = 1e-5;
    so.seed = seed;
    SynthResult log;
    sample_log(p, rows, so, &log);
    const IdentifyResult id = identify(p, heavy_loads(), log.log, opt);
    ASSERT_TRUE(id.status.ok()) << id.status.message;
    // identify on another draw of the noise may take a window of the prediction's near tie
    // (seed 2: 12 against 10, the walk's predicted bias 0.702 and 0.667 std); a rule other than
    // identify's read 33 here
    EXPECT_NEAR(id.sg_half_window, r.sg_half_window, 2) << seed << ": " << r.window_choice;
    for (int i = 0; i < dp.size(); ++i) {
      const double ratio = id.parameters[i].std / r.std_dev[i];
      EXPECT_GT(ratio, 0.85) << seed << " " << id.parameters[i].name;
      EXPECT_LT(ratio, 1.2) << seed << " " << id.parameters[i].name;
    }
  }
}

}  // namespace
}  // namespace fivebar::identification
