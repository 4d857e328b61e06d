// The command line's settings turned into library options (fivebar::commands).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/io/commands.h"
#include "fivebar/io/scene.h"
#include "fivebar/model/friction.h"

namespace fivebar::io {
namespace {

const std::string kRoot = FIVEBAR_SOURCE_DIR;

// --start-from-scene: the coefficients the scene's law uses start the fit at the scene's values
// (issue 9 left a LuGre scene's coulomb at the neutral 0.1, as LuGre identifies nothing)
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

}  // namespace
}  // namespace fivebar::io
