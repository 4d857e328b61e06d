// The five-bar's sample structure in closed form (sample_structure) against the model's own
// passes: the inertial columns by forward differences of the frictionless inverse dynamics, the
// friction columns by Jets over the pin radii through the full inverse dynamics, on the paper
// scene and on seeded random mechanisms and states.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "fivebar/identification/residual.h"
#include "jet_dynamics.h"
#include "random_samples.h"

namespace fivebar::identification {
namespace {

using Outputs = Eigen::Matrix<double, 12, 1>;

/// The reactions (10) and drive torques (2) of the frictionless inverse dynamics of sample s at
/// the standard inertial parameters pi; false where it fails.
bool frictionless(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                  const std::array<double, kInertialParams>& pi, Outputs* out) {
  Params<double> p = scene;
  p.friction.law = FrictionLaw::kNone;
  p.actuators = ActuatorParams<double>();
  set_standard_inertial(pi.data(), &p);
  EvalOptions eo = eval;
  eo.want_angles = false;
  Evaluation<double> ev;
  if (!inverse_dynamics(p, s.loads, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, nullptr, eo, &ev).ok()) {
    return false;
  }
  for (int k = 0; k < kJoints; ++k) (*out)(2 * k) = ev.F[k].x(), (*out)(2 * k + 1) = ev.F[k].y();
  (*out)(10) = ev.M1, (*out)(11) = ev.M2;
  return out->allFinite();
}

/// The inertial parameter i's scale: the forward differences' step is 1e-3 of it.
double parameter_scale(const Params<double>& scene, const std::array<double, kInertialParams>& pi,
                       int i) {
  const Link<double>& L = scene.links[i / kInertialPerLink];
  return std::max(std::abs(pi[i]), L.mass * L.length);
}

/// The structure from the model's passes: the inertial columns as forward differences of the
/// frictionless inverse dynamics (exact up to rounding: it is affine in pi), the friction
/// columns from one inverse_dynamics in Jets over the pin radii at 0 with unit Coulomb
/// coefficients (phi_j = r_j slip_j, so d(F, M) / d r_j = (dF_j, G_j) slip_j N0_j). `v0`: the
/// frictionless outputs at the scene.
bool reference_structure(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                         SampleStructure* out, Outputs* v0) {
  const std::array<double, kInertialParams> pi0 = standard_inertial(scene);
  if (!frictionless(scene, s, eval, pi0, v0)) return false;
  Eigen::Matrix<double, 12, kInertialParams> D;
  for (int i = 0; i < kInertialParams; ++i) {
    std::array<double, kInertialParams> pi = pi0;
    const double h = 1e-3 * parameter_scale(scene, pi0, i);
    pi[i] += h;
    Outputs v1;
    if (!frictionless(scene, s, eval, pi, &v1)) return false;
    D.col(i) = (v1 - *v0) / h;
  }
  const Eigen::Map<const Eigen::Matrix<double, kInertialParams, 1>> pv(pi0.data());
  out->A = D.topRows(10);
  out->b = v0->head(10) - out->A * pv;
  out->Y = D.bottomRows(2);
  out->c = v0->tail(2) - out->Y * pv;
  using J5 = ceres::Jet<double, kJoints>;
  Params<J5> p = scene.cast<J5>();
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.smoothing_velocity = J5(0);
  p.actuators = ActuatorParams<J5>();
  for (int j = 0; j < kJoints; ++j) {
    p.friction.coulomb[j] = J5(1);
    p.friction.viscous[j] = J5(0);
    p.friction.pin_radius[j] = J5(0, j);
  }
  EvalOptions eo = eval;
  eo.want_angles = false;
  Evaluation<J5> ev;
  if (!inverse_dynamics(p, s.loads.cast<J5>(), J5(s.th1), J5(s.th2), J5(s.w1), J5(s.w2), J5(s.a1),
                        J5(s.a2), nullptr, eo, &ev)
           .ok()) {
    return false;
  }
  double nmax = 1e-300;
  for (int k = 0; k < kJoints; ++k) nmax = std::max(nmax, ev.N[k].a);
  for (int j = 0; j < kJoints; ++j) {
    out->slip[j] = ev.slip[j];
    out->w[j] = ev.w[j].a;
    const bool acts = ev.slip[j] != kStuck && ev.slip[j] != JointMode::kRest;
    if (!acts && ev.slip[j] == JointMode::kRest && out->w[j] != 0 &&
        scene.friction.pin_radius[j] != 0) {
      return false;
    }
    const double scale = acts ? coulomb_sign(ev.slip[j]) * ev.N[j].a : 0.0;
    if (acts && std::abs(scale) < 1e-9 * nmax) return false;
    for (int k = 0; k < kJoints; ++k) {
      out->dF(2 * k, j) = acts ? ev.F[k].x().v[j] / scale : 0.0;
      out->dF(2 * k + 1, j) = acts ? ev.F[k].y().v[j] / scale : 0.0;
    }
    out->G(0, j) = acts ? ev.M1.v[j] / scale : 0.0;
    out->G(1, j) = acts ? ev.M2.v[j] / scale : 0.0;
  }
  return out->A.allFinite() && out->dF.allFinite() && out->G.allFinite();
}

/// Relative errors of the structure `st` against the reference `ref`: each inertial column
/// (A and Y together) against its own size plus the outputs' size per unit of the parameter's
/// scale (the differences' rounding); b and c against the outputs' size; each friction column
/// (dF and G together) against its own size.
struct StructureErrors {
  double inertial = 0, offset = 0, friction = 0;
};

StructureErrors structure_errors(const Params<double>& scene, const SampleStructure& st,
                                 const SampleStructure& ref, const Outputs& v0) {
  const std::array<double, kInertialParams> pi0 = standard_inertial(scene);
  const double size = v0.cwiseAbs().maxCoeff();
  StructureErrors e;
  for (int i = 0; i < kInertialParams; ++i) {
    Outputs a, b;
    a << st.A.col(i), st.Y.col(i);
    b << ref.A.col(i), ref.Y.col(i);
    const double scale = b.cwiseAbs().maxCoeff() + size / parameter_scale(scene, pi0, i);
    e.inertial = std::max(e.inertial, (a - b).cwiseAbs().maxCoeff() / scale);
  }
  Outputs a, b;
  a << st.b, st.c;
  b << ref.b, ref.c;
  e.offset = (a - b).cwiseAbs().maxCoeff() / size;
  for (int j = 0; j < kJoints; ++j) {
    a << st.dF.col(j), st.G.col(j);
    b << ref.dF.col(j), ref.G.col(j);
    const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
    e.friction = std::max(e.friction, (a - b).cwiseAbs().maxCoeff() / scale);
  }
  return e;
}

/// Compares sample_structure with reference_structure on `samples`: both refuse the same
/// samples, and where they read the structure its modes are the same, its rates to rounding and
/// its columns within 1e-9 (structure_errors). Returns how many samples were read.
int compare(const Params<double>& scene, const std::vector<Sample>& samples,
            const EvalOptions& eval, StructureErrors* worst) {
  int read = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    SampleStructure st, ref;
    Outputs v0;
    const bool ok = sample_structure(scene, s, eval, &st);
    EXPECT_EQ(ok, reference_structure(scene, s, eval, &ref, &v0)) << "sample " << i;
    if (!ok) continue;
    ++read;
    for (int j = 0; j < kJoints; ++j) {
      EXPECT_EQ(st.slip[j], ref.slip[j]) << "sample " << i << ", joint " << j;
      EXPECT_NEAR(st.w[j], ref.w[j], 1e-13 * (1 + std::abs(ref.w[j])))
          << "sample " << i << ", joint " << j;
    }
    const StructureErrors e = structure_errors(scene, st, ref, v0);
    EXPECT_LT(e.inertial, 1e-9) << "sample " << i;
    EXPECT_LT(e.offset, 1e-9) << "sample " << i;
    EXPECT_LT(e.friction, 1e-9) << "sample " << i;
    worst->inertial = std::max(worst->inertial, e.inertial);
    worst->offset = std::max(worst->offset, e.offset);
    worst->friction = std::max(worst->friction, e.friction);
  }
  return read;
}

/// A random five-bar near the paper's proportions: every length, mass and inertia drawn, centres
/// of mass off the links' lines, one of them on its proximal joint, either assembly.
Params<double> random_mechanism(std::mt19937_64* rng) {
  auto u = [rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(*rng); };
  Params<double> p = paper_params();
  p.ground_length = u(0.2, 0.35);
  const double lengths[][2] = {{0.05, 0.12}, {0.04, 0.1}, {0.2, 0.3}, {0.2, 0.3}};
  const int on_joint = static_cast<int>(u(0, kLinks));
  for (int i = 0; i < kLinks; ++i) {
    Link<double>& L = p.links[i];
    L.length = u(lengths[i][0], lengths[i][1]);
    L.mass = u(0.3, 2.0);
    L.inertia = u(0.01, 0.2);
    L.com_offset = i == on_joint ? 0.0 : u(0.0, 0.9) * L.length;
    L.com_angle = i == on_joint ? 0.0 : u(-1.0, 1.0);
  }
  p.point_p = u(0.0, 0.3);
  p.assembly = u(0, 1) < 0.5 ? kElbowUp : kElbowDown;
  p.gravity = u(0.0, 10.0);
  for (int j = 0; j < kJoints; ++j) p.friction.pin_radius[j] = u(0.005, 0.02);
  return p;
}

/// Random states and loads of `scene` (those that fail are the comparison's too); every fourth
/// sample with a crank held within the rest rule of `eval`.
std::vector<Sample> random_states(std::mt19937_64* rng, int n, const EvalOptions& eval) {
  auto u = [rng](double a, double b) { return std::uniform_real_distribution<double>(a, b)(*rng); };
  std::vector<Sample> out(n);
  for (int i = 0; i < n; ++i) {
    Sample& s = out[i];
    s.th1 = u(0.0, M_PI);
    s.th2 = u(0.0, M_PI);
    s.w1 = u(-8, 8), s.w2 = u(-8, 8);
    s.a1 = u(-50, 50), s.a2 = u(-50, 50);
    if (i % 4 == 3) s.w2 = 0.5 * eval.rest_rate, s.a2 = -0.5 * eval.rest_acceleration;
    s.loads = {0.0, 0.0, u(-6, 6), u(0, 60), u(-M_PI, M_PI)};
  }
  return out;
}

TEST(SampleStructure, ClosedFormIsTheModelsPassesOnThePaperScene) {
  const Params<double> scene = paper_params();
  StructureErrors worst;
  EXPECT_EQ(compare(scene, testing::random_samples(scene, 40, 21), EvalOptions{}, &worst), 40);
  EvalOptions rest;  // the rest rule on, a crank held
  rest.rest_rate = 1e-3;
  rest.rest_acceleration = 1e-2;
  std::vector<Sample> samples = testing::random_samples(scene, 10, 22);
  samples[0].w1 = 5e-4, samples[0].a1 = -5e-3;
  samples[1].w2 = 0.0, samples[1].a2 = 0.0;
  EXPECT_EQ(compare(scene, samples, rest, &worst), 10);
  RecordProperty("inertial", ::testing::PrintToString(worst.inertial));
  RecordProperty("offset", ::testing::PrintToString(worst.offset));
  RecordProperty("friction", ::testing::PrintToString(worst.friction));
}

TEST(SampleStructure, ClosedFormIsTheModelsPassesOnRandomMechanisms) {
  std::mt19937_64 rng(1234);
  EvalOptions eval;
  eval.singular_margin = 0.05;
  eval.rest_rate = 1e-3;
  eval.rest_acceleration = 1e-2;
  StructureErrors worst;
  int read = 0;
  for (int m = 0; m < 30; ++m) {
    const Params<double> scene = random_mechanism(&rng);
    read += compare(scene, random_states(&rng, 12, eval), eval, &worst);
  }
  EXPECT_GT(read, 100);  // most random states close
  RecordProperty("inertial", ::testing::PrintToString(worst.inertial));
  RecordProperty("offset", ::testing::PrintToString(worst.offset));
  RecordProperty("friction", ::testing::PrintToString(worst.friction));
}

/// The samples whose structure cannot be read: a moving joint with no Coulomb sign (the rest
/// rule without stuck joints: at rest by its rate, its relative acceleration exactly 0), and a
/// joint that slips under a vanishing reaction (crank 1 alone has more than 1e-12 of mass and
/// inertia, without gravity: only O carries a reaction, while B slips). Each beside a control
/// that is read.
TEST(SampleStructure, RefusesWhereTheReferenceDoes) {
  Params<double> scene = paper_params();
  EvalOptions eval;
  eval.rest_rate = 1e-3;
  Sample s = testing::random_samples(scene, 1, 5)[0];
  SampleStructure st, ref;
  Outputs v0;
  ASSERT_TRUE(sample_structure(scene, s, eval, &st));
  s.w1 = 5e-4, s.a1 = 0.0;  // O at rest by its rate, not accelerating
  EXPECT_FALSE(sample_structure(scene, s, eval, &st));
  EXPECT_FALSE(reference_structure(scene, s, eval, &ref, &v0));
  scene.friction.pin_radius[0] = 0.0;  // no friction there: no Coulomb sign needed
  EXPECT_TRUE(sample_structure(scene, s, eval, &st));

  Params<double> light = paper_params();
  light.gravity = 0.0;
  for (int i = 1; i < kLinks; ++i) light.links[i].mass = light.links[i].inertia = 1e-12;
  Sample t = s;
  t.w1 = t.w2 = 0.0, t.a1 = 3.0, t.a2 = 0.0;
  t.loads = Loads<double>();
  EXPECT_FALSE(sample_structure(light, t, EvalOptions{}, &st));
  EXPECT_FALSE(reference_structure(light, t, EvalOptions{}, &ref, &v0));
  light.links[2].mass = 0.5;  // a coupler's mass loads every joint
  EXPECT_TRUE(sample_structure(light, t, EvalOptions{}, &st));
}

}  // namespace
}  // namespace fivebar::identification
