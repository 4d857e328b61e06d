// The command line's settings turned into library options (fivebar::commands).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/errors.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/friction.h"

namespace fivebar::io {
namespace {

const std::string kRoot = FIVEBAR_SOURCE_DIR;

// --start-from-scene: the coefficients the scene's law uses start the fit at the scene's values
// (a LuGre scene's coulomb too, not the neutral 0.1, though LuGre itself identifies nothing)
TEST(StartFromScene, KeepsTheCoefficientsTheScenesLawUses) {
  IdentifySettings settings;
  settings.start_from_scene = true;
  auto start = [&](const Scene& scene) {
    const identification::IdentifyOptions opt = identify_options(settings, scene);
    const std::vector<std::string> names = opt.layout.names();
    EXPECT_EQ(names, (std::vector<std::string>{"coulomb", "viscous"}));
    return opt.initial;
  };
  const Scene paper = load_scene(kRoot + "/datasets/scenes/paper.yaml",
                                 {"friction.coulomb=0.13", "friction.viscous=0.03"});
  EXPECT_EQ(start(paper), (std::vector<double>{0.13, 0.03}));
  const Scene lugre =
      load_scene(kRoot + "/datasets/scenes/paper_lugre.yaml", {"friction.coulomb=0.13"});
  // LuGre has no viscous coefficient (its sigma2 is another term): the neutral start
  EXPECT_EQ(start(lugre),
            (std::vector<double>{0.13, coefficient_info(Coefficient::kViscous).start}));
}

// the best design on a bound of its range is named, with the side, once per key and side
TEST(Bounds, BestOnABoundIsNamedWithItsSide) {
  const std::vector<std::string> keys = {"mechanism.links.0.length", "mechanism.links.1.length",
                                         "mechanism.point_p"};
  const std::vector<double> lo = {0.06, 0.04, 0.1}, hi = {0.10, 0.07, 0.1};
  const std::vector<BoundHit> hits = bounds_hit(keys, {0.06, 0.07 - 1e-9, 0.1}, lo, hi);
  ASSERT_EQ(hits.size(), 2u);  // a fixed key (lo == hi) is no bound of a search
  EXPECT_EQ(hits[0].key, keys[0]);
  EXPECT_EQ(hits[0].side, "lower");
  EXPECT_EQ(hits[1].key, keys[1]);
  EXPECT_EQ(hits[1].side, "upper");
  EXPECT_THAT(bounds_advice(hits),
              ::testing::HasSubstr("lies on the upper bound of mechanism.links.1.length (0.07)"));
  EXPECT_TRUE(bounds_hit(keys, {0.08, 0.05, 0.1}, lo, hi).empty());
}

// the default objective follows the scene's winding data; the smooth objectives refine to 0.01%
TEST(Objective, DefaultFollowsTheWindingData) {
  const Scene paper = load_scene(kRoot + "/datasets/scenes/paper.yaml");
  const Scene motors = load_scene(kRoot + "/datasets/scenes/paper_motors.yaml");
  const OptimizeSettings s = optimize_defaults();
  const trajectory::BatchOptions a = batch_options(s, paper.windings);
  const trajectory::BatchOptions b = batch_options(s, motors.windings);
  EXPECT_EQ(a.problem.objective, trajectory::Objective::kDissipatedEnergy);
  EXPECT_EQ(b.problem.objective, trajectory::Objective::kTotalDissipation);
  EXPECT_EQ(b.refine.tol, 1e-4);
  EXPECT_EQ(b.refine.control_points, trajectory::kSmoothRefineLevels);
  EXPECT_GT(b.problem.winding_heat[0], 0.0);
  EXPECT_NE(objective_note(a).find("actuators.M1.winding_resistance"), std::string::npos);
  EXPECT_TRUE(objective_note(b).empty());
  // the note goes to solved tasks only: a task the design cannot do keeps its reason alone
  std::vector<trajectory::TaskResult> results(2);
  results[0].x = {0.0};
  results[1].message = "goal out of reach";
  add_objective_note(a, &results);
  EXPECT_EQ(results[0].message, objective_note(a));
  EXPECT_EQ(results[1].message, "goal out of reach");
  EXPECT_EQ(b.problem.end_acceleration, trajectory::EndAcceleration::kFree);
  OptimizeSettings zero = s;
  zero.end_acceleration = "zero";
  zero.regeneration = "shared_bus";
  const trajectory::BatchOptions z = batch_options(zero, motors.windings);
  EXPECT_EQ(z.problem.end_acceleration, trajectory::EndAcceleration::kZero);
  EXPECT_EQ(z.problem.regeneration, trajectory::Regeneration::kSharedBus);
  OptimizeSettings bad = s;
  bad.objective = "supply_energy";
  EXPECT_THROW(batch_options(bad, paper.windings), InputError);
  bad.regeneration = "bus";
  EXPECT_THROW(batch_options(bad, motors.windings), InputError);
}

}  // namespace
}  // namespace fivebar::io
