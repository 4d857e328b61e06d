// Scene loading: the canonical scene, every kind of bad input (each InputError names the file,
// the key and the reason), --set overrides, and the scene_to_yaml round trip.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "fivebar/io/errors.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/friction.h"

namespace fivebar::io {
namespace {

using ::testing::HasSubstr;

const std::string kPaperPath = std::string(FIVEBAR_SOURCE_DIR) + "/datasets/scenes/paper.yaml";

// The canonical scene as text, so that each test can break one line of it.
const std::string kPaper = R"yaml(mechanism:
  ground_length: 0.29
  links:
    - {length: 0.08, mass: 1.0, inertia: 0.1, com_offset: 0.05, com_angle: 0.0}
    - {length: 0.05, mass: 1.0, inertia: 0.1, com_offset: 0.03, com_angle: 0.0}
    - {length: 0.25, mass: 1.0, inertia: 0.1, com_offset: 0.20, com_angle: 0.0}
    - {length: 0.25, mass: 1.0, inertia: 0.1, com_offset: 0.15, com_angle: 0.0}
  point_p: 0.20
  assembly: elbow_up
gravity: 9.81
friction:
  model: coulomb_viscous
  pin_radius: 0.01
  coulomb: 0.12
  viscous: 0.02
loads:
  M1: "2 + 5*sin(8*pi*t)"
  M2: "3 + 5*cos(pi*t)"
  M3: "6"
  F: "50"
  F_angle: 1.5707963267948966
initial: {theta1: 1.5707963267948966, theta2: 1.5707963267948966, omega1: 0.0, omega2: 0.0}
simulation: {duration: 2.0, output_step: 0.001}
)yaml";

// kPaper with the first occurrence of `from` replaced by `to` (which must exist)
std::string with(const std::string& from, const std::string& to, std::string text = kPaper) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

// Expects parse_scene to throw an InputError with file "bad.yaml", exactly `key`, and a reason
// containing `reason`; the message is `bad.yaml: <key>: <reason>`.
void expect_error(const std::string& yaml, const std::vector<std::string>& sets,
                  const std::string& key, const std::string& reason) {
  try {
    parse_scene(yaml, "bad.yaml", sets);
    ADD_FAILURE() << "no InputError; expected " << key << ": " << reason;
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "bad.yaml");
    EXPECT_EQ(e.key(), key) << e.what();
    EXPECT_THAT(e.reason(), HasSubstr(reason)) << e.what();
    EXPECT_EQ(std::string(e.what()), "bad.yaml: " + e.key() + ": " + e.reason());
  }
}

void expect_error(const std::string& yaml, const std::string& key, const std::string& reason) {
  expect_error(yaml, {}, key, reason);
}

TEST(Scene, PaperFileMatchesTheModelSpec) {
  const Scene s = load_scene(kPaperPath);
  const Params<double> p = paper_params();
  EXPECT_EQ(s.path, kPaperPath);
  EXPECT_EQ(s.params.ground_length, p.ground_length);
  for (int i = 0; i < kLinks; ++i) {
    EXPECT_EQ(s.params.links[i].length, p.links[i].length) << i;
    EXPECT_EQ(s.params.links[i].mass, p.links[i].mass) << i;
    EXPECT_EQ(s.params.links[i].inertia, p.links[i].inertia) << i;
    EXPECT_EQ(s.params.links[i].com_offset, p.links[i].com_offset) << i;
    EXPECT_EQ(s.params.links[i].com_angle, p.links[i].com_angle) << i;
  }
  EXPECT_EQ(s.params.point_p, p.point_p);
  EXPECT_EQ(s.params.assembly, kElbowUp);
  EXPECT_EQ(s.params.gravity, 9.81);
  EXPECT_EQ(s.params.friction.law, FrictionLaw::kCoulombViscous);
  EXPECT_EQ(s.params.friction.pin_radius, p.friction.pin_radius);
  EXPECT_EQ(s.params.friction.coulomb, p.friction.coulomb);
  EXPECT_EQ(s.params.friction.viscous, p.friction.viscous);
  EXPECT_EQ(s.params.friction.smoothing_velocity, 0.0);
  EXPECT_EQ(s.M1, "2 + 5*sin(8*pi*t)");
  EXPECT_EQ(s.M2, "3 + 5*cos(pi*t)");
  EXPECT_EQ(s.M3, "6");
  EXPECT_EQ(s.F, "50");
  EXPECT_EQ(s.F_angle, M_PI / 2);
  EXPECT_EQ(s.initial.theta1, M_PI / 2);
  EXPECT_EQ(s.initial.theta2, M_PI / 2);
  EXPECT_EQ(s.initial.omega1, 0.0);
  EXPECT_EQ(s.options.duration, 2.0);
  EXPECT_EQ(s.options.output_step, 1e-3);
  // omitted solver settings take the sim::Options defaults
  const sim::Options d;
  EXPECT_EQ(s.options.method, sim::default_method(s.params.friction.law));
  EXPECT_EQ(s.options.method, sim::Method::kCvodeAdams);
  EXPECT_EQ(s.options.rtol, d.rtol);
  EXPECT_EQ(s.options.atol, d.atol);
  EXPECT_EQ(s.options.max_steps, d.max_steps);
  EXPECT_EQ(s.options.friction_max_iter, d.friction_max_iter);
}

TEST(Scene, FrictionlessTwinFileDiffersOnlyInTheModel) {
  const Scene a = load_scene(kPaperPath);
  const Scene b =
      load_scene(std::string(FIVEBAR_SOURCE_DIR) + "/datasets/scenes/paper_frictionless.yaml");
  EXPECT_EQ(b.params.friction.law, FrictionLaw::kNone);
  Scene b_on = b;
  b_on.params.friction.law = FrictionLaw::kCoulombViscous;
  b_on.path = a.path;
  EXPECT_EQ(scene_to_yaml(b_on), scene_to_yaml(a));
}

TEST(Scene, InlineTextParsesLikeTheFile) {
  const Scene a = load_scene(kPaperPath);
  Scene b = parse_scene(kPaper, kPaperPath);
  EXPECT_EQ(scene_to_yaml(a), scene_to_yaml(b));
}

// --- every kind of bad input -----------------------------------------------------------------

TEST(SceneErrors, MissingFile) {
  EXPECT_THAT([] { load_scene("/nonexistent/scene.yaml"); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr("/nonexistent/scene.yaml: (file): cannot open")));
}

TEST(SceneErrors, MalformedYamlGivesTheLine) {
  expect_error("mechanism:\n  ground_length: 0.29\n  links: [1, 2\n", "line 4, column 1",
               "malformed YAML");
  expect_error(with("gravity: 9.81", "gravity: : 9.81"), "line 10, column 10", "malformed YAML");
}

TEST(SceneErrors, TopLevelMustBeAMap) {
  expect_error("- 1\n- 2\n", "(top level)", "expected a map of sections");
}

TEST(SceneErrors, UnknownKeysAnywhereAreNamedInFull) {
  expect_error(kPaper + "colour: red\n", "colour", "unknown key (line 24)");
  expect_error(with("  point_p: 0.20", "  point_q: 0.20"), "mechanism.point_q",
               "unknown key (line 8); keys of mechanism: type, ground_length, links, point_p, assembly");
  expect_error(with("{length: 0.25, mass: 1.0, inertia: 0.1, com_offset: 0.15",
                    "{length: 0.25, mass: 1.0, inertia: 0.1, com_ofset: 0.15"),
               "mechanism.links.3.com_ofset", "unknown key");
  expect_error(with("{duration: 2.0,", "{duration: 2.0, rtoll: 1e-8,"), "simulation.rtoll",
               "unknown key");
  expect_error(with("  F_angle:", "  F_angel:"), "loads.F_angel", "unknown key");
}

TEST(SceneErrors, DuplicateKey) {
  expect_error(with("gravity: 9.81", "gravity: 9.81\ngravity: 1.62"), "gravity", "duplicate key");
}

TEST(SceneErrors, MissingRequiredKey) {
  expect_error(with("  ground_length: 0.29\n", ""), "mechanism.ground_length",
               "missing (required)");
  expect_error(with("{length: 0.05, mass: 1.0, inertia: 0.1,", "{length: 0.05, mass: 1.0,"),
               "mechanism.links.1.inertia", "missing (required)");
  expect_error(with("theta2: 1.5707963267948966, ", ""), "initial.theta2", "missing (required)");
  expect_error("", "mechanism.ground_length", "missing (required)");
}

TEST(SceneErrors, WrongType) {
  expect_error(with("mass: 1.0, inertia: 0.1, com_offset: 0.20",
                    "mass: heavy, inertia: 0.1, "
                    "com_offset: 0.20"),
               "mechanism.links.2.mass", "expected a number, got 'heavy' (line 6)");
  expect_error(with("gravity: 9.81", "gravity: [9.81]"), "gravity",
               "expected a single value, got a list");
  expect_error(with("gravity: 9.81", "gravity:"), "gravity", "no value given");
  expect_error(with("  assembly: elbow_up", "  assembly: {a: 1}"), "mechanism.assembly",
               "expected a single value, got a map");
  expect_error(with("friction:\n  model: coulomb_viscous", "friction: 3\nfoo:\n  model: x"),
               "friction", "expected a map of keys");
}

TEST(SceneErrors, WrongNumberOfLinks) {
  expect_error(with("    - {length: 0.25, mass: 1.0, inertia: 0.1, com_offset: 0.15, "
                    "com_angle: 0.0}\n",
                    ""),
               "mechanism.links", "expected 4 links, got 3");
}

/// One edit of the paper scene and the error it must give: exactly `key`, a reason containing
/// `reason`.
struct BadEdit {
  const char* from;
  const char* to;
  const char* key;
  const char* reason;
};

const BadEdit kBadEdits[] = {
    // wrong list length
    {"coulomb: 0.12", "coulomb: [0.12, 0.12, 0.12, 0.12]", "friction.coulomb",
     "expected 1 or 5 numbers, got 4"},
    {"viscous: 0.02", "viscous: [0.02, 0.02, 0.02, 0.02, 0.02, 0.02]", "friction.viscous",
     "expected 1 or 5 numbers, got 6"},
    // lengths, masses, inertias must be positive
    {"ground_length: 0.29", "ground_length: 0", "mechanism.ground_length", "must be > 0, got 0"},
    {"{length: 0.08,", "{length: -0.08,", "mechanism.links.0.length", "must be > 0, got -0.08"},
    {"{length: 0.05, mass: 1.0,", "{length: 0.05, mass: 0,", "mechanism.links.1.mass",
     "must be > 0"},
    {"inertia: 0.1, com_offset: 0.20", "inertia: -0.1, com_offset: 0.20",
     "mechanism.links.2.inertia", "must be > 0"},
    // centre-of-mass offsets must not be negative
    {"com_offset: 0.15", "com_offset: -0.15", "mechanism.links.3.com_offset",
     "must be >= 0, got -0.15"},
    // NaN or Inf anywhere
    {"gravity: 9.81", "gravity: .nan", "gravity", "must be a finite number"},
    {"theta1: 1.5707963267948966", "theta1: .inf", "initial.theta1", "must be a finite number"},
    {"F_angle: 1.5707963267948966", "F_angle: -.inf", "loads.F_angle", "must be a finite number"},
    {"coulomb: 0.12", "coulomb: [0.12, 0.12, nan, 0.12, 0.12]", "friction.coulomb.2",
     "must be a finite number"},
    {"{duration: 2.0", "{duration: inf", "simulation.duration", "must be a finite number"},
    // friction coefficients must not be negative
    {"viscous: 0.02", "viscous: -0.02", "friction.viscous", "must be >= 0"},
    {"coulomb: 0.12", "coulomb: [0.12, 0.12, 0.12, -0.1, 0.12]", "friction.coulomb.3",
     "must be >= 0, got -0.1"},
    {"  viscous: 0.02", "  viscous: 0.02\n  smoothing_velocity: -1", "friction.smoothing_velocity",
     "must be >= 0"},
    // the duration and the output step
    {"{duration: 2.0,", "{duration: 0,", "simulation.duration", "must be > 0, got 0"},
    {"{duration: 2.0,", "{duration: -1,", "simulation.duration", "must be > 0"},
    {"output_step: 0.001", "output_step: 0", "simulation.output_step", "must be > 0"},
    {"output_step: 0.001", "output_step: 3", "simulation.output_step",
     "must not exceed simulation.duration = 2, got 3"},
};

TEST(SceneErrors, BadValuesNameTheKeyAndTheReason) {
  for (const BadEdit& bad : kBadEdits) {
    SCOPED_TRACE(std::string(bad.from) + " -> " + bad.to);
    expect_error(with(bad.from, bad.to), bad.key, bad.reason);
  }
}

TEST(SceneErrors, PinRadiusMustBePositiveWhenFrictionIsOn) {
  expect_error(with("pin_radius: 0.01", "pin_radius: 0"), "friction.pin_radius",
               "must be > 0, got 0");
  expect_error(with("pin_radius: 0.01", "pin_radius: [0.01, 0.01, 0.01, 0.01, 0]"),
               "friction.pin_radius.4", "must be > 0");
  // without friction the radius is unused: 0 is accepted
  EXPECT_NO_THROW(parse_scene(
      with("pin_radius: 0.01", "pin_radius: 0", with("model: coulomb_viscous", "model: none")),
      "ok.yaml"));
  // and the coefficients are then optional
  expect_error(with("  coulomb: 0.12\n", ""), "friction.coulomb",
               "missing (required by friction.model coulomb_viscous)");
  EXPECT_NO_THROW(parse_scene(
      with("  coulomb: 0.12\n", "", with("model: coulomb_viscous", "model: none")), "ok.yaml"));
}

TEST(SceneErrors, BadNames) {
  expect_error(with("assembly: elbow_up", "assembly: elbow_left"), "mechanism.assembly",
               "expected elbow_up or elbow_down, got 'elbow_left'");
  expect_error(with("model: coulomb_viscous", "model: dahl"), "friction.model",
               "expected one of " + law_names() + ", got 'dahl'");
  expect_error(with("{duration: 2.0,", "{integrator: rk4, duration: 2.0,"), "simulation.integrator",
               "unknown integrator 'rk4' (known: cvode_adams, ");
}

TEST(SceneErrors, EachFrictionLawRequiresItsCoefficients) {
  expect_error(kPaper, {"friction.model=stribeck"}, "friction.stribeck_velocity",
               "missing (required by friction.model stribeck)");
  expect_error(kPaper, {"friction.model=stribeck", "friction.stribeck_velocity=0"},
               "friction.stribeck_velocity", "must be > 0, got 0 (from --set)");
  expect_error(
      kPaper,
      {"friction.model=stribeck", "friction.stribeck_velocity=0.1", "friction.stribeck_exponent=0"},
      "friction.stribeck_exponent", "must be > 0");
  expect_error(kPaper, {"friction.model=lugre"}, "friction.sigma0",
               "missing (required by friction.model lugre)");
  expect_error(kPaper, {"friction.model=lugre", "friction.sigma0=1e5", "friction.sigma1=-1"},
               "friction.sigma1", "must be >= 0");
  expect_error(kPaper, {"friction.static_coulomb=[0.2, 0.2]"}, "friction.static_coulomb",
               "expected 1 or 5 numbers, got 2");
}

TEST(Scene, FrictionLawsAndTheirDefaults) {
  const Scene c = parse_scene(kPaper, "p.yaml");
  EXPECT_EQ(c.params.friction.static_coulomb, c.params.friction.coulomb);  // mu_s = mu_c
  EXPECT_EQ(c.params.friction.stribeck_exponent[0], 2.0);
  const Scene s = parse_scene(kPaper, "p.yaml",
                              {"friction.model=stribeck", "friction.stribeck_velocity=0.1",
                               "friction.static_coulomb=0.18"});
  EXPECT_EQ(s.params.friction.law, FrictionLaw::kStribeck);
  EXPECT_EQ(s.params.friction.stribeck_velocity[4], 0.1);
  EXPECT_EQ(s.params.friction.static_coulomb[2], 0.18);
  // LuGre needs no viscous coefficient (sigma2 plays its part)
  const Scene l = parse_scene(with("  viscous: 0.02\n", ""), "p.yaml",
                              {"friction.model=lugre", "friction.sigma0=1e5", "friction.sigma1=300",
                               "friction.sigma2=0.02"});
  EXPECT_EQ(l.params.friction.law, FrictionLaw::kLuGre);
  EXPECT_EQ(l.params.friction.sigma0[0], 1e5);
  EXPECT_EQ(l.params.friction.viscous[0], 0.0);
  EXPECT_EQ(l.options.method, sim::Method::kCvodeBdf);  // the law's default integrator
  EXPECT_EQ(friction_law_name(FrictionLaw::kLuGre), std::string("lugre"));
}

TEST(SceneErrors, SolverSettings) {
  expect_error(kPaper, {"simulation.rtol=0"}, "simulation.rtol", "must be in (0, 1), got 0");
  expect_error(kPaper, {"simulation.atol=1"}, "simulation.atol", "must be in (0, 1)");
  expect_error(kPaper, {"simulation.max_steps=1.5"}, "simulation.max_steps", "expected an integer");
  expect_error(kPaper, {"simulation.max_steps=0"}, "simulation.max_steps", "must be >= 1");
  expect_error(kPaper, {"simulation.locate_switches=maybe"}, "simulation.locate_switches",
               "expected true or false");
  expect_error(kPaper, {"simulation.friction_max_iter=0"}, "simulation.friction_max_iter",
               "must be in [1, 1000000]");
  expect_error(kPaper, {"simulation.singular_margin=-0.1"}, "simulation.singular_margin",
               "must be in [0, 1)");
}

TEST(SceneErrors, BadLoadExpressions) {
  expect_error(with("M1: \"2 + 5*sin(8*pi*t)\"", "M1: \"2 + 5*sin(8*pi*t\""), "loads.M1",
               "'2 + 5*sin(8*pi*t': ");
  expect_error(with("M2: \"3 + 5*cos(pi*t)\"", "M2: \"3 + 5*cos(pi*x)\""), "loads.M2",
               "Unexpected token \"x\"");
  expect_error(with("F: \"50\"", "F: \"1/t\""), "loads.F", "not finite at t = 0");
  expect_error(with("M3: \"6\"", "M3: \"\""), "loads.M3", "''");
}

TEST(SceneErrors, InitialPoseThatCannotAssemble) {
  // |BD| = |(0.29, 0.05 - 0.08)| + a longer ground: B and D too far apart for l3 + l4 = 0.5
  expect_error(with("ground_length: 0.29", "ground_length: 0.7"), "initial",
               "cannot assemble at theta1 = 1.5707963267948966, theta2 = 1.5707963267948966: "
               "|BD| = ");
  // the couplers cannot reach: |BD| = 0.2915 < |l3 - l4| = 0.35
  expect_error(kPaper, {"mechanism.links.2.length=0.6"}, "initial",
               "is outside [|l3 - l4|, l3 + l4] = [0.35, 0.85] m");
}

TEST(SceneErrors, InitialPoseNearTheSingularity) {
  // ground length chosen so that |BD| = l3 + l4 - 1e-8: couplers almost aligned,
  // |sin(th4 - th3)| ~ 4e-4 < the default margin 1e-3
  const double bd = 0.5 - 1e-8;
  const double l0 = std::sqrt(bd * bd - 0.03 * 0.03);
  char set[64];
  std::snprintf(set, sizeof set, "mechanism.ground_length=%.17g", l0);
  expect_error(kPaper, {set}, "initial", "too close to a singular configuration");
  // a smaller margin accepts it
  EXPECT_NO_THROW(parse_scene(kPaper, "ok.yaml", {set, "simulation.singular_margin=1e-4"}));
}

TEST(Scene, CouplerSineMatchesTheReferencePose) {
  // reference trajectory at t = 0: th3 = 0.845181298522063, th4 = 2.09024813802233
  constexpr double kTol = 1e-12;  // closed-form geometry, a few roundings
  const double expected = std::fabs(std::sin(2.09024813802233 - 0.845181298522063));
  EXPECT_NEAR(coupler_sine(paper_params(), M_PI / 2, M_PI / 2), expected, kTol);
  Params<double> far = paper_params();
  far.ground_length = 1.0;
  EXPECT_EQ(coupler_sine(far, M_PI / 2, M_PI / 2), -1);
}

// --- --set overrides -------------------------------------------------------------------------

TEST(SceneSet, NestedAndListIndex) {
  const Scene s = parse_scene(kPaper, "p.yaml",
                              {"friction.coulomb=0.2", "mechanism.links.2.mass=1.5", "gravity=1.62",
                               "mechanism.assembly=elbow_down"});
  for (double c : s.params.friction.coulomb) EXPECT_EQ(c, 0.2);
  EXPECT_EQ(s.params.links[2].mass, 1.5);
  EXPECT_EQ(s.params.links[1].mass, 1.0);
  EXPECT_EQ(s.params.gravity, 1.62);
  EXPECT_EQ(s.params.assembly, kElbowDown);
}

TEST(SceneSet, OneJointOfAPerJointList) {
  const Scene s = parse_scene(kPaper, "p.yaml", {"friction.coulomb.3=0.5"});
  EXPECT_EQ(s.params.friction.coulomb, (std::array<double, 5>{0.12, 0.12, 0.12, 0.5, 0.12}));
  // keys absent from the file start from their default
  const Scene d = parse_scene(kPaper, "p.yaml",
                              {"friction.static_coulomb.1=0.2", "friction.stribeck_exponent.4=3"});
  EXPECT_EQ(d.params.friction.static_coulomb, (std::array<double, 5>{0.12, 0.2, 0.12, 0.12, 0.12}));
  EXPECT_EQ(d.params.friction.stribeck_exponent, (std::array<double, 5>{2, 2, 2, 2, 3}));
  expect_error(with("  pin_radius: 0.01\n", ""), {"friction.pin_radius.0=0.1"},
               "friction.pin_radius", "the scene has no value to take element 0 of");
  const Scene l = parse_scene(kPaper, "p.yaml", {"friction.viscous=[0.1, 0.2, 0.3, 0.4, 0.5]"});
  EXPECT_EQ(l.params.friction.viscous, (std::array<double, 5>{0.1, 0.2, 0.3, 0.4, 0.5}));
}

TEST(SceneSet, KeysMissingFromTheFile) {
  // paper.yaml has no simulation.rtol, initial omega, friction.smoothing_velocity
  const Scene s =
      load_scene(kPaperPath, {"simulation.rtol=1e-8", "simulation.integrator=arkode_erk87",
                              "simulation.locate_switches=false",
                              "friction.smoothing_velocity=0.01", "simulation.max_steps=1000"});
  EXPECT_EQ(s.options.rtol, 1e-8);
  EXPECT_EQ(s.options.method, sim::Method::kArkodeErk87);
  EXPECT_FALSE(s.options.locate_switches);
  EXPECT_EQ(s.params.friction.smoothing_velocity, 0.01);
  EXPECT_EQ(s.options.max_steps, 1000);
  // a whole section absent from the file
  const std::string no_sim = with("simulation: {duration: 2.0, output_step: 0.001}\n", "");
  EXPECT_EQ(parse_scene(no_sim, "p.yaml").options.duration, sim::Options().duration);
  EXPECT_EQ(parse_scene(no_sim, "p.yaml", {"simulation.duration=0.5"}).options.duration, 0.5);
  // an expression with blanks and operators
  EXPECT_EQ(parse_scene(kPaper, "p.yaml", {"loads.M3=2 + 3*t"}).M3, "2 + 3*t");
}

TEST(SceneSet, LaterSetsWin) {
  EXPECT_EQ(parse_scene(kPaper, "p.yaml", {"gravity=1", "gravity=2"}).params.gravity, 2.0);
}

TEST(SceneSet, UnknownOrMalformedKeysFail) {
  expect_error(kPaper, {"friction.foo=1"}, "friction.foo", "unknown key in --set friction.foo=1");
  expect_error(kPaper, {"mechanism.links.7.mass=1"}, "mechanism.links.7", "no such link");
  expect_error(kPaper, {"mechanism.links.x.mass=1"}, "mechanism.links.x", "no such link");
  expect_error(kPaper, {"friction.coulomb.5=0.1"}, "friction.coulomb.5", "no such joint");
  expect_error(kPaper, {"gravity.0=1"}, "gravity.0", "unknown key");
  expect_error(kPaper, {"mechanism=1"}, "mechanism", "is a section, not a value");
  expect_error(kPaper, {"gravity"}, "--set", "expected KEY=VALUE, got 'gravity'");
  expect_error(kPaper, {"=1"}, "--set", "expected KEY=VALUE");
  expect_error(kPaper, {"mechanism..mass=1"}, "mechanism..mass", "malformed key");
}

TEST(SceneSet, BadValuesNameTheirOrigin) {
  expect_error(kPaper, {"friction.coulomb=-1"}, "friction.coulomb",
               "must be >= 0, got -1 (from --set)");
  expect_error(kPaper, {"mechanism.links.0.length=abc"}, "mechanism.links.0.length",
               "expected a number, got 'abc' (from --set)");
  expect_error(kPaper, {"friction.coulomb=[1, 2]"}, "friction.coulomb",
               "expected 1 or 5 numbers, got 2 (from --set)");
}

// --- writing ---------------------------------------------------------------------------------

// every field of two scenes
void expect_same(const Scene& a, const Scene& b) {
  EXPECT_EQ(a.params.ground_length, b.params.ground_length);
  for (int i = 0; i < kLinks; ++i) {
    EXPECT_EQ(a.params.links[i].length, b.params.links[i].length);
    EXPECT_EQ(a.params.links[i].mass, b.params.links[i].mass);
    EXPECT_EQ(a.params.links[i].inertia, b.params.links[i].inertia);
    EXPECT_EQ(a.params.links[i].com_offset, b.params.links[i].com_offset);
    EXPECT_EQ(a.params.links[i].com_angle, b.params.links[i].com_angle);
  }
  EXPECT_EQ(a.params.point_p, b.params.point_p);
  EXPECT_EQ(a.params.assembly, b.params.assembly);
  EXPECT_EQ(a.params.gravity, b.params.gravity);
  EXPECT_EQ(a.params.friction.law, b.params.friction.law);
  EXPECT_EQ(a.params.friction.pin_radius, b.params.friction.pin_radius);
  EXPECT_EQ(a.params.friction.coulomb, b.params.friction.coulomb);
  EXPECT_EQ(a.params.friction.viscous, b.params.friction.viscous);
  EXPECT_EQ(a.params.friction.static_coulomb, b.params.friction.static_coulomb);
  EXPECT_EQ(a.params.friction.stribeck_velocity, b.params.friction.stribeck_velocity);
  EXPECT_EQ(a.params.friction.stribeck_exponent, b.params.friction.stribeck_exponent);
  EXPECT_EQ(a.params.friction.sigma0, b.params.friction.sigma0);
  EXPECT_EQ(a.params.friction.sigma1, b.params.friction.sigma1);
  EXPECT_EQ(a.params.friction.sigma2, b.params.friction.sigma2);
  EXPECT_EQ(a.params.friction.smoothing_velocity, b.params.friction.smoothing_velocity);
  EXPECT_EQ(a.params.actuators.offset, b.params.actuators.offset);
  EXPECT_EQ(a.params.actuators.coulomb, b.params.actuators.coulomb);
  EXPECT_EQ(a.params.actuators.viscous, b.params.actuators.viscous);
  EXPECT_EQ(a.M1, b.M1);
  EXPECT_EQ(a.M2, b.M2);
  EXPECT_EQ(a.M3, b.M3);
  EXPECT_EQ(a.F, b.F);
  EXPECT_EQ(a.F_angle, b.F_angle);
  EXPECT_EQ(a.initial.theta1, b.initial.theta1);
  EXPECT_EQ(a.initial.theta2, b.initial.theta2);
  EXPECT_EQ(a.initial.omega1, b.initial.omega1);
  EXPECT_EQ(a.initial.omega2, b.initial.omega2);
  EXPECT_EQ(a.options.duration, b.options.duration);
  EXPECT_EQ(a.options.output_step, b.options.output_step);
  EXPECT_EQ(a.options.method, b.options.method);
  EXPECT_EQ(a.options.rtol, b.options.rtol);
  EXPECT_EQ(a.options.atol, b.options.atol);
  EXPECT_EQ(a.options.locate_switches, b.options.locate_switches);
  EXPECT_EQ(a.options.stick, b.options.stick);
  EXPECT_EQ(a.options.max_steps, b.options.max_steps);
  EXPECT_EQ(a.options.singular_margin, b.options.singular_margin);
  EXPECT_EQ(a.options.friction_tol, b.options.friction_tol);
  EXPECT_EQ(a.options.friction_max_iter, b.options.friction_max_iter);
}

TEST(SceneYaml, RoundTripsThePaperScene) {
  const Scene a = load_scene(kPaperPath);
  const Scene b = parse_scene(scene_to_yaml(a), "written.yaml");
  expect_same(a, b);
  EXPECT_EQ(scene_to_yaml(b), scene_to_yaml(a));
}

TEST(SceneYaml, RoundTripsNonDefaultSettings) {
  const Scene a = parse_scene(kPaper, "p.yaml",
                              {"friction.coulomb=[0.1, 0.2, 0.3, 0.4, 0.123456789012345678]",
                               "friction.viscous.0=0.5",
                               "friction.pin_radius=0.0125",
                               "friction.smoothing_velocity=1e-3",
                               "mechanism.assembly=elbow_down",
                               "mechanism.links.3.com_angle=-0.1",
                               "gravity=0",
                               "loads.M1=2 + 5*sin(8*pi*t) - t^2/3",
                               "loads.F_angle=0.1",
                               "initial.omega1=-1.25",
                               "simulation.integrator=cvode_bdf",
                               "simulation.rtol=1e-7",
                               "simulation.atol=3e-9",
                               "simulation.locate_switches=false",
                               "simulation.stick=false",
                               "simulation.max_steps=12345",
                               "simulation.singular_margin=0.01",
                               "simulation.friction_tol=1e-9",
                               "simulation.friction_max_iter=7",
                               "simulation.duration=0.1",
                               "simulation.output_step=0.01"});
  const Scene b = parse_scene(scene_to_yaml(a), "written.yaml");
  expect_same(a, b);
}

TEST(SceneYaml, RoundTripsStribeckAndLuGre) {
  for (const std::vector<std::string>& sets : std::vector<std::vector<std::string>>{
           {"friction.model=stribeck", "friction.stribeck_velocity=[0.1, 0.2, 0.1, 0.1, 0.1]",
            "friction.static_coulomb=0.18", "friction.stribeck_exponent=1.5"},
           {"friction.model=lugre", "friction.sigma0=1e5", "friction.sigma1=316.2",
            "friction.sigma2=0.02", "friction.stribeck_velocity=0.05"}}) {
    const Scene a = parse_scene(kPaper, "p.yaml", sets);
    const std::string yaml = scene_to_yaml(a);
    const Scene b = parse_scene(yaml, "written.yaml");
    expect_same(a, b);
    EXPECT_EQ(scene_to_yaml(b), yaml);
  }
}

}  // namespace
}  // namespace fivebar::io

namespace fivebar::io {
namespace {

// the rest rule's thresholds are optional (-1: derived), >= 0, and round-trip
TEST(Scene, RestThresholdsDefaultToDerivedAndRoundTrip) {
  const Scene d = parse_scene(kPaper, "paper.yaml");
  EXPECT_EQ(d.rest_rate_threshold, -1.0);
  EXPECT_EQ(d.rest_acceleration_threshold, -1.0);
  const Scene s = parse_scene(kPaper, "paper.yaml",
                              {"simulation.rest_rate_threshold=1e-6",
                               "simulation.rest_acceleration_threshold=0"});
  EXPECT_EQ(s.rest_rate_threshold, 1e-6);
  EXPECT_EQ(s.rest_acceleration_threshold, 0.0);
  const Scene back = parse_scene(scene_to_yaml(s), "back.yaml");
  EXPECT_EQ(back.rest_rate_threshold, 1e-6);
  EXPECT_EQ(back.rest_acceleration_threshold, 0.0);
  expect_error(kPaper, {"simulation.rest_acceleration_threshold=-1e-3"},
               "simulation.rest_acceleration_threshold", "must be >= 0");
}

// The friction keys come from the law descriptors (friction.h). For every law, each of
// its coefficients (per joint, distinct values) round-trips through scene_to_yaml, and each
// coefficient it requires is reported missing, naming the law, when absent.
TEST(SceneLaws, EveryDescriptorCoefficientRoundTripsAndIsRequiredWhereTheLawSaysSo) {
  for (const LawDescriptor& law : kLaws) {
    if (law.law == FrictionLaw::kNone) continue;
    SCOPED_TRACE(law.name);
    std::string friction = "friction:\n  model: " + std::string(law.name) + "\n  pin_radius: 0.01\n";
    for (int i = 0; i < law.count; ++i) {
      const CoefficientInfo& c = coefficient_info(law.coefficients[i].id);
      const double base = 0.1 * (i + 1);
      friction += "  " + std::string(c.key) + ": [" + std::to_string(base) + ", " +
                  std::to_string(base + 0.01) + ", " + std::to_string(base + 0.02) + ", " +
                  std::to_string(base + 0.03) + ", " + std::to_string(base + 0.04) + "]\n";
    }
    const std::string paper_friction =
        "friction:\n  model: coulomb_viscous\n  pin_radius: 0.01\n  coulomb: 0.12\n  viscous: 0.02\n";
    const std::string yaml = with(paper_friction, friction);
    const Scene a = parse_scene(yaml, "law.yaml", {});
    const Scene b = parse_scene(scene_to_yaml(a), "law_again.yaml", {});
    EXPECT_EQ(a.params.friction.law, law.law);
    for (int i = 0; i < law.count; ++i) {
      const Coefficient id = law.coefficients[i].id;
      EXPECT_NEAR(coefficient(a.params.friction, id)[3], 0.1 * (i + 1) + 0.03, 1e-15);
      EXPECT_EQ(coefficient(b.params.friction, id), coefficient(a.params.friction, id));
      if (!law.coefficients[i].required) continue;
      const std::string key = coefficient_info(id).key;
      const auto line_start = yaml.find("  " + key + ": [");
      const auto line_end = yaml.find('\n', line_start);
      std::string missing = yaml;
      missing.erase(line_start, line_end - line_start + 1);
      expect_error(missing, {}, "friction." + key,
                   "required by friction.model " + std::string(law.name));
    }
  }
}

// the actuators: section (per motor offset, Coulomb, viscous), written back only when present
TEST(SceneYaml, RoundTripsTheActuators) {
  const Scene a = parse_scene(kPaper + "actuators:\n  M1: {offset: 0.05, coulomb: 0.03}\n",
                              "p.yaml", {"actuators.M2.viscous=0.0015"});
  EXPECT_EQ(a.params.actuators.offset[0], 0.05);
  EXPECT_EQ(a.params.actuators.offset[1], 0.0);
  EXPECT_EQ(a.params.actuators.coulomb[0], 0.03);
  EXPECT_EQ(a.params.actuators.viscous[1], 0.0015);
  const std::string yaml = scene_to_yaml(a);
  EXPECT_THAT(yaml, HasSubstr("actuators:\n  M1: {offset: 0.05, coulomb: 0.03, viscous: 0}"));
  const Scene b = parse_scene(yaml, "written.yaml");
  expect_same(a, b);
  EXPECT_EQ(scene_to_yaml(b), yaml);
  // absent: defaults 0, and nothing written
  const Scene plain = parse_scene(kPaper, "p.yaml");
  EXPECT_EQ(plain.params.actuators.coulomb, (std::array<double, 2>{0.0, 0.0}));
  EXPECT_THAT(scene_to_yaml(plain), ::testing::Not(HasSubstr("actuators")));
}

// the motors' winding data: read, written back, the heat coefficient R / (k_t G)^2
TEST(SceneYaml, RoundTripsTheWindingData) {
  const Scene a = parse_scene(
      kPaper + "actuators:\n  M1: {winding_resistance: 0.3, torque_constant: 0.03}\n"
               "  M2: {winding_resistance: 0.6, torque_constant: 0.05}\n",
      "p.yaml", {"actuators.M1.gear_ratio=66"});
  ASSERT_TRUE(a.windings.present());
  EXPECT_EQ(a.windings.gear_ratio[0], 66.0);
  EXPECT_EQ(a.windings.gear_ratio[1], 1.0);
  EXPECT_DOUBLE_EQ(a.windings.heat_coefficient(0), 0.3 / std::pow(0.03 * 66, 2));
  EXPECT_DOUBLE_EQ(a.windings.heat_coefficient(1), 0.6 / (0.05 * 0.05));
  const std::string yaml = scene_to_yaml(a);
  EXPECT_THAT(yaml, HasSubstr("winding_resistance: 0.3, torque_constant: 0.03, gear_ratio: 66}"));
  const Scene b = parse_scene(yaml, "written.yaml");
  EXPECT_EQ(a.windings.resistance, b.windings.resistance);
  EXPECT_EQ(a.windings.torque_constant, b.windings.torque_constant);
  EXPECT_EQ(a.windings.gear_ratio, b.windings.gear_ratio);
  EXPECT_EQ(scene_to_yaml(b), yaml);
  // the shipped scene with motors
  const Scene motors =
      load_scene(std::string(FIVEBAR_SOURCE_DIR) + "/datasets/scenes/paper_motors.yaml");
  const double c = motors.windings.heat_coefficient(0);
  EXPECT_GT(c, 5e-4);
  EXPECT_LT(c, 0.1);
  EXPECT_FALSE(parse_scene(kPaper, "p.yaml").windings.present());
}

TEST(SceneErrors, WindingValues) {
  const std::string both = "actuators.M2.winding_resistance=0.3";
  const std::vector<std::string> ok = {"actuators.M1.winding_resistance=0.3",
                                       "actuators.M1.torque_constant=0.03", both,
                                       "actuators.M2.torque_constant=0.03"};
  EXPECT_NO_THROW(parse_scene(kPaper, "p.yaml", ok));
  for (const char* key : {"actuators.M1.winding_resistance", "actuators.M2.torque_constant",
                          "actuators.M1.gear_ratio"}) {
    for (const char* bad : {"0", "-1"}) {
      std::vector<std::string> sets = ok;
      sets.push_back(std::string(key) + "=" + bad);
      expect_error(kPaper, sets, key, "> 0");
    }
    std::vector<std::string> sets = ok;
    sets.push_back(std::string(key) + "=nan");
    expect_error(kPaper, sets, key, "finite");
    sets.back() = std::string(key) + "=ohm";
    expect_error(kPaper, sets, key, "expected a number");
  }
  // one motor's data without the other's: the missing key is named
  expect_error(kPaper, {"actuators.M1.winding_resistance=0.3", "actuators.M1.torque_constant=0.03"},
               "actuators.M2.winding_resistance", "missing");
}

TEST(SceneErrors, ActuatorValues) {
  expect_error(kPaper, {"actuators.M1.coulomb=-0.1"}, "actuators.M1.coulomb", ">= 0");
  expect_error(kPaper, {"actuators.M2.viscous=-1"}, "actuators.M2.viscous", ">= 0");
  expect_error(kPaper, {"actuators.M3.offset=1"}, "actuators.M3.offset", "M1, M2");
  // friction that needs a Coulomb sign for its stick-slip logic
  expect_error(kPaper, {"friction.model=none", "actuators.M2.coulomb=0.1"},
               "actuators.M2.coulomb", "Coulomb sign");
  // an offset alone is a sensor property: fine without friction
  EXPECT_NO_THROW(parse_scene(kPaper, "p.yaml", {"friction.model=none", "actuators.M1.offset=1"}));
}

}  // namespace
}  // namespace fivebar::io
